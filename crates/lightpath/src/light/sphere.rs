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
use crate::geometry::{Prim, Ray};
use crate::sampling::{uniform_cone, uniform_cone_pdf, Frame};
use glam::{Vec2, Vec3A};
use std::f32::consts::PI;

#[derive(Clone, Debug)]
pub struct Sphere {
    pub center: Vec3A,
    pub radius: f32,
}

impl Sphere {
    fn prim(&self) -> Prim {
        Prim::Sphere {
            center: self.center,
            radius: self.radius,
        }
    }
}

impl LightModel for Sphere {
    /// A direction in the cone the sphere subtends from `p`, uniformly.
    fn sample(&self, color: Vec3A, p: Vec3A, u: Vec2, _: &[Prim]) -> Option<LightSample> {
        let (center, radius) = (self.center, self.radius);
        let to_c = center - p;
        let d2 = to_c.length_squared();
        if d2 <= radius * radius {
            return None;
        }
        let cos_max = (1.0 - radius * radius / d2).max(0.0).sqrt();
        let frame = Frame::new(to_c / d2.sqrt());
        let wi = frame.to_world(uniform_cone(u, cos_max));
        let dist = self
            .prim()
            .intersect(p, wi, 0.0, f32::INFINITY)
            // A grazing direction may miss in floating point: use its closest approach.
            .min(to_c.dot(wi));
        Some(LightSample {
            wi,
            dist,
            radiance: color,
            pdf: uniform_cone_pdf(cos_max),
            delta: false,
        })
    }
    fn pdf(&self, p: Vec3A, _: Vec3A, _: f32, _: Vec3A) -> f32 {
        let radius = self.radius;
        let d2 = (self.center - p).length_squared();
        if d2 <= radius * radius {
            return 0.0;
        }
        uniform_cone_pdf((1.0 - radius * radius / d2).max(0.0).sqrt())
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
        let t = self.prim().intersect(ray.origin, ray.dir, 0.0, tmax);
        t.is_finite()
            .then(|| (t, (ray.origin + ray.dir * t - self.center) / self.radius))
    }
}
