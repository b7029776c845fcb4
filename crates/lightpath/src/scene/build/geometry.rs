//! Geometry: object shapes become primitives, collected (with shading normals and trace
//! sets) into the acceleration structure.

use crate::geometry::shapes::{self, MeshAttrs, ShapePrims, VertexAttrs};
use crate::geometry::{Accel, Instance, Prim, SurfaceAttrs, Visibility, RAY_EPSILON};
use crate::scene::desc::{MeshData, ObjectDesc, Origin, ShapeDesc};
use crate::scene::SceneError;
use glam::{Affine3A, Vec2, Vec3, Vec3A, Vec4};
use rayon::prelude::*;
use std::collections::HashMap;
use std::ops::Range;
use std::sync::Arc;

/// The primitives of a shape placed by `xf`.
pub fn shape_prims(
    shape: &ShapeDesc,
    xf: &Affine3A,
    origin: &Origin,
) -> Result<ShapePrims, SceneError> {
    let v3 = Vec3A::from;
    check_transform(xf, origin)?;
    let prims = match shape {
        ShapeDesc::Rectangle => shapes::rectangle(xf),
        ShapeDesc::Cube => shapes::cube(xf),
        ShapeDesc::Disk { segments } => shapes::disk(xf, disk_segments(*segments, origin)?),
        ShapeDesc::Quad { corners } => shapes::quad(corners.map(v3)),
        ShapeDesc::Sphere { center, radius } => {
            let c = xf.transform_point3a(v3(*center));
            match *radius {
                r if r > 0.0 && r.is_finite() => shapes::sphere(c, r),
                r => return Err(origin.error(format!("sphere radius must be positive, got {r}"))),
            }
        }
        ShapeDesc::Mesh { parts } => mesh_parts(parts, xf, origin)?,
        ShapeDesc::SharedMesh { parts } => mesh_parts(parts, xf, origin)?,
    };
    check_finite(&prims, origin)?;
    Ok(prims)
}

/// A disk's triangle count, within `Limits::segments` (at least 3).
pub fn disk_segments(segments: u32, origin: &Origin) -> Result<usize, SceneError> {
    crate::limits::Limits::current()
        .check_segments(segments as u64, "this disk")
        .map_err(|e| origin.error(e))?;
    Ok(segments.max(3) as usize)
}

/// A placement whose numbers are not all finite (NaN, inf, or a value like `1e300` that
/// overflows an f32) is an error here, before it reaches the primitives.
pub fn check_transform(xf: &Affine3A, origin: &Origin) -> Result<(), SceneError> {
    if xf.is_finite() {
        Ok(())
    } else {
        Err(origin.error(
            "the placement (translate, rotate, scale or matrix) has a number that is NaN, \
             infinite or too large for 32-bit floats",
        ))
    }
}

/// Primitives with a coordinate that is NaN or infinite (also after the transform, or
/// through overflow of an edge) are an error naming the shape's origin: the BVH builder
/// and every ray test assume finite bounds.
pub fn check_finite(shape: &ShapePrims, origin: &Origin) -> Result<(), SceneError> {
    for (i, p) in shape.prims.iter().enumerate() {
        let finite = match *p {
            Prim::Triangle { p0, e1, e2, .. } => {
                let (lo, hi) = p.bounds();
                p0.is_finite()
                    && e1.is_finite()
                    && e2.is_finite()
                    && lo.is_finite()
                    && hi.is_finite()
            }
            Prim::Sphere { center, radius } => {
                let (lo, hi) = p.bounds();
                center.is_finite() && radius.is_finite() && lo.is_finite() && hi.is_finite()
            }
            Prim::Cylinder { .. } | Prim::Instance { .. } => {
                let (lo, hi) = p.bounds();
                lo.is_finite() && hi.is_finite()
            }
        };
        if !finite {
            return Err(origin.error(format!(
                "primitive {i} has a coordinate that is NaN, infinite or too large for \
                 32-bit floats once placed: expected finite positions"
            )));
        }
    }
    if let Some((i, _)) = shape
        .normals
        .iter()
        .find(|(_, n)| n.iter().any(|v| !v.is_finite()))
    {
        return Err(origin.error(format!(
            "triangle {i} has a shading normal that is NaN or infinite"
        )));
    }
    Ok(())
}

/// The triangles of mesh parts placed by `xf`.
fn mesh_parts(
    parts: &[MeshData],
    xf: &Affine3A,
    origin: &Origin,
) -> Result<ShapePrims, SceneError> {
    let parts = parts
        .iter()
        .map(|part| mesh(part, xf, origin))
        .collect::<Result<Vec<_>, _>>()?;
    // UVs and tangents stay one entry per normal across parts with and without.
    let any_attrs = parts.iter().any(|p| !p.attrs.is_empty());
    let mut out = ShapePrims::default();
    for part in parts {
        let base = out.prims.len();
        if any_attrs {
            if part.attrs.len() == part.normals.len() {
                out.attrs.extend(part.attrs);
            } else {
                out.attrs.extend(std::iter::repeat_n(
                    VertexAttrs::default(),
                    part.normals.len(),
                ));
            }
        }
        out.normals
            .extend(part.normals.into_iter().map(|(i, n)| (i + base, n)));
        out.prims.extend(part.prims);
    }
    Ok(out)
}

fn mesh(m: &MeshData, xf: &Affine3A, origin: &Origin) -> Result<ShapePrims, SceneError> {
    let pos: Vec<Vec3A> = m.positions.iter().map(|p| Vec3A::from(*p)).collect();
    if let Some(k) = pos.iter().position(|p| !p.is_finite()) {
        return Err(origin.error(format!(
            "mesh position {k} is {:?}: expected finite numbers",
            m.positions[k]
        )));
    }
    if let Some(bad) = m
        .indices
        .iter()
        .flatten()
        .find(|&&i| i as usize >= pos.len())
    {
        return Err(origin.error(format!(
            "mesh index {bad} is out of range: there are {} positions",
            pos.len()
        )));
    }
    let normals: Option<Vec<Vec3A>> = m
        .normals
        .as_ref()
        .map(|n| n.iter().map(|p| Vec3A::from(*p)).collect());
    if let Some(n) = &normals {
        if n.len() != pos.len() {
            return Err(origin.error(format!(
                "mesh has {} normals for {} positions",
                n.len(),
                pos.len()
            )));
        }
    }
    let uvs: Option<Vec<Vec2>> = m
        .uvs
        .as_ref()
        .map(|uv| uv.iter().map(|t| Vec2::from(*t)).collect());
    if let Some(uv) = &uvs {
        if uv.len() != pos.len() {
            return Err(origin.error(format!(
                "mesh has {} UVs for {} positions",
                uv.len(),
                pos.len()
            )));
        }
    }
    let tangents: Option<Vec<Vec4>> = m
        .tangents
        .as_ref()
        .map(|ts| ts.iter().map(|t| Vec4::from(*t)).collect());
    if let Some(ts) = &tangents {
        if ts.len() != pos.len() {
            return Err(origin.error(format!(
                "mesh has {} tangents for {} positions",
                ts.len(),
                pos.len()
            )));
        }
    }
    let colors: Option<Vec<Vec3>> = match &m.colors {
        Some(cs) if cs.len() != pos.len() => {
            return Err(origin.error(format!(
                "mesh has {} vertex colours for {} positions",
                cs.len(),
                pos.len()
            )))
        }
        Some(cs) => {
            if let Some(k) = cs
                .iter()
                .position(|c| !c.iter().all(|v| v.is_finite() && *v >= 0.0))
            {
                return Err(origin.error(format!(
                    "vertex colour {k} is {:?}: expected finite, non-negative numbers",
                    cs[k]
                )));
            }
            Some(cs.iter().map(|c| Vec3::from(*c)).collect())
        }
        None => None,
    };
    let attrs = MeshAttrs {
        normals: normals.as_deref(),
        uvs: uvs.as_deref(),
        tangents: tangents.as_deref(),
        colors: colors.as_deref(),
    };
    Ok(shapes::mesh(xf, &pos, &m.indices, attrs))
}

/// The key of shared mesh parts: their address.
pub fn mesh_key(parts: &Arc<Vec<MeshData>>) -> usize {
    Arc::as_ptr(parts) as usize
}

/// How many objects use each shared mesh (by `mesh_key`).
pub fn shared_mesh_users(objects: &[ObjectDesc]) -> HashMap<usize, usize> {
    let mut users = HashMap::new();
    for o in objects {
        if let ShapeDesc::SharedMesh { parts } = &o.shape {
            *users.entry(mesh_key(parts)).or_insert(0) += 1;
        }
    }
    users
}

/// Collects primitives of all objects, with their shading normals, UVs and tangents, and
/// the shared meshes with their placements.
#[derive(Default)]
pub struct GeometryBuilder {
    prims: Vec<Prim>,
    objects: Vec<u32>,
    normals: Vec<[Vec3A; 3]>,
    surface: SurfaceAttrs,
    visibility: Vec<u8>,
    /// Each shared mesh's primitives in its own space, with their bounds, by the address
    /// of the parts the objects share.
    meshes: Vec<(GeometryBuilder, (Vec3A, Vec3A))>,
    mesh_ids: HashMap<usize, u32>,
    instances: Vec<Instance>,
}

impl GeometryBuilder {
    /// Adds an object's primitives; returns their range in the scene's primitive list.
    pub fn add(&mut self, object: u32, mut shape: ShapePrims, visibility: u8) -> Range<u32> {
        for (k, (i, n)) in shape.normals.drain(..).enumerate() {
            if let Prim::Triangle { normals, .. } = &mut shape.prims[i] {
                *normals = self.normals.len() as u32;
                let attrs = shape.attrs.get(k).copied().unwrap_or_default();
                self.surface.push(self.normals.len(), attrs);
                self.normals.push(n);
            }
        }
        let start = self.prims.len() as u32;
        self.objects
            .extend(std::iter::repeat_n(object, shape.prims.len()));
        self.visibility
            .extend(std::iter::repeat_n(visibility, shape.prims.len()));
        self.prims.extend(shape.prims);
        start..self.prims.len() as u32
    }

    /// Places the shared `parts` by `xf` as one more instance of object `object` (the
    /// parts are stored the first time they are seen).
    pub fn add_instance(
        &mut self,
        object: u32,
        parts: &Arc<Vec<MeshData>>,
        xf: &Affine3A,
        visibility: u8,
        origin: &Origin,
    ) -> Result<(), SceneError> {
        check_transform(xf, origin)?;
        let key = mesh_key(parts);
        let mesh = match self.mesh_ids.get(&key) {
            Some(&id) => id,
            None => {
                let mut local = GeometryBuilder::default();
                let shape = mesh_parts(parts, &Affine3A::IDENTITY, origin)?;
                check_finite(&shape, origin)?;
                local.add(0, shape, Visibility::ALL);
                let bounds = local.prims.iter().fold(
                    (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY)),
                    |(lo, hi), p| {
                        let (a, b) = p.bounds();
                        (lo.min(a), hi.max(b))
                    },
                );
                let id = self.meshes.len() as u32;
                self.meshes.push((local, bounds));
                self.mesh_ids.insert(key, id);
                id
            }
        };
        let (_, (lo, hi)) = &self.meshes[mesh as usize];
        if lo.x > hi.x {
            // No triangles: nothing to place.
            return Ok(());
        }
        let instance = Instance::new(mesh, *xf).ok_or_else(|| {
            origin.error("the object's transform is not invertible (a zero scale?)")
        })?;
        let (lo, hi) = instance.world_bounds(*lo, *hi);
        if !(lo.is_finite() && hi.is_finite()) {
            return Err(origin.error(
                "the placed mesh has a coordinate too large for 32-bit floats: expected \
                 finite positions",
            ));
        }
        let index = self.instances.len() as u32;
        self.instances.push(instance);
        self.prims.push(Prim::Instance { lo, hi, index });
        self.objects.push(object);
        self.visibility.push(visibility);
        Ok(())
    }

    /// How many primitives the scene's own list holds so far.
    pub fn len(&self) -> u32 {
        self.prims.len() as u32
    }

    pub fn is_empty(&self) -> bool {
        self.prims.is_empty()
    }

    /// The acceleration structure, and the UVs and tangents textures read (the shared
    /// meshes' own in `SurfaceAttrs::meshes`, by mesh).
    pub fn build(self) -> (Accel, SurfaceAttrs) {
        // The shared meshes' trees on every core (each build also splits its work).
        let (meshes, mesh_surfaces): (Vec<Accel>, Vec<SurfaceAttrs>) = self
            .meshes
            .into_par_iter()
            .map(|(m, _)| {
                (
                    Accel::build(m.prims, m.objects, m.normals, m.visibility),
                    m.surface,
                )
            })
            .unzip();
        let accel = Accel::build(self.prims, self.objects, self.normals, self.visibility)
            .with_instances(meshes, self.instances);
        let mut surface = self.surface;
        surface.meshes = mesh_surfaces;
        (accel, surface)
    }
}

/// Half the diagonal of the scene's bounds (1 if it has none), and the ray offset against
/// self-intersection scaled to it.
pub fn scene_size(accel: &Accel) -> (Vec3A, f32, f32) {
    let (mut lo, mut hi) = (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY));
    for p in accel.prims() {
        let (a, b) = p.bounds();
        lo = lo.min(a);
        hi = hi.max(b);
    }
    let (center, scene_radius) = if lo.x.is_finite() {
        (0.5 * (lo + hi), 0.5 * (hi - lo).length())
    } else {
        (Vec3A::ZERO, 1.0)
    };
    (center, scene_radius, RAY_EPSILON * scene_radius.max(1.0))
}
