//! glTF 2.0 (`.gltf` with its buffers and images, or `.glb`) → `SceneDesc`, so that
//! `lightpath render shot.glb` needs no TOML. See docs/scene-format.md ("glTF") for the
//! table of what each glTF property becomes, with its LPE event.
//!
//! - Nodes: the default scene's hierarchy, transforms composed from the root. A mesh
//!   node's LPE groups are its own name and every ancestor's (a parent node is a
//!   collection: `C<..'props'>` selects everything under it), plus `extras.lpegroup`
//!   (a string or a list).
//! - Cameras: perspective ones, by node name; the first is used (`--camera NAME` picks
//!   another).
//! - Lights (`KHR_lights_punctual`): converted as Blender's glTF importer does (its
//!   "Standard" lighting mode): point and spot W = cd · 4π / 683, sun W/m² = lux / 683;
//!   then as Cycles emits them: a point or spot of P watts has radiant intensity P / 4π
//!   W/sr. So Lightpath's intensity is cd / 683 W/sr and its irradiance lux / 683.
//!   A light's group is its node's name (else the light's), or `extras.lightgroup`.
//!   Emissive materials make their primitives mesh lights. With no camera or no light
//!   at all, `defaults::complete` adds one, and a warning.
//! - Extensions: those in [`SUPPORTED`]; any other used one is a warning naming it, any
//!   other required one an error.

use super::defaults;
use crate::camera::FovAxis;
use crate::material::openpbr::{self, InputMut, OpenPbr};
use crate::material::texture::{UvTransform, Wrap};
use crate::scene::desc::InputTexture;
use crate::scene::desc::{
    CameraDesc, ImageSource, InteriorDesc, LightDesc, LightKind, MaterialDesc, MaterialKind,
    MediumDesc, MeshData, NameRef, NamedCamera, ObjectDesc, Origin, SceneDesc, ShapeDesc,
    TextureDesc, TexturesDesc,
};
use crate::scene::SceneError;
use glam::{Affine3A, Mat4, Vec3, Vec3A};
use gltf::Document;
use std::collections::HashMap;
use std::f32::consts::PI;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The extensions Lightpath reads.
pub const SUPPORTED: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_anisotropy",
    "KHR_materials_clearcoat",
    "KHR_materials_diffuse_transmission",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_iridescence",
    "KHR_materials_sheen",
    "KHR_materials_specular",
    "KHR_materials_transmission",
    "KHR_materials_volume",
    "KHR_texture_transform",
];

/// KHR_materials_anisotropy's strength as Blender reads it: its importer makes the
/// strength the Principled BSDF's Anisotropic (not KHR's own α_t = mix(α, 1, s²)), which
/// Cycles renders as α/ρ along the tangent and α·ρ across, ρ = √(1 − 0.9 s), α =
/// roughness². OpenPBR gives those alphas with anisotropy 1 − ρ² and the roughness scaled
/// by (ρ √(2 / (1 + ρ⁴)))^(−½): a factor, so a roughness texture stays exact; a strength
/// texture is exact in the anisotropy and takes the roughness scale of the factor.
fn blender_anisotropy(p: &mut OpenPbr) {
    let s = p.specular_roughness_anisotropy.clamp(0.0, 1.0);
    if s <= 0.0 {
        return;
    }
    let rho2 = 1.0 - 0.9 * s;
    let scale = (rho2.sqrt() * (2.0 / (1.0 + rho2 * rho2)).sqrt()).powf(-0.5);
    p.specular_roughness_anisotropy = 1.0 - rho2;
    p.specular_roughness = (p.specular_roughness * scale).min(1.0);
}

/// Lumens per watt of the photometric conversion Blender's importer uses (555 nm).
pub const WATTS_TO_LUMENS: f32 = 683.0;

/// Longer side of the film when the file's camera gives only an aspect ratio.
const FILM_SIZE: f32 = 512.0;

/// Reads a glTF file into a scene description, without defaults (the caller adds a
/// camera or a dome where the file has none: `defaults::complete`). `at` is where the
/// file was named, for an error opening it.
pub fn load_scene(path: &Path, at: &Origin) -> Result<SceneDesc, SceneError> {
    let file = path.display().to_string();
    // Within the input-size limit, and never a device or pipe (limits.rs).
    let bytes = crate::limits::read_input(path)
        .map_err(|e| at.error(format!("cannot read glTF file {file}: {e}")))?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    // The checks above the `gltf` crate cover the panics its readers were found to have
    // (tests/it/mutation.rs); a panic still left in it becomes an error naming the file.
    let load = std::panic::catch_unwind(|| Loader::new(&file, dir, &bytes)?.scene());
    load.unwrap_or_else(|panic| {
        let why = panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_default();
        Err(at.error(format!(
            "{file}: the glTF reader failed on malformed data ({why})"
        )))
    })
}

/// Material extensions' numbers: (extension, glTF key, OpenPBR input, default).
const NUMBERS: &[(&str, &str, &str, f32)] = &[
    (
        "KHR_materials_clearcoat",
        "clearcoatFactor",
        "coat_weight",
        0.0,
    ),
    (
        "KHR_materials_clearcoat",
        "clearcoatRoughnessFactor",
        "coat_roughness",
        0.0,
    ),
    (
        "KHR_materials_sheen",
        "sheenRoughnessFactor",
        "fuzz_roughness",
        0.0,
    ),
    // KHR's specular factor is Blender's "Specular IOR Level" × 2: OpenPBR's weight, which
    // scales F0 through the index as Blender's level does (KHR's own definition scales the
    // whole lobe; artists check against Blender).
    (
        "KHR_materials_specular",
        "specularFactor",
        "specular_weight",
        1.0,
    ),
    (
        "KHR_materials_anisotropy",
        "anisotropyStrength",
        "specular_roughness_anisotropy",
        0.0,
    ),
    (
        "KHR_materials_iridescence",
        "iridescenceFactor",
        "thin_film_weight",
        0.0,
    ),
    (
        "KHR_materials_iridescence",
        "iridescenceIor",
        "thin_film_ior",
        1.3,
    ),
    (
        "KHR_materials_diffuse_transmission",
        "diffuseTransmissionFactor",
        "subsurface_weight",
        0.0,
    ),
];
/// Material extensions' colours: (extension, glTF key, OpenPBR input, default).
const COLORS: &[(&str, &str, &str, [f32; 3])] = &[
    (
        "KHR_materials_sheen",
        "sheenColorFactor",
        "fuzz_color",
        [0.0; 3],
    ),
    (
        "KHR_materials_specular",
        "specularColorFactor",
        "specular_color",
        [1.0; 3],
    ),
    (
        "KHR_materials_diffuse_transmission",
        "diffuseTransmissionColorFactor",
        "subsurface_color",
        [1.0; 3],
    ),
];
/// Material extensions' textures: (extension, glTF key, OpenPBR input, channel, sRGB).
const TEXTURES: &[(&str, &str, &str, u8, bool)] = &[
    (
        "KHR_materials_clearcoat",
        "clearcoatTexture",
        "coat_weight",
        0,
        false,
    ),
    (
        "KHR_materials_clearcoat",
        "clearcoatRoughnessTexture",
        "coat_roughness",
        1,
        false,
    ),
    (
        "KHR_materials_sheen",
        "sheenColorTexture",
        "fuzz_color",
        0,
        true,
    ),
    (
        "KHR_materials_sheen",
        "sheenRoughnessTexture",
        "fuzz_roughness",
        3,
        false,
    ),
    (
        "KHR_materials_specular",
        "specularTexture",
        "specular_weight",
        3,
        false,
    ),
    (
        "KHR_materials_specular",
        "specularColorTexture",
        "specular_color",
        0,
        true,
    ),
    (
        "KHR_materials_anisotropy",
        "anisotropyTexture",
        "specular_roughness_anisotropy",
        2,
        false,
    ),
    (
        "KHR_materials_iridescence",
        "iridescenceTexture",
        "thin_film_weight",
        0,
        false,
    ),
    (
        "KHR_materials_iridescence",
        "iridescenceThicknessTexture",
        "thin_film_thickness",
        1,
        false,
    ),
    (
        "KHR_materials_diffuse_transmission",
        "diffuseTransmissionTexture",
        "subsurface_weight",
        3,
        false,
    ),
    (
        "KHR_materials_diffuse_transmission",
        "diffuseTransmissionColorTexture",
        "subsurface_color",
        0,
        true,
    ),
];

/// Decoded file and what the walk collects.
struct Loader {
    file: String,
    dir: PathBuf,
    doc: Document,
    buffers: Vec<gltf::buffer::Data>,
    desc: SceneDesc,
    /// Material index (None: glTF's default material) → name in `desc.materials`.
    materials: HashMap<Option<usize>, String>,
    images: HashMap<usize, ImageSource>,
    /// Each primitive's mesh data, read once however many nodes place it (by mesh,
    /// primitive, and whether the placement mirrors): nodes sharing a mesh become
    /// instances of it.
    meshes: HashMap<(usize, usize, bool), std::sync::Arc<Vec<MeshData>>>,
    /// Material name → the medium of its interior (KHR_materials_volume), in
    /// `desc.media`.
    interiors: HashMap<String, String>,
}

/// Every accessor's data within its buffer view and every view within its buffer, in
/// checked arithmetic: the `gltf` crate's readers compute `offset + stride · (count − 1)`
/// unchecked (a `count` of 0 or a huge one overflows, in release builds silently), and
/// its validator indexes before it checks.
fn check_accessor_bounds(json: &gltf::json::Root) -> Result<(), String> {
    use gltf::json::validation::Checked;
    let view_end = |v: usize| -> Result<u64, String> {
        let view = json
            .buffer_views
            .get(v)
            .ok_or_else(|| format!("/bufferViews/{v} does not exist"))?;
        let buffer = json
            .buffers
            .get(view.buffer.value())
            .ok_or_else(|| format!("/bufferViews/{v}/buffer: no such buffer"))?;
        let start = view.byte_offset.map_or(0, |o| o.0);
        match start.checked_add(view.byte_length.0) {
            Some(end) if end <= buffer.byte_length.0 => Ok(view.byte_length.0),
            _ => Err(format!(
                "/bufferViews/{v}: bytes {start}..+{} lie outside its buffer of {} bytes",
                view.byte_length.0, buffer.byte_length.0
            )),
        }
    };
    for v in 0..json.buffer_views.len() {
        view_end(v)?;
    }
    check_primitive_types(json)?;
    for (i, a) in json.accessors.iter().enumerate() {
        let (Checked::Valid(component), Checked::Valid(ty)) = (&a.component_type, &a.type_) else {
            continue; // the crate's validation names it
        };
        let element = (component.0.size() * ty.multiplicity()) as u64;
        if a.count.0 == 0 {
            return Err(format!(
                "/accessors/{i}/count: expected at least 1, found 0"
            ));
        }
        let Some(v) = a.buffer_view.map(|v| v.value()) else {
            continue;
        };
        let length = view_end(v)?;
        let stride = json.buffer_views[v]
            .byte_stride
            .map_or(element, |s| s.0 as u64);
        let end = (a.count.0 - 1)
            .checked_mul(stride.max(element))
            .and_then(|n| n.checked_add(a.byte_offset.map_or(0, |o| o.0)))
            .and_then(|n| n.checked_add(element));
        if stride < element || end.is_none_or(|end| end > length) {
            return Err(format!(
                "/accessors/{i}: {} elements of {element} bytes (stride {stride}) do not fit \
                 in buffer view {v} of {length} bytes",
                a.count.0
            ));
        }
        if a.sparse.is_some() {
            return Err(format!(
                "/accessors/{i}/sparse: sparse accessors are not supported"
            ));
        }
    }
    Ok(())
}

/// The types the `gltf` crate's readers assume (they reach `unreachable!` on others):
/// indices unsigned scalars, positions and normals float VEC3, tangents float VEC4,
/// texture coordinates VEC2 and colours VEC3/VEC4 of floats or normalised integers.
fn check_primitive_types(json: &gltf::json::Root) -> Result<(), String> {
    use gltf::json::accessor::{ComponentType as C, Type as T};
    use gltf::json::mesh::Semantic as S;
    use gltf::json::validation::Checked;
    let kind = |i: usize| match json.accessors.get(i) {
        Some(a) => match (&a.component_type, &a.type_) {
            (Checked::Valid(c), Checked::Valid(t)) => Some((c.0, *t)),
            _ => None,
        },
        None => None,
    };
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let at = format!("/meshes/{m}/primitives/{p}");
            if let Some(i) = prim.indices {
                if !matches!(
                    kind(i.value()),
                    Some((C::U8 | C::U16 | C::U32, T::Scalar)) | None
                ) {
                    return Err(format!(
                        "{at}/indices: accessor {} is not of unsigned integer scalars",
                        i.value()
                    ));
                }
            }
            for (semantic, a) in &prim.attributes {
                // gltf-json 1.4's validator indexes a POSITION accessor before it checks
                // the index: an index out of range is reported here first.
                if a.value() >= json.accessors.len() {
                    let name = match semantic {
                        Checked::Valid(s) => s.to_string(),
                        Checked::Invalid => "?".into(),
                    };
                    return Err(format!(
                        "{at}/attributes/{name}: accessor {} does not exist (the file has {})",
                        a.value(),
                        json.accessors.len()
                    ));
                }
                let Checked::Valid(semantic) = semantic else {
                    continue;
                };
                let ok = match (semantic, kind(a.value())) {
                    (_, None) => true,
                    (S::Positions | S::Normals, Some(k)) => k == (C::F32, T::Vec3),
                    (S::Tangents, Some(k)) => k == (C::F32, T::Vec4),
                    (S::TexCoords(_), Some((c, t))) => {
                        t == T::Vec2 && matches!(c, C::F32 | C::U8 | C::U16)
                    }
                    (S::Colors(_), Some((c, t))) => {
                        matches!(t, T::Vec3 | T::Vec4) && matches!(c, C::F32 | C::U8 | C::U16)
                    }
                    _ => true,
                };
                if !ok {
                    return Err(format!(
                        "{at}/attributes/{}: accessor {} has a type the glTF \
                         specification does not allow for it",
                        semantic.to_string(),
                        a.value()
                    ));
                }
            }
        }
    }
    Ok(())
}

fn pointer_of(path: &gltf::json::Path) -> String {
    // "nodes[3].mesh" → "/nodes/3/mesh"
    let mut out = String::new();
    for part in path.as_str().split('.') {
        for piece in part.split('[') {
            let piece = piece.trim_end_matches(']');
            if !piece.is_empty() {
                out.push('/');
                out.push_str(piece);
            }
        }
    }
    out
}

impl Loader {
    fn new(file: &str, dir: PathBuf, bytes: &[u8]) -> Result<Loader, SceneError> {
        let at = Origin::file(file);
        let gltf::Gltf { document, blob } = gltf::Gltf::from_slice_without_validation(bytes)
            .map_err(|e| {
                let hint = if bytes.starts_with(b"v ") || bytes.starts_with(b"# ") {
                    " (is it an OBJ file named .gltf?)"
                } else {
                    ""
                };
                at.error(format!("not a glTF 2.0 file: {e}{hint}"))
            })?;
        if let Some(ext) = document
            .extensions_required()
            .find(|e| !SUPPORTED.contains(e))
        {
            return Err(at.error(format!(
                "/extensionsRequired: the file requires extension '{ext}', which Lightpath \
                 does not support (it reads {})",
                SUPPORTED.join(", ")
            )));
        }
        let mut warnings = Vec::new();
        for ext in document.extensions_used() {
            if !SUPPORTED.contains(&ext) {
                warnings.push(format!(
                    "{file}: /extensionsUsed: extension '{ext}' is not supported; what it \
                     adds is ignored"
                ));
            }
        }
        let json = document.as_json();
        check_accessor_bounds(json).map_err(|e| at.error(e))?;
        // The crate's validation (index ranges, accessor types) with its JSON paths.
        if let Err(gltf::Error::Validation(errors)) = gltf::Gltf::from_slice(bytes) {
            if let Some((path, e)) = errors.iter().find(|(p, _)| {
                // Extensions we read but the crate does not know are not errors.
                !p.as_str().contains("extensionsRequired")
            }) {
                return Err(at.error(format!("{}: {e}", pointer_of(path))));
            }
        }
        let buffers = read_buffers(&document, &dir, blob).map_err(|e| at.error(e))?;
        let desc = SceneDesc {
            source: file.to_string(),
            warnings,
            ..SceneDesc::default()
        };
        Ok(Loader {
            file: file.to_string(),
            dir,
            doc: document,
            buffers,
            desc,
            materials: HashMap::new(),
            images: HashMap::new(),
            meshes: HashMap::new(),
            interiors: HashMap::new(),
        })
    }

    fn error(&self, pointer: &str, message: impl std::fmt::Display) -> SceneError {
        Origin::file(&self.file).error(format!("{pointer}: {message}"))
    }

    fn warn(&mut self, pointer: &str, message: impl std::fmt::Display) {
        self.desc
            .warnings
            .push(format!("{}: {pointer}: {message}", self.file));
    }

    fn scene(mut self) -> Result<SceneDesc, SceneError> {
        let doc = self.doc.clone();
        let Some(scene) = doc.default_scene().or_else(|| doc.scenes().next()) else {
            return Err(self.error("/scenes", "the file has no scene"));
        };
        // Depth-first, with each node's world transform and its ancestors' names.
        let mut stack: Vec<(gltf::Node, Mat4, Vec<String>)> = scene
            .nodes()
            .map(|n| (n, Mat4::IDENTITY, Vec::new()))
            .collect();
        stack.reverse();
        let mut seen = vec![false; doc.nodes().len()];
        while let Some((node, parent, ancestors)) = stack.pop() {
            let pointer = format!("/nodes/{}", node.index());
            if std::mem::replace(&mut seen[node.index()], true) {
                return Err(self.error(&pointer, "the node appears twice in the hierarchy"));
            }
            let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
            if !world.is_finite() {
                return Err(self.error(&pointer, "the node's transform is not finite"));
            }
            let name = node.name().map(str::to_string);
            if let Some(mesh) = node.mesh() {
                self.mesh_node(&node, &mesh, world, &ancestors)?;
            }
            if let Some(camera) = node.camera() {
                self.camera(&node, &camera, world);
            }
            if let Some(light) = node.light() {
                self.light(&node, &light, world)?;
            }
            let mut below = ancestors.clone();
            below.extend(name);
            for child in node.children().collect::<Vec<_>>().into_iter().rev() {
                stack.push((child, world, below.clone()));
            }
        }
        Ok(self.desc)
    }

    fn mesh_node(
        &mut self,
        node: &gltf::Node,
        mesh: &gltf::Mesh,
        world: Mat4,
        ancestors: &[String],
    ) -> Result<(), SceneError> {
        let node_name = node
            .name()
            .or(mesh.name())
            .map(str::to_string)
            .unwrap_or_else(|| format!("node{}", node.index()));
        let mut groups = vec![node_name.clone()];
        groups.extend(ancestors.iter().rev().cloned());
        groups.extend(extra_strings(node.extras(), "lpegroup"));
        groups.dedup();
        let xf = Affine3A::from_mat4(world);
        let flip = world.determinant() < 0.0;
        for prim in mesh.primitives() {
            let pointer = format!("/meshes/{}/primitives/{}", mesh.index(), prim.index());
            if prim.mode() != gltf::mesh::Mode::Triangles {
                self.warn(
                    &pointer,
                    format!(
                        "mode {:?} is not triangles; the primitive is skipped",
                        prim.mode()
                    ),
                );
                continue;
            }
            let key = (mesh.index(), prim.index(), flip);
            let parts = match self.meshes.get(&key) {
                Some(parts) => parts.clone(),
                None => {
                    let parts = std::sync::Arc::new(vec![self.mesh_data(&prim, &pointer, flip)?]);
                    self.meshes.insert(key, parts.clone());
                    parts
                }
            };
            let material = self.material(prim.material())?;
            let name = if prim.index() == 0 {
                node_name.clone()
            } else {
                format!("{node_name}.{}", prim.index())
            };
            // An emissive material makes the primitive a mesh light (light group: its
            // name), as Blender and RenderMan treat emissive meshes.
            if let Some(radiance) = self.emission(prim.material()) {
                let object = self.desc.objects.len();
                let at = Origin::file(&self.file);
                self.desc
                    .lights
                    .push(defaults::mesh_light(object, &name, radiance, at));
            }
            self.desc.objects.push(ObjectDesc {
                name: Some(name),
                shape_name: "mesh".into(),
                shape: ShapeDesc::SharedMesh { parts },
                transform: xf,
                material: Some(NameRef {
                    name: material.clone(),
                    origin: Origin::file(&self.file),
                }),
                lpegroups: Some(groups.clone()),
                emission: None,
                holdout: false,
                visible_camera: true,
                visible_indirect: true,
                casts_shadows: true,
                // Cryptomatte's asset: the top-level node the mesh is under.
                asset: Some(ancestors.first().unwrap_or(&node_name).clone()),
                origin: Origin::file(&self.file),
            });
            if let Some(medium) = self.interiors.get(&material) {
                let origin = Origin::file(&self.file);
                self.desc.media.interiors.push(InteriorDesc {
                    object: self.desc.objects.len() - 1,
                    medium: NameRef {
                        name: medium.clone(),
                        origin,
                    },
                    priority: 0,
                });
            }
        }
        Ok(())
    }

    fn mesh_data(
        &self,
        prim: &gltf::Primitive,
        pointer: &str,
        flip: bool,
    ) -> Result<MeshData, SceneError> {
        let reader = prim.reader(|b| self.buffers.get(b.index()).map(|d| &d.0[..]));
        let positions: Vec<[f32; 3]> = reader
            .read_positions()
            .ok_or_else(|| self.error(&format!("{pointer}/attributes"), "no POSITION attribute"))?
            .collect();
        if let Some(i) = positions
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            return Err(self.error(
                &format!("{pointer}/attributes/POSITION"),
                format!("vertex {i} is not finite: {:?}", positions[i]),
            ));
        }
        let n = positions.len() as u32;
        let flat: Vec<u32> = match reader.read_indices() {
            Some(ix) => ix.into_u32().collect(),
            None => (0..n).collect(),
        };
        if let Some(bad) = flat.iter().find(|&&i| i >= n) {
            return Err(self.error(
                &format!("{pointer}/indices"),
                format!("index {bad} is out of range: there are {n} vertices"),
            ));
        }
        let indices: Vec<[u32; 3]> = flat
            .chunks_exact(3)
            .map(|t| {
                if flip {
                    [t[0], t[2], t[1]]
                } else {
                    [t[0], t[1], t[2]]
                }
            })
            .collect();
        let same = |len: usize| len == positions.len();
        let normals: Option<Vec<[f32; 3]>> = reader
            .read_normals()
            .map(|it| it.collect::<Vec<_>>())
            .filter(|v| same(v.len()));
        let set = uv_set(prim.material());
        let uvs: Option<Vec<[f32; 2]>> = reader
            .read_tex_coords(set)
            .map(|t| t.into_f32().collect::<Vec<_>>())
            .filter(|v| same(v.len()));
        let tangents: Option<Vec<[f32; 4]>> = reader
            .read_tangents()
            .map(|it| it.collect::<Vec<_>>())
            .filter(|v| same(v.len()));
        // COLOR_0 is linear (RGB or RGBA; alpha is ignored, as the material's is).
        let colors: Option<Vec<[f32; 3]>> = reader
            .read_colors(0)
            .map(|c| c.into_rgb_f32().collect::<Vec<_>>())
            .filter(|v| same(v.len()));
        if let Some((i, c)) = colors
            .iter()
            .flatten()
            .enumerate()
            .find(|(_, c)| !c.iter().all(|v| v.is_finite() && *v >= 0.0))
        {
            return Err(self.error(
                &format!("{pointer}/attributes/COLOR_0"),
                format!("colour {i} is {c:?}: expected finite, non-negative numbers"),
            ));
        }
        Ok(MeshData {
            positions,
            indices,
            normals,
            uvs,
            tangents,
            colors,
        })
    }

    /// The scene material for a glTF material (None: glTF's default), made once: an
    /// OpenPBR material, mapped as Blender's glTF importer maps the file to its Principled
    /// BSDF (artists check their files against Blender), extensions included
    /// (docs/scene-format.md#gltf-materials).
    fn material(&mut self, m: gltf::Material) -> Result<String, SceneError> {
        if let Some(name) = self.materials.get(&m.index()) {
            return Ok(name.clone());
        }
        let pointer = match m.index() {
            Some(i) => format!("/materials/{i}"),
            None => "/materials".into(),
        };
        let base_name = match (m.index(), m.name()) {
            (None, _) => "gltf default".to_string(),
            (Some(i), None) => format!("material{i}"),
            (Some(_), Some(n)) => n.to_string(),
        };
        let mut name = base_name.clone();
        let mut k = 1;
        while self.desc.materials.contains_key(&name) {
            name = format!("{base_name}.{k}");
            k += 1;
        }
        let pbr = m.pbr_metallic_roughness();
        let [r, g, b, alpha] = pbr.base_color_factor();
        let base_color = Vec3A::new(r, g, b);
        let mut p = OpenPbr {
            base_color,
            base_metalness: pbr.metallic_factor(),
            specular_roughness: pbr.roughness_factor(),
            specular_ior: m.ior().unwrap_or(1.5),
            // glTF's transmission is tinted by the base colour.
            transmission_weight: m.transmission().map_or(0.0, |t| t.transmission_factor()),
            transmission_color: base_color,
            // KHR_materials_clearcoat's coat is of index 1.5, and does not darken the base
            // (Blender's Principled coat, which artists check against, does not).
            coat_ior: 1.5,
            coat_darkening: 0.0,
            // KHR_materials_specular's colour tints F0 only (as Blender's Principled BSDF
            // does); with the default white it is the same as OpenPBR's.
            specular_color_f0_only: true,
            ..OpenPbr::default()
        };
        let mut textures = TexturesDesc::default();
        if let Some(info) = pbr.base_color_texture() {
            let t = self.texture(&info.texture(), info.texture_transform(), &pointer)?;
            // The base colour texture tints transmission as the factor does: by its
            // square root at each crossing (below).
            textures.inputs.push(InputTexture {
                exponent: 0.5,
                ..input_texture("transmission_color", t.clone(), 0, true)
            });
            textures.base_color = Some(t);
        } else {
            // Blender's Principled glass tints by √(base colour) at each crossing, so a
            // ray through a solid takes the base colour once.
            p.transmission_color = base_color.max(Vec3A::ZERO).powf(0.5);
        }
        if let Some(info) = pbr.metallic_roughness_texture() {
            textures.metallic_roughness =
                Some(self.texture(&info.texture(), info.texture_transform(), &pointer)?);
        }
        if let Some(info) = m.transmission().and_then(|t| t.transmission_texture()) {
            let t = self.texture(&info.texture(), info.texture_transform(), &pointer)?;
            textures
                .inputs
                .push(input_texture("transmission_weight", t, 0, false));
        }
        if let Some(nt) = m.normal_texture() {
            let t = self.texture(&nt.texture(), None, &pointer)?;
            textures.normal = Some((t, nt.scale()));
        }
        if let Some(info) = m.emissive_texture() {
            textures.emissive =
                Some(self.texture(&info.texture(), info.texture_transform(), &pointer)?);
        }
        // Presence: MASK cuts out where alpha (factor × the base colour texture's alpha)
        // is below alphaCutoff; BLEND lets a fraction 1 − alpha of rays through.
        if m.alpha_mode() != gltf::material::AlphaMode::Opaque {
            p.geometry_opacity = alpha.clamp(0.0, 1.0);
            if let Some(t) = &textures.base_color {
                textures
                    .inputs
                    .push(input_texture("geometry_opacity", t.clone(), 3, false));
            }
            if m.alpha_mode() == gltf::material::AlphaMode::Mask {
                textures.opacity_cutoff = Some(m.alpha_cutoff().unwrap_or(0.5));
            }
        }
        self.extensions(&m, &pointer, &mut p, &mut textures)?;
        if let Some(sigma_a) = self.volume(&m, &mut p) {
            let medium = format!("{name} (volume)");
            let origin = Origin::file(&self.file);
            let desc = MediumDesc {
                sigma_a,
                sigma_s: [0.0; 3],
                g: 0.0,
                emission: None,
                density: None,
                origin,
            };
            self.desc.media.media.insert(medium.clone(), desc);
            self.interiors.insert(name.clone(), medium);
        }
        self.desc.materials.insert(
            name.clone(),
            MaterialDesc {
                kind: MaterialKind::OpenPbr(Box::new(p)),
                roughness: pbr.roughness_factor(),
                user_color: None,
                textures,
                base_color_map: None,
                normal_map: None,
                origin: Origin::file(&self.file),
            },
        );
        self.materials.insert(m.index(), name.clone());
        Ok(name)
    }

    /// The material extensions the `gltf` crate does not read, from the file's JSON:
    /// each factor sets an OpenPBR parameter and each texture multiplies it.
    fn extensions(
        &mut self,
        m: &gltf::Material,
        pointer: &str,
        p: &mut OpenPbr,
        textures: &mut TexturesDesc,
    ) -> Result<(), SceneError> {
        let value = |ext: &str, key: &str| m.extension_value(ext).and_then(|e| e.get(key));
        let at = |ext: &str, key: &str| format!("{pointer}/extensions/{ext}/{key}");
        for &(ext, key, input, default) in NUMBERS {
            let Some(v) = value(ext, key) else {
                if m.extension_value(ext).is_some() {
                    set_number(p, input, default);
                }
                continue;
            };
            let v = v
                .as_f64()
                .map(|v| v as f32)
                .filter(|v| v.is_finite() && *v >= 0.0)
                .ok_or_else(|| {
                    self.error(
                        &at(ext, key),
                        format!("expected a non-negative number, got {v}"),
                    )
                })?;
            set_number(p, input, v);
        }
        for &(ext, key, input, default) in COLORS {
            let c = match value(ext, key) {
                None if m.extension_value(ext).is_none() => continue,
                None => default,
                Some(v) => v
                    .as_array()
                    .filter(|a| a.len() == 3)
                    .and_then(|a| {
                        let c = [a[0].as_f64()?, a[1].as_f64()?, a[2].as_f64()?];
                        Some(c.map(|x| x as f32))
                    })
                    .filter(|c| c.iter().all(|x| x.is_finite() && *x >= 0.0))
                    .ok_or_else(|| {
                        self.error(
                            &at(ext, key),
                            format!("expected [r, g, b] of non-negative numbers, got {v}"),
                        )
                    })?,
            };
            if let Some(InputMut::Color(slot)) = openpbr::input(input).map(|i| (i.get)(p)) {
                *slot = Vec3A::from(c);
            }
        }
        // A sheen is on wherever its colour is not black (Blender sets its weight to 1).
        if m.extension_value("KHR_materials_sheen").is_some() && p.fuzz_color != Vec3A::ZERO {
            p.fuzz_weight = 1.0;
        }
        // KHR_materials_specular may exceed 1; OpenPBR's weight allows it too.
        if let Some(ir) = m.extension_value("KHR_materials_iridescence") {
            let max = ir
                .get("iridescenceThicknessMaximum")
                .and_then(|v| v.as_f64())
                .unwrap_or(400.0);
            // Nanometres to OpenPBR's micrometres; a thickness texture scales the maximum.
            p.thin_film_thickness = (max as f32 / 1000.0).max(0.0);
        }
        if let Some(dt) = m.extension_value("KHR_materials_diffuse_transmission") {
            let _ = dt;
            // Without KHR_materials_volume the surface is a thin sheet: translucency.
            p.geometry_thin_walled = m.extension_value("KHR_materials_volume").is_none();
        }
        // Anisotropy follows the mesh's tangent, turned by the rotation and by the
        // texture's direction (red, green; its blue is the strength, in TEXTURES).
        if m.extension_value("KHR_materials_anisotropy").is_some() {
            let rotation = value("KHR_materials_anisotropy", "anisotropyRotation")
                .and_then(|v| v.as_f64())
                .filter(|r| r.is_finite())
                .unwrap_or(0.0) as f32;
            let texture = match value("KHR_materials_anisotropy", "anisotropyTexture") {
                Some(info) => Some(
                    self.texture_info(info, &at("KHR_materials_anisotropy", "anisotropyTexture"))?,
                ),
                None => None,
            };
            textures.anisotropy_direction = Some((rotation, texture));
            blender_anisotropy(p);
        }
        for &(ext, key, input, channel, srgb) in TEXTURES {
            let Some(info) = value(ext, key) else {
                continue;
            };
            let t = self.texture_info(info, &at(ext, key))?;
            textures.inputs.push(input_texture(input, t, channel, srgb));
        }
        Ok(())
    }

    /// KHR_materials_volume: with a thickness (a closed mesh around a volume) and a
    /// transmissive material, the absorption coefficient of its interior, σa =
    /// −ln(attenuationColor) / attenuationDistance (the extension's Beer–Lambert law,
    /// distances in world units); the base colour stays the interface's tint. With
    /// thickness 0 (thin-walled) the attenuation colour tints the interface. With a
    /// diffuse transmission the distance is the subsurface radius.
    fn volume(&mut self, m: &gltf::Material, p: &mut OpenPbr) -> Option<[f32; 3]> {
        let v = m.extension_value("KHR_materials_volume")?;
        let distance = v.get("attenuationDistance").and_then(|d| d.as_f64());
        let d = distance.filter(|d| d.is_finite() && *d > 0.0)? as f32;
        let color = v
            .get("attenuationColor")
            .and_then(|c| c.as_array())
            .filter(|a| a.len() == 3)
            .and_then(|a| {
                Some([
                    a[0].as_f64()? as f32,
                    a[1].as_f64()? as f32,
                    a[2].as_f64()? as f32,
                ])
            })
            .unwrap_or([1.0; 3])
            .map(|c| {
                if c.is_finite() {
                    c.clamp(0.0, 1.0)
                } else {
                    1.0
                }
            });
        let thickness = v
            .get("thicknessFactor")
            .and_then(|t| t.as_f64())
            .unwrap_or(0.0);
        if p.subsurface_weight > 0.0 {
            p.transmission_depth = d;
            p.transmission_color *= Vec3A::from(color);
            p.subsurface_radius = d;
            return None;
        }
        if thickness > 0.0 && p.transmission_weight > 0.0 {
            // A colour of 0 absorbs everything: a large finite coefficient, so that a
            // ray's transmittance is 0 without infinities in the arithmetic.
            return Some(color.map(|c| (-c.max(1e-30).ln() / d).min(1e30)));
        }
        p.transmission_color *= Vec3A::from(color);
        None
    }

    /// A texture a material extension names by its JSON `textureInfo`.
    fn texture_info(
        &mut self,
        info: &serde_json::Value,
        pointer: &str,
    ) -> Result<TextureDesc, SceneError> {
        let index = info
            .get("index")
            .and_then(|i| i.as_u64())
            .ok_or_else(|| self.error(pointer, "expected a texture index"))?;
        // The document is borrowed by the texture while `self` reads its image.
        let doc = self.doc.clone();
        let texture = usize::try_from(index)
            .ok()
            .and_then(|i| doc.textures().nth(i))
            .ok_or_else(|| self.error(pointer, format!("no texture {index} in /textures")))?;
        let mut t = self.texture(&texture, None, pointer)?;
        if let Some(x) = info
            .get("extensions")
            .and_then(|e| e.get("KHR_texture_transform"))
        {
            let pair = |key: &str, default: [f32; 2]| {
                x.get(key)
                    .and_then(|v| v.as_array())
                    .filter(|a| a.len() == 2)
                    .and_then(|a| Some([a[0].as_f64()? as f32, a[1].as_f64()? as f32]))
                    .unwrap_or(default)
            };
            let rotation = x.get("rotation").and_then(|r| r.as_f64()).unwrap_or(0.0) as f32;
            t.transform =
                UvTransform::new(pair("offset", [0.0; 2]), rotation, pair("scale", [1.0; 2]));
        }
        Ok(t)
    }

    /// Emission of a material's surface (factor × KHR_materials_emissive_strength).
    fn emission(&self, m: gltf::Material) -> Option<[f32; 3]> {
        let e = Vec3::from(m.emissive_factor()) * m.emissive_strength().unwrap_or(1.0);
        (e != Vec3::ZERO).then_some(e.into())
    }

    fn texture(
        &mut self,
        t: &gltf::Texture,
        transform: Option<gltf::texture::TextureTransform>,
        pointer: &str,
    ) -> Result<TextureDesc, SceneError> {
        use gltf::texture::WrappingMode as W;
        let wrap = |w: W| match w {
            W::Repeat => Wrap::Repeat,
            W::ClampToEdge => Wrap::Clamp,
            W::MirroredRepeat => Wrap::Mirror,
        };
        let sampler = t.sampler();
        let image = self.image(&t.source(), pointer)?;
        let transform = transform.map_or_else(UvTransform::default, |x| {
            UvTransform::new(x.offset(), x.rotation(), x.scale())
        });
        Ok(TextureDesc {
            image,
            wrap: [wrap(sampler.wrap_s()), wrap(sampler.wrap_t())],
            transform,
            origin: Origin::file(&self.file),
        })
    }

    fn image(&mut self, img: &gltf::Image, pointer: &str) -> Result<ImageSource, SceneError> {
        if let Some(s) = self.images.get(&img.index()) {
            return Ok(s.clone());
        }
        let at = format!("{pointer}: /images/{}", img.index());
        let label = img
            .name()
            .map(str::to_string)
            .unwrap_or_else(|| format!("{} image {}", self.file, img.index()));
        let source = match img.source() {
            gltf::image::Source::View { view, .. } => {
                let buffer = &self.buffers[view.buffer().index()].0;
                let (start, len) = (view.offset(), view.length());
                let bytes = buffer.get(start..start + len).ok_or_else(|| {
                    self.error(
                        &at,
                        format!(
                            "its buffer view ends past its buffer ({} bytes)",
                            buffer.len()
                        ),
                    )
                })?;
                ImageSource::Bytes {
                    name: label,
                    bytes: Arc::from(bytes),
                }
            }
            gltf::image::Source::Uri { uri, .. } => match uri.strip_prefix("data:") {
                Some(rest) => {
                    let (_, data) = rest
                        .split_once(";base64,")
                        .ok_or_else(|| self.error(&at, "a data URI that is not base64"))?;
                    let bytes = base64_decode(data)
                        .ok_or_else(|| self.error(&at, "its data URI is not valid base64"))?;
                    ImageSource::Bytes {
                        name: label,
                        bytes: Arc::from(bytes),
                    }
                }
                None => {
                    ImageSource::File(uri_path(&self.dir, uri).map_err(|e| self.error(&at, e))?)
                }
            },
        };
        self.images.insert(img.index(), source.clone());
        Ok(source)
    }

    fn camera(&mut self, node: &gltf::Node, camera: &gltf::Camera, world: Mat4) {
        let pointer = format!("/cameras/{}", camera.index());
        let gltf::camera::Projection::Perspective(p) = camera.projection() else {
            self.warn(
                &pointer,
                "orthographic cameras are not supported; it is skipped",
            );
            return;
        };
        let name = node
            .name()
            .or(camera.name())
            .map(str::to_string)
            .unwrap_or_else(|| format!("camera{}", camera.index()));
        let xf = Affine3A::from_mat4(world);
        // A glTF camera looks down its local −Z with +Y up.
        let position = xf.transform_point3a(Vec3A::ZERO);
        let forward = xf.transform_vector3a(-Vec3A::Z).normalize_or(-Vec3A::Z);
        let up = xf.transform_vector3a(Vec3A::Y).normalize_or(Vec3A::Y);
        let desc = CameraDesc {
            position: position.into(),
            look_at: (position + forward).into(),
            up: up.into(),
            fov: p.yfov().to_degrees(),
            fov_axis: FovAxis::Y,
            origin: Origin::file(&self.file),
            ..CameraDesc::default()
        };
        let resolution = p
            .aspect_ratio()
            .filter(|a| *a > 0.0 && a.is_finite())
            .map(|a| {
                if a >= 1.0 {
                    [FILM_SIZE as u32, (FILM_SIZE / a).round().max(1.0) as u32]
                } else {
                    [(FILM_SIZE * a).round().max(1.0) as u32, FILM_SIZE as u32]
                }
            });
        if self.desc.camera.is_none() {
            self.desc.camera = Some(desc.clone());
            if let Some(r) = resolution {
                self.desc.render.resolution = r;
            }
        }
        self.desc.cameras.push(NamedCamera {
            name,
            camera: desc,
            resolution,
        });
    }

    fn light(
        &mut self,
        node: &gltf::Node,
        light: &gltf::khr_lights_punctual::Light,
        world: Mat4,
    ) -> Result<(), SceneError> {
        use gltf::khr_lights_punctual::Kind;
        let xf = Affine3A::from_mat4(world);
        let position: [f32; 3] = xf.transform_point3a(Vec3A::ZERO).into();
        // Lights point down their local −Z.
        let direction: [f32; 3] = xf
            .transform_vector3a(-Vec3A::Z)
            .normalize_or(-Vec3A::Z)
            .into();
        let name = node
            .name()
            .or(light.name())
            .map(str::to_string)
            .unwrap_or_else(|| format!("light{}", light.index()));
        let group = extra_strings(node.extras(), "lightgroup")
            .into_iter()
            .chain(extra_strings(light.extras(), "lightgroup"))
            .next()
            .unwrap_or_else(|| name.clone());
        let intensity = light.intensity();
        let (kind, strength) = match light.kind() {
            Kind::Point => (LightKind::Point { position }, point_intensity(intensity)),
            Kind::Spot {
                inner_cone_angle,
                outer_cone_angle,
            } => {
                let (cone_angle, cone_softness) = spot_cone(inner_cone_angle, outer_cone_angle);
                (
                    LightKind::Spot {
                        position,
                        direction,
                        cone_angle,
                        cone_softness,
                    },
                    point_intensity(intensity),
                )
            }
            Kind::Directional => (
                LightKind::Distant {
                    direction,
                    angle: SUN_ANGLE_DEG,
                },
                sun_irradiance(intensity),
            ),
        };
        if !(strength.is_finite() && strength >= 0.0) {
            return Err(self.error(
                &format!(
                    "/extensions/KHR_lights_punctual/lights/{}/intensity",
                    light.index()
                ),
                format!("expected a non-negative intensity, got {intensity}"),
            ));
        }
        self.desc.lights.push(LightDesc {
            kind,
            name: Some(name),
            groups: vec![group],
            color: light.color(),
            strength,
            camera_visible: false,
            casts_shadows: true,
            shaping: None,
            two_sided: false,
            material: None,
            transform: Affine3A::IDENTITY,
            include: None,
            exclude: Vec::new(),
            shadow_include: None,
            shadow_exclude: Vec::new(),
            origin: Origin::file(&self.file),
        });
        Ok(())
    }
}

/// A point or spot light's radiant intensity (W/sr) from its luminous intensity (cd):
/// Blender's importer makes it cd · 4π / 683 W, which Cycles emits as W / 4π per sr.
pub fn point_intensity(candela: f32) -> f32 {
    let watts = candela * 4.0 * PI / WATTS_TO_LUMENS;
    watts / (4.0 * PI)
}

/// The angular diameter (degrees) of a directional light's disc. glTF has none, and
/// Blender's importer leaves a new sun's default, 0.526° (the real sun's), which Cycles
/// then renders: the sun shows in smooth reflections and refractions, and smooth glass
/// throws its caustics. A delta direction would show neither (benches/materials/RESULTS.md).
pub const SUN_ANGLE_DEG: f32 = 0.526;

/// A directional light's irradiance (W/m²) from its illuminance (lux), as Blender's
/// importer sets a sun's strength.
pub fn sun_irradiance(lux: f32) -> f32 {
    lux / WATTS_TO_LUMENS
}

/// A spot's full cone angle and soft edge (degrees) from glTF's inner and outer cone
/// half-angles (radians), the way Blender imports them and Cycles shades them: spot
/// size 2·outer, blend 1 − inner/outer, and a smoothstep over cos θ from cos(outer) up
/// to cos(outer) + (1 − cos(outer)) · blend.
pub fn spot_cone(inner: f32, outer: f32) -> (f32, f32) {
    let outer = outer.clamp(1e-4, PI / 2.0);
    let blend = (1.0 - inner.clamp(0.0, outer) / outer).clamp(0.0, 1.0);
    let cos_outer = outer.cos();
    let cos_inner = cos_outer + (1.0 - cos_outer) * blend;
    let inner_eff = cos_inner.clamp(-1.0, 1.0).acos();
    (2.0 * outer.to_degrees(), (outer - inner_eff).to_degrees())
}

/// The texture coordinate set a material's textures read (0 unless its base colour
/// texture names another).
fn uv_set(m: gltf::Material) -> u32 {
    m.pbr_metallic_roughness()
        .base_color_texture()
        .map_or(0, |t| {
            t.texture_transform()
                .and_then(|x| x.tex_coord())
                .unwrap_or(t.tex_coord())
        })
}

/// `extras.<key>` as strings: a string, or a list of them.
fn extra_strings(extras: &gltf::json::Extras, key: &str) -> Vec<String> {
    let Some(raw) = extras else {
        return Vec::new();
    };
    let Ok(v) = serde_json::from_str::<serde_json::Value>(raw.get()) else {
        return Vec::new();
    };
    match v.get(key) {
        Some(serde_json::Value::String(s)) => vec![s.clone()],
        Some(serde_json::Value::Array(a)) => a
            .iter()
            .filter_map(|x| x.as_str().map(str::to_string))
            .collect(),
        _ => Vec::new(),
    }
}

/// Each buffer's bytes: the binary chunk of a `.glb`, a data URI, or a file read through
/// `limits::read_input` (within the input-size limit, and an input of the render's
/// identity); padded to a multiple of 4 bytes as the `gltf` crate's readers expect.
fn read_buffers(
    document: &Document,
    dir: &Path,
    mut blob: Option<Vec<u8>>,
) -> Result<Vec<gltf::buffer::Data>, String> {
    let mut out = Vec::new();
    for buffer in document.buffers() {
        let at = format!("/buffers/{}", buffer.index());
        let mut data = match buffer.source() {
            gltf::buffer::Source::Bin => blob
                .take()
                .ok_or_else(|| format!("{at}: it is the binary chunk, which the file lacks"))?,
            gltf::buffer::Source::Uri(uri) => match uri.strip_prefix("data:") {
                Some(rest) => rest
                    .split_once(";base64,")
                    .and_then(|(_, data)| base64_decode(data))
                    .ok_or_else(|| format!("{at}: its data URI is not valid base64"))?,
                None => {
                    let path = uri_path(dir, uri).map_err(|e| format!("{at}: {e}"))?;
                    crate::limits::read_input(&path).map_err(|e| {
                        format!("{at}: cannot load a buffer from {}: {e}", path.display())
                    })?
                }
            },
        };
        if data.len() < buffer.length() {
            return Err(format!(
                "{at}: it holds {} bytes, fewer than its byteLength {}",
                data.len(),
                buffer.length()
            ));
        }
        while data.len() % 4 != 0 {
            data.push(0);
        }
        out.push(gltf::buffer::Data(data));
    }
    Ok(out)
}

/// The file a (non-data) URI names: `file:` URIs as they are, relative references
/// against the glTF's folder; any other scheme is refused.
fn uri_path(dir: &Path, uri: &str) -> Result<PathBuf, String> {
    let file = uri.strip_prefix("file://").or(uri.strip_prefix("file:"));
    match file {
        Some(path) => Ok(PathBuf::from(percent_decode(path))),
        None if uri.contains(':') => Err(format!(
            "'{uri}': only relative paths, file: and data: URIs are read"
        )),
        None => Ok(dir.join(percent_decode(uri))),
    }
}

fn base64_decode(s: &str) -> Option<Vec<u8>> {
    let val = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            _ => return None,
        } as u32)
    };
    let bytes: Vec<u8> = s
        .bytes()
        .filter(|c| !c.is_ascii_whitespace() && *c != b'=')
        .collect();
    let mut out = Vec::with_capacity(bytes.len() * 3 / 4);
    for chunk in bytes.chunks(4) {
        let mut acc = 0u32;
        for (i, &c) in chunk.iter().enumerate() {
            acc |= val(c)? << (18 - 6 * i);
        }
        let n = match chunk.len() {
            4 => 3,
            3 => 2,
            2 => 1,
            _ => return None,
        };
        out.extend_from_slice(&acc.to_be_bytes()[1..1 + n]);
    }
    Some(out)
}

fn percent_decode(uri: &str) -> String {
    let b = uri.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            let hex = |c: u8| (c as char).to_digit(16);
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Sets OpenPBR number `input` (a name from the table).
fn set_number(p: &mut OpenPbr, input: &str, v: f32) {
    if let Some(InputMut::Scalar(slot)) = openpbr::input(input).map(|i| (i.get)(p)) {
        *slot = v;
    }
}

/// A texture on OpenPBR input `input` (a name from the table).
fn input_texture(input: &str, texture: TextureDesc, channel: u8, srgb: bool) -> InputTexture {
    InputTexture {
        input: openpbr::input(input)
            .expect("glTF maps to OpenPBR inputs")
            .name,
        texture,
        channel,
        srgb,
        exponent: 1.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_numbers() {
        assert_eq!(base64_decode("TWFu").unwrap(), b"Man");
        assert_eq!(base64_decode("TWE=").unwrap(), b"Ma");
        assert_eq!(base64_decode("TQ==").unwrap(), b"M");
        assert!(base64_decode("T").is_none());
        assert!(base64_decode("T!==").is_none());
    }

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("a%20b.png"), "a b.png");
        assert_eq!(percent_decode("100%"), "100%");
        assert_eq!(percent_decode("%é%4"), "%é%4");
    }

    #[test]
    fn photometric_units_as_blender_imports_them() {
        // Blender exports a 1000 W point light as 1000 / 4π · 683 cd.
        let cd = 1000.0 / (4.0 * PI) * 683.0;
        assert!((point_intensity(cd) - 1000.0 / (4.0 * PI)).abs() < 1e-2);
        assert!((sun_irradiance(683.0) - 1.0).abs() < 1e-6);
        // No blend: a hard edge at the outer angle.
        let (angle, soft) = spot_cone(0.5, 0.5);
        assert!((angle - 2.0 * 0.5f32.to_degrees()).abs() < 1e-4);
        assert!(soft.abs() < 1e-3);
        // Inner 0: Blender's blend 1, the smoothstep spans cos(outer)..1.
        let (_, soft) = spot_cone(0.0, 0.5);
        assert!((soft - 0.5f32.to_degrees()).abs() < 1e-3);
    }
}
