//! Primitives (triangles and spheres) and the acceleration structure behind a small
//! `intersect` / `occluded` seam; `obvhs` builds the BVH, `bvh` lays it out 4 or 8 wide
//! (`lanes`: SSE2 or, where the CPU has AVX2, AVX).

pub mod attrs;
mod bvh;
#[cfg(feature = "embree")]
mod embree;
mod instance;
mod lanes;
mod sah;
pub mod shapes;

pub use attrs::{SurfaceAttrs, SurfaceUv};
pub use bvh::{Accel, Visibility};
pub use instance::Instance;

use glam::Vec3A;

/// Which code traces rays (`render --accel`): Lightpath's own BVH, or Intel Embree 3 in a
/// build with the `embree` feature. Both find the same hits up to float rounding.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Backend {
    #[default]
    Bvh,
    Embree,
}

impl Backend {
    /// Whether this build can trace with Embree (cargo feature `embree`).
    pub const EMBREE_AVAILABLE: bool = cfg!(feature = "embree");

    /// The error of `--accel embree` in a build without the feature.
    pub const EMBREE_UNAVAILABLE: &'static str =
        "--accel embree: this lightpath was built without Embree (cargo feature `embree`). \
         To get it: `apt-get install libembree-dev` (Embree 3.13), then `cargo install --path \
         crates/lightpath --features embree` (or `cargo run --release --features embree -- \
         render --accel embree ...`)";

    pub fn parse(s: &str) -> Result<Backend, String> {
        match s {
            "bvh" => Ok(Backend::Bvh),
            "embree" => Ok(Backend::Embree),
            other => Err(format!(
                "unknown accelerator '{other}': expected bvh or embree"
            )),
        }
    }

    pub fn as_str(self) -> &'static str {
        match self {
            Backend::Bvh => "bvh",
            Backend::Embree => "embree",
        }
    }
}

/// A ray with its valid interval.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    pub origin: Vec3A,
    pub dir: Vec3A,
    pub tmax: f32,
}

/// One primitive of the scene, tagged with the object it belongs to.
#[derive(Clone, Copy, Debug)]
pub enum Prim {
    /// Vertex `p0` and edges; `normals` indexes per-vertex shading normals, or `u32::MAX`.
    Triangle {
        p0: Vec3A,
        e1: Vec3A,
        e2: Vec3A,
        normals: u32,
    },
    Sphere {
        center: Vec3A,
        radius: f32,
    },
    /// A placement of a shared mesh (`Accel::instance`), with its world bounds; the
    /// accelerator traces it in the mesh's own space.
    Instance {
        lo: Vec3A,
        hi: Vec3A,
        index: u32,
    },
}

/// A surface hit: where, which object, and the two normals.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    pub t: f32,
    pub p: Vec3A,
    /// Geometric normal, unit length, as the primitive defines it (not flipped).
    pub ng: Vec3A,
    /// Shading normal, on the same side as `ng`.
    pub ns: Vec3A,
    pub prim: u32,
    /// On an instance (`prim` is a `Prim::Instance`): the shared mesh's primitive hit;
    /// otherwise `u32::MAX`.
    pub inner: u32,
    pub object: u32,
}

/// Self-intersection offset, relative to the scene's size (set at build).
pub const RAY_EPSILON: f32 = 1e-4;

impl Prim {
    pub fn bounds(&self) -> (Vec3A, Vec3A) {
        match *self {
            Prim::Triangle { p0, e1, e2, .. } => {
                let (p1, p2) = (p0 + e1, p0 + e2);
                (p0.min(p1).min(p2), p0.max(p1).max(p2))
            }
            Prim::Sphere { center, radius } => {
                (center - Vec3A::splat(radius), center + Vec3A::splat(radius))
            }
            Prim::Instance { lo, hi, .. } => (lo, hi),
        }
    }

    /// Distance along the ray to the nearest hit in (tmin, tmax), or infinity (always for
    /// an instance, which only the accelerator holding its mesh can trace).
    #[inline]
    pub fn intersect(&self, origin: Vec3A, dir: Vec3A, tmin: f32, tmax: f32) -> f32 {
        match *self {
            // Möller–Trumbore.
            Prim::Triangle { p0, e1, e2, .. } => {
                let pv = dir.cross(e2);
                let det = e1.dot(pv);
                if det.abs() < 1e-12 {
                    return f32::INFINITY;
                }
                let inv = 1.0 / det;
                let tv = origin - p0;
                let u = tv.dot(pv) * inv;
                if !(0.0..=1.0).contains(&u) {
                    return f32::INFINITY;
                }
                let qv = tv.cross(e1);
                let v = dir.dot(qv) * inv;
                if v < 0.0 || u + v > 1.0 {
                    return f32::INFINITY;
                }
                let t = e2.dot(qv) * inv;
                if t > tmin && t < tmax {
                    t
                } else {
                    f32::INFINITY
                }
            }
            Prim::Sphere { center, radius } => {
                let oc = origin - center;
                let a = dir.length_squared();
                let half_b = oc.dot(dir);
                let c = oc.length_squared() - radius * radius;
                let disc = half_b * half_b - a * c;
                if disc < 0.0 {
                    return f32::INFINITY;
                }
                let sq = disc.sqrt();
                // The numerically stable pair of roots.
                let q = -(half_b + sq.copysign(half_b));
                let (mut t0, mut t1) = (q / a, c / q);
                if t0 > t1 {
                    std::mem::swap(&mut t0, &mut t1);
                }
                if t0 > tmin && t0 < tmax {
                    t0
                } else if t1 > tmin && t1 < tmax {
                    t1
                } else {
                    f32::INFINITY
                }
            }
            Prim::Instance { .. } => f32::INFINITY,
        }
    }

    /// The unit geometric normal of a triangle (its winding's side); `+Z` for a sphere,
    /// whose normal depends on the point.
    pub fn face_normal(&self) -> Vec3A {
        match *self {
            Prim::Triangle { e1, e2, .. } => e1.cross(e2).normalize_or(Vec3A::Z),
            Prim::Sphere { .. } | Prim::Instance { .. } => Vec3A::Z,
        }
    }

    pub fn area(&self) -> f32 {
        match *self {
            Prim::Triangle { e1, e2, .. } => 0.5 * e1.cross(e2).length(),
            Prim::Sphere { radius, .. } => 4.0 * std::f32::consts::PI * radius * radius,
            // Lights are never instances; the area of a placement is not needed.
            Prim::Instance { .. } => 0.0,
        }
    }
}
