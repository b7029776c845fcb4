//! Primitives (triangles and spheres) and the acceleration structure behind a small
//! `intersect` / `occluded` seam; `obvhs` builds the BVH, `bvh` lays it out 4 or 8 wide
//! (`lanes`: SSE2 or, where the CPU has AVX2, AVX).

mod accel;
pub mod attrs;
mod bvh;
#[cfg(feature = "embree")]
mod embree;
mod instance;
mod lanes;
mod sah;
pub mod shapes;

pub use accel::{Accel, Visibility};
pub use attrs::{SurfaceAttrs, SurfaceUv};
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

    pub fn parse(s: &str) -> Result<Backend, crate::error::InvalidValue> {
        match s {
            "bvh" => Ok(Backend::Bvh),
            "embree" => Ok(Backend::Embree),
            other => Err(crate::error::InvalidValue(format!(
                "unknown accelerator '{other}': expected bvh or embree"
            ))),
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
    /// The side of a cylinder, open at both ends (a cylinder light's surface): points
    /// within `radius` of the segment `center ± axis · half_length`, `axis` unit length.
    Cylinder {
        center: Vec3A,
        axis: Vec3A,
        radius: f32,
        half_length: f32,
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

/// e1 × e2, unnormalised: the triangle tests' normal, computed one way everywhere.
#[inline(always)]
pub(crate) fn edge_normal(e1: Vec3A, e2: Vec3A) -> Vec3A {
    Vec3A::new(
        e1.y * e2.z - e1.z * e2.y,
        e1.z * e2.x - e1.x * e2.z,
        e1.x * e2.y - e1.y * e2.x,
    )
}

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
            Prim::Cylinder {
                center,
                axis,
                radius,
                half_length,
            } => {
                // Per world axis: the segment's half extent plus the rim circle's, whose
                // plane is tilted from that axis by the cylinder's axis.
                let rim = (Vec3A::ONE - axis * axis).max(Vec3A::ZERO);
                let half = axis.abs() * half_length
                    + Vec3A::new(rim.x.sqrt(), rim.y.sqrt(), rim.z.sqrt()) * radius;
                (center - half, center + half)
            }
            Prim::Instance { lo, hi, .. } => (lo, hi),
        }
    }

    /// Distance along the ray to the nearest hit in (tmin, tmax), or infinity (always for
    /// an instance, which only the accelerator holding its mesh can trace).
    #[inline]
    pub fn intersect(&self, origin: Vec3A, dir: Vec3A, tmin: f32, tmax: f32) -> f32 {
        match *self {
            // The normal precomputed (as the BVH's leaves store it) and the division
            // left to the end: Embree's and pbrt's layout. Written out component by
            // component, in the order the BVH's lanes compute, so both round alike.
            Prim::Triangle { p0, e1, e2, .. } => {
                let n = edge_normal(e1, e2);
                let (d, tv) = (dir, origin - p0);
                let r = Vec3A::new(
                    d.y * tv.z - d.z * tv.y,
                    d.z * tv.x - d.x * tv.z,
                    d.x * tv.y - d.y * tv.x,
                );
                let den = d.x * n.x + d.y * n.y + d.z * n.z;
                let absden = den.abs();
                let flip = |x: f32, of: f32| if of.is_sign_negative() { -x } else { x };
                let u = flip(e2.x * r.x + e2.y * r.y + e2.z * r.z, den);
                let v = flip(e1.x * r.x + e1.y * r.y + e1.z * r.z, -den);
                let tn = flip(tv.x * n.x + tv.y * n.y + tv.z * n.z, -den);
                if absden >= 1e-12
                    && u >= 0.0
                    && v >= 0.0
                    && u + v <= absden
                    && tn > tmin * absden
                    && tn < tmax * absden
                {
                    tn / absden
                } else {
                    f32::INFINITY
                }
            }
            Prim::Sphere { center, radius } => {
                sphere_intersect(center, radius, origin, dir, tmin, tmax)
            }
            Prim::Cylinder { .. } => self.cylinder_intersect(origin, dir, tmin, tmax),
            Prim::Instance { .. } => f32::INFINITY,
        }
    }

    /// The unit geometric normal at `p` on a sphere or cylinder: outwards.
    pub fn curved_normal(&self, p: Vec3A) -> Vec3A {
        match *self {
            Prim::Sphere { center, radius } => (p - center) / radius,
            Prim::Cylinder { center, axis, .. } => {
                let q = p - center;
                (q - axis * q.dot(axis)).normalize_or(Vec3A::Z)
            }
            Prim::Triangle { .. } | Prim::Instance { .. } => self.face_normal(),
        }
    }

    /// The unit geometric normal of a triangle (its winding's side); `+Z` for a sphere
    /// or cylinder, whose normal depends on the point (`curved_normal`).
    pub fn face_normal(&self) -> Vec3A {
        match *self {
            Prim::Triangle { e1, e2, .. } => e1.cross(e2).normalize_or(Vec3A::Z),
            Prim::Sphere { .. } | Prim::Cylinder { .. } | Prim::Instance { .. } => Vec3A::Z,
        }
    }

    pub fn area(&self) -> f32 {
        match *self {
            Prim::Triangle { e1, e2, .. } => 0.5 * e1.cross(e2).length(),
            Prim::Sphere { radius, .. } => 4.0 * std::f32::consts::PI * radius * radius,
            Prim::Cylinder {
                radius,
                half_length,
                ..
            } => 4.0 * std::f32::consts::PI * radius * half_length,
            // Lights are never instances; the area of a placement is not needed.
            Prim::Instance { .. } => 0.0,
        }
    }

    /// The nearest t in (tmin, tmax) where the ray meets the side of a cylinder, or infinity:
    /// the sphere's quadratic in the plane across the axis, each root kept if it lies within
    /// the cylinder's length.
    #[inline]
    fn cylinder_intersect(&self, origin: Vec3A, dir: Vec3A, tmin: f32, tmax: f32) -> f32 {
        let Prim::Cylinder {
            center,
            axis,
            radius,
            half_length,
        } = *self
        else {
            return f32::INFINITY;
        };
        let oc = origin - center;
        let (o_along, d_along) = (oc.dot(axis), dir.dot(axis));
        let (o_across, d_across) = (oc - axis * o_along, dir - axis * d_along);
        let a = d_across.length_squared();
        let half_b = o_across.dot(d_across);
        let c = o_across.length_squared() - radius * radius;
        let disc = half_b * half_b - a * c;
        if a == 0.0 || disc < 0.0 {
            return f32::INFINITY;
        }
        let sq = disc.sqrt();
        let q = -(half_b + sq.copysign(half_b));
        let (mut t0, mut t1) = (q / a, c / q);
        if t0 > t1 {
            std::mem::swap(&mut t0, &mut t1);
        }
        for t in [t0, t1] {
            if t > tmin && t < tmax && (o_along + t * d_along).abs() <= half_length {
                return t;
            }
        }
        f32::INFINITY
    }
}

/// Distance along the ray to the nearest hit in (tmin, tmax) on the sphere, or infinity.
/// On its own so that sphere lights, which know their shape, call it without going
/// through [`Prim::intersect`]'s match (which is too large to inline there).
#[inline]
pub fn sphere_intersect(
    center: Vec3A,
    radius: f32,
    origin: Vec3A,
    dir: Vec3A,
    tmin: f32,
    tmax: f32,
) -> f32 {
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
