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

/// UsdLux ShapingAPI's emission profile about the normal (the schema's `shaping:focus`,
/// `shaping:focusTint` and `shaping:cone:*` formulas): at θ off the normal, with
/// focusFactor = |cos θ|^focus, emission times
/// lerp(focusFactor, focusTint, white) · (1 − smoothstep(θ; start, cutoff)), zero beyond
/// `cutoff`. A black tint (the schema's default) makes the focus a plain cosine power; a
/// white one disables it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shaping {
    /// Cutoff angle in radians.
    pub cutoff: f32,
    /// Where the fade to the cutoff starts, in radians (at most `cutoff`).
    pub start: f32,
    pub focus: f32,
    /// The colour emission fades to off the axis, per channel.
    pub tint: Vec3A,
}

impl Shaping {
    /// The factor, per channel, at cosine `cos` off the normal.
    pub fn factor(&self, cos: f32) -> Vec3A {
        let c = cos.abs().min(1.0);
        let theta = c.acos();
        if theta > self.cutoff {
            return Vec3A::ZERO;
        }
        let cone = if self.start < self.cutoff && theta > self.start {
            let t = (theta - self.start) / (self.cutoff - self.start);
            1.0 - t * t * (3.0 - 2.0 * t)
        } else {
            1.0
        };
        // The schema ignores a focus below zero; at zero the factor is 1 (no tint).
        if self.focus > 0.0 {
            let f = c.powf(self.focus);
            (self.tint + (Vec3A::ONE - self.tint) * f) * cone
        } else {
            Vec3A::splat(cone)
        }
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
            None => Vec3A::ONE,
        };
        if shaped.max_element() <= 0.0 {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The UsdLux schema's ShapingAPI formulas, written out separately in f64:
    /// focusFactor = |cos θ|^focus, focusColor = lerp(focusFactor, focusTint, white),
    /// times 1 − smoothstep(θ; lerp(softness, cutoff, 0), cutoff), zero past the cutoff.
    fn schema(theta: f64, focus: f64, tint: [f64; 3], cone: f64, softness: f64) -> [f64; 3] {
        let cutoff = cone.to_radians();
        let smooth_start = cutoff + softness * (0.0 - cutoff);
        let scalar = if theta > cutoff {
            0.0
        } else if theta <= smooth_start {
            1.0
        } else {
            let t = (theta - smooth_start) / (cutoff - smooth_start);
            1.0 - t * t * (3.0 - 2.0 * t)
        };
        let ff = if focus > 0.0 {
            theta.cos().abs().powf(focus)
        } else {
            1.0
        };
        tint.map(|t| (t + ff * (1.0 - t)) * scalar)
    }

    /// A one-sided unit square facing +z with the given shaping.
    fn panel(shaping: Shaping) -> Triangles {
        Triangles {
            prims: Vec::new(),
            normals: vec![Vec3A::Z],
            parallelogram: Some([Vec3A::new(-0.5, -0.5, 0.0), Vec3A::X, Vec3A::Y]),
            by_area: Distribution1D::new(&[1.0]),
            area: 1.0,
            two_sided: false,
            shaping: Some(shaping),
        }
    }

    #[test]
    fn emitted_radiance_against_angle_is_the_schemas_focus_tint_and_cone() {
        let color = Vec3A::new(2.0, 3.0, 5.0);
        let cases: [(f32, [f32; 3], f32, f32); 5] = [
            (3.0, [0.0; 3], 90.0, 0.0),
            (3.0, [0.9, 0.2, 0.0], 90.0, 0.0),
            (8.0, [0.1, 0.5, 1.0], 60.0, 0.4),
            (1.5, [1.0; 3], 45.0, 1.0),
            (0.0, [0.3, 0.6, 0.9], 70.0, 0.25),
        ];
        for (focus, tint, cone, softness) in cases {
            let cutoff = cone.to_radians();
            let light = panel(Shaping {
                cutoff,
                start: cutoff * (1.0 - softness),
                focus,
                tint: Vec3A::from(tint),
            });
            for deg in (0..90).step_by(3) {
                let theta = (deg as f32).to_radians();
                // A ray arriving at the light from θ off its normal.
                let dir = -Vec3A::new(theta.sin(), 0.0, theta.cos());
                let got = light.emitted(color, Vec3A::Z, dir);
                let want = schema(
                    theta as f64,
                    focus as f64,
                    tint.map(f64::from),
                    cone as f64,
                    softness as f64,
                );
                for k in 0..3 {
                    let w = want[k] * color[k] as f64;
                    assert!(
                        (got[k] as f64 - w).abs() <= 1e-5 * (1.0 + w),
                        "focus {focus} tint {tint:?} cone {cone}/{softness} at {deg}°: \
                         {got} against {want:?}"
                    );
                }
                // Sampled from a point along that direction: the same radiance.
                let p = -dir * 10.0;
                if let Some(s) = light.sample(color, p, Vec2::splat(0.5), &[]) {
                    let cos = (-s.wi).dot(Vec3A::Z);
                    let again = schema(
                        cos.acos() as f64,
                        focus as f64,
                        tint.map(f64::from),
                        cone as f64,
                        softness as f64,
                    );
                    for k in 0..3 {
                        let w = again[k] * color[k] as f64;
                        assert!((s.radiance[k] as f64 - w).abs() <= 1e-5 * (1.0 + w));
                    }
                } else {
                    assert!(want.iter().all(|&w| w == 0.0), "{deg}°: {want:?}");
                }
            }
        }
    }

    #[test]
    fn a_white_tint_disables_the_focus_and_a_negative_focus_is_none() {
        let s = |focus: f32, tint: f32| Shaping {
            cutoff: PI / 2.0,
            start: PI / 2.0,
            focus,
            tint: Vec3A::splat(tint),
        };
        for cos in [1.0, 0.7, 0.2, 0.01] {
            assert_eq!(s(20.0, 1.0).factor(cos), Vec3A::ONE);
            assert_eq!(s(-2.0, 0.0).factor(cos), Vec3A::ONE);
        }
    }
}
