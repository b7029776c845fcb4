//! The scene file as written: plain data deserialised from TOML, with spans kept where a
//! later check needs to point at the file (see `docs/scene-format.md`).

use serde::Deserialize;
use std::collections::BTreeMap;
use toml::Spanned;

#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct SceneDesc {
    #[serde(default)]
    pub camera: Option<Spanned<CameraDesc>>,
    #[serde(default)]
    pub film: FilmDesc,
    #[serde(default)]
    pub render: RenderDesc,
    #[serde(default)]
    pub materials: BTreeMap<String, Spanned<MaterialDesc>>,
    #[serde(default)]
    pub objects: Vec<Spanned<ObjectDesc>>,
    #[serde(default)]
    pub lights: Vec<Spanned<LightDesc>>,
    /// AOV name → definition (`lpe:…` or a standard name).
    #[serde(default)]
    pub aovs: BTreeMap<String, Spanned<String>>,
    /// Split beauty per light group (`beauty_<group>`).
    #[serde(default)]
    pub light_groups: bool,
    /// Also split these AOVs per light group.
    #[serde(default)]
    pub light_group_aovs: Vec<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    #[serde(default = "default_position")]
    pub position: [f32; 3],
    #[serde(default)]
    pub look_at: [f32; 3],
    #[serde(default = "default_up")]
    pub up: [f32; 3],
    #[serde(default = "default_fov")]
    pub fov: f32,
    #[serde(default)]
    pub fov_axis: Option<Spanned<String>>,
    #[serde(default)]
    pub aperture_radius: f32,
    #[serde(default)]
    pub focus_distance: Option<f32>,
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

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FilmDesc {
    #[serde(default = "default_resolution")]
    pub resolution: [u32; 2],
    /// `box` or `gaussian`.
    #[serde(default)]
    pub filter: Option<Spanned<String>>,
    /// Standard deviation of the Gaussian filter, in pixels.
    #[serde(default = "default_stddev")]
    pub filter_stddev: f32,
}

fn default_resolution() -> [u32; 2] {
    [256, 256]
}
fn default_stddev() -> f32 {
    0.5
}

impl Default for FilmDesc {
    fn default() -> Self {
        FilmDesc {
            resolution: default_resolution(),
            filter: None,
            filter_stddev: default_stddev(),
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderDesc {
    #[serde(default = "default_spp")]
    pub spp: u32,
    /// Path segments, as Mitsuba counts them: 1 = emitters seen directly.
    #[serde(default = "default_max_depth")]
    pub max_depth: u32,
    #[serde(default)]
    pub max_diffuse_depth: Option<u32>,
    #[serde(default)]
    pub max_specular_depth: Option<u32>,
    #[serde(default = "default_rr_depth")]
    pub rr_depth: u32,
    /// Maximum luminance of one contribution (0: off), for direct and indirect light.
    #[serde(default)]
    pub clamp_direct: f32,
    #[serde(default)]
    pub clamp_indirect: f32,
    #[serde(default)]
    pub seed: u64,
}

fn default_spp() -> u32 {
    16
}
fn default_max_depth() -> u32 {
    8
}
fn default_rr_depth() -> u32 {
    5
}

impl Default for RenderDesc {
    fn default() -> Self {
        RenderDesc {
            spp: default_spp(),
            max_depth: default_max_depth(),
            max_diffuse_depth: None,
            max_specular_depth: None,
            rr_depth: default_rr_depth(),
            clamp_direct: 0.0,
            clamp_indirect: 0.0,
            seed: 0,
        }
    }
}

#[derive(Debug, Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub struct MaterialDesc {
    #[serde(rename = "type")]
    pub kind: Spanned<String>,
    pub albedo: Option<[f32; 3]>,
    /// Translucent: reflected and transmitted albedo.
    pub reflect: Option<[f32; 3]>,
    pub transmit: Option<[f32; 3]>,
    /// Conductor: reflectance at normal incidence.
    pub f0: Option<[f32; 3]>,
    #[serde(default)]
    pub roughness: f32,
    pub ior: Option<f32>,
    pub tint: Option<[f32; 3]>,
    /// Colour reported by the `U4` user lobe.
    pub user_color: Option<[f32; 3]>,
}

/// Object-to-world placement: scale, then rotate (degrees about X, then Y, then Z), then
/// translate; or a row-major 4×4 `matrix`.
pub fn placement(
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

#[derive(Debug, Deserialize, Clone, Copy)]
#[serde(untagged)]
pub enum ScaleDesc {
    Uniform(f32),
    PerAxis([f32; 3]),
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectDesc {
    pub name: Option<String>,
    /// rectangle | quad | cube | disk | sphere | mesh | obj
    pub shape: Spanned<String>,
    pub material: Option<Spanned<String>>,
    /// LPE labels of every event on this object; defaults to the object's name.
    pub lpegroups: Option<Vec<String>>,
    pub translate: Option<[f32; 3]>,
    pub rotate: Option<[f32; 3]>,
    pub scale: Option<ScaleDesc>,
    pub matrix: Option<[f32; 16]>,
    pub center: Option<[f32; 3]>,
    pub radius: Option<f32>,
    pub corners: Option<[[f32; 3]; 4]>,
    pub positions: Option<Vec<[f32; 3]>>,
    pub indices: Option<Vec<[u32; 3]>>,
    pub normals: Option<Vec<[f32; 3]>>,
    /// OBJ file, relative to the scene file.
    pub file: Option<Spanned<String>>,
    pub segments: Option<u32>,
    /// Radiance of a glowing (non-light) surface: seen as an `O` event.
    pub emission: Option<[f32; 3]>,
    #[serde(default)]
    pub holdout: bool,
    /// Trace sets: which rays see this object.
    #[serde(default = "yes")]
    pub visible_camera: bool,
    #[serde(default = "yes")]
    pub visible_indirect: bool,
    #[serde(default = "yes")]
    pub casts_shadows: bool,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightDesc {
    #[serde(rename = "type")]
    pub kind: Spanned<String>,
    pub name: Option<String>,
    #[serde(default)]
    pub groups: Vec<String>,
    pub radiance: Option<[f32; 3]>,
    pub intensity: Option<[f32; 3]>,
    pub irradiance: Option<[f32; 3]>,
    /// Multiplies the colour.
    #[serde(default = "one")]
    pub strength: f32,
    #[serde(default = "yes")]
    pub camera_visible: bool,
    #[serde(default)]
    pub two_sided: bool,
    /// The surface material of an area light (it can reflect too); none by default.
    pub material: Option<Spanned<String>>,
    pub translate: Option<[f32; 3]>,
    pub rotate: Option<[f32; 3]>,
    pub scale: Option<ScaleDesc>,
    pub matrix: Option<[f32; 16]>,
    pub corners: Option<[[f32; 3]; 4]>,
    pub center: Option<[f32; 3]>,
    pub radius: Option<f32>,
    pub position: Option<[f32; 3]>,
    pub direction: Option<[f32; 3]>,
    /// Spot: full cone angle and the width of its soft edge, in degrees.
    pub cone_angle: Option<f32>,
    pub cone_softness: Option<f32>,
    /// Dome: an equirectangular EXR, relative to the scene file.
    pub map: Option<Spanned<String>>,
    pub segments: Option<u32>,
    /// Light linking: only objects in these lpegroups are lit (default: all) …
    pub include: Option<Vec<String>>,
    /// … except objects in these.
    #[serde(default)]
    pub exclude: Vec<String>,
}

fn one() -> f32 {
    1.0
}
fn yes() -> bool {
    true
}
