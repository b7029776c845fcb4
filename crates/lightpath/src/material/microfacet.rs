//! The GGX (Trowbridge–Reitz) microfacet distribution with Smith shadowing.

use glam::{Vec2, Vec3A};
use std::f32::consts::PI;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ggx {
    pub alpha: f32,
}

impl Ggx {
    pub fn d(&self, m: Vec3A) -> f32 {
        let a2 = self.alpha * self.alpha;
        let c2 = m.z * m.z;
        let t = c2 * (a2 - 1.0) + 1.0;
        a2 / (PI * t * t)
    }
    fn lambda(&self, w: Vec3A) -> f32 {
        let c2 = w.z * w.z;
        if c2 == 0.0 {
            return f32::INFINITY;
        }
        let tan2 = (1.0 - c2).max(0.0) / c2;
        ((1.0 + self.alpha * self.alpha * tan2).sqrt() - 1.0) / 2.0
    }
    fn g1(&self, w: Vec3A) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }
    pub fn g(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }
    /// Density of visible normals from `wo` (Heitz 2018), per solid angle of `m`.
    pub fn pdf_visible(&self, wo: Vec3A, m: Vec3A) -> f32 {
        if wo.z == 0.0 {
            return 0.0;
        }
        self.g1(wo) * wo.dot(m).abs() * self.d(m) / wo.z.abs()
    }
    /// Samples a visible normal (Heitz 2018, "Sampling the GGX Distribution of Visible
    /// Normals"), for `wo` in the upper hemisphere.
    pub fn sample_visible(&self, wo: Vec3A, u: Vec2) -> Vec3A {
        let wo = if wo.z < 0.0 { -wo } else { wo };
        let vh = Vec3A::new(self.alpha * wo.x, self.alpha * wo.y, wo.z).normalize();
        let len2 = vh.x * vh.x + vh.y * vh.y;
        let t1 = if len2 > 0.0 {
            Vec3A::new(-vh.y, vh.x, 0.0) / len2.sqrt()
        } else {
            Vec3A::X
        };
        let t2 = vh.cross(t1);
        let r = u.x.sqrt();
        let (sin_phi, cos_phi) = crate::sampling::sin_cos_turns(u.y);
        let p1 = r * cos_phi;
        let s = 0.5 * (1.0 + vh.z);
        let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * sin_phi;
        let nh = t1 * p1 + t2 * p2 + vh * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
        Vec3A::new(self.alpha * nh.x, self.alpha * nh.y, nh.z.max(1e-6)).normalize()
    }
}
