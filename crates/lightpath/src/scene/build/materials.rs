//! Materials: each description becomes a BSDF (a list of lobes) and a user colour.

use crate::material::pbr::{PbrParams, MIN_TEXTURED_ROUGHNESS};
use crate::material::texture::{ColorSpace, MipMap, Texture, UvTransform, Wrap};
use crate::material::textured::{MaterialTextures, ShadeModel, Textured};
use crate::material::{roughness_to_alpha, Bsdf};
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
        let mut built = material(name, m, &mut images, colored.contains(name.as_str()))?;
        let roughness = desc.render.regularize;
        // A textured material makes its BSDF at each hit, unregularised.
        if built.textured.is_none()
            && roughness > m.roughness
            && !matches!(m.kind, MaterialKind::Diffuse { .. })
        {
            let rough = MaterialDesc {
                roughness,
                ..m.clone()
            };
            let bsdf = material(name, &rough, &mut images, false)?.bsdf;
            // Regularising changes how lobes scatter, never which events they emit.
            let same_events = bsdf.lobes().len() == built.bsdf.lobes().len()
                && bsdf
                    .lobes()
                    .iter()
                    .zip(built.bsdf.lobes())
                    .all(|(a, b)| (a.transmit, a.scatter) == (b.transmit, b.scatter));
            built.regularized = same_events.then_some(bsdf);
        }
        materials.push(built);
    }
    Ok((materials, ids))
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

/// Material `name`; `colored`: some object using it has vertex colours, so it is made
/// textured (evaluated at each hit) even without a texture.
fn material(
    name: &str,
    m: &MaterialDesc,
    images: &mut Images,
    colored: bool,
) -> Result<Material, SceneError> {
    check_parameters(name, m)?;
    let t = &textures_of(m);
    let textured = colored
        || t.base_color.is_some()
        || t.metallic_roughness.is_some()
        || t.normal.is_some()
        || t.emissive.is_some();
    // A roughness texture keeps the lobes rough everywhere (their events are fixed).
    let roughness = if t.metallic_roughness.is_some() {
        m.roughness.max(MIN_TEXTURED_ROUGHNESS)
    } else {
        m.roughness
    };
    let alpha = roughness_to_alpha(roughness);
    let eta = index_of_refraction(name, m)?;
    let v3 = Vec3A::from;
    let bsdf = match &m.kind {
        MaterialKind::Diffuse { albedo } => Bsdf::diffuse(v3(*albedo)),
        MaterialKind::Translucent { reflect, transmit } => {
            Bsdf::translucent(v3(*reflect), v3(*transmit))
        }
        MaterialKind::Conductor { f0 } => Bsdf::conductor(v3(*f0), alpha),
        MaterialKind::Dielectric { tint, .. } => {
            Bsdf::dielectric(eta, alpha, tint.map(v3).unwrap_or(Vec3A::ONE))
        }
        MaterialKind::Plastic { albedo, .. } => Bsdf::plastic(v3(*albedo), eta, alpha),
        MaterialKind::Pbr { .. } => Bsdf::pbr(&pbr_params(m, alpha, eta)),
    };
    let textured = if textured {
        Some(Box::new(Textured {
            model: shade_model(m, roughness, alpha, eta),
            textures: material_textures(t, images)?,
        }))
    } else {
        None
    };
    Ok(Material {
        bsdf,
        regularized: None,
        user_color: m.user_color.map(v3),
        textured,
    })
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
        MaterialKind::Pbr { .. } => pbr_ior(m),
        _ => None,
    };
    match given.unwrap_or(1.5) {
        eta if eta > 0.0 && eta.is_finite() => Ok(eta),
        eta => Err(m.origin.error(format!(
            "material '{name}': ior must be positive, got {eta}"
        ))),
    }
}

/// What a textured material evaluates at each hit, before its textures.
fn shade_model(m: &MaterialDesc, roughness: f32, alpha: f32, eta: f32) -> ShadeModel {
    let v3 = Vec3A::from;
    match &m.kind {
        MaterialKind::Diffuse { albedo } => ShadeModel::Diffuse {
            albedo: v3(*albedo),
        },
        MaterialKind::Translucent { reflect, transmit } => ShadeModel::Translucent {
            reflect: v3(*reflect),
            transmit: v3(*transmit),
        },
        MaterialKind::Conductor { f0 } => ShadeModel::Conductor {
            f0: v3(*f0),
            roughness,
        },
        MaterialKind::Dielectric { tint, .. } => ShadeModel::Dielectric {
            eta,
            roughness,
            tint: tint.map(v3).unwrap_or(Vec3A::ONE),
        },
        MaterialKind::Plastic { albedo, .. } => ShadeModel::Plastic {
            albedo: v3(*albedo),
            eta,
            roughness,
        },
        MaterialKind::Pbr {
            clearcoat_roughness,
            ..
        } => ShadeModel::Pbr {
            params: pbr_params(m, alpha, eta),
            roughness,
            clearcoat_roughness: *clearcoat_roughness,
        },
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
    })
}

/// The material's textures, with an MTL's `map_Kd` and `map_Bump`/`norm` (OBJ UVs) where
/// the material names no other.
fn textures_of(m: &MaterialDesc) -> TexturesDesc {
    let mut t = m.textures.clone();
    // OBJ's v grows up the image, glTF's (Lightpath's) down it: v' = 1 − v.
    let from_map = |r: &TextureRef| TextureDesc {
        image: ImageSource::File(r.path.clone()),
        wrap: [Wrap::Repeat; 2],
        transform: UvTransform {
            rows: [[1.0, 0.0, 0.0], [0.0, -1.0, 1.0]],
        },
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

fn pbr_ior(m: &MaterialDesc) -> Option<f32> {
    match &m.kind {
        MaterialKind::Pbr { ior, .. } => *ior,
        _ => None,
    }
}

/// The untextured parameters of a metallic-roughness material.
fn pbr_params(m: &MaterialDesc, alpha: f32, ior: f32) -> PbrParams {
    let MaterialKind::Pbr {
        base_color,
        metallic,
        transmission,
        clearcoat,
        clearcoat_roughness,
        ..
    } = &m.kind
    else {
        unreachable!("pbr_params of a metallic-roughness material")
    };
    PbrParams {
        base: Vec3A::from(*base_color),
        metallic: *metallic,
        alpha,
        ior,
        glass: *transmission >= 0.5,
        clearcoat: *clearcoat,
        clearcoat_alpha: roughness_to_alpha(*clearcoat_roughness),
    }
}
