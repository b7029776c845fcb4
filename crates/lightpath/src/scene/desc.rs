//! The scene as neutral plain data: what every loader (TOML, OBJ, the built-in scenes)
//! produces and the build step consumes. No parser types; every entity carries the
//! `Origin` that errors about it point at (see `docs/scene-format.md`).

use crate::camera::FovAxis;
pub use crate::settings::RenderDesc;
use glam::Affine3A;
use std::collections::BTreeMap;
use std::fmt;
use std::path::PathBuf;

/// Where an entity was written: file, 1-based line and column (line 0: the whole file).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Origin {
    pub file: String,
    pub line: usize,
    pub col: usize,
}

impl Origin {
    /// The whole file, for errors no single entity is to blame for.
    pub fn file(file: impl Into<String>) -> Origin {
        Origin {
            file: file.into(),
            line: 0,
            col: 0,
        }
    }
}

impl fmt::Display for Origin {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line > 0 {
            write!(f, "{}:{}:{}", self.file, self.line, self.col)
        } else {
            write!(f, "{}", self.file)
        }
    }
}

/// A name that refers to another entity, with where the reference was written.
#[derive(Clone, Debug)]
pub struct NameRef {
    pub name: String,
    pub origin: Origin,
}

#[derive(Clone, Debug, Default)]
pub struct SceneDesc {
    /// The scene's file (or built-in) name, for errors about the scene as a whole.
    pub source: String,
    /// None: the default camera.
    pub camera: Option<CameraDesc>,
    /// The render settings (`[render]` and `[film]`; `settings.rs` declares them).
    pub render: RenderDesc,
    pub materials: BTreeMap<String, MaterialDesc>,
    pub objects: Vec<ObjectDesc>,
    pub lights: Vec<LightDesc>,
    /// AOV name → definition (`lpe:…` or a standard name).
    pub aovs: BTreeMap<String, AovDesc>,
    /// Split beauty per light group (`beauty_<group>`).
    pub light_groups: bool,
    /// Also split these AOVs per light group.
    pub light_group_aovs: Vec<String>,
    /// Every camera a file names (glTF), for `--camera NAME`; `camera` is the first.
    pub cameras: Vec<NamedCamera>,
    /// What the loaders want the user told (a default camera or light added, statements
    /// skipped, unsupported glTF extensions), each naming its file.
    pub warnings: Vec<String>,
    /// Write these AOVs' per-pixel variance too (`<aov>_var`).
    pub variance: Vec<String>,
    /// Participating media and the objects that bound them.
    pub media: MediaDesc,
    /// The output the scene names (a USD render product's `productName`); `-o` wins.
    pub output: Option<PathBuf>,
    /// A USD stage's render products when it has several: each is a file of its own
    /// (`output` is the first's). Empty: one file, `output`.
    pub products: Vec<ProductDesc>,
    /// Whether the standard AOVs are added unless the command line says (None: yes;
    /// a USD stage with render settings: no, its RenderVars are the AOVs).
    pub standard_aovs: Option<bool>,
}

/// One output file of several (a USD `RenderProduct`): its path and the AOVs it holds.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ProductDesc {
    /// The product's file (its `productName`).
    pub output: PathBuf,
    /// The AOVs it holds (its vars' names, in order).
    pub aovs: Vec<String>,
    /// Whether it holds the beauty (R, G, B, A): one of its vars names it (`Ci`, `C`,
    /// `color`, …).
    pub beauty: bool,
}

/// Participating media (`[media.NAME]`), which objects bound them, and the atmosphere.
#[derive(Clone, Debug, Default)]
pub struct MediaDesc {
    pub media: BTreeMap<String, MediumDesc>,
    /// The objects with an `interior`.
    pub interiors: Vec<InteriorDesc>,
    /// `[render] atmosphere`: the medium outside every interior.
    pub atmosphere: Option<NameRef>,
}

/// A medium: coefficients per scene unit (at density 1 where a grid gives the density),
/// Henyey–Greenstein `g`, emitted radiance per unit length.
#[derive(Clone, Debug)]
pub struct MediumDesc {
    pub sigma_a: [f32; 3],
    pub sigma_s: [f32; 3],
    pub g: f32,
    pub emission: Option<[f32; 3]>,
    /// A density grid (a heterogeneous medium); None: homogeneous.
    pub density: Option<DensityDesc>,
    pub origin: Origin,
}

/// `density = "smoke.vdb"`, `grid`, `density_scale`: a float grid of an OpenVDB file.
#[derive(Clone, Debug)]
pub struct DensityDesc {
    /// Resolved against the scene file's folder.
    pub path: std::path::PathBuf,
    pub grid: String,
    pub scale: f32,
    /// The `density` key, which errors loading the file point at.
    pub origin: Origin,
}

/// Object `object` (an index of `SceneDesc::objects`) bounds medium `medium`; overlaps
/// go to the higher `priority`.
#[derive(Clone, Debug)]
pub struct InteriorDesc {
    pub object: usize,
    pub medium: NameRef,
    pub priority: i32,
}

impl SceneDesc {
    /// Renders through the named camera (and its film size, if it implies one).
    pub fn use_camera(&mut self, name: &str) -> Result<(), crate::scene::SceneError> {
        let Some(c) = self.cameras.iter().find(|c| c.name == name) else {
            let known: Vec<&str> = self.cameras.iter().map(|c| c.name.as_str()).collect();
            return Err(Origin::file(&self.source).error(format!(
                "no camera named '{name}': the scene's cameras are {known:?}"
            )));
        };
        self.camera = Some(c.camera.clone());
        if let Some(r) = c.resolution {
            self.render.resolution = r;
        }
        Ok(())
    }
}

/// A camera a scene file names, and the film size it implies (from its aspect ratio).
#[derive(Clone, Debug)]
pub struct NamedCamera {
    pub name: String,
    pub camera: CameraDesc,
    pub resolution: Option<[u32; 2]>,
}

#[derive(Clone, Debug)]
pub struct AovDesc {
    pub definition: String,
    pub origin: Origin,
}

#[derive(Clone, Debug)]
pub struct CameraDesc {
    pub position: [f32; 3],
    pub look_at: [f32; 3],
    pub up: [f32; 3],
    pub fov: f32,
    pub fov_axis: FovAxis,
    pub aperture_radius: f32,
    pub focus_distance: Option<f32>,
    pub origin: Origin,
}

impl Default for CameraDesc {
    fn default() -> Self {
        CameraDesc {
            position: [0.0, 0.0, 5.0],
            look_at: [0.0; 3],
            up: [0.0, 1.0, 0.0],
            fov: 40.0,
            fov_axis: FovAxis::Smaller,
            aperture_radius: 0.0,
            focus_distance: None,
            origin: Origin::default(),
        }
    }
}

#[derive(Clone, Debug)]
pub enum MaterialKind {
    Diffuse {
        albedo: [f32; 3],
    },
    Translucent {
        reflect: [f32; 3],
        transmit: [f32; 3],
    },
    Conductor {
        f0: [f32; 3],
    },
    /// `ior` None: 1.5.
    Dielectric {
        ior: Option<f32>,
        tint: Option<[f32; 3]>,
    },
    Plastic {
        albedo: [f32; 3],
        ior: Option<f32>,
    },
    /// glTF's metallic-roughness material (`material::pbr`); roughness is the
    /// material's. Transmission ≥ ½ makes it glass.
    Pbr {
        base_color: [f32; 3],
        metallic: f32,
        ior: Option<f32>,
        transmission: f32,
        clearcoat: f32,
        clearcoat_roughness: f32,
    },
    /// OpenPBR Surface (`material::openpbr`): every parameter, the specification's
    /// default where the scene gives none. The material's `roughness` is not used.
    OpenPbr(Box<crate::material::openpbr::OpenPbr>),
}

/// Where an image comes from: a file, or bytes inside a scene file (glTF buffers, data
/// URIs) with a name for messages.
#[derive(Clone, Debug)]
pub enum ImageSource {
    File(PathBuf),
    Bytes {
        name: String,
        bytes: std::sync::Arc<[u8]>,
    },
}

impl fmt::Display for ImageSource {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ImageSource::File(p) => write!(f, "{}", p.display()),
            ImageSource::Bytes { name, .. } => f.write_str(name),
        }
    }
}

/// An image texture as a material names it.
#[derive(Clone, Debug)]
pub struct TextureDesc {
    pub image: ImageSource,
    /// In u and v.
    pub wrap: [crate::material::texture::Wrap; 2],
    pub transform: crate::material::texture::UvTransform,
    pub origin: Origin,
}

/// A material's textures; each multiplies the parameter it names.
#[derive(Clone, Debug, Default)]
pub struct TexturesDesc {
    /// Albedo, f0, tint or base colour (sRGB-decoded).
    pub base_color: Option<TextureDesc>,
    /// Roughness in green, metallic in blue (glTF's layout, linear).
    pub metallic_roughness: Option<TextureDesc>,
    /// Tangent-space normal map and its scale.
    pub normal: Option<(TextureDesc, f32)>,
    /// Multiplies the object's emission (sRGB-decoded).
    pub emissive: Option<TextureDesc>,
    /// OpenPBR inputs, each multiplied by a texture.
    pub inputs: Vec<InputTexture>,
    /// glTF's `alphaCutoff` (alphaMode MASK): the surface is there where its opacity
    /// (`geometry_opacity` × its texture) reaches this, absent elsewhere.
    pub opacity_cutoff: Option<f32>,
    /// glTF's `KHR_materials_anisotropy`: anisotropy follows the mesh's tangent turned by
    /// this rotation (radians) and by the direction in this texture's red and green.
    pub anisotropy_direction: Option<(f32, Option<TextureDesc>)>,
}

/// A texture on one OpenPBR input: colours take its RGB (sRGB-decoded when `srgb`), numbers
/// one channel.
#[derive(Clone, Debug)]
pub struct InputTexture {
    /// The input's name, as `material::openpbr::INPUTS` has it.
    pub input: &'static str,
    pub texture: TextureDesc,
    /// The channel a number is read from (0 red … 3 alpha); unused for colours.
    pub channel: u8,
    pub srgb: bool,
    /// The texel is raised to this power (after decoding) before it multiplies the input:
    /// 1, or ½ where glTF's base colour tints glass at each of a solid's two crossings.
    pub exponent: f32,
}

#[derive(Clone, Debug)]
pub struct MaterialDesc {
    pub kind: MaterialKind,
    pub roughness: f32,
    /// Colour reported by the `U4` user lobe.
    pub user_color: Option<[f32; 3]>,
    pub textures: TexturesDesc,
    /// Image maps of the base colour and the normal (OBJ `map_Kd`, `map_Bump`/`norm`),
    /// used where `textures` names none (build/materials.rs, `textures_of`).
    pub base_color_map: Option<TextureRef>,
    pub normal_map: Option<TextureRef>,
    pub origin: Origin,
}

/// An image file a material names: its resolved path, a factor (a bump map's `-bm`), and
/// where it was named.
#[derive(Clone, Debug)]
pub struct TextureRef {
    pub path: PathBuf,
    pub scale: f32,
    pub origin: Origin,
}

/// Triangle mesh data; optional per-vertex attributes have one entry per position.
#[derive(Clone, Debug, Default)]
pub struct MeshData {
    pub positions: Vec<[f32; 3]>,
    pub indices: Vec<[u32; 3]>,
    /// Shading normals.
    pub normals: Option<Vec<[f32; 3]>>,
    /// Texture coordinates, glTF's convention: (0, 0) is the image's top-left corner.
    pub uvs: Option<Vec<[f32; 2]>>,
    /// Tangents (xyz) and the bitangent's sign (w), for normal maps; without them the
    /// tangent follows the UVs.
    pub tangents: Option<Vec<[f32; 4]>>,
    /// Linear RGB vertex colours (glTF `COLOR_0`, PLY `red green blue`): they multiply
    /// the material's base colour.
    pub colors: Option<Vec<[f32; 3]>>,
}

/// A shape in its local space; the object's `transform` places it.
#[derive(Clone, Debug)]
pub enum ShapeDesc {
    /// The square [-1, 1]² in the z = 0 plane, facing +z.
    Rectangle,
    Cube,
    Disk {
        segments: u32,
    },
    /// Corners in world space (the transform does not apply).
    Quad {
        corners: [[f32; 3]; 4],
    },
    Sphere {
        center: [f32; 3],
        radius: f32,
    },
    /// Inline mesh or the models of an OBJ file.
    Mesh {
        parts: Vec<MeshData>,
    },
    /// Mesh parts several objects share (the same OBJ file named twice): stored once, and
    /// each object that uses them is an instance (`docs/scene-format.md`).
    SharedMesh {
        parts: std::sync::Arc<Vec<MeshData>>,
    },
}

impl ShapeDesc {
    /// The triangle mesh parts of a `Mesh` or `SharedMesh`.
    pub fn mesh_parts(&self) -> Option<&[MeshData]> {
        match self {
            ShapeDesc::Mesh { parts } => Some(parts),
            ShapeDesc::SharedMesh { parts } => Some(parts),
            _ => None,
        }
    }
}

#[derive(Clone, Debug)]
pub struct ObjectDesc {
    pub name: Option<String>,
    /// The shape's name as written, for messages (`sphere shape needs …`).
    pub shape_name: String,
    pub shape: ShapeDesc,
    /// Object to world.
    pub transform: Affine3A,
    pub material: Option<NameRef>,
    /// LPE labels of every event on this object; None: the object's name.
    pub lpegroups: Option<Vec<String>>,
    /// The asset it belongs to (Cryptomatte's `CryptoAsset`; a glTF's top-level node);
    /// None: the object's own name.
    pub asset: Option<String>,
    /// Radiance of a glowing (non-light) surface: seen as an `O` event.
    pub emission: Option<[f32; 3]>,
    pub holdout: bool,
    /// Trace sets: which rays see this object.
    pub visible_camera: bool,
    pub visible_indirect: bool,
    pub casts_shadows: bool,
    pub origin: Origin,
}

#[derive(Clone, Debug)]
pub enum LightKind {
    /// Area lights, in the shape's local space (quad: world corners).
    Rectangle,
    Quad {
        corners: [[f32; 3]; 4],
    },
    Disk {
        segments: u32,
    },
    Sphere {
        center: [f32; 3],
        radius: f32,
    },
    /// The side of a cylinder along local X, centred at the origin (UsdLux's).
    Cylinder {
        radius: f32,
        length: f32,
    },
    Point {
        position: [f32; 3],
    },
    /// Full cone angle and the width of its soft edge, in degrees.
    Spot {
        position: [f32; 3],
        direction: [f32; 3],
        cone_angle: f32,
        cone_softness: f32,
    },
    /// `angle`: the angular diameter of its disc, in degrees (0: one direction).
    Distant {
        direction: [f32; 3],
        angle: f32,
    },
    /// An optional equirectangular EXR (resolved path, and where it was named), and the
    /// corners of the portals it is sampled through (light/portal.rs).
    Dome {
        map: Option<(PathBuf, Origin)>,
        portals: Vec<[[f32; 3]; 4]>,
    },
    /// A mesh light: the triangles of `SceneDesc::objects[object]` emit (its transform,
    /// material and trace sets are the object's; the light's own are not used).
    Mesh {
        object: usize,
    },
}

/// An area light's emission profile, as UsdLux's ShapingAPI defines it: off its normal by
/// θ, emission is scaled by lerp(|cos θ|^focus, focus_tint, white) and by
/// 1 − smoothstep(θ; (1 − softness)·angle, angle), zero beyond `cone_angle`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreaShaping {
    /// The cutoff angle off the normal, in degrees (90: none).
    pub cone_angle: f32,
    /// The share of the cone over which emission fades to zero, in [0, 1].
    pub cone_softness: f32,
    /// The exponent of the cosine falloff (0: none).
    pub focus: f32,
    /// The colour the focus fades emission to off the axis (black: to nothing).
    pub focus_tint: [f32; 3],
}

#[derive(Clone, Debug)]
pub struct LightDesc {
    pub kind: LightKind,
    pub name: Option<String>,
    pub groups: Vec<String>,
    /// Radiance, intensity or irradiance, as the kind needs; `strength` multiplies it.
    pub color: [f32; 3],
    pub strength: f32,
    pub camera_visible: bool,
    /// Whether the light's surface blocks other lights' shadow rays (UsdLux lights, as
    /// in the renderers that read them, do not).
    pub casts_shadows: bool,
    /// UsdLux ShapingAPI on an area light (rect, disk): its emission narrowed about its
    /// normal. None: no shaping.
    pub shaping: Option<AreaShaping>,
    pub two_sided: bool,
    /// The surface material of an area light (it can reflect too); none by default.
    pub material: Option<NameRef>,
    pub transform: Affine3A,
    /// Light linking: only objects in these lpegroups are lit (None: all) …
    pub include: Option<Vec<String>>,
    /// … except objects in these.
    pub exclude: Vec<String>,
    /// Shadow linking: only objects in these lpegroups cast shadows from this light
    /// (None: all) …
    pub shadow_include: Option<Vec<String>>,
    /// … except objects in these.
    pub shadow_exclude: Vec<String>,
    pub origin: Origin,
}
