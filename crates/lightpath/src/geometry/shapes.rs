//! Shapes as primitives: rectangles, boxes and disks become triangles (in their local
//! space, as Mitsuba defines them), spheres stay analytic, meshes come inline or from OBJ.

use super::Prim;
use glam::{Affine3A, Vec3A};
use std::f32::consts::PI;

/// Primitives of one shape, plus per-vertex normals for smooth meshes.
#[derive(Default)]
pub struct ShapePrims {
    pub prims: Vec<Prim>,
    /// For each triangle with shading normals: its index in `prims` and the normals.
    pub normals: Vec<(usize, [Vec3A; 3])>,
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
        normals: vec![],
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
        normals: vec![],
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
        normals: vec![],
    }
}

/// A triangle mesh; `normals` (one per vertex), if given, are interpolated for shading.
pub fn mesh(
    xf: &Affine3A,
    positions: &[Vec3A],
    indices: &[[u32; 3]],
    normals: Option<&[Vec3A]>,
) -> ShapePrims {
    let mut out = ShapePrims::default();
    let normal_xf = xf.matrix3.inverse().transpose();
    for idx in indices {
        let [a, b, c] = idx.map(|i| positions[i as usize]);
        let t = tri(xf, a, b, c);
        if let Some(ns) = normals {
            let n = idx.map(|i| (normal_xf * ns[i as usize]).normalize_or(Vec3A::Z));
            out.normals.push((out.prims.len(), n));
        }
        out.prims.push(t);
    }
    out
}
