//! Shapes as primitives: rectangles, boxes and disks become triangles (in their local
//! space, as Mitsuba defines them), spheres stay analytic, meshes come inline or from OBJ.

use super::Prim;
use glam::{Affine3A, Vec2, Vec3, Vec3A, Vec4};
use std::f32::consts::PI;

/// Primitives of one shape, plus per-vertex normals for smooth meshes.
#[derive(Default)]
pub struct ShapePrims {
    pub prims: Vec<Prim>,
    /// For each triangle with shading normals: its index in `prims` and the normals.
    pub normals: Vec<(usize, [Vec3A; 3])>,
    /// UVs, world tangents and colours of the triangles in `normals`: empty, or one
    /// entry each.
    pub attrs: Vec<VertexAttrs>,
}

/// A triangle's per-vertex UVs, world-space tangents (w: bitangent sign) and linear RGB
/// colours, if given.
#[derive(Clone, Copy, Debug, Default)]
pub struct VertexAttrs {
    pub uvs: Option<[Vec2; 3]>,
    pub tangents: Option<[Vec4; 3]>,
    pub colors: Option<[Vec3; 3]>,
}

/// Per-vertex attributes of a mesh beyond positions, one entry per position each.
#[derive(Clone, Copy, Default)]
pub struct MeshAttrs<'a> {
    pub normals: Option<&'a [Vec3A]>,
    pub uvs: Option<&'a [Vec2]>,
    pub tangents: Option<&'a [Vec4]>,
    pub colors: Option<&'a [Vec3]>,
}

fn tri(xf: &Affine3A, a: Vec3A, b: Vec3A, c: Vec3A) -> Prim {
    let (a, b, c) = (
        xf.transform_point3a(a),
        xf.transform_point3a(b),
        xf.transform_point3a(c),
    );
    Prim::Triangle {
        p0: a,
        e1: b - a,
        e2: c - a,
        normals: u32::MAX,
    }
}

/// The square [-1, 1]² in the z = 0 plane, facing +z.
pub fn rectangle(xf: &Affine3A) -> ShapePrims {
    let c = [
        Vec3A::new(-1.0, -1.0, 0.0),
        Vec3A::new(1.0, -1.0, 0.0),
        Vec3A::new(1.0, 1.0, 0.0),
        Vec3A::new(-1.0, 1.0, 0.0),
    ];
    ShapePrims {
        prims: vec![tri(xf, c[0], c[1], c[2]), tri(xf, c[0], c[2], c[3])],
        ..ShapePrims::default()
    }
}

/// A quad from four world-space corners, counter-clockwise seen from its front.
pub fn quad(corners: [Vec3A; 4]) -> ShapePrims {
    let id = Affine3A::IDENTITY;
    ShapePrims {
        prims: vec![
            tri(&id, corners[0], corners[1], corners[2]),
            tri(&id, corners[0], corners[2], corners[3]),
        ],
        ..ShapePrims::default()
    }
}

/// The cube [-1, 1]³ with outward faces.
pub fn cube(xf: &Affine3A) -> ShapePrims {
    let mut out = ShapePrims::default();
    // Each face: outward normal axis and sign; corners counter-clockwise seen from outside.
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let n = Vec3A::from(match axis {
                0 => [sign, 0.0, 0.0],
                1 => [0.0, sign, 0.0],
                _ => [0.0, 0.0, sign],
            });
            let u = Vec3A::from(match axis {
                0 => [0.0, 1.0, 0.0],
                1 => [0.0, 0.0, 1.0],
                _ => [1.0, 0.0, 0.0],
            });
            let v = n.cross(u);
            let corner = |a: f32, b: f32| n + u * a + v * b;
            let (c0, c1, c2, c3) = (
                corner(-1.0, -1.0),
                corner(1.0, -1.0),
                corner(1.0, 1.0),
                corner(-1.0, 1.0),
            );
            out.prims.push(tri(xf, c0, c1, c2));
            out.prims.push(tri(xf, c0, c2, c3));
        }
    }
    out
}

/// The unit disk in the z = 0 plane, facing +z, as a fan of `segments` triangles.
pub fn disk(xf: &Affine3A, segments: usize) -> ShapePrims {
    let mut out = ShapePrims::default();
    for i in 0..segments {
        let a0 = 2.0 * PI * i as f32 / segments as f32;
        let a1 = 2.0 * PI * (i + 1) as f32 / segments as f32;
        out.prims.push(tri(
            xf,
            Vec3A::ZERO,
            Vec3A::new(a0.cos(), a0.sin(), 0.0),
            Vec3A::new(a1.cos(), a1.sin(), 0.0),
        ));
    }
    out
}

pub fn sphere(center: Vec3A, radius: f32) -> ShapePrims {
    ShapePrims {
        prims: vec![Prim::Sphere { center, radius }],
        ..ShapePrims::default()
    }
}

/// A triangle mesh; normals (one per vertex), if given, are interpolated for shading,
/// and UVs, tangents and colours are kept for textured shading (a mesh with those but no
/// normals gets its face normals, so every such triangle has an attribute entry).
pub fn mesh(
    xf: &Affine3A,
    positions: &[Vec3A],
    indices: &[[u32; 3]],
    attrs: MeshAttrs,
) -> ShapePrims {
    let mut out = ShapePrims::default();
    let normal_xf = xf.matrix3.inverse().transpose();
    let extra = attrs.uvs.is_some() || attrs.tangents.is_some() || attrs.colors.is_some();
    // A mirroring placement flips the bitangent with the winding.
    let handedness = xf.matrix3.determinant().signum();
    for idx in indices {
        let [a, b, c] = idx.map(|i| positions[i as usize]);
        let t = tri(xf, a, b, c);
        let n = match attrs.normals {
            Some(ns) => Some(idx.map(|i| (normal_xf * ns[i as usize]).normalize_or(Vec3A::Z))),
            None if extra => Some([t.face_normal(); 3]),
            None => None,
        };
        if let Some(n) = n {
            out.normals.push((out.prims.len(), n));
            if extra {
                let uvs = attrs.uvs.map(|uv| idx.map(|i| uv[i as usize]));
                let tangents = attrs.tangents.map(|ts| {
                    idx.map(|i| {
                        let t = ts[i as usize];
                        let w = xf.transform_vector3a(Vec3A::from(t.truncate()));
                        w.normalize_or(Vec3A::X).extend(t.w * handedness)
                    })
                });
                let colors = attrs.colors.map(|cs| idx.map(|i| cs[i as usize]));
                out.attrs.push(VertexAttrs {
                    uvs,
                    tangents,
                    colors,
                });
            }
        }
        out.prims.push(t);
    }
    out
}
