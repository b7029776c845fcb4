//! A point light: intensity `color` from one point, the same in every direction.
//!
//! ```toml
//! [[lights]]
//! type = "point"
//! position = [0, 2, 0]
//! intensity = [10, 10, 10]
//! ```

use super::select::{Cone, LightBounds, Reach};
use super::{LightModel, LightSample};
use crate::geometry::Prim;
use glam::{Vec2, Vec3A};
use std::f32::consts::PI;

#[derive(Clone, Debug)]
pub struct Point {
    pub position: Vec3A,
}

impl LightModel for Point {
    fn sample(&self, color: Vec3A, p: Vec3A, _: Vec3A, _: Vec2, _: &[Prim]) -> Option<LightSample> {
        let d = self.position - p;
        let dist2 = d.length_squared();
        let dist = dist2.sqrt();
        Some(LightSample {
            wi: d / dist,
            dist,
            radiance: color / dist2,
            pdf: 1.0,
            delta: true,
        })
    }
    fn power(&self, c: f32, _: f32) -> f32 {
        c * 4.0 * PI
    }
    fn reach(&self, c: f32, _: &[Prim]) -> Reach {
        Reach::Bounded(LightBounds {
            min: self.position,
            max: self.position,
            phi: c,
            normals: Cone::SPHERE,
            cos_e: 0.0,
            two_sided: false,
        })
    }
    fn is_delta(&self) -> bool {
        true
    }
}
