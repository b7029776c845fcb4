//! Geometry: object shapes become primitives, collected (with shading normals and trace
//! sets) into the acceleration structure.

use crate::geometry::shapes::{self, MeshAttrs, ShapePrims};
use crate::geometry::{Accel, Prim, SurfaceAttrs, RAY_EPSILON};
use crate::scene::desc::{MeshData, Origin, ShapeDesc};
use crate::scene::SceneError;
use glam::{Affine3A, Vec2, Vec3A, Vec4};
use std::ops::Range;

/// The primitives of a shape placed by `xf`.
pub fn shape_prims(
    shape: &ShapeDesc,
    xf: &Affine3A,
    origin: &Origin,
) -> Result<ShapePrims, SceneError> {
    let v3 = Vec3A::from;
    Ok(match shape {
        ShapeDesc::Rectangle => shapes::rectangle(xf),
        ShapeDesc::Cube => shapes::cube(xf),
        ShapeDesc::Disk { segments } => shapes::disk(xf, (*segments).max(3) as usize),
        ShapeDesc::Quad { corners } => shapes::quad(corners.map(v3)),
        ShapeDesc::Sphere { center, radius } => {
            let c = xf.transform_point3a(v3(*center));
            match *radius {
                r if r > 0.0 && r.is_finite() => shapes::sphere(c, r),
                r => return Err(origin.error(format!("sphere radius must be positive, got {r}"))),
            }
        }
        ShapeDesc::Mesh { parts } => {
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
                        out.attrs
                            .extend(std::iter::repeat_n((None, None), part.normals.len()));
                    }
                }
                out.normals
                    .extend(part.normals.into_iter().map(|(i, n)| (i + base, n)));
                out.prims.extend(part.prims);
            }
            out
        }
    })
}

fn mesh(m: &MeshData, xf: &Affine3A, origin: &Origin) -> Result<ShapePrims, SceneError> {
    let pos: Vec<Vec3A> = m.positions.iter().map(|p| Vec3A::from(*p)).collect();
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
    let attrs = MeshAttrs {
        normals: normals.as_deref(),
        uvs: uvs.as_deref(),
        tangents: tangents.as_deref(),
    };
    Ok(shapes::mesh(xf, &pos, &m.indices, attrs))
}

/// Collects primitives of all objects, with their shading normals, UVs and tangents.
#[derive(Default)]
pub struct GeometryBuilder {
    prims: Vec<Prim>,
    objects: Vec<u32>,
    normals: Vec<[Vec3A; 3]>,
    surface: SurfaceAttrs,
    visibility: Vec<u8>,
}

impl GeometryBuilder {
    /// Adds an object's primitives; returns their range in the scene's primitive list.
    pub fn add(&mut self, object: u32, mut shape: ShapePrims, visibility: u8) -> Range<u32> {
        for (k, (i, n)) in shape.normals.drain(..).enumerate() {
            if let Prim::Triangle { normals, .. } = &mut shape.prims[i] {
                *normals = self.normals.len() as u32;
                let (uvs, tangents) = shape.attrs.get(k).copied().unwrap_or((None, None));
                self.surface.push(self.normals.len(), uvs, tangents);
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

    /// The acceleration structure, and the UVs and tangents textures read.
    pub fn build(self) -> (Accel, SurfaceAttrs) {
        let accel = Accel::build(self.prims, self.objects, self.normals, self.visibility);
        (accel, self.surface)
    }
}

/// Half the diagonal of the scene's bounds (1 if it has none), and the ray offset against
/// self-intersection scaled to it.
pub fn scene_size(accel: &Accel) -> (f32, f32) {
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
    (scene_radius, RAY_EPSILON * scene_radius.max(1.0))
}
