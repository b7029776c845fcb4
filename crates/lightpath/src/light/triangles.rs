//! Area lights made of triangles: a rectangle, a quad or a disk (`type = "rect"`,
//! `"quad"`, `"disk"`), sampled uniformly by area (directly on the parallelogram when the
//! triangles form one). They emit on the side of their normal unless `two_sided`. A
//! [`Shaping`] (UsdLux's ShapingAPI on rect and disk lights) narrows their emission about
//! the normal.
//!
//! ```toml
//! [[lights]]
//! type = "rect"            # the unit square in z = 0, facing +z, placed by its transform
//! radiance = [17, 12, 4]
//! translate = [0, 0.99, 0]
//! rotate = [90, 0, 0]
//! scale = [0.25, 0.25, 1]
//! ```

use super::select::{Cone, LightBounds, Reach};
use super::{LightModel, LightSample};
use crate::geometry::{Prim, Ray};
use crate::sampling::{uniform_triangle, Distribution1D};
use glam::{Vec2, Vec3A};
use std::f32::consts::PI;

#[derive(Clone, Debug)]
pub struct Triangles {
    /// The triangles, as indices into the scene's primitive list (`Accel::prims`).
    pub prims: Vec<u32>,
    /// Unit normal of each triangle, precomputed for sampling.
    pub normals: Vec<Vec3A>,
    /// Corner and edges when the triangles form one parallelogram (rectangle and most
    /// quad lights): sampled directly, uniformly in area.
    pub parallelogram: Option<[Vec3A; 3]>,
    pub by_area: Distribution1D,
    pub area: f32,
    pub two_sided: bool,
    pub shaping: Option<Shaping>,
}

/// UsdLux ShapingAPI's emission profile about the normal (the schema's `shaping:focus`
/// and `shaping:cone:*` formulas, focusTint black): at θ off the normal, emission times
/// |cos θ|^focus · (1 − smoothstep(θ; start, cutoff)), zero beyond `cutoff`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shaping {
    /// Cutoff angle in radians.
    pub cutoff: f32,
    /// Where the fade to the cutoff starts, in radians (at most `cutoff`).
    pub start: f32,
    pub focus: f32,
}

impl Shaping {
    /// The factor at cosine `cos` off the normal.
    pub fn factor(&self, cos: f32) -> f32 {
        let c = cos.abs().min(1.0);
        let theta = c.acos();
        if theta > self.cutoff {
            return 0.0;
        }
        let cone = if self.start < self.cutoff && theta > self.start {
            let t = (theta - self.start) / (self.cutoff - self.start);
            1.0 - t * t * (3.0 - 2.0 * t)
        } else {
            1.0
        };
        let focus = if self.focus > 0.0 {
            c.powf(self.focus)
        } else {
            1.0
        };
        cone * focus
    }
}

impl LightModel for Triangles {
    /// A point on the triangles (directly on the parallelogram when they are one), in
    /// solid angle.
    #[inline(always)]
    fn sample(&self, color: Vec3A, p: Vec3A, u: Vec2, prims: &[Prim]) -> Option<LightSample> {
        let (q, n) = match self.parallelogram {
            Some([p0, e1, e2]) => (p0 + e1 * u.x + e2 * u.y, self.normals[0]),
            None => {
                let (i, _, ux) = self.by_area.sample(u.x);
                let Prim::Triangle { p0, e1, e2, .. } = prims[self.prims[i] as usize] else {
                    return None;
                };
                let (b1, b2) = uniform_triangle(Vec2::new(ux, u.y));
                (p0 + e1 * b1 + e2 * b2, self.normals[i])
            }
        };
        let d = q - p;
        let dist2 = d.length_squared();
        let dist = dist2.sqrt();
        let wi = d / dist;
        let cos_l = -wi.dot(n);
        if cos_l <= 0.0 && !self.two_sided || cos_l == 0.0 {
            return None;
        }
        let shaped = match &self.shaping {
            Some(s) => s.factor(cos_l),
            None => 1.0,
        };
        if shaped <= 0.0 {
            return None;
        }
        Some(LightSample {
            wi,
            dist,
            radiance: color * shaped,
            pdf: dist2 / (cos_l.abs() * self.area),
            delta: false,
        })
    }
    fn pdf(&self, _: Vec3A, dir: Vec3A, t: f32, ng: Vec3A) -> f32 {
        let cos_l = ng.dot(dir).abs();
        if cos_l == 0.0 {
            0.0
        } else {
            t * t / (cos_l * self.area)
        }
    }
    fn emitted(&self, color: Vec3A, ng: Vec3A, dir: Vec3A) -> Vec3A {
        if self.two_sided || ng.dot(dir) < 0.0 {
            match &self.shaping {
                Some(s) => color * s.factor(ng.dot(dir)),
                None => color,
            }
        } else {
            Vec3A::ZERO
        }
    }
    fn power(&self, c: f32, _: f32) -> f32 {
        c * self.area * PI * if self.two_sided { 2.0 } else { 1.0 }
    }
    fn reach(&self, c: f32, prims: &[Prim]) -> Reach {
        let mut min = Vec3A::splat(f32::INFINITY);
        let mut max = Vec3A::splat(f32::NEG_INFINITY);
        for &i in &self.prims {
            if let Prim::Triangle { p0, e1, e2, .. } = prims[i as usize] {
                for q in [p0, p0 + e1, p0 + e2] {
                    min = min.min(q);
                    max = max.max(q);
                }
            }
        }
        let mut cone: Option<Cone> = None;
        for n in &self.normals {
            let one = Cone {
                w: *n,
                cos_theta: 1.0,
            };
            cone = Some(cone.map_or(one, |c| Cone::union(c, one)));
        }
        if min.x > max.x {
            return Reach::Nowhere;
        }
        Reach::Bounded(LightBounds {
            min,
            max,
            phi: c * self.area,
            normals: cone.unwrap_or(Cone::SPHERE),
            cos_e: 0.0,
            two_sided: self.two_sided,
        })
    }
    /// The nearest of its triangles, one by one (an area light has few).
    fn intersect(&self, ray: &Ray, tmax: f32, prims: &[Prim]) -> Option<(f32, Vec3A)> {
        let mut nearest = None;
        let mut tmax = tmax;
        for (&i, n) in self.prims.iter().zip(&self.normals) {
            let t = prims[i as usize].intersect(ray.origin, ray.dir, 0.0, tmax);
            if t < tmax {
                tmax = t;
                nearest = Some((t, *n));
            }
        }
        nearest
    }
}
