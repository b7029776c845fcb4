//! A sphere light: emits outwards from its surface, sampled uniformly in the cone it
//! subtends from the shading point.
//!
//! ```toml
//! [[lights]]
//! type = "sphere"
//! center = [0, 1, 0]
//! radius = 0.1
//! radiance = [50, 50, 50]
//! ```

use super::select::{Cone, LightBounds, Reach};
use super::{LightModel, LightSample};
use crate::geometry::{sphere_intersect, Prim, Ray};
use crate::sampling::{uniform_cone, Frame};
use glam::{Vec2, Vec3A};
use std::f32::consts::PI;

/// 1 − cos θmax of the cone a sphere of `radius` subtends at squared distance `d2`
/// (outside it), from sin² θmax without the cancellation of 1 − √(1 − sin²): for a small
/// or distant sphere cos θmax rounds to within a few ulps of 1 in f32, and its solid
/// angle (the pdf's inverse) would be off by up to a few percent (radius 0.002 a unit
/// away: 1 − cos θmax = 2·10⁻⁶, an f32 ulp below 1 is 6·10⁻⁸). Directions are still drawn in the rounded cone; the estimate
/// only needs the true solid angle, the radiance being uniform over it.
#[inline]
fn cone_height(radius: f32, d2: f32) -> f32 {
    let s2 = (radius * radius / d2).min(1.0);
    s2 / (1.0 + (1.0 - s2).sqrt())
}

#[derive(Clone, Debug)]
pub struct Sphere {
    pub center: Vec3A,
    pub radius: f32,
}

impl LightModel for Sphere {
    /// A direction in the cone the sphere subtends from `p`, uniformly.
    fn sample(&self, color: Vec3A, p: Vec3A, _: Vec3A, u: Vec2, _: &[Prim]) -> Option<LightSample> {
        let (center, radius) = (self.center, self.radius);
        let to_c = center - p;
        let d2 = to_c.length_squared();
        if d2 <= radius * radius {
            return None;
        }
        let one_minus_cos = cone_height(radius, d2);
        let cos_max = 1.0 - one_minus_cos;
        let frame = Frame::new(to_c / d2.sqrt());
        let wi = frame.to_world(uniform_cone(u, cos_max));
        let dist = sphere_intersect(center, radius, p, wi, 0.0, f32::INFINITY)
            // A grazing direction may miss in floating point: use its closest approach.
            .min(to_c.dot(wi));
        Some(LightSample {
            wi,
            dist,
            radiance: color,
            pdf: 1.0 / (2.0 * PI * one_minus_cos),
            delta: false,
        })
    }
    fn pdf(&self, p: Vec3A, _: Vec3A, _: Vec3A, _: f32, _: Vec3A) -> f32 {
        let radius = self.radius;
        let d2 = (self.center - p).length_squared();
        if d2 <= radius * radius {
            return 0.0;
        }
        1.0 / (2.0 * PI * cone_height(radius, d2))
    }
    fn emitted(&self, color: Vec3A, ng: Vec3A, dir: Vec3A) -> Vec3A {
        if ng.dot(dir) < 0.0 {
            color
        } else {
            Vec3A::ZERO
        }
    }
    fn power(&self, c: f32, _: f32) -> f32 {
        let radius = self.radius;
        c * 4.0 * PI * radius * radius * PI
    }
    fn reach(&self, c: f32, _: &[Prim]) -> Reach {
        let (center, radius) = (self.center, self.radius);
        Reach::Bounded(LightBounds {
            min: center - Vec3A::splat(radius),
            max: center + Vec3A::splat(radius),
            phi: c * PI * radius * radius,
            normals: Cone::SPHERE,
            cos_e: 0.0,
            two_sided: false,
        })
    }
    fn intersect(&self, ray: &Ray, tmax: f32, _: &[Prim]) -> Option<(f32, Vec3A)> {
        let t = sphere_intersect(self.center, self.radius, ray.origin, ray.dir, 0.0, tmax);
        t.is_finite()
            .then(|| (t, (ray.origin + ray.dir * t - self.center) / self.radius))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pdf of a small, distant sphere is the inverse of its solid angle computed in
    /// f64, to f32 precision (it was off by percents from 1 − cos θmax's cancellation).
    #[test]
    fn a_small_spheres_pdf_is_its_solid_angle() {
        let sphere = Sphere {
            center: Vec3A::new(0.3, 0.9, -0.2),
            radius: 0.002,
        };
        for p in [
            Vec3A::ZERO,
            Vec3A::new(0.1, 0.2, 0.3),
            Vec3A::new(-2.0, 1.0, 0.5),
        ] {
            let d2 = f64::from((sphere.center - p).length_squared());
            let s2 = f64::from(sphere.radius).powi(2) / d2;
            let exact = 1.0 / (2.0 * std::f64::consts::PI * s2 / (1.0 + (1.0 - s2).sqrt()));
            let got = f64::from(sphere.pdf(p, Vec3A::ZERO, Vec3A::X, 1.0, Vec3A::Z));
            assert!((got / exact - 1.0).abs() < 1e-5, "{got} vs {exact}");
            let s = sphere
                .sample(Vec3A::ONE, p, Vec3A::ZERO, Vec2::new(0.3, 0.7), &[])
                .unwrap();
            assert!((f64::from(s.pdf) / exact - 1.0).abs() < 1e-5);
        }
    }
}
