//! Scenes: loaders (`load`: TOML, OBJ, built-ins) produce the neutral description
//! (`desc`); the build step (`build`) turns it into the renderable `Scene` — BVH,
//! materials with LPE-classified lobes, lights, and the compiled automaton of the AOVs.

pub mod build;
pub mod desc;
pub mod load;

pub use crate::error::SceneError;
pub use crate::events::DataLobe;
pub use load::Source;

use crate::camera::{Camera, PixelFilter};
use crate::geometry::{Accel, SurfaceAttrs};
use crate::light::Light;
use crate::material::textured::Textured;
use crate::material::Bsdf;
use glam::Vec3A;
use lpe::{Automaton, ClassId, Flags};

/// A material: its BSDF and the colour of its `U4` user lobe.
#[derive(Clone, Debug)]
pub struct Material {
    /// The BSDF (a textured material's lobes and events, with untextured values).
    pub bsdf: Bsdf,
    /// The BSDF after a diffuse bounce under path regularisation (`[render] regularize`):
    /// specular lobes roughened, the same lobes and events. `None`: unchanged.
    pub regularized: Option<Bsdf>,
    pub user_color: Option<Vec3A>,
    /// Textures, if any: the BSDF is then rebuilt at each hit.
    pub textured: Option<Box<Textured>>,
    /// Where the surface is only partly there (cut-outs, `geometry_opacity` < 1);
    /// `None`: opaque.
    pub presence: Option<Box<crate::material::presence::Presence>>,
    /// The direction anisotropy follows on meshes with tangents (glTF); `None`: the
    /// shading frame's first axis.
    pub anisotropy: Option<Box<crate::material::anisotropy::AnisotropyDirection>>,
}

/// One scene object after building: what it is made of and its precomputed LPE classes.
#[derive(Clone, Debug)]
pub struct Object {
    pub name: String,
    pub groups: Vec<String>,
    pub material: Option<u32>,
    /// Radiance of a glowing (non-light) surface.
    pub emission: Vec3A,
    pub light: Option<u32>,
    pub holdout: bool,
    /// Lights that do not illuminate this object (light linking).
    pub unlit_by: Vec<u32>,
    /// Lights whose shadow rays pass this object (shadow linking).
    pub unshadowing: Vec<u32>,
    /// Class of each BSDF lobe's event on this object.
    pub lobe_classes: Vec<ClassId>,
    /// Data lobes with their classes.
    pub data_lobes: Vec<(DataLobe, ClassId)>,
    /// Class of this object's `O` event, if it glows.
    pub glow_class: Option<ClassId>,
    /// The light that samples this glowing object (`build/glows.rs`), if any.
    pub glow_light: Option<u32>,
    /// The medium inside, if the object bounds one (`interior`).
    pub interior: Option<MediumUse>,
    /// Overlapping interiors go to the higher priority (`media::MediumStack`).
    pub priority: i32,
    /// `material = "null"`: an index-matched boundary, no surface event at all.
    pub null_surface: bool,
}

/// A medium where the path meets it: the volume (an index of `Scene::volumes`) and the
/// classes of its events, `V` at a scattering vertex and `O` for its emission (both with
/// the bounding object's groups, none for the atmosphere).
#[derive(Clone, Copy, Debug)]
pub struct MediumUse {
    pub volume: u32,
    pub scatter_class: ClassId,
    pub glow_class: ClassId,
}

/// One output AOV: its name, definition and rule flags (its rule id is its index).
#[derive(Clone, Debug)]
pub struct Aov {
    pub name: String,
    pub definition: String,
    pub expression: String,
    pub flags: Flags,
    /// For a rule's AOV split per light group: the index of its first part (one per
    /// group, then the default group).
    pub split_base: Option<u32>,
    /// For a part of a split: the AOV it is a part of.
    pub part_of: Option<u32>,
}

pub struct Scene {
    pub accel: Accel,
    /// UVs and tangents of textured meshes (read only by textured materials).
    pub surface: SurfaceAttrs,
    /// The triangles of every mesh light (object id: the light), for the lights-only
    /// test of `unoccluded`/`shadows` AOVs.
    pub mesh_lights: Accel,
    pub objects: Vec<Object>,
    pub materials: Vec<Material>,
    /// Declared lights, then from `first_glow_light` on the glowing objects that light
    /// sampling also picks (`build/glows.rs`, each with `Light::glow` set). Each light
    /// carries its events' classes and its part in split AOVs.
    pub lights: Vec<Light>,
    pub first_glow_light: u32,
    pub light_select: crate::light::select::LightSelector,
    /// Lights reached by rays that escape the scene.
    pub escape_lights: Vec<u32>,
    pub camera: Camera,
    pub filter: PixelFilter,
    /// The render settings, checked (`settings.rs`).
    pub settings: crate::settings::RenderDesc,
    pub automaton: Automaton,
    pub aovs: Vec<Aov>,
    pub camera_class: ClassId,
    /// `L` with no labels: the unit light data lobes are evaluated under.
    pub data_light_class: ClassId,
    /// The centre and radius of a sphere round every primitive.
    pub scene_center: Vec3A,
    pub scene_radius: f32,
    /// Ray offset against self-intersection, scaled to the scene.
    pub epsilon: f32,
    /// Light group names, sorted; split AOV parts follow this order, then the default.
    pub light_groups: Vec<String>,
    /// Per automaton state: can a light's event from here reach an `unoccluded` or
    /// `shadows` AOV (build/mod.rs, `lights_only_live`)?
    pub lights_only_live: Vec<bool>,
    /// Per automaton state: can some object's data lobe be accepted from here? Most
    /// states cannot, and the integrator skips the data lobes there.
    pub data_live: Vec<bool>,
    /// AOVs whose per-pixel variance is written too (`<aov>_var`); set by the render job.
    pub variance_aovs: Vec<u32>,
    /// The scene's media (`[media.NAME]` that something uses).
    pub volumes: Vec<crate::media::Volume>,
    /// The medium outside every interior (`[render] atmosphere`).
    pub atmosphere: Option<MediumUse>,
    /// The interiors the camera is inside.
    pub camera_media: crate::media::MediumStack,
    /// Whether any object bounds a medium, has a null surface, or there is an
    /// atmosphere: paths then track media and shadow rays pass null boundaries.
    pub has_media: bool,
    /// Whether any object's material is only partly there (`Material::presence`): rays
    /// then test what they hit for presence.
    pub has_presence: bool,
}
