//! Materials: each description becomes a BSDF (a list of lobes) and a user colour.

use crate::material::anisotropy::AnisotropyDirection;
use crate::material::openpbr::{self, InputKind, InputMut, LobeSet, OpenPbr};
use crate::material::pbr::MIN_TEXTURED_ROUGHNESS;
use crate::material::presence::Presence;
use crate::material::texture::{ColorSpace, MipMap, Texture, UvTransform, Wrap};
use crate::material::textured::{InputRef, MaterialTextures, ShadeModel, Textured};
use crate::material::Bsdf;
use crate::scene::desc::{
    ImageSource, MaterialDesc, MaterialKind, NameRef, SceneDesc, ShapeDesc, TextureDesc,
    TextureRef, TexturesDesc,
};
use crate::scene::{Material, SceneError};
use glam::Vec3A;
use std::collections::{HashMap, HashSet};
use std::sync::Arc;

/// Decoded images, each read once however many materials use it.
#[derive(Default)]
struct Images {
    decoded: HashMap<(String, bool), Arc<MipMap>>,
}

impl Images {
    fn texture(&mut self, t: &TextureDesc, space: ColorSpace) -> Result<Texture, SceneError> {
        let key = (t.image.to_string(), space == ColorSpace::Srgb);
        let image = match self.decoded.get(&key) {
            Some(image) => image.clone(),
            None => {
                let decoded = match &t.image {
                    ImageSource::File(path) => MipMap::read(path, space),
                    ImageSource::Bytes { bytes, .. } => MipMap::decode(bytes, space),
                }
                .map_err(|e| t.origin.error(format!("texture {}: {e}", t.image)))?;
                let image = Arc::new(decoded);
                self.decoded.insert(key, image.clone());
                image
            }
        };
        Ok(Texture {
            image,
            wrap: t.wrap,
            transform: t.transform,
        })
    }
}

/// The scene's materials in name order, and each name's index.
pub fn build(desc: &SceneDesc) -> Result<(Vec<Material>, HashMap<String, u32>), SceneError> {
    let mut materials = Vec::new();
    let mut ids = HashMap::new();
    let mut images = Images::default();
    let colored = colored_materials(desc);
    for (name, m) in &desc.materials {
        ids.insert(name.clone(), materials.len() as u32);
        let (mut built, model) = material(name, m, &mut images, colored.contains(name.as_str()))?;
        // A textured material makes its BSDF at each hit, unregularised.
        if built.textured.is_none() {
            built.regularized = regularized(&model, desc.render.regularize);
        }
        materials.push(built);
    }
    Ok((materials, ids))
}

/// The material with its specular and coat at least `roughness` rough, if that changes
/// it and keeps its events (regularising changes how lobes scatter, never which events
/// they emit).
fn regularized(model: &ShadeModel, roughness: f32) -> Option<Bsdf> {
    let p = &model.params;
    let rough = OpenPbr {
        specular_roughness: p.specular_roughness.max(roughness),
        coat_roughness: p.coat_roughness.max(roughness),
        ..*p
    };
    if rough == *p {
        return None;
    }
    let bsdf = Bsdf::openpbr(&rough, &model.lobes).regularized_glass();
    let before = Bsdf::openpbr(p, &model.lobes);
    let same_events = bsdf.lobes().len() == before.lobes().len()
        && bsdf
            .lobes()
            .iter()
            .zip(before.lobes())
            .all(|(a, b)| (a.transmit, a.scatter) == (b.transmit, b.scatter));
    same_events.then_some(bsdf)
}

/// The materials of objects whose meshes have vertex colours: those shade through the
/// textured path (the colours multiply the base colour), the others pay nothing.
fn colored_materials(desc: &SceneDesc) -> HashSet<&str> {
    desc.objects
        .iter()
        .filter(|o| match &o.shape {
            ShapeDesc::Mesh { parts } => parts.iter().any(|p| p.colors.is_some()),
            ShapeDesc::SharedMesh { parts } => parts.iter().any(|p| p.colors.is_some()),
            _ => false,
        })
        .filter_map(|o| o.material.as_ref().map(|m| m.name.as_str()))
        .collect()
}

/// A colour must be finite and not negative: a NaN albedo reached the `albedo` AOV and
/// every pixel that saw it.
pub fn check_color(c: [f32; 3], what: &str) -> Result<(), String> {
    if c.iter().all(|v| v.is_finite() && *v >= 0.0) {
        Ok(())
    } else {
        Err(format!(
            "{what} is {c:?}: expected finite, non-negative numbers"
        ))
    }
}

/// Resolves a material reference, pointing at it if the scene has no such material.
pub fn find(
    desc: &SceneDesc,
    ids: &HashMap<String, u32>,
    m: &Option<NameRef>,
) -> Result<Option<u32>, SceneError> {
    match m {
        None => Ok(None),
        Some(r) => ids.get(&r.name).copied().map(Some).ok_or_else(|| {
            let known: Vec<&String> = desc.materials.keys().collect();
            r.origin.error(format!(
                "unknown material '{}': the scene defines {known:?}",
                r.name
            ))
        }),
    }
}

/// Material `name` and the model it was made from; `colored`: some object using it has
/// vertex colours, so it is made textured (evaluated at each hit) even without a texture.
fn material(
    name: &str,
    m: &MaterialDesc,
    images: &mut Images,
    colored: bool,
) -> Result<(Material, ShadeModel), SceneError> {
    check_parameters(name, m)?;
    let eta = index_of_refraction(name, m)?;
    let mut t = textures_of(m);
    // The opacity's texture is the presence's, not the BSDF's (it changes no lobe).
    let opacity_texture = t
        .inputs
        .iter()
        .position(|i| i.input == "geometry_opacity")
        .map(|k| t.inputs.remove(k));
    t.inputs.retain(|i| i.input != "geometry_opacity");
    let t = &t;
    let (mut params, color_targets) = preset(m, eta);
    check_openpbr(name, m, &params)?;
    let rough_textured = t.metallic_roughness.is_some();
    let colors_vary = t.base_color.is_some() || colored;
    let is_textured = |input: &str| {
        t.inputs.iter().any(|i| i.input == input)
            || (rough_textured && matches!(input, "specular_roughness" | "base_metalness"))
            || (colors_vary && color_targets.contains(&input))
    };
    let lobes = LobeSet::of(&params, is_textured);
    // A roughness texture keeps the lobes rough everywhere (their events are fixed).
    if is_textured("specular_roughness") {
        params.specular_roughness = params.specular_roughness.max(MIN_TEXTURED_ROUGHNESS);
    }
    if is_textured("coat_roughness") {
        params.coat_roughness = params.coat_roughness.max(MIN_TEXTURED_ROUGHNESS);
    }
    let textured = colored
        || t.base_color.is_some()
        || t.metallic_roughness.is_some()
        || t.normal.is_some()
        || t.emissive.is_some()
        || !t.inputs.is_empty();
    let model = ShadeModel {
        params,
        lobes,
        color_targets: color_targets.iter().map(|n| input_ref(n)).collect(),
    };
    let textured = if textured {
        Some(Box::new(Textured {
            model: model.clone(),
            textures: material_textures(t, images)?,
        }))
    } else {
        None
    };
    let opacity_texture = match opacity_texture {
        Some(i) => Some((images.texture(&i.texture, ColorSpace::Linear)?, i.channel)),
        None => None,
    };
    let presence = Presence::new(params.geometry_opacity, opacity_texture, t.opacity_cutoff);
    let anisotropic =
        params.specular_roughness_anisotropy > 0.0 || is_textured("specular_roughness_anisotropy");
    let anisotropy = match &t.anisotropy_direction {
        Some((rotation, texture)) if anisotropic => Some(Box::new(AnisotropyDirection {
            rotation: *rotation,
            texture: match texture {
                Some(d) => Some(images.texture(d, ColorSpace::Linear)?),
                None => None,
            },
        })),
        _ => None,
    };
    let material = Material {
        bsdf: Bsdf::openpbr(&params, &lobes),
        regularized: None,
        user_color: m.user_color.map(Vec3A::from),
        textured,
        presence: presence.map(Box::new),
        anisotropy,
    };
    Ok((material, model))
}

/// The emission an OpenPBR material gives the objects made of it (`emission_luminance`
/// × `emission_color`: luminance 1 is radiance 1, as Cycles' emission strength).
pub fn emission(m: &MaterialDesc) -> Option<Vec3A> {
    match &m.kind {
        MaterialKind::OpenPbr(p) if p.emission_luminance > 0.0 => {
            Some(p.emission_color * p.emission_luminance)
        }
        _ => None,
    }
}

/// The accessor of OpenPBR input `name` (a name from the table).
fn input_ref(name: &str) -> InputRef {
    openpbr::input(name)
        .expect("presets name OpenPBR inputs")
        .get
}

/// The OpenPBR parameters of a material, and the colour inputs its colour texture (and
/// vertex colours) multiply. The older material types are presets of OpenPBR.
pub fn preset(m: &MaterialDesc, eta: f32) -> (OpenPbr, &'static [&'static str]) {
    let v3 = Vec3A::from;
    let mut p = OpenPbr {
        specular_roughness: m.roughness.min(1.0),
        specular_ior: eta,
        ..OpenPbr::default()
    };
    let targets: &'static [&'static str] = match &m.kind {
        MaterialKind::Diffuse { albedo } => {
            p.base_color = v3(*albedo);
            p.specular_weight = 0.0;
            &["base_color"]
        }
        MaterialKind::Translucent { reflect, transmit } => {
            // A thin sheet: diffuse reflection and transmission, split by their share.
            let (r, t) = (v3(*reflect), v3(*transmit));
            let (lr, lt) = (crate::light::luminance(r), crate::light::luminance(t));
            let w = if lr + lt > 0.0 { lt / (lr + lt) } else { 0.0 };
            p.geometry_thin_walled = true;
            p.specular_weight = 0.0;
            p.subsurface_weight = w;
            p.base_color = if w < 1.0 { r / (1.0 - w) } else { Vec3A::ZERO };
            p.subsurface_color = if w > 0.0 { t / w } else { Vec3A::ZERO };
            &["base_color", "subsurface_color"]
        }
        MaterialKind::Conductor { f0 } => {
            p.base_color = v3(*f0);
            p.base_metalness = 1.0;
            &["base_color"]
        }
        MaterialKind::Dielectric { tint, .. } => {
            let tint = tint.map(v3).unwrap_or(Vec3A::ONE);
            p.base_color = tint;
            p.transmission_weight = 1.0;
            p.transmission_color = tint;
            &["base_color", "transmission_color"]
        }
        MaterialKind::Plastic { albedo, .. } => {
            p.base_color = v3(*albedo);
            &["base_color"]
        }
        MaterialKind::Pbr {
            base_color,
            metallic,
            transmission,
            clearcoat,
            clearcoat_roughness,
            ..
        } => {
            // glTF: transmission is tinted by the base colour; KHR_materials_clearcoat's
            // coat has index 1.5.
            p.base_color = v3(*base_color);
            p.base_metalness = *metallic;
            p.transmission_weight = *transmission;
            p.transmission_color = v3(*base_color);
            p.coat_weight = *clearcoat;
            p.coat_roughness = *clearcoat_roughness;
            p.coat_ior = 1.5;
            p.coat_darkening = 0.0;
            &["base_color", "transmission_color"]
        }
        MaterialKind::OpenPbr(params) => {
            p = **params;
            &["base_color"]
        }
    };
    (p, targets)
}

/// Every OpenPBR parameter within its range (a loader that builds them directly, such
/// as glTF's, is checked here as the TOML loader checks what it reads).
fn check_openpbr(name: &str, m: &MaterialDesc, p: &OpenPbr) -> Result<(), SceneError> {
    let mut p = *p;
    for input in openpbr::INPUTS {
        let ok = match (input.kind, (input.get)(&mut p)) {
            (InputKind::Scalar { min, max, .. }, InputMut::Scalar(v)) => {
                v.is_finite() && (min..=max).contains(v)
            }
            (InputKind::Color { .. }, InputMut::Color(c)) => {
                c.is_finite() && c.cmpge(Vec3A::ZERO).all()
            }
            _ => true,
        };
        if !ok {
            return Err(m.origin.error(format!(
                "material '{name}': OpenPBR {} is out of its range",
                input.name
            )));
        }
    }
    Ok(())
}

/// Colours finite and not negative, weights from 0 to 1, roughness from 0 up.
fn check_parameters(name: &str, m: &MaterialDesc) -> Result<(), SceneError> {
    let mut colors = match &m.kind {
        MaterialKind::Diffuse { albedo } | MaterialKind::Plastic { albedo, .. } => {
            vec![("albedo", *albedo)]
        }
        MaterialKind::Translucent { reflect, transmit } => {
            vec![("reflect", *reflect), ("transmit", *transmit)]
        }
        MaterialKind::Conductor { f0 } => vec![("f0", *f0)],
        MaterialKind::Dielectric { tint, .. } => tint.map(|t| ("tint", t)).into_iter().collect(),
        MaterialKind::Pbr { base_color, .. } => vec![("base_color", *base_color)],
        // Checked against OpenPBR's table after the preset.
        MaterialKind::OpenPbr(_) => vec![],
    };
    colors.extend(m.user_color.map(|c| ("user_color", c)));
    for (what, c) in colors {
        check_color(c, &format!("material '{name}': {what}")).map_err(|e| m.origin.error(e))?;
    }
    if let MaterialKind::Pbr {
        metallic,
        transmission,
        clearcoat,
        clearcoat_roughness,
        ..
    } = &m.kind
    {
        for (what, v) in [
            ("metallic", metallic),
            ("transmission", transmission),
            ("clearcoat", clearcoat),
            ("clearcoat_roughness", clearcoat_roughness),
        ] {
            if !(v.is_finite() && (0.0..=1.0).contains(v)) {
                return Err(m.origin.error(format!(
                    "material '{name}': {what} must be a number from 0 to 1, got {v}"
                )));
            }
        }
    }
    if !(m.roughness.is_finite() && m.roughness >= 0.0) {
        return Err(m.origin.error(format!(
            "material '{name}': roughness must be a number from 0 up, got {}",
            m.roughness
        )));
    }
    Ok(())
}

/// The index of refraction of a material that has one (1.5 unless given), checked
/// positive; materials without one get 1.5, unused.
fn index_of_refraction(name: &str, m: &MaterialDesc) -> Result<f32, SceneError> {
    let given = match &m.kind {
        MaterialKind::Dielectric { ior, .. } | MaterialKind::Plastic { ior, .. } => *ior,
        MaterialKind::Pbr { ior, .. } => *ior,
        MaterialKind::OpenPbr(p) => Some(p.specular_ior),
        _ => None,
    };
    match given.unwrap_or(1.5) {
        eta if eta > 0.0 && eta.is_finite() => Ok(eta),
        eta => Err(m.origin.error(format!(
            "material '{name}': ior must be positive, got {eta}"
        ))),
    }
}

/// The material's textures, each image decoded once for the whole scene.
fn material_textures(
    t: &TexturesDesc,
    images: &mut Images,
) -> Result<MaterialTextures, SceneError> {
    let tex = |images: &mut Images, d: &Option<TextureDesc>, space| {
        d.as_ref().map(|d| images.texture(d, space)).transpose()
    };
    Ok(MaterialTextures {
        base_color: tex(images, &t.base_color, ColorSpace::Srgb)?,
        metallic_roughness: tex(images, &t.metallic_roughness, ColorSpace::Linear)?,
        normal: match &t.normal {
            Some((d, scale)) => Some((images.texture(d, ColorSpace::Linear)?, *scale)),
            None => None,
        },
        emissive: tex(images, &t.emissive, ColorSpace::Srgb)?,
        inputs: t
            .inputs
            .iter()
            .map(|i| {
                let space = if i.srgb {
                    ColorSpace::Srgb
                } else {
                    ColorSpace::Linear
                };
                Ok((
                    input_ref(i.input),
                    images.texture(&i.texture, space)?,
                    i.channel,
                    i.exponent,
                ))
            })
            .collect::<Result<_, SceneError>>()?,
    })
}

/// The material's textures, with an MTL's `map_Kd` and `map_Bump`/`norm` (OBJ UVs) where
/// the material names no other.
fn textures_of(m: &MaterialDesc) -> TexturesDesc {
    let mut t = m.textures.clone();
    // No flip here: the OBJ reader already turned OBJ's v (up the image) into ours
    // (down it, glTF's), obj.rs `vt`.
    let from_map = |r: &TextureRef| TextureDesc {
        image: ImageSource::File(r.path.clone()),
        wrap: [Wrap::Repeat; 2],
        transform: UvTransform::default(),
        origin: r.origin.clone(),
    };
    if t.base_color.is_none() {
        t.base_color = m.base_color_map.as_ref().map(from_map);
    }
    if t.normal.is_none() {
        t.normal = m.normal_map.as_ref().map(|r| (from_map(r), r.scale));
    }
    t
}
