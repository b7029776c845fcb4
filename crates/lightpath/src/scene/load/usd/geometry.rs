//! Geometry: `Mesh` (polygons as fans of triangles, holes, GeomSubset material
//! bindings, `normals`/`primvars:normals`, `primvars:st`, `primvars:displayColor`, each
//! with its interpolation and indices), the `Sphere`/`Cube`/`Cylinder`/`Cone`/`Plane`
//! gprims, and `PointInstancer`s whose prototypes are read once and shared.
//!
//! A mesh keeps USD's shared points as its vertices; with a `uniform` or `faceVarying`
//! primvar, a point is split into one vertex per distinct set of corner values.
//! Subdivision surfaces are rendered as their control cage.

use super::{stage, Context, Loader};
use crate::scene::desc::{MeshData, NameRef, ObjectDesc, ShapeDesc};
use crate::scene::SceneError;
use glam::{Affine3A, Mat4, Quat, Vec3};
use openusd::sdf::Value;
use openusd::usd::{Prim, TimeCode};
use std::sync::Arc;

/// LPE tags of an object from the renderers' attributes, in this order: Karma, RenderMan,
/// Arnold (each may list several, separated by commas or spaces).
pub const OBJECT_TAGS: &[&str] = &[
    "primvars:karma:object:lpetag",
    "primvars:ri:attributes:identifier:lpegroup",
    "primvars:arnold:aov",
];

pub fn object_tags(prim: &Prim, time: TimeCode) -> Vec<String> {
    let mut out = Vec::new();
    for name in OBJECT_TAGS {
        if let Some(v) = stage::value(prim, name, time) {
            for s in stage::strings_of(&v) {
                out.extend(
                    s.split([',', ' '])
                        .filter(|t| !t.is_empty())
                        .map(str::to_string),
                );
            }
        }
    }
    out
}

/// A mesh's points, face vertex counts and face vertex indices.
type Topology = (Vec<[f32; 3]>, Vec<i64>, Vec<i64>);

/// A GeomSubset's material (its name in the scene) and faces.
type Subset = (Option<String>, Vec<usize>);

/// A primvar as read: values, optional indices, interpolation.
struct Primvar<T> {
    values: Vec<T>,
    indices: Option<Vec<i64>>,
    interpolation: String,
}

impl<T: Copy> Primvar<T> {
    /// The value at a corner: `face` its face, `corner` its face-vertex index, `point`
    /// its point index.
    fn at(&self, face: usize, corner: usize, point: usize) -> Option<T> {
        let k = match self.interpolation.as_str() {
            "constant" => 0,
            "uniform" => face,
            "faceVarying" => corner,
            _ => point,
        };
        let k = match &self.indices {
            Some(ix) => usize::try_from(*ix.get(k)?).ok()?,
            None => k,
        };
        self.values.get(k).copied()
    }

    fn per_corner(&self) -> bool {
        matches!(self.interpolation.as_str(), "uniform" | "faceVarying")
    }
}

impl Loader {
    fn primvar<T>(
        &self,
        prim: &Prim,
        name: &str,
        default_interp: &str,
        convert: fn(Value) -> Option<Vec<T>>,
    ) -> Option<Primvar<T>> {
        let values = convert(stage::value(prim, name, self.time)?)?;
        let indices =
            stage::value(prim, &format!("{name}:indices"), self.time).and_then(stage::int_array);
        Some(Primvar {
            values,
            indices,
            interpolation: stage::interpolation(prim, name, default_interp),
        })
    }

    /// A gprim and what it becomes: one object per material part.
    pub(super) fn gprim(
        &mut self,
        prim: &Prim,
        ty: &str,
        world: Affine3A,
        ctx: &Context,
        out: &mut Vec<ObjectDesc>,
    ) -> Result<(), SceneError> {
        let name = stage::name_of(prim.path());
        let mut groups: Vec<String> = ctx.tags.clone();
        groups.push(name.clone());
        groups.extend(ctx.ancestors.iter().rev().cloned());
        let mut seen = std::collections::HashSet::new();
        groups.retain(|g| seen.insert(g.clone()));
        let display = self.display_color(prim);
        let origin = self.origin(prim);
        let asset = ctx.ancestors.first().unwrap_or(&name).clone();
        let first = out.len();
        let object = |shape: ShapeDesc, transform: Affine3A, material: String| ObjectDesc {
            name: Some(name.clone()),
            emission: None,
            shape_name: ty.to_string(),
            shape,
            transform,
            material: Some(NameRef {
                name: material,
                origin: origin.clone(),
            }),
            lpegroups: Some(groups.clone()),
            asset: Some(asset.clone()),
            holdout: false,
            visible_camera: true,
            visible_indirect: true,
            casts_shadows: true,
            origin: origin.clone(),
        };
        let time = self.time;
        let f = |n: &str, default: f32| {
            stage::value(prim, n, time)
                .and_then(|v| stage::f32_of(&v))
                .filter(|x| x.is_finite())
                .unwrap_or(default)
        };
        let axis = stage::value(prim, "axis", self.time)
            .and_then(|v| stage::string_of(&v))
            .unwrap_or_else(|| "Z".into());
        // Gprims along Z are turned to their `axis`.
        let to_axis = match axis.as_str() {
            "X" => Affine3A::from_rotation_y(std::f32::consts::FRAC_PI_2),
            "Y" => Affine3A::from_rotation_x(-std::f32::consts::FRAC_PI_2),
            _ => Affine3A::IDENTITY,
        };
        let parts: Vec<(ShapeDesc, Affine3A, Option<String>)> = match ty {
            "Mesh" => {
                let flip = world.matrix3.determinant() < 0.0;
                self.mesh(prim, world, flip, display, out, &object)?;
                self.glow(first, out);
                if !ctx.prototype {
                    self.mesh_light(prim, first..out.len(), out)?;
                }
                return Ok(());
            }
            "Sphere" => vec![(
                ShapeDesc::Sphere {
                    center: [0.0; 3],
                    radius: f("radius", 1.0),
                },
                world,
                None,
            )],
            "Cube" => {
                let h = f("size", 2.0) * 0.5;
                vec![(
                    ShapeDesc::Cube,
                    world * Affine3A::from_scale(Vec3::splat(h)),
                    None,
                )]
            }
            "Cylinder" | "Cone" | "Capsule" => {
                if ty == "Capsule" {
                    self.warn_once("capsule", prim, "capsules are rendered as cylinders");
                }
                let r = f("radius", 1.0);
                let h = f("height", 2.0);
                let top = if ty == "Cone" { 0.0 } else { r };
                vec![(
                    ShapeDesc::Mesh {
                        parts: vec![lathe(r, top, h, 64)],
                    },
                    world * to_axis,
                    None,
                )]
            }
            "Plane" => {
                let w = f("width", 2.0) * 0.5;
                let l = f("length", 2.0) * 0.5;
                vec![(
                    ShapeDesc::Rectangle,
                    world * to_axis * Affine3A::from_scale(Vec3::new(w, l, 1.0)),
                    None,
                )]
            }
            _ => return Ok(()),
        };
        let material = self.surface_material(prim, display)?;
        for (shape, xf, _) in parts {
            out.push(object(shape, xf, material.clone()));
        }
        self.glow(first, out);
        Ok(())
    }

    /// Objects from `first` on glow with their material's emissiveColor.
    fn glow(&self, first: usize, out: &mut [ObjectDesc]) {
        for o in &mut out[first..] {
            if let Some(m) = &o.material {
                o.emission = self.emissive.get(&m.name).copied();
            }
        }
    }

    /// The constant displayColor (and displayOpacity is ignored), if authored.
    fn display_color(&self, prim: &Prim) -> Option<[f32; 3]> {
        let v = stage::value(prim, "primvars:displayColor", self.time)?;
        let colors = stage::vec3_array(v)?;
        (colors.len() == 1
            || stage::interpolation(prim, "primvars:displayColor", "constant") == "constant")
            .then(|| colors.first().copied())
            .flatten()
    }

    fn mesh(
        &mut self,
        prim: &Prim,
        world: Affine3A,
        flip: bool,
        display: Option<[f32; 3]>,
        out: &mut Vec<ObjectDesc>,
        object: &dyn Fn(ShapeDesc, Affine3A, String) -> ObjectDesc,
    ) -> Result<(), SceneError> {
        let t = self.time;
        let Some((points, counts, indices)) = self.topology(prim)? else {
            return Ok(());
        };
        let left = stage::value(prim, "orientation", t)
            .and_then(|v| stage::string_of(&v))
            .is_some_and(|o| o == "leftHanded");
        let flip = flip ^ left;
        let holes: std::collections::HashSet<i64> = stage::value(prim, "holeIndices", t)
            .and_then(stage::int_array)
            .unwrap_or_default()
            .into_iter()
            .collect();
        let normals = self
            .primvar(prim, "primvars:normals", "vertex", stage::vec3_array)
            .or_else(|| self.primvar(prim, "normals", "vertex", stage::vec3_array));
        let st = [
            "primvars:st",
            "primvars:st0",
            "primvars:UVMap",
            "primvars:uv",
        ]
        .iter()
        .find_map(|n| self.primvar(prim, n, "vertex", stage::vec2_array));
        let colors = self
            .primvar(prim, "primvars:displayColor", "constant", stage::vec3_array)
            .filter(|c| c.interpolation != "constant" && c.values.len() > 1);
        let per_corner = normals.as_ref().is_some_and(Primvar::per_corner)
            || st.as_ref().is_some_and(Primvar::per_corner)
            || colors.as_ref().is_some_and(Primvar::per_corner);
        // Face starts, and each face's part (a GeomSubset with a material, or the mesh's).
        let mut starts = Vec::with_capacity(counts.len());
        let mut at = 0usize;
        for &c in &counts {
            starts.push(at);
            at += c.max(0) as usize;
        }
        let subsets = self.subsets(prim, counts.len())?;
        let mut part_of = vec![0usize; counts.len()];
        for (k, (_, faces)) in subsets.iter().enumerate() {
            for &f in faces {
                part_of[f] = k + 1;
            }
        }
        let n_parts = subsets.len() + 1;
        let mut builders: Vec<PartBuilder> = (0..n_parts)
            .map(|_| PartBuilder::new(points.len(), per_corner))
            .collect();
        let mut poly: Vec<u32> = Vec::new();
        for (f, &count) in counts.iter().enumerate() {
            if count < 3 || holes.contains(&(f as i64)) {
                continue;
            }
            let b = &mut builders[part_of[f]];
            let s = starts[f];
            poly.clear();
            for (c, &p) in indices.iter().enumerate().skip(s).take(count as usize) {
                let p = p as usize;
                poly.push(b.vertex(p, || {
                    (
                        points[p],
                        normals.as_ref().and_then(|n| n.at(f, c, p)),
                        st.as_ref()
                            .and_then(|u| u.at(f, c, p))
                            .map(|[s, t]| [s, 1.0 - t]),
                        colors.as_ref().and_then(|k| k.at(f, c, p)),
                    )
                }));
            }
            for i in 2..poly.len() {
                let (v0, prev, next) = (poly[0], poly[i - 1], poly[i]);
                b.indices.push(if flip {
                    [v0, next, prev]
                } else {
                    [v0, prev, next]
                });
            }
        }
        let own = self.surface_material(prim, display)?;
        for (k, b) in builders.into_iter().enumerate() {
            if b.indices.is_empty() {
                continue;
            }
            let material = match k {
                0 => own.clone(),
                _ => match &subsets[k - 1].0 {
                    Some(m) => m.clone(),
                    None => own.clone(),
                },
            };
            let data = b.finish(normals.is_some(), st.is_some(), colors.is_some());
            let shape = ShapeDesc::SharedMesh {
                parts: Arc::new(vec![data]),
            };
            out.push(object(shape, world, material));
        }
        Ok(())
    }

    /// A mesh's points, face vertex counts and indices, checked (None: no points).
    fn topology(&self, prim: &Prim) -> Result<Option<Topology>, SceneError> {
        let t = self.time;
        let points = stage::value(prim, "points", t)
            .and_then(stage::vec3_array)
            .unwrap_or_default();
        if points.is_empty() {
            return Ok(None);
        }
        if let Some(i) = points.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
            return Err(self.error(prim, format!("points[{i}] is not finite: {:?}", points[i])));
        }
        let counts = stage::value(prim, "faceVertexCounts", t)
            .and_then(stage::int_array)
            .unwrap_or_default();
        let indices = stage::value(prim, "faceVertexIndices", t)
            .and_then(stage::int_array)
            .unwrap_or_default();
        let total: i64 = counts.iter().map(|&c| c.max(0)).sum();
        if total != indices.len() as i64 {
            return Err(self.error(
                prim,
                format!(
                    "faceVertexCounts add up to {total} but faceVertexIndices has {} entries",
                    indices.len()
                ),
            ));
        }
        if let Some(bad) = indices
            .iter()
            .find(|&&i| i < 0 || i as usize >= points.len())
        {
            return Err(self.error(
                prim,
                format!(
                    "faceVertexIndices holds {bad}, out of range: there are {} points",
                    points.len()
                ),
            ));
        }
        Ok(Some((points, counts, indices)))
    }

    /// The mesh's face subsets that bind a material: (material, faces).
    fn subsets(&mut self, prim: &Prim, faces: usize) -> Result<Vec<Subset>, SceneError> {
        let mut out = Vec::new();
        let children = prim
            .children()
            .map_err(|e| self.error(prim, format!("{e:#}")))?;
        for child in children {
            if stage::type_of(&child) != "GeomSubset" {
                continue;
            }
            let element = stage::value(&child, "elementType", self.time)
                .and_then(|v| stage::string_of(&v))
                .unwrap_or_else(|| "face".into());
            if element != "face" {
                continue;
            }
            let Some(material) = self.bound_material_path(&child) else {
                continue;
            };
            let name = self.material(&material, &child)?;
            let indices = stage::value(&child, "indices", self.time)
                .and_then(stage::int_array)
                .unwrap_or_default();
            let mut list = Vec::with_capacity(indices.len());
            for i in indices {
                match usize::try_from(i).ok().filter(|&i| i < faces) {
                    Some(i) => list.push(i),
                    None => {
                        return Err(self.error(
                            &child,
                            format!(
                                "indices holds face {i}, out of range: the mesh has {faces} faces"
                            ),
                        ))
                    }
                }
            }
            out.push((Some(name), list));
        }
        Ok(out)
    }

    /// A `PointInstancer`: each instance a copy of its prototype's objects, placed by
    /// position, orientation and scale.
    pub(super) fn point_instancer(
        &mut self,
        prim: &Prim,
        world: Affine3A,
        ctx: &Context,
        out: &mut Vec<ObjectDesc>,
    ) -> Result<(), SceneError> {
        let t = self.time;
        let protos = prim
            .relationship("prototypes")
            .targets()
            .map_err(|e| self.error(prim, format!("{e:#}")))?;
        let ids = stage::value(prim, "protoIndices", t)
            .and_then(stage::int_array)
            .unwrap_or_default();
        let positions = stage::value(prim, "positions", t)
            .and_then(stage::vec3_array)
            .unwrap_or_default();
        let orients = stage::value(prim, "orientations", t)
            .or_else(|| stage::value(prim, "orientationsf", t))
            .and_then(stage::vec4_array)
            .unwrap_or_default();
        let scales = stage::value(prim, "scales", t)
            .and_then(stage::vec3_array)
            .unwrap_or_default();
        let invisible: std::collections::HashSet<i64> = stage::value(prim, "invisibleIds", t)
            .and_then(stage::int_array)
            .unwrap_or_default()
            .into_iter()
            .collect();
        let inst_ids = stage::value(prim, "ids", t).and_then(stage::int_array);
        let mut templates = Vec::new();
        for p in &protos {
            let proto = self.stage.prim(p.clone());
            // The prototype root's own transform applies under the instance's.
            let (local, _) =
                stage::local_transform(&proto, t).map_err(|e| self.error(&proto, e))?;
            let mut objects = Vec::new();
            let mut inner = ctx.clone();
            inner.prototype = true;
            self.walk(&proto, local, &inner, &mut objects)?;
            templates.push(objects);
        }
        for (i, &k) in ids.iter().enumerate() {
            let id = inst_ids
                .as_ref()
                .and_then(|v| v.get(i).copied())
                .unwrap_or(i as i64);
            if invisible.contains(&id) {
                continue;
            }
            let Some(objects) = usize::try_from(k).ok().and_then(|k| templates.get(k)) else {
                return Err(self.error(
                    prim,
                    format!(
                        "protoIndices[{i}] is {k}; there are {} prototypes",
                        templates.len()
                    ),
                ));
            };
            let pos = positions.get(i).copied().unwrap_or([0.0; 3]);
            let q = orients
                .get(i)
                .map(|&[x, y, z, w]| Quat::from_xyzw(x, y, z, w).normalize())
                .filter(|q| q.is_finite())
                .unwrap_or(Quat::IDENTITY);
            let s = scales.get(i).copied().unwrap_or([1.0; 3]);
            let m = Mat4::from_scale_rotation_translation(s.into(), q, pos.into());
            if !m.is_finite() {
                return Err(self.error(prim, format!("instance {i}'s placement is not finite")));
            }
            let placed = world * Affine3A::from_mat4(m);
            for o in objects {
                let mut o = o.clone();
                o.transform = placed * o.transform;
                out.push(o);
            }
        }
        Ok(())
    }
}

/// Vertices of one material part: USD's points, split where a point's corners differ
/// (a UV seam, a hard edge): a point's vertices are chained and a corner reuses one whose
/// attributes are bit for bit its own.
struct PartBuilder {
    per_corner: bool,
    /// Point → its latest vertex (u32::MAX: none yet).
    head: Vec<u32>,
    /// Vertex → the point's previous vertex (u32::MAX: none).
    next: Vec<u32>,
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    uvs: Vec<[f32; 2]>,
    colors: Vec<[f32; 3]>,
    indices: Vec<[u32; 3]>,
}

type Corner = (
    [f32; 3],
    Option<[f32; 3]>,
    Option<[f32; 2]>,
    Option<[f32; 3]>,
);

impl PartBuilder {
    fn new(points: usize, per_corner: bool) -> PartBuilder {
        PartBuilder {
            per_corner,
            head: vec![u32::MAX; points],
            next: Vec::new(),
            positions: Vec::new(),
            normals: Vec::new(),
            uvs: Vec::new(),
            colors: Vec::new(),
            indices: Vec::new(),
        }
    }

    fn vertex(&mut self, point: usize, data: impl FnOnce() -> Corner) -> u32 {
        if !self.per_corner && self.head[point] != u32::MAX {
            return self.head[point];
        }
        let (p, n, uv, c) = data();
        let (n, uv, c) = (
            n.unwrap_or([0.0, 0.0, 1.0]),
            uv.unwrap_or([0.0; 2]),
            c.unwrap_or([1.0; 3]),
        );
        let bits3 = |v: [f32; 3]| v.map(f32::to_bits);
        let mut k = self.head[point];
        while k != u32::MAX {
            let i = k as usize;
            if bits3(self.normals[i]) == bits3(n)
                && self.uvs[i].map(f32::to_bits) == uv.map(f32::to_bits)
                && bits3(self.colors[i]) == bits3(c)
            {
                return k;
            }
            k = self.next[i];
        }
        let k = self.positions.len() as u32;
        self.positions.push(p);
        self.normals.push(n);
        self.uvs.push(uv);
        self.colors.push(c);
        self.next.push(self.head[point]);
        self.head[point] = k;
        k
    }

    fn finish(self, normals: bool, uvs: bool, colors: bool) -> MeshData {
        let normals = normals
            && self
                .normals
                .iter()
                .all(|n| n.iter().all(|c| c.is_finite()) && n != &[0.0; 3]);
        MeshData {
            positions: self.positions,
            indices: self.indices,
            normals: normals.then_some(self.normals),
            uvs: uvs.then_some(self.uvs),
            tangents: None,
            colors: colors.then(|| {
                self.colors
                    .into_iter()
                    .map(|c| c.map(|x| if x.is_finite() { x.max(0.0) } else { 0.0 }))
                    .collect()
            }),
        }
    }
}

/// A cylinder (or a cone, `top` 0) of radius `bottom` at z = −h/2 and `top` at +h/2,
/// with its caps, in `n` segments.
fn lathe(bottom: f32, top: f32, h: f32, n: u32) -> MeshData {
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    let z0 = -h * 0.5;
    let z1 = h * 0.5;
    let ring = |r: f32, z: f32, positions: &mut Vec<[f32; 3]>| {
        let first = positions.len() as u32;
        for i in 0..n {
            let a = i as f32 / n as f32 * std::f32::consts::TAU;
            positions.push([r * a.cos(), r * a.sin(), z]);
        }
        first
    };
    let b = ring(bottom, z0, &mut positions);
    let t = ring(top, z1, &mut positions);
    for i in 0..n {
        let j = (i + 1) % n;
        indices.push([b + i, b + j, t + j]);
        indices.push([b + i, t + j, t + i]);
    }
    let cb = positions.len() as u32;
    positions.push([0.0, 0.0, z0]);
    let ct = positions.len() as u32;
    positions.push([0.0, 0.0, z1]);
    for i in 0..n {
        let j = (i + 1) % n;
        indices.push([cb, b + j, b + i]);
        if top > 0.0 {
            indices.push([ct, t + i, t + j]);
        }
    }
    MeshData {
        positions,
        indices,
        ..MeshData::default()
    }
}
