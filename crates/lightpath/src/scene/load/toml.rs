//! The TOML scene format (`docs/scene-format.md`): the file as written, deserialised with
//! spans, then converted to the neutral `SceneDesc` with an `Origin` on every entity.
//! Kinds and required fields are checked here, where the spans are.

use super::include::Override;
use super::obj;
use super::Source;
use crate::camera::FovAxis;
use crate::scene::desc::{self as d, NameRef};
use crate::scene::SceneError;
use serde::Deserialize;
use std::collections::{BTreeMap, HashMap};
use std::ops::Range;
use toml::Spanned;

#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    #[serde(default)]
    camera: Option<Spanned<CameraDesc>>,
    /// `[film]` and `[render]`: keys of settings (`settings.rs`), read through its table.
    #[serde(default)]
    film: BTreeMap<String, Spanned<toml::Value>>,
    #[serde(default)]
    render: BTreeMap<String, Spanned<toml::Value>>,
    #[serde(default)]
    materials: BTreeMap<String, Spanned<MaterialDesc>>,
    #[serde(default)]
    objects: Vec<Spanned<ObjectDesc>>,
    #[serde(default)]
    lights: Vec<Spanned<LightDesc>>,
    /// AOV name → definition (`lpe:…` or a standard name).
    #[serde(default)]
    aovs: BTreeMap<String, Spanned<String>>,
    /// Split beauty per light group (`beauty_<group>`).
    #[serde(default)]
    light_groups: bool,
    /// Also split these AOVs per light group.
    #[serde(default)]
    light_group_aovs: Vec<String>,
    /// Write these AOVs' per-pixel variance too (`<aov>_var`).
    #[serde(default)]
    variance: Vec<String>,
    /// Scene files (OBJ, PLY, glTF) merged into this one, their objects overridden by
    /// name.
    #[serde(default)]
    include: Vec<Spanned<IncludeDesc>>,
    /// `[media.NAME]`: participating media that objects' `interior` and `[render]
    /// atmosphere` name.
    #[serde(default)]
    media: BTreeMap<String, Spanned<MediumToml>>,
}

/// A `[media.NAME]` table: a homogeneous medium.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MediumToml {
    /// Absorption and scattering coefficients (RGB, per scene unit).
    #[serde(default)]
    sigma_a: [f32; 3],
    #[serde(default)]
    sigma_s: [f32; 3],
    /// Henyey–Greenstein asymmetry.
    #[serde(default)]
    g: f32,
    /// Radiance emitted per unit length (at density 1 with a grid).
    emission: Option<[f32; 3]>,
    /// An OpenVDB file (relative to the scene file) whose float grid is the density.
    density: Option<Spanned<String>>,
    /// The grid's name in that file (default "density").
    grid: Option<Spanned<String>>,
    /// Multiplies the grid's values (default 1).
    density_scale: Option<f32>,
}

/// `[[include]]`: a scene file, placed, with overrides of its objects by name.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct IncludeDesc {
    file: Spanned<String>,
    translate: Option<[f32; 3]>,
    rotate: Option<[f32; 3]>,
    scale: Option<ScaleDesc>,
    matrix: Option<[f32; 16]>,
    /// `[include.objects.NAME]`: what changes on every object of that name.
    #[serde(default)]
    objects: BTreeMap<String, Spanned<OverrideDesc>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct OverrideDesc {
    material: Option<Spanned<String>>,
    lpegroups: Option<Vec<String>>,
    visible_camera: Option<bool>,
    visible_indirect: Option<bool>,
    casts_shadows: Option<bool>,
    holdout: Option<bool>,
    /// false: an emissive object glows (`O`) instead of being a mesh light; true: the
    /// reverse.
    light: Option<bool>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraDesc {
    #[serde(default = "default_position")]
    position: [f32; 3],
    #[serde(default)]
    look_at: [f32; 3],
    #[serde(default = "default_up")]
    up: [f32; 3],
    #[serde(default = "default_fov")]
    fov: f32,
    #[serde(default)]
    fov_axis: Option<Spanned<String>>,
    #[serde(default)]
    aperture_radius: f32,
    #[serde(default)]
    focus_distance: Option<f32>,
}

fn default_position() -> [f32; 3] {
    [0.0, 0.0, 5.0]
}
fn default_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}
fn default_fov() -> f32 {
    40.0
}

impl Default for CameraDesc {
    fn default() -> Self {
        CameraDesc {
            position: default_position(),
            look_at: [0.0; 3],
            up: default_up(),
            fov: default_fov(),
            fov_axis: None,
            aperture_radius: 0.0,
            focus_distance: None,
        }
    }
}

/// The `[film]` and `[render]` settings, each read and checked by its entry in the
/// settings table; the settings not written keep their defaults.
fn settings(src: &Source, file: &SceneFile) -> Result<d::RenderDesc, SceneError> {
    use crate::settings::{self, Section};
    let mut render = d::RenderDesc::default();
    for (section, values) in [(Section::Film, &file.film), (Section::Render, &file.render)] {
        for (key, value) in values {
            // The atmosphere names a medium; the scene's media read it (`media`).
            if section == Section::Render && key == "atmosphere" {
                continue;
            }
            let setting = settings::find(section, key).ok_or_else(|| {
                src.error(Some(value.span()), settings::unknown_key(section, key))
            })?;
            (setting.read_toml)(value.get_ref(), &mut render)
                .map_err(|e| src.error(Some(value.span()), e))?;
        }
    }
    settings::check_together(&render).map_err(|e| src.error(None, e))?;
    Ok(render)
}

/// A `[materials.NAME]` table. The keys of the older types are fields; an `openpbr`
/// material's parameters (and `<parameter>_texture` keys) are collected in `inputs` and
/// checked against OpenPBR's table, which also rejects unknown keys of the other types.
#[derive(Debug, Deserialize, Clone)]
struct MaterialDesc {
    #[serde(rename = "type")]
    kind: Spanned<String>,
    albedo: Option<[f32; 3]>,
    /// Translucent: reflected and transmitted albedo.
    reflect: Option<[f32; 3]>,
    transmit: Option<[f32; 3]>,
    /// Conductor: reflectance at normal incidence.
    f0: Option<[f32; 3]>,
    roughness: Option<f32>,
    ior: Option<f32>,
    tint: Option<[f32; 3]>,
    /// Colour reported by the `U4` user lobe.
    user_color: Option<[f32; 3]>,
    /// pbr: glTF's metallic-roughness parameters (and openpbr's base colour).
    base_color: Option<[f32; 3]>,
    metallic: Option<f32>,
    transmission: Option<f32>,
    clearcoat: Option<f32>,
    clearcoat_roughness: Option<f32>,
    /// Textures (paths relative to the scene file): colour multiplies albedo, f0, tint
    /// or base colour; metallic-roughness is glTF's layout (green, blue).
    color_texture: Option<Spanned<String>>,
    metallic_roughness_texture: Option<Spanned<String>>,
    normal_texture: Option<Spanned<String>>,
    #[serde(default = "one")]
    normal_scale: f32,
    emission_texture: Option<Spanned<String>>,
    /// repeat | clamp | mirror, for all the material's textures.
    texture_wrap: Option<Spanned<String>>,
    /// Every other key: OpenPBR parameters, or mistakes.
    #[serde(flatten)]
    inputs: BTreeMap<String, toml::Value>,
}

/// Object-to-world placement: scale, then rotate (degrees about X, then Y, then Z), then
/// translate; or a row-major 4×4 `matrix`.
fn placement(
    translate: Option<[f32; 3]>,
    rotate: Option<[f32; 3]>,
    scale: Option<ScaleDesc>,
    matrix: Option<[f32; 16]>,
) -> glam::Affine3A {
    use glam::{Affine3A, Mat4, Quat, Vec3};
    if let Some(m) = matrix {
        return Affine3A::from_mat4(Mat4::from_cols_array(&m).transpose());
    }
    let s = match scale {
        None => Vec3::ONE,
        Some(ScaleDesc::Uniform(k)) => Vec3::splat(k),
        Some(ScaleDesc::PerAxis(v)) => Vec3::from(v),
    };
    let r = rotate.unwrap_or([0.0; 3]);
    let q = Quat::from_rotation_z(r[2].to_radians())
        * Quat::from_rotation_y(r[1].to_radians())
        * Quat::from_rotation_x(r[0].to_radians());
    Affine3A::from_scale_rotation_translation(s, q, Vec3::from(translate.unwrap_or([0.0; 3])))
}

#[derive(Debug, Clone, Copy)]
enum ScaleDesc {
    Uniform(f32),
    PerAxis([f32; 3]),
}

/// `scale = 2` or `scale = [1, 2, 1]`, with an error that says so (serde's untagged enums
/// only say "data did not match any variant of untagged enum ScaleDesc").
impl<'de> Deserialize<'de> for ScaleDesc {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<ScaleDesc, D::Error> {
        struct Scale;
        impl<'de> serde::de::Visitor<'de> for Scale {
            type Value = ScaleDesc;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("one number or three, as in scale = 2 or scale = [1, 2, 1]")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<ScaleDesc, E> {
                Ok(ScaleDesc::Uniform(v as f32))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<ScaleDesc, E> {
                Ok(ScaleDesc::Uniform(v as f32))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<ScaleDesc, E> {
                Ok(ScaleDesc::Uniform(v as f32))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<ScaleDesc, A::Error> {
                let mut v = [0.0f32; 3];
                for (i, slot) in v.iter_mut().enumerate() {
                    *slot = seq
                        .next_element()?
                        .ok_or_else(|| serde::de::Error::invalid_length(i, &self))?;
                }
                if seq.next_element::<serde::de::IgnoredAny>()?.is_some() {
                    return Err(serde::de::Error::invalid_length(4, &self));
                }
                Ok(ScaleDesc::PerAxis(v))
            }
        }
        d.deserialize_any(Scale)
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectDesc {
    name: Option<String>,
    /// rectangle | quad | cube | disk | sphere | mesh | obj
    shape: Spanned<String>,
    material: Option<Spanned<String>>,
    /// LPE labels of every event on this object; defaults to the object's name.
    lpegroups: Option<Vec<String>>,
    /// The asset the object belongs to (Cryptomatte's CryptoAsset); defaults to its name.
    asset: Option<String>,
    translate: Option<[f32; 3]>,
    rotate: Option<[f32; 3]>,
    scale: Option<ScaleDesc>,
    matrix: Option<[f32; 16]>,
    center: Option<[f32; 3]>,
    radius: Option<f32>,
    corners: Option<[[f32; 3]; 4]>,
    positions: Option<Vec<[f32; 3]>>,
    indices: Option<Vec<[u32; 3]>>,
    normals: Option<Vec<[f32; 3]>>,
    /// OBJ file, relative to the scene file.
    file: Option<Spanned<String>>,
    segments: Option<u32>,
    /// Radiance of a glowing (non-light) surface: seen as an `O` event.
    emission: Option<[f32; 3]>,
    /// The medium inside this (closed) object, a `[media.NAME]`.
    interior: Option<Spanned<String>>,
    /// Overlapping interiors go to the higher priority.
    priority: Option<i32>,
    #[serde(default)]
    holdout: bool,
    /// Trace sets: which rays see this object.
    #[serde(default = "yes")]
    visible_camera: bool,
    #[serde(default = "yes")]
    visible_indirect: bool,
    #[serde(default = "yes")]
    casts_shadows: bool,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct LightDesc {
    #[serde(rename = "type")]
    kind: Spanned<String>,
    name: Option<String>,
    #[serde(default)]
    groups: Vec<String>,
    radiance: Option<[f32; 3]>,
    intensity: Option<[f32; 3]>,
    irradiance: Option<[f32; 3]>,
    /// Multiplies the colour.
    #[serde(default = "one")]
    strength: f32,
    #[serde(default = "yes")]
    camera_visible: bool,
    /// Whether the light's surface blocks other lights' shadow rays.
    #[serde(default = "yes")]
    casts_shadows: bool,
    #[serde(default)]
    two_sided: bool,
    /// The surface material of an area light (it can reflect too); none by default.
    material: Option<Spanned<String>>,
    translate: Option<[f32; 3]>,
    rotate: Option<[f32; 3]>,
    scale: Option<ScaleDesc>,
    matrix: Option<[f32; 16]>,
    corners: Option<[[f32; 3]; 4]>,
    center: Option<[f32; 3]>,
    radius: Option<f32>,
    /// Cylinder: its length along local X.
    length: Option<f32>,
    position: Option<[f32; 3]>,
    direction: Option<[f32; 3]>,
    /// Spot: full cone angle and the width of its soft edge, in degrees.
    cone_angle: Option<f32>,
    /// Distant: the angular diameter of its disc, in degrees (default 0: one direction).
    angle: Option<f32>,
    cone_softness: Option<f32>,
    /// Dome: an equirectangular EXR, relative to the scene file.
    map: Option<Spanned<String>>,
    /// Dome: the openings it lights an interior through, four corners each.
    portals: Option<Vec<[[f32; 3]; 4]>>,
    /// Mesh: the name of the object(s) whose surface emits.
    object: Option<Spanned<String>>,
    segments: Option<u32>,
    /// Light linking: only objects in these lpegroups are lit (default: all) …
    include: Option<Vec<String>>,
    /// … except objects in these.
    #[serde(default)]
    exclude: Vec<String>,
    /// Shadow linking: only objects in these lpegroups cast shadows from this light
    /// (default: all) …
    shadow_include: Option<Vec<String>>,
    /// … except objects in these.
    #[serde(default)]
    shadow_exclude: Vec<String>,
}

fn one() -> f32 {
    1.0
}
fn yes() -> bool {
    true
}

/// Parses a TOML scene into the neutral description; OBJ files it names are loaded too.
pub fn load(src: &Source) -> Result<d::SceneDesc, SceneError> {
    let file: SceneFile = toml::from_str(&src.text).map_err(|e| {
        let message = match e.message().trim() {
            // The parser has nothing to say about a key with no value at the end of a file.
            "" => "expected a value here (a number, string, array or table)",
            m => m,
        };
        src.error(e.span(), message)
    })?;
    let render = settings(src, &file)?;
    let at = |span: Range<usize>| src.origin(Some(span));
    // Included files first: their materials are renamed where this file's take a name.
    let mut scene = d::SceneDesc::default();
    for (name, m) in &file.materials {
        scene
            .materials
            .insert(name.clone(), material(src, name, m)?);
    }
    for inc in &file.include {
        include(src, inc, &mut scene)?;
    }
    // OBJ files by path: objects naming the same file share its triangles.
    let mut files = HashMap::new();
    for (name, m) in &file.media {
        let medium = medium(src, name, m)?;
        scene.media.media.insert(name.clone(), medium);
    }
    for o in &file.objects {
        if let Some(interior) = &o.get_ref().interior {
            scene.media.interiors.push(d::InteriorDesc {
                object: scene.objects.len(),
                medium: NameRef {
                    name: interior.get_ref().clone(),
                    origin: at(interior.span()),
                },
                priority: o.get_ref().priority.unwrap_or(0),
            });
        }
        scene.objects.push(object(src, o, &mut files)?);
    }
    scene.media.atmosphere = match file.render.get("atmosphere") {
        None => None,
        Some(v) => match v.get_ref() {
            toml::Value::String(name) => Some(NameRef {
                name: name.clone(),
                origin: at(v.span()),
            }),
            _ => {
                return Err(src.error(
                    Some(v.span()),
                    "atmosphere: expected the name of a [media.NAME] table, in quotes",
                ))
            }
        },
    };
    for l in &file.lights {
        if l.get_ref().kind.get_ref() == "mesh" {
            let lights = mesh_lights(src, l, &scene.objects)?;
            scene.lights.extend(lights);
        } else {
            scene.lights.push(light(src, l)?);
        }
    }
    let d::SceneDesc {
        materials,
        objects,
        lights,
        warnings,
        camera: included_camera,
        media,
        ..
    } = scene;
    let camera = match file.camera.as_ref() {
        Some(c) => Some(camera(src, c)?),
        None => included_camera,
    };
    Ok(d::SceneDesc {
        source: src.name.clone(),
        camera,
        render,
        materials,
        objects,
        lights,
        aovs: file
            .aovs
            .iter()
            .map(|(n, s)| {
                let aov = d::AovDesc {
                    definition: s.get_ref().clone(),
                    origin: at(s.span()),
                };
                (n.clone(), aov)
            })
            .collect(),
        light_groups: file.light_groups,
        cameras: Vec::new(),
        light_group_aovs: file.light_group_aovs,
        warnings,
        variance: file.variance,
        media,
        output: None,
        products: Vec::new(),
        standard_aovs: None,
    })
}

/// A `[media.NAME]` table, its numbers checked: coefficients finite and not negative,
/// |g| < 1.
fn medium(src: &Source, name: &str, m: &Spanned<MediumToml>) -> Result<d::MediumDesc, SceneError> {
    let span = m.span();
    let m = m.get_ref();
    let fail = |key: &str, msg: String| {
        Err(src.error(key_span(src, &span, key), format!("medium '{name}': {msg}")))
    };
    for (key, v) in [
        ("sigma_a", Some(m.sigma_a)),
        ("sigma_s", Some(m.sigma_s)),
        ("emission", m.emission),
    ] {
        if let Some(v) = v.filter(|v| v.iter().any(|c| !c.is_finite() || *c < 0.0)) {
            return fail(
                key,
                format!("{key} is {v:?}: expected finite numbers ≥ 0 (per scene unit)"),
            );
        }
    }
    if m.g.is_nan() || m.g.abs() >= 1.0 {
        return fail(
            "g",
            format!(
                "g is {}: expected a number between -1 and 1 (exclusive)",
                m.g
            ),
        );
    }
    if let Some(scale) = m.density_scale.filter(|s| !s.is_finite() || *s < 0.0) {
        return fail(
            "density_scale",
            format!("density_scale is {scale}: expected a finite number ≥ 0"),
        );
    }
    if m.density.is_none() {
        for (key, set) in [
            ("grid", m.grid.is_some()),
            ("density_scale", m.density_scale.is_some()),
        ] {
            if set {
                return fail(
                    key,
                    format!(
                        "{key} without density: name the OpenVDB file with density = \"….vdb\""
                    ),
                );
            }
        }
    }
    let density = m.density.as_ref().map(|f| d::DensityDesc {
        path: src.dir.join(f.get_ref()),
        grid: m
            .grid
            .as_ref()
            .map_or_else(|| "density".to_string(), |g| g.get_ref().clone()),
        scale: m.density_scale.unwrap_or(1.0),
        origin: src.origin(Some(f.span())),
    });
    Ok(d::MediumDesc {
        sigma_a: m.sigma_a,
        sigma_s: m.sigma_s,
        g: m.g,
        emission: m.emission,
        density,
        origin: src.origin(Some(span)),
    })
}

fn name_ref(src: &Source, s: &Option<Spanned<String>>) -> Option<NameRef> {
    s.as_ref().map(|s| NameRef {
        name: s.get_ref().clone(),
        origin: src.origin(Some(s.span())),
    })
}

fn camera(src: &Source, c: &Spanned<CameraDesc>) -> Result<d::CameraDesc, SceneError> {
    let origin = src.origin(Some(c.span()));
    let c = c.get_ref();
    let fov_axis = match c.fov_axis.as_ref().map(|s| s.get_ref().as_str()) {
        None | Some("smaller") => FovAxis::Smaller,
        Some("larger") => FovAxis::Larger,
        Some("x") => FovAxis::X,
        Some("y") => FovAxis::Y,
        Some(other) => {
            return Err(src.error(
                c.fov_axis.as_ref().map(|s| s.span()),
                format!("unknown fov_axis '{other}': expected x, y, smaller or larger"),
            ))
        }
    };
    Ok(d::CameraDesc {
        position: c.position,
        look_at: c.look_at,
        up: c.up,
        fov: c.fov,
        fov_axis,
        aperture_radius: c.aperture_radius,
        focus_distance: c.focus_distance,
        origin,
    })
}

fn material(
    src: &Source,
    name: &str,
    m: &Spanned<MaterialDesc>,
) -> Result<d::MaterialDesc, SceneError> {
    let span = m.span();
    let m = m.get_ref();
    let need = |v: Option<[f32; 3]>, what: &str| -> Result<[f32; 3], SceneError> {
        v.ok_or_else(|| {
            src.error(
                Some(span.clone()),
                format!("material '{name}': expected '{what}' = [r, g, b]"),
            )
        })
    };
    let kind_name = m.kind.get_ref().as_str();
    if kind_name != "openpbr" {
        if let Some(key) = m.inputs.keys().next() {
            return Err(src.error(
                key_span(src, &span, key),
                format!(
                    "material '{name}': unknown key '{key}' for type '{kind_name}'{}",
                    hint_openpbr(key)
                ),
            ));
        }
    }
    let metallic = m.metallic.unwrap_or(0.0);
    let kind = match kind_name {
        "diffuse" => d::MaterialKind::Diffuse { albedo: need(m.albedo, "albedo")? },
        "translucent" => d::MaterialKind::Translucent { reflect: need(m.reflect, "reflect")?, transmit: need(m.transmit, "transmit")? },
        "conductor" => d::MaterialKind::Conductor { f0: need(m.f0, "f0")? },
        "dielectric" => d::MaterialKind::Dielectric { ior: m.ior, tint: m.tint },
        "plastic" => d::MaterialKind::Plastic { albedo: need(m.albedo, "albedo")?, ior: m.ior },
        "pbr" => d::MaterialKind::Pbr {
            base_color: need(m.base_color, "base_color")?,
            metallic,
            ior: m.ior,
            transmission: m.transmission.unwrap_or(0.0),
            clearcoat: m.clearcoat.unwrap_or(0.0),
            clearcoat_roughness: m.clearcoat_roughness.unwrap_or(0.0),
        },
        "openpbr" => d::MaterialKind::OpenPbr(Box::new(openpbr(src, name, &span, m)?)),
        other => {
            return Err(src.error(
                Some(m.kind.span()),
                format!("unknown material type '{other}': expected openpbr, diffuse, translucent, conductor, dielectric, plastic or pbr"),
            ))
        }
    };
    Ok(d::MaterialDesc {
        kind,
        roughness: m.roughness.unwrap_or(0.0),
        user_color: m.user_color,
        textures: textures(src, name, &span, m)?,
        base_color_map: None,
        normal_map: None,
        origin: src.origin(Some(span)),
    })
}

/// Where `key` is written inside the table at `table`: its own position when it can be
/// found, else the table's.
fn key_span(src: &Source, table: &Range<usize>, key: &str) -> Option<Range<usize>> {
    let text = src.text.get(table.clone())?;
    let mut from = 0;
    while let Some(i) = text[from..].find(key) {
        let at = from + i;
        let before_ok = at == 0
            || !text.as_bytes()[at - 1].is_ascii_alphanumeric() && text.as_bytes()[at - 1] != b'_';
        let rest = text[at + key.len()..].trim_start_matches([' ', '\t', '"']);
        if before_ok && rest.starts_with('=') {
            return Some(table.start + at..table.start + at + key.len());
        }
        from = at + key.len();
    }
    Some(table.clone())
}

/// A hint for a key that is an OpenPBR parameter written on another type.
fn hint_openpbr(key: &str) -> String {
    use crate::material::openpbr;
    if openpbr::input(key.trim_end_matches("_texture")).is_some() {
        return " (it is an OpenPBR parameter: write type = \"openpbr\")".to_string();
    }
    let names = openpbr::INPUTS
        .iter()
        .map(|i| i.name)
        .chain(LEGACY_KEYS.iter().copied());
    crate::suggest::did_you_mean(key, names)
}

/// The keys of the older material types.
const LEGACY_KEYS: &[&str] = &[
    "type",
    "albedo",
    "reflect",
    "transmit",
    "f0",
    "roughness",
    "ior",
    "tint",
    "user_color",
    "base_color",
    "metallic",
    "transmission",
    "clearcoat",
    "clearcoat_roughness",
    "color_texture",
    "metallic_roughness_texture",
    "normal_texture",
    "normal_scale",
    "emission_texture",
    "texture_wrap",
];

/// An `openpbr` material's parameters: the specification's defaults, then each key
/// written, checked against its kind and range.
fn openpbr(
    src: &Source,
    name: &str,
    span: &Range<usize>,
    m: &MaterialDesc,
) -> Result<crate::material::openpbr::OpenPbr, SceneError> {
    use crate::material::openpbr::{self, InputKind, InputMut, OpenPbr};
    let legacy = [
        ("albedo", m.albedo.is_some(), "base_color"),
        ("reflect", m.reflect.is_some(), "base_color"),
        ("transmit", m.transmit.is_some(), "subsurface_color"),
        ("f0", m.f0.is_some(), "base_color with base_metalness = 1"),
        ("roughness", m.roughness.is_some(), "specular_roughness"),
        ("ior", m.ior.is_some(), "specular_ior"),
        ("tint", m.tint.is_some(), "transmission_color"),
        ("metallic", m.metallic.is_some(), "base_metalness"),
        (
            "transmission",
            m.transmission.is_some(),
            "transmission_weight",
        ),
        ("clearcoat", m.clearcoat.is_some(), "coat_weight"),
        (
            "clearcoat_roughness",
            m.clearcoat_roughness.is_some(),
            "coat_roughness",
        ),
    ];
    if let Some((key, _, instead)) = legacy.iter().find(|l| l.1) {
        return Err(src.error(
            key_span(src, span, key),
            format!("material '{name}': '{key}' is not an OpenPBR parameter: write {instead}"),
        ));
    }
    let mut p = OpenPbr::default();
    if let Some(c) = m.base_color {
        p.base_color = glam::Vec3A::from(c);
    }
    for (key, value) in &m.inputs {
        if key.ends_with("_texture") && openpbr::input(key.trim_end_matches("_texture")).is_some() {
            continue;
        }
        let at = || key_span(src, span, key);
        let Some(input) = openpbr::input(key) else {
            let names = openpbr::INPUTS
                .iter()
                .map(|i| i.name)
                .chain(LEGACY_KEYS.iter().copied());
            let hint = crate::suggest::did_you_mean(key, names);
            return Err(src.error(
                at(),
                format!("material '{name}': unknown OpenPBR parameter '{key}'{hint}"),
            ));
        };
        let number = |v: &toml::Value| match v {
            toml::Value::Float(f) => Some(*f as f32),
            toml::Value::Integer(i) => Some(*i as f32),
            _ => None,
        };
        match (input.kind, (input.get)(&mut p)) {
            (InputKind::Scalar { min, max, .. }, InputMut::Scalar(slot)) => {
                let v = number(value)
                    .filter(|v| v.is_finite() && (min..=max).contains(v))
                    .ok_or_else(|| {
                        let range = if max == f32::MAX {
                            format!("from {min} up")
                        } else {
                            format!("from {min} to {max}")
                        };
                        src.error(
                            at(),
                            format!(
                                "material '{name}': {key} must be a number {range}, got {value}"
                            ),
                        )
                    })?;
                *slot = v;
            }
            (InputKind::Color { .. }, InputMut::Color(slot)) => {
                let c = value
                    .as_array()
                    .filter(|a| a.len() == 3)
                    .and_then(|a| Some([number(&a[0])?, number(&a[1])?, number(&a[2])?]))
                    .filter(|c| c.iter().all(|v| v.is_finite() && *v >= 0.0))
                    .ok_or_else(|| src.error(at(), format!("material '{name}': {key} must be [r, g, b] of finite, non-negative numbers, got {value}")))?;
                *slot = glam::Vec3A::from(c);
            }
            (InputKind::Bool { .. }, InputMut::Bool(slot)) => {
                *slot = value.as_bool().ok_or_else(|| {
                    src.error(
                        at(),
                        format!("material '{name}': {key} must be true or false, got {value}"),
                    )
                })?;
            }
            _ => unreachable!("an input's kind matches its value"),
        }
    }
    Ok(p)
}

/// The OBJ files a scene has loaded, by path.
type ObjFiles = HashMap<std::path::PathBuf, std::sync::Arc<Vec<d::MeshData>>>;

/// A material's textures, their paths resolved against the scene file's directory.
fn textures(
    src: &Source,
    name: &str,
    span: &Range<usize>,
    m: &MaterialDesc,
) -> Result<d::TexturesDesc, SceneError> {
    use crate::material::openpbr::{self, InputKind};
    use crate::material::texture::{UvTransform, Wrap};
    let wrap = match m.texture_wrap.as_ref().map(|w| (w.get_ref().as_str(), w.span())) {
        None | Some(("repeat", _)) => Wrap::Repeat,
        Some(("clamp", _)) => Wrap::Clamp,
        Some(("mirror", _)) => Wrap::Mirror,
        Some((other, span)) => {
            return Err(src.error(
                Some(span),
                format!("material '{name}': unknown texture_wrap '{other}': expected repeat, clamp or mirror"),
            ))
        }
    };
    let tex = |t: &Option<Spanned<String>>| {
        t.as_ref().map(|t| d::TextureDesc {
            image: d::ImageSource::File(src.dir.join(t.get_ref())),
            wrap: [wrap; 2],
            transform: UvTransform::default(),
            origin: src.origin(Some(t.span())),
        })
    };
    let mut inputs = Vec::new();
    for (key, value) in &m.inputs {
        let Some(input) = key.strip_suffix("_texture").and_then(openpbr::input) else {
            continue;
        };
        let at = key_span(src, span, key);
        let Some(path) = value.as_str() else {
            return Err(src.error(
                at,
                format!("material '{name}': {key} must be an image file's path, got {value}"),
            ));
        };
        let color = matches!(input.kind, InputKind::Color { .. });
        inputs.push(d::InputTexture {
            input: input.name,
            texture: d::TextureDesc {
                image: d::ImageSource::File(src.dir.join(path)),
                wrap: [wrap; 2],
                transform: UvTransform::default(),
                origin: src.origin(at),
            },
            // Numbers from the red channel (a grey image's every channel).
            channel: 0,
            srgb: color,
            exponent: 1.0,
        });
    }
    Ok(d::TexturesDesc {
        base_color: tex(&m.color_texture),
        metallic_roughness: tex(&m.metallic_roughness_texture),
        normal: tex(&m.normal_texture).map(|t| (t, m.normal_scale)),
        emissive: tex(&m.emission_texture),
        inputs,
        opacity_cutoff: None,
        anisotropy_direction: None,
    })
}

fn object(
    src: &Source,
    o: &Spanned<ObjectDesc>,
    files: &mut ObjFiles,
) -> Result<d::ObjectDesc, SceneError> {
    let span = o.span();
    let o = o.get_ref();
    let missing = |what: &str| {
        src.error(
            Some(span.clone()),
            format!("{} shape needs '{what}'", o.shape.get_ref()),
        )
    };
    let shape = match o.shape.get_ref().as_str() {
        "rectangle" | "rect" => d::ShapeDesc::Rectangle,
        "cube" | "box" => d::ShapeDesc::Cube,
        "disk" => d::ShapeDesc::Disk { segments: o.segments.unwrap_or(64) },
        "quad" => d::ShapeDesc::Quad { corners: o.corners.ok_or_else(|| missing("corners"))? },
        "sphere" => d::ShapeDesc::Sphere {
            center: o.center.unwrap_or([0.0; 3]),
            radius: o.radius.ok_or_else(|| missing("radius"))?,
        },
        "mesh" => {
            let positions = o.positions.clone().ok_or_else(|| missing("positions"))?;
            let indices = o.indices.clone().ok_or_else(|| missing("indices"))?;
            let mesh = d::MeshData { positions, indices, normals: o.normals.clone(), uvs: None, tangents: None, colors: None };
            d::ShapeDesc::Mesh { parts: vec![mesh] }
        }
        "obj" => {
            let file = o.file.as_ref().ok_or_else(|| missing("file"))?;
            let path = src.dir.join(file.get_ref());
            let path = std::fs::canonicalize(&path).unwrap_or(path);
            let parts = match files.get(&path) {
                Some(parts) => parts.clone(),
                None => {
                    let parts = obj::load_meshes(&path, &src.origin(Some(file.span())))?;
                    files.entry(path).or_insert(std::sync::Arc::new(parts)).clone()
                }
            };
            d::ShapeDesc::SharedMesh { parts }
        }
        other => {
            return Err(src.error(
                Some(o.shape.span()),
                format!("unknown shape '{other}': expected rectangle, quad, cube, disk, sphere, mesh or obj"),
            ))
        }
    };
    Ok(d::ObjectDesc {
        name: o.name.clone(),
        shape_name: o.shape.get_ref().clone(),
        shape,
        transform: placement(o.translate, o.rotate, o.scale, o.matrix),
        material: name_ref(src, &o.material),
        lpegroups: o.lpegroups.clone(),
        asset: o.asset.clone(),
        emission: o.emission,
        holdout: o.holdout,
        visible_camera: o.visible_camera,
        visible_indirect: o.visible_indirect,
        casts_shadows: o.casts_shadows,
        origin: src.origin(Some(span)),
    })
}

fn light(src: &Source, l: &Spanned<LightDesc>) -> Result<d::LightDesc, SceneError> {
    let span = l.span();
    let l = l.get_ref();
    let kind = l.kind.get_ref().as_str();
    let need = |v: Option<[f32; 3]>, what: &str| -> Result<[f32; 3], SceneError> {
        v.ok_or_else(|| src.error(Some(span.clone()), format!("{kind} light needs '{what}'")))
    };
    let color = |v: Option<[f32; 3]>, what: &str| -> Result<[f32; 3], SceneError> {
        v.ok_or_else(|| {
            src.error(
                Some(span.clone()),
                format!("{kind} light needs '{what}' = [r, g, b]"),
            )
        })
    };
    let (shape, color) = match kind {
        "rect" | "rectangle" => (d::LightKind::Rectangle, color(l.radiance, "radiance")?),
        "quad" => {
            let corners = l.corners.ok_or_else(|| src.error(Some(span.clone()), "quad light needs 'corners'"))?;
            (d::LightKind::Quad { corners }, color(l.radiance, "radiance")?)
        }
        "disk" => (d::LightKind::Disk { segments: l.segments.unwrap_or(64) }, color(l.radiance, "radiance")?),
        "sphere" => {
            let radius = l.radius.ok_or_else(|| src.error(Some(span.clone()), "sphere light needs 'radius'"))?;
            (d::LightKind::Sphere { center: l.center.unwrap_or([0.0; 3]), radius }, color(l.radiance, "radiance")?)
        }
        "cylinder" => {
            let size = |v: Option<f32>, what| v.ok_or_else(|| src.error(Some(span.clone()), format!("cylinder light needs '{what}'")));
            (d::LightKind::Cylinder { radius: size(l.radius, "radius")?, length: size(l.length, "length")? }, color(l.radiance, "radiance")?)
        }
        "point" => {
            let position = need(l.position, "position")?;
            (d::LightKind::Point { position }, color(l.intensity, "intensity")?)
        }
        "spot" => {
            let position = need(l.position, "position")?;
            let direction = need(l.direction, "direction")?;
            let cone_angle = l.cone_angle.unwrap_or(60.0);
            let cone_softness = l.cone_softness.unwrap_or(10.0);
            (d::LightKind::Spot { position, direction, cone_angle, cone_softness }, color(l.intensity, "intensity")?)
        }
        "distant" => {
            let direction = need(l.direction, "direction")?;
            let angle = l.angle.unwrap_or(0.0);
            if !(0.0..=180.0).contains(&angle) {
                return Err(src.error(Some(span.clone()), format!("distant light angle {angle}: expected 0 to 180 degrees")));
            }
            (d::LightKind::Distant { direction, angle }, color(l.irradiance, "irradiance")?)
        }
        "dome" => {
            let map = l.map.as_ref().map(|f| (src.dir.join(f.get_ref()), src.origin(Some(f.span()))));
            // Without a colour the dome is white: strength alone.
            let portals = l.portals.clone().unwrap_or_default();
            (d::LightKind::Dome { map, portals }, l.radiance.unwrap_or([1.0; 3]))
        }
        other => {
            return Err(src.error(
                Some(l.kind.span()),
                format!("unknown light type '{other}': expected rect, quad, disk, sphere, cylinder, point, spot, distant, dome or mesh"),
            ))
        }
    };
    Ok(d::LightDesc {
        kind: shape,
        name: l.name.clone(),
        // A named light without `groups` is its own light group (docs/scene-format.md).
        groups: if l.groups.is_empty() {
            l.name.iter().cloned().collect()
        } else {
            l.groups.clone()
        },
        color,
        strength: l.strength,
        camera_visible: l.camera_visible,
        casts_shadows: l.casts_shadows,
        shaping: None,
        two_sided: l.two_sided,
        material: name_ref(src, &l.material),
        transform: placement(l.translate, l.rotate, l.scale, l.matrix),
        include: l.include.clone(),
        exclude: l.exclude.clone(),
        shadow_include: l.shadow_include.clone(),
        shadow_exclude: l.shadow_exclude.clone(),
        origin: src.origin(Some(span)),
    })
}

/// Merges an `[[include]]`d file into `scene`.
fn include(
    src: &Source,
    inc: &Spanned<IncludeDesc>,
    scene: &mut d::SceneDesc,
) -> Result<(), SceneError> {
    let i = inc.get_ref();
    let path = src.dir.join(i.file.get_ref());
    let from = super::load_file(&path, &src.origin(Some(i.file.span())))?;
    let overrides: Vec<Override> = i
        .objects
        .iter()
        .map(|(name, o)| {
            let origin = src.origin(Some(o.span()));
            let o = o.get_ref();
            Override {
                name: name.clone(),
                material: name_ref(src, &o.material),
                lpegroups: o.lpegroups.clone(),
                visible_camera: o.visible_camera,
                visible_indirect: o.visible_indirect,
                casts_shadows: o.casts_shadows,
                holdout: o.holdout,
                light: o.light,
                origin,
            }
        })
        .collect();
    let xf = placement(i.translate, i.rotate, i.scale, i.matrix);
    super::include::merge(scene, from, xf, &overrides)
}

/// `type = "mesh"`: one mesh light per object named `object`.
fn mesh_lights(
    src: &Source,
    l: &Spanned<LightDesc>,
    objects: &[d::ObjectDesc],
) -> Result<Vec<d::LightDesc>, SceneError> {
    let span = l.span();
    let origin = src.origin(Some(span.clone()));
    let l = l.get_ref();
    let Some(object) = &l.object else {
        return Err(origin.error("mesh light needs 'object' = the name of the object that emits"));
    };
    let radiance = l
        .radiance
        .ok_or_else(|| origin.error("mesh light needs 'radiance' = [r, g, b]"))?;
    if l.material.is_some() {
        return Err(
            origin.error("a mesh light's surface is its object: set 'material' on the object")
        );
    }
    let name = object.get_ref();
    let at = src.origin(Some(object.span()));
    let found: Vec<usize> = (0..objects.len())
        .filter(|&i| objects[i].name.as_deref() == Some(name.as_str()))
        .collect();
    if found.is_empty() {
        let mut names: Vec<&str> = objects.iter().filter_map(|o| o.name.as_deref()).collect();
        names.sort();
        names.dedup();
        return Err(at.error(format!(
            "no object named '{name}' (objects are declared or included before lights): the scene has {names:?}"
        )));
    }
    if let Some(&i) = found.iter().find(|&&i| objects[i].emission.is_some()) {
        return Err(objects[i].origin.error(format!(
            "object '{name}' has 'emission' (a glowing surface) and is a mesh light: choose one"
        )));
    }
    Ok(found
        .into_iter()
        .map(|i| d::LightDesc {
            kind: d::LightKind::Mesh { object: i },
            name: Some(l.name.clone().unwrap_or_else(|| name.clone())),
            groups: if l.groups.is_empty() {
                vec![name.clone()]
            } else {
                l.groups.clone()
            },
            color: radiance,
            strength: l.strength,
            camera_visible: l.camera_visible,
            casts_shadows: l.casts_shadows,
            shaping: None,
            two_sided: l.two_sided,
            material: None,
            transform: glam::Affine3A::IDENTITY,
            include: l.include.clone(),
            exclude: l.exclude.clone(),
            shadow_include: l.shadow_include.clone(),
            shadow_exclude: l.shadow_exclude.clone(),
            origin: origin.clone(),
        })
        .collect())
}
