//! Scenes: the TOML description (`desc`), the built-in scenes, and the build step that
//! turns a description into the renderable `Scene` — BVH, materials with LPE-classified
//! lobes, lights, and the compiled automaton of the AOVs.

pub mod builtin;
pub mod desc;

use crate::aov::AovSpec;
use crate::camera::{Camera, FovAxis, PixelFilter};
use crate::geometry::shapes::{self, ShapePrims};
use crate::geometry::{Accel, Prim, Visibility};
use crate::light::{EnvMap, Light, LightShape};
use crate::material::{roughness_to_alpha, Bsdf};
use crate::sampling::Distribution1D;
use desc::{placement, LightDesc, MaterialDesc, ObjectDesc, SceneDesc};
use glam::Vec3A;
use lpe::{Automaton, ClassId, Event, EventType, Flags, Scatter};
use std::collections::HashMap;
use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// A scene error: which file, where in it, and what was expected.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SceneError {
    pub file: String,
    pub line: usize,
    pub column: usize,
    pub message: String,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line > 0 {
            write!(
                f,
                "{}:{}:{}: {}",
                self.file, self.line, self.column, self.message
            )
        } else {
            write!(f, "{}: {}", self.file, self.message)
        }
    }
}

impl std::error::Error for SceneError {}

/// Maps byte offsets of a scene file to lines and columns for error messages.
pub struct Source {
    pub name: String,
    pub text: String,
    /// Directory that relative paths in the file are resolved against.
    pub dir: PathBuf,
}

impl Source {
    pub fn from_file(path: &Path) -> Result<Source, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|e| SceneError {
            file: path.display().to_string(),
            line: 0,
            column: 0,
            message: format!("cannot read the scene file: {e}"),
        })?;
        Ok(Source {
            name: path.display().to_string(),
            text,
            dir: path.parent().map(Path::to_path_buf).unwrap_or_default(),
        })
    }

    pub fn error(&self, span: Option<Range<usize>>, message: impl Into<String>) -> SceneError {
        let (line, column) = match span {
            Some(r) => {
                let at = r.start.min(self.text.len());
                let before = &self.text[..at];
                let line = before.matches('\n').count() + 1;
                let column = before.rfind('\n').map_or(at, |i| at - i - 1) + 1;
                (line, column)
            }
            None => (0, 0),
        };
        SceneError {
            file: self.name.clone(),
            line,
            column,
            message: message.into(),
        }
    }

    pub fn parse(&self) -> Result<SceneDesc, SceneError> {
        toml::from_str(&self.text).map_err(|e| self.error(e.span(), e.message().to_string()))
    }
}

/// A material: its BSDF and the colour of its `U4` user lobe.
#[derive(Clone, Debug)]
pub struct Material {
    pub bsdf: Bsdf,
    pub user_color: Option<Vec3A>,
}

/// What a user (data) lobe reports (LPE.md §1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DataLobe {
    Albedo,
    Position,
    Normal,
    UserColor,
}

impl DataLobe {
    pub fn scatter(self) -> Scatter {
        Scatter::user(match self {
            DataLobe::Albedo => 2,
            DataLobe::Position => 3,
            DataLobe::UserColor => 4,
            DataLobe::Normal => 6,
        })
    }
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
    /// Class of each BSDF lobe's event on this object.
    pub lobe_classes: Vec<ClassId>,
    /// Data lobes with their classes.
    pub data_lobes: Vec<(DataLobe, ClassId)>,
    /// Class of this object's `O` event, if it glows.
    pub glow_class: Option<ClassId>,
}

#[derive(Clone, Debug)]
pub struct RenderSettings {
    pub spp: u32,
    pub max_depth: u32,
    pub max_diffuse_depth: u32,
    pub max_specular_depth: u32,
    pub rr_depth: u32,
    pub clamp_direct: f32,
    pub clamp_indirect: f32,
    pub seed: u64,
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
    pub objects: Vec<Object>,
    pub materials: Vec<Material>,
    pub lights: Vec<Light>,
    /// Class of each light's `L` and `O` events.
    pub light_classes: Vec<(ClassId, ClassId)>,
    pub light_select: Distribution1D,
    /// Lights reached by rays that escape the scene.
    pub escape_lights: Vec<u32>,
    pub camera: Camera,
    pub filter: PixelFilter,
    pub settings: RenderSettings,
    pub automaton: Automaton,
    pub aovs: Vec<Aov>,
    pub camera_class: ClassId,
    /// `L` with no labels: the unit light data lobes are evaluated under.
    pub data_light_class: ClassId,
    pub scene_radius: f32,
    /// Ray offset against self-intersection, scaled to the scene.
    pub epsilon: f32,
    /// Light group names, sorted; split AOV parts follow this order, then the default.
    pub light_groups: Vec<String>,
    /// Each light's part in split AOVs (its first group, or the default part).
    pub light_parts: Vec<u32>,
    /// True if any rule has the `unoccluded` or `shadows` prefix.
    pub any_unoccluded: bool,
    /// Per automaton state: can some object's data lobe be accepted from here? Most
    /// states cannot, and the integrator skips the data lobes there.
    pub data_live: Vec<bool>,
}

fn v3(a: [f32; 3]) -> Vec3A {
    Vec3A::from(a)
}

fn material(
    src: &Source,
    name: &str,
    m: &MaterialDesc,
    span: Range<usize>,
) -> Result<Material, SceneError> {
    let need = |v: Option<[f32; 3]>, what: &str| -> Result<Vec3A, SceneError> {
        v.map(v3).ok_or_else(|| {
            src.error(
                Some(span.clone()),
                format!("material '{name}': expected '{what}' = [r, g, b]"),
            )
        })
    };
    let alpha = roughness_to_alpha(m.roughness);
    let ior = || match m.ior.unwrap_or(1.5) {
        eta if eta > 0.0 && eta.is_finite() => Ok(eta),
        eta => Err(src.error(
            Some(span.clone()),
            format!("material '{name}': ior must be positive, got {eta}"),
        )),
    };
    let bsdf = match m.kind.get_ref().as_str() {
        "diffuse" => Bsdf::Diffuse { albedo: need(m.albedo, "albedo")? },
        "translucent" => Bsdf::Translucent { reflect: need(m.reflect, "reflect")?, transmit: need(m.transmit, "transmit")? },
        "conductor" => Bsdf::Conductor { f0: need(m.f0, "f0")?, alpha },
        "dielectric" => Bsdf::Dielectric { eta: ior()?, alpha, tint: m.tint.map(v3).unwrap_or(Vec3A::ONE) },
        "plastic" => Bsdf::Plastic { albedo: need(m.albedo, "albedo")?, eta: ior()?, alpha },
        other => {
            return Err(src.error(
                Some(m.kind.span()),
                format!("unknown material type '{other}': expected diffuse, translucent, conductor, dielectric or plastic"),
            ))
        }
    };
    Ok(Material {
        bsdf,
        user_color: m.user_color.map(v3),
    })
}

fn object_shape(
    src: &Source,
    o: &ObjectDesc,
    span: Range<usize>,
) -> Result<ShapePrims, SceneError> {
    let xf = placement(o.translate, o.rotate, o.scale, o.matrix);
    let missing = |what: &str| {
        src.error(
            Some(span.clone()),
            format!("{} shape needs '{what}'", o.shape.get_ref()),
        )
    };
    Ok(match o.shape.get_ref().as_str() {
        "rectangle" | "rect" => shapes::rectangle(&xf),
        "cube" | "box" => shapes::cube(&xf),
        "disk" => shapes::disk(&xf, o.segments.unwrap_or(64).max(3) as usize),
        "quad" => shapes::quad(o.corners.ok_or_else(|| missing("corners"))?.map(v3)),
        "sphere" => {
            let c = xf.transform_point3a(v3(o.center.unwrap_or([0.0; 3])));
            match o.radius.ok_or_else(|| missing("radius"))? {
                r if r > 0.0 && r.is_finite() => shapes::sphere(c, r),
                r => return Err(src.error(Some(span), format!("sphere radius must be positive, got {r}"))),
            }
        }
        "mesh" => {
            let pos: Vec<Vec3A> = o.positions.as_ref().ok_or_else(|| missing("positions"))?.iter().map(|p| v3(*p)).collect();
            let idx = o.indices.as_ref().ok_or_else(|| missing("indices"))?;
            if let Some(bad) = idx.iter().flatten().find(|&&i| i as usize >= pos.len()) {
                return Err(src.error(Some(span), format!("mesh index {bad} is out of range: there are {} positions", pos.len())));
            }
            let normals: Option<Vec<Vec3A>> = o.normals.as_ref().map(|n| n.iter().map(|p| v3(*p)).collect());
            if let Some(n) = &normals {
                if n.len() != pos.len() {
                    return Err(src.error(Some(span), format!("mesh has {} normals for {} positions", n.len(), pos.len())));
                }
            }
            shapes::mesh(&xf, &pos, idx, normals.as_deref())
        }
        "obj" => {
            let file = o.file.as_ref().ok_or_else(|| missing("file"))?;
            load_obj(src, &src.dir.join(file.get_ref()), &xf, file.span())?
        }
        other => {
            return Err(src.error(
                Some(o.shape.span()),
                format!("unknown shape '{other}': expected rectangle, quad, cube, disk, sphere, mesh or obj"),
            ))
        }
    })
}

fn load_obj(
    src: &Source,
    path: &Path,
    xf: &glam::Affine3A,
    span: Range<usize>,
) -> Result<ShapePrims, SceneError> {
    let (models, _) = tobj::load_obj(path, &tobj::GPU_LOAD_OPTIONS).map_err(|e| {
        src.error(
            Some(span.clone()),
            format!("cannot load OBJ file {}: {e}", path.display()),
        )
    })?;
    let mut out = ShapePrims::default();
    for m in models {
        let pos: Vec<Vec3A> = m
            .mesh
            .positions
            .chunks_exact(3)
            .map(|p| Vec3A::new(p[0], p[1], p[2]))
            .collect();
        let idx: Vec<[u32; 3]> = m
            .mesh
            .indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect();
        let normals: Option<Vec<Vec3A>> =
            (m.mesh.normals.len() == m.mesh.positions.len()).then(|| {
                m.mesh
                    .normals
                    .chunks_exact(3)
                    .map(|p| Vec3A::new(p[0], p[1], p[2]))
                    .collect()
            });
        let part = shapes::mesh(xf, &pos, &idx, normals.as_deref());
        let base = out.prims.len();
        out.normals
            .extend(part.normals.into_iter().map(|(i, n)| (i + base, n)));
        out.prims.extend(part.prims);
    }
    if out.prims.is_empty() {
        return Err(src.error(
            Some(span),
            format!("OBJ file {} has no triangles", path.display()),
        ));
    }
    Ok(out)
}

/// A light's shape and, for area lights, the primitives it adds to the scene.
fn light_shape(
    src: &Source,
    l: &LightDesc,
    span: Range<usize>,
) -> Result<(LightShape, Option<ShapePrims>, Vec3A), SceneError> {
    let kind = l.kind.get_ref().as_str();
    let color = |v: Option<[f32; 3]>, what: &str| -> Result<Vec3A, SceneError> {
        v.map(|c| v3(c) * l.strength).ok_or_else(|| {
            src.error(
                Some(span.clone()),
                format!("{kind} light needs '{what}' = [r, g, b]"),
            )
        })
    };
    let xf = placement(l.translate, l.rotate, l.scale, l.matrix);
    let area = |prims: ShapePrims| {
        let areas: Vec<f32> = prims.prims.iter().map(Prim::area).collect();
        let normals = prims.prims.iter().map(Prim::face_normal).collect();
        let shape = LightShape::Triangles {
            parallelogram: parallelogram(&prims.prims),
            prims: prims.prims.clone(),
            normals,
            by_area: Distribution1D::new(&areas),
            area: areas.iter().sum(),
            two_sided: l.two_sided,
        };
        (shape, Some(prims))
    };
    Ok(match kind {
        "rect" | "rectangle" => {
            let (s, p) = area(shapes::rectangle(&xf));
            (s, p, color(l.radiance, "radiance")?)
        }
        "quad" => {
            let corners = l.corners.ok_or_else(|| src.error(Some(span.clone()), "quad light needs 'corners'"))?;
            let (s, p) = area(shapes::quad(corners.map(v3)));
            (s, p, color(l.radiance, "radiance")?)
        }
        "disk" => {
            let (s, p) = area(shapes::disk(&xf, l.segments.unwrap_or(64).max(3) as usize));
            (s, p, color(l.radiance, "radiance")?)
        }
        "sphere" => {
            let center = xf.transform_point3a(v3(l.center.unwrap_or([0.0; 3])));
            let radius = l.radius.ok_or_else(|| src.error(Some(span.clone()), "sphere light needs 'radius'"))?;
            if !(radius > 0.0 && radius.is_finite()) {
                return Err(src.error(Some(span), format!("sphere light radius must be positive, got {radius}")));
            }
            (LightShape::Sphere { center, radius }, Some(shapes::sphere(center, radius)), color(l.radiance, "radiance")?)
        }
        "point" => {
            let position = v3(l.position.ok_or_else(|| src.error(Some(span.clone()), "point light needs 'position'"))?);
            (LightShape::Point { position }, None, color(l.intensity, "intensity")?)
        }
        "spot" => {
            let position = v3(l.position.ok_or_else(|| src.error(Some(span.clone()), "spot light needs 'position'"))?);
            let dir = v3(l.direction.ok_or_else(|| src.error(Some(span.clone()), "spot light needs 'direction'"))?).normalize_or(-Vec3A::Y);
            let half = l.cone_angle.unwrap_or(60.0).to_radians() * 0.5;
            let soft = l.cone_softness.unwrap_or(10.0).to_radians();
            let shape = LightShape::Spot { position, axis: dir, cos_inner: (half - soft).max(0.0).cos(), cos_outer: half.cos() };
            (shape, None, color(l.intensity, "intensity")?)
        }
        "distant" => {
            let dir = v3(l.direction.ok_or_else(|| src.error(Some(span.clone()), "distant light needs 'direction'"))?).normalize_or(-Vec3A::Y);
            (LightShape::Distant { dir }, None, color(l.irradiance, "irradiance")?)
        }
        "dome" => {
            let map = match &l.map {
                None => None,
                Some(file) => Some(load_env(src, &src.dir.join(file.get_ref()), file.span())?),
            };
            let c = l.radiance.map(|c| v3(c) * l.strength).unwrap_or(Vec3A::splat(l.strength));
            (LightShape::Dome { map }, None, c)
        }
        other => {
            return Err(src.error(
                Some(l.kind.span()),
                format!("unknown light type '{other}': expected rect, quad, disk, sphere, point, spot, distant or dome"),
            ))
        }
    })
}

/// Two triangles `(c0, c1, c2)`, `(c0, c2, c3)` that form a parallelogram, as corner and
/// edges.
fn parallelogram(prims: &[Prim]) -> Option<[Vec3A; 3]> {
    let [Prim::Triangle {
        p0, e1: a1, e2: a2, ..
    }, Prim::Triangle {
        p0: q0,
        e1: b1,
        e2: b2,
        ..
    }] = prims
    else {
        return None;
    };
    let same_start = (*p0 - *q0).length() <= 1e-6 * (1.0 + p0.length());
    let diagonal_shared = (*a2 - *b1).length() <= 1e-6 * (1.0 + a2.length());
    // c1 + c3 = c0 + c2  ⇔  a1 + b2 = a2.
    let closes = (*a1 + *b2 - *a2).length() <= 1e-5 * (1.0 + a2.length());
    (same_start && diagonal_shared && closes).then_some([*p0, *a1, *b2])
}

fn load_env(src: &Source, path: &Path, span: Range<usize>) -> Result<EnvMap, SceneError> {
    use exr::prelude::*;
    let image = read_first_rgba_layer_from_file(
        path,
        |res, _| (res.width(), vec![Vec3A::ZERO; res.width() * res.height()]),
        |(w, px), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            px[pos.y() * *w + pos.x()] = Vec3A::new(r, g, b)
        },
    )
    .map_err(|e| {
        src.error(
            Some(span),
            format!("cannot read environment map {}: {e}", path.display()),
        )
    })?;
    let size = image.layer_data.size;
    let (_, texels) = image.layer_data.channel_data.pixels;
    Ok(EnvMap::new(size.width(), size.height(), texels))
}

impl Scene {
    /// Builds a scene from its description and the AOVs to render (beauty first).
    pub fn build(src: &Source, desc: &SceneDesc, aovs: &[AovSpec]) -> Result<Scene, SceneError> {
        // Materials.
        let mut materials = Vec::new();
        let mut material_ids = HashMap::new();
        for (name, m) in &desc.materials {
            material_ids.insert(name.clone(), materials.len() as u32);
            materials.push(material(src, name, m.get_ref(), m.span())?);
        }
        let find_material = |m: &Option<toml::Spanned<String>>| -> Result<Option<u32>, SceneError> {
            match m {
                None => Ok(None),
                Some(name) => material_ids
                    .get(name.get_ref())
                    .copied()
                    .map(Some)
                    .ok_or_else(|| {
                        let known: Vec<&String> = desc.materials.keys().collect();
                        src.error(
                            Some(name.span()),
                            format!(
                                "unknown material '{}': the scene defines {known:?}",
                                name.get_ref()
                            ),
                        )
                    }),
            }
        };

        let mut objects: Vec<Object> = Vec::new();
        let mut geometry = GeometryBuilder::default();
        for o in &desc.objects {
            let span = o.span();
            let o = o.get_ref();
            let name = o
                .name
                .clone()
                .unwrap_or_else(|| format!("object{}", objects.len()));
            let shape = object_shape(src, o, span.clone())?;
            let id = objects.len() as u32;
            let visibility = (o.visible_camera as u8 * Visibility::CAMERA)
                | (o.visible_indirect as u8 * Visibility::INDIRECT)
                | (o.casts_shadows as u8 * Visibility::SHADOW);
            geometry.add(id, shape, visibility);
            objects.push(Object {
                groups: o.lpegroups.clone().unwrap_or_else(|| vec![name.clone()]),
                name,
                material: find_material(&o.material)?,
                emission: o.emission.map(v3).unwrap_or(Vec3A::ZERO),
                light: None,
                holdout: o.holdout,
                unlit_by: Vec::new(),
                lobe_classes: Vec::new(),
                data_lobes: Vec::new(),
                glow_class: None,
            });
        }
        let mut lights = Vec::new();
        for l in &desc.lights {
            let span = l.span();
            let l = l.get_ref();
            let (shape, surface, color) = light_shape(src, l, span)?;
            let light_id = lights.len() as u32;
            let object = surface.map(|sp| {
                let id = objects.len() as u32;
                let camera = if l.camera_visible {
                    Visibility::CAMERA
                } else {
                    0
                };
                geometry.add(id, sp, camera | Visibility::INDIRECT | Visibility::SHADOW);
                let name = l.name.clone().unwrap_or_else(|| format!("light{light_id}"));
                objects.push(Object {
                    groups: if l.groups.is_empty() {
                        vec![name.clone()]
                    } else {
                        l.groups.clone()
                    },
                    name,
                    material: None,
                    emission: Vec3A::ZERO,
                    light: Some(light_id),
                    holdout: false,
                    unlit_by: Vec::new(),
                    lobe_classes: Vec::new(),
                    data_lobes: Vec::new(),
                    glow_class: None,
                });
                id
            });
            if let Some(id) = object {
                objects[id as usize].material = find_material(&l.material)?;
            }
            lights.push(Light {
                shape,
                color,
                groups: l.groups.clone(),
                camera_visible: l.camera_visible,
                object,
            });
        }
        let accel = geometry.build();
        // Light linking, resolved per object once.
        for (light_id, l) in desc.lights.iter().enumerate() {
            let l = l.get_ref();
            let lit = |o: &Object| {
                let any = |set: &[String]| o.groups.iter().any(|g| set.contains(g));
                l.include.as_deref().is_none_or(any) && !any(&l.exclude)
            };
            let light_id = light_id as u32;
            for o in objects.iter_mut().filter(|o| o.light != Some(light_id)) {
                if !lit(o) {
                    o.unlit_by.push(light_id);
                }
            }
        }

        // Scene size, for ray offsets and the power of infinite lights.
        let (mut lo, mut hi) = (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY));
        for p in accel.prims() {
            let (a, b) = p.bounds();
            lo = lo.min(a);
            hi = hi.max(b);
        }
        let scene_radius = if lo.x.is_finite() {
            0.5 * (hi - lo).length()
        } else {
            1.0
        };
        let epsilon = 1e-4 * scene_radius.max(1.0);

        let automaton = compile_aovs(src, desc, aovs, &materials, &objects, &lights)?;
        let classify = |e: &Event| {
            automaton
                .classify(e)
                .expect("every scene event is in the vocabulary")
        };
        for o in &mut objects {
            let (lobes, data) = object_events(o, &materials);
            o.lobe_classes = lobes.iter().map(classify).collect();
            // Keep only data lobes some rule can accept: the others would cost two steps
            // per vertex for nothing.
            let data_light = classify(&Event::bare(EventType::Light));
            o.data_lobes = data
                .iter()
                .map(|(k, e)| (*k, classify(e)))
                .filter(|(_, class)| {
                    automaton.states().any(|s| {
                        let after = automaton.step(s, *class);
                        !automaton
                            .accepting(automaton.step(after, data_light))
                            .is_empty()
                    })
                })
                .collect();
            o.glow_class = (o.emission != Vec3A::ZERO)
                .then(|| classify(&Event::new(EventType::Emission, None, o.groups.iter())));
        }
        let light_classes = lights
            .iter()
            .map(|l| {
                (
                    classify(&Event::new(EventType::Light, None, l.groups.iter())),
                    classify(&Event::new(EventType::Emission, None, l.groups.iter())),
                )
            })
            .collect();
        // Lights are chosen in proportion to their power at unit colour, with a floor so
        // small lights still get samples.
        let powers: Vec<f32> = lights
            .iter()
            .map(|l| l.sampling_weight(scene_radius))
            .collect();
        let total: f32 = powers.iter().sum();
        let weights: Vec<f32> = powers
            .iter()
            .map(|p| {
                if total > 0.0 {
                    p / total + 0.1 / lights.len() as f32
                } else {
                    1.0
                }
            })
            .collect();
        let escape_lights = lights
            .iter()
            .enumerate()
            .filter(|(_, l)| matches!(l.shape, LightShape::Dome { .. }))
            .map(|(i, _)| i as u32)
            .collect();

        let [w, h] = desc.film.resolution;
        if w == 0 || h == 0 {
            return Err(src.error(None, "film resolution must be at least 1x1"));
        }
        let default_camera = desc::CameraDesc::default();
        let (c, camera_span) = match &desc.camera {
            Some(c) => (c.get_ref(), Some(c.span())),
            None => (&default_camera, None),
        };
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
        let position = v3(c.position);
        let look_at = v3(c.look_at);
        let forward = look_at - position;
        if !forward.is_finite() || forward.length() < 1e-9 {
            return Err(src.error(
                camera_span.clone(),
                "[camera]: look_at must differ from position",
            ));
        }
        if v3(c.up).cross(forward).length() < 1e-9 * forward.length() {
            return Err(src.error(
                camera_span.clone(),
                "[camera]: up must not point along the view direction",
            ));
        }
        if !(c.fov > 0.0 && c.fov < 180.0) {
            return Err(src.error(
                camera_span.clone(),
                format!(
                    "[camera]: fov must be between 0 and 180 degrees, got {}",
                    c.fov
                ),
            ));
        }
        let camera = Camera::new(
            position,
            look_at,
            v3(c.up),
            c.fov,
            fov_axis,
            w,
            h,
            c.aperture_radius,
            c.focus_distance.unwrap_or((look_at - position).length()),
        );
        let filter = match desc.film.filter.as_ref().map(|s| s.get_ref().as_str()) {
            None | Some("box") => PixelFilter::Box,
            Some("gaussian") => PixelFilter::Gaussian {
                stddev: desc.film.filter_stddev,
            },
            Some(other) => {
                return Err(src.error(
                    desc.film.filter.as_ref().map(|s| s.span()),
                    format!("unknown filter '{other}': expected box or gaussian"),
                ))
            }
        };
        let r = &desc.render;
        let settings = RenderSettings {
            spp: r.spp.max(1),
            max_depth: r.max_depth,
            max_diffuse_depth: r.max_diffuse_depth.unwrap_or(u32::MAX),
            max_specular_depth: r.max_specular_depth.unwrap_or(u32::MAX),
            rr_depth: r.rr_depth,
            clamp_direct: r.clamp_direct,
            clamp_indirect: r.clamp_indirect,
            seed: r.seed,
        };
        let mut light_groups: Vec<String> = lights
            .iter()
            .flat_map(|l| l.groups.iter().cloned())
            .collect();
        light_groups.sort();
        light_groups.dedup();
        let default_part = light_groups.len() as u32;
        let light_parts = lights
            .iter()
            .map(|l| {
                l.groups
                    .first()
                    .and_then(|g| light_groups.iter().position(|x| x == g))
                    .map_or(default_part, |p| p as u32)
            })
            .collect();
        let mut out: Vec<Aov> = automaton
            .rules()
            .iter()
            .zip(aovs)
            .map(|(rule, spec)| Aov {
                name: spec.name.clone(),
                definition: spec.definition.clone(),
                expression: rule.expression.clone(),
                flags: rule.flags,
                split_base: None,
                part_of: None,
            })
            .collect();
        for (k, spec) in aovs.iter().enumerate() {
            if !spec.split_light_groups {
                continue;
            }
            out[k].split_base = Some(out.len() as u32);
            let parts: Vec<Option<&str>> = light_groups
                .iter()
                .map(|g| Some(g.as_str()))
                .chain([None])
                .collect();
            for g in parts {
                let base = &out[k];
                out.push(Aov {
                    name: crate::aov::naming::split_name(&spec.name, g),
                    definition: crate::aov::naming::split_definition(&spec.definition, g),
                    expression: base.expression.clone(),
                    flags: base.flags,
                    split_base: None,
                    part_of: Some(k as u32),
                });
            }
        }
        let data_classes: Vec<ClassId> = objects
            .iter()
            .flat_map(|o| o.data_lobes.iter().map(|d| d.1))
            .collect();
        let data_light = automaton.classify(&Event::bare(EventType::Light));
        let data_live = automaton
            .states()
            .map(|s| {
                data_light.is_some_and(|l| {
                    data_classes.iter().any(|c| {
                        !automaton
                            .accepting(automaton.step(automaton.step(s, *c), l))
                            .is_empty()
                    })
                })
            })
            .collect();
        let any_unoccluded = out.iter().any(|a| {
            a.flags.contains(lpe::Prefix::Unoccluded) || a.flags.contains(lpe::Prefix::Shadows)
        });
        let aovs = out;
        Ok(Scene {
            accel,
            objects,
            materials,
            light_classes,
            light_select: Distribution1D::new(&weights),
            lights,
            escape_lights,
            camera,
            filter,
            settings,
            camera_class: classify(&Event::camera()),
            data_light_class: classify(&Event::bare(EventType::Light)),
            automaton,
            aovs,
            scene_radius,
            epsilon,
            light_groups,
            light_parts,
            any_unoccluded,
            data_live,
        })
    }
}

/// Collects primitives of all objects, with their shading normals.
#[derive(Default)]
struct GeometryBuilder {
    prims: Vec<Prim>,
    objects: Vec<u32>,
    normals: Vec<[Vec3A; 3]>,
    visibility: Vec<u8>,
}

impl GeometryBuilder {
    fn add(&mut self, object: u32, mut shape: ShapePrims, visibility: u8) {
        for (i, n) in shape.normals.drain(..) {
            if let Prim::Triangle { normals, .. } = &mut shape.prims[i] {
                *normals = self.normals.len() as u32;
                self.normals.push(n);
            }
        }
        self.objects
            .extend(std::iter::repeat_n(object, shape.prims.len()));
        self.visibility
            .extend(std::iter::repeat_n(visibility, shape.prims.len()));
        self.prims.extend(shape.prims);
    }

    fn build(self) -> Accel {
        Accel::build(self.prims, self.objects, self.normals, self.visibility)
    }
}

/// The events an object emits: one per BSDF lobe, and its data lobes.
fn object_events(o: &Object, materials: &[Material]) -> (Vec<Event>, Vec<(DataLobe, Event)>) {
    let Some(m) = o.material.map(|m| &materials[m as usize]) else {
        return (Vec::new(), Vec::new());
    };
    let lobes = m
        .bsdf
        .lobes()
        .iter()
        .map(|t| {
            Event::new(
                if t.transmit {
                    EventType::Transmit
                } else {
                    EventType::Reflect
                },
                Some(t.scatter),
                o.groups.iter(),
            )
        })
        .collect();
    let mut kinds = vec![DataLobe::Albedo, DataLobe::Position, DataLobe::Normal];
    if m.user_color.is_some() {
        kinds.push(DataLobe::UserColor);
    }
    let data = kinds
        .into_iter()
        .map(|k| {
            (
                k,
                Event::new(EventType::Reflect, Some(k.scatter()), o.groups.iter()),
            )
        })
        .collect();
    (lobes, data)
}

/// Compiles the AOVs into one automaton whose alphabet is exactly the scene's events.
fn compile_aovs(
    src: &Source,
    desc: &SceneDesc,
    aovs: &[AovSpec],
    materials: &[Material],
    objects: &[Object],
    lights: &[Light],
) -> Result<Automaton, SceneError> {
    let mut compiler = lpe::Compiler::new().default_alphabet(false);
    for spec in aovs {
        compiler.add(&spec.definition).map_err(|e| {
            let span = desc.aovs.get(&spec.name).map(|s| s.span());
            src.error(
                span,
                format!(
                    "AOV '{}': {}",
                    spec.name,
                    e.render(&spec.definition).trim_end()
                ),
            )
        })?;
    }
    let mut vocabulary = vec![Event::camera(), Event::bare(EventType::Light)];
    for o in objects {
        let (lobes, data) = object_events(o, materials);
        vocabulary.extend(lobes);
        vocabulary.extend(data.into_iter().map(|(_, e)| e));
        if o.emission != Vec3A::ZERO {
            vocabulary.push(Event::new(EventType::Emission, None, o.groups.iter()));
        }
    }
    for l in lights {
        vocabulary.push(Event::new(EventType::Light, None, l.groups.iter()));
        vocabulary.push(Event::new(EventType::Emission, None, l.groups.iter()));
    }
    compiler.vocabulary(vocabulary);
    compiler.compile().map_err(|e| {
        src.error(
            None,
            format!(
                "the AOV expressions are too complex together: {}",
                e.message
            ),
        )
    })
}
