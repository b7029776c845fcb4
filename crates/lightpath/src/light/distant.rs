//! A distant light: parallel light of irradiance `color` travelling along `dir`, as
//! from the sun.
//!
//! ```toml
//! [[lights]]
//! type = "distant"
//! direction = [0.3, -1, 0.1]   # the direction the light travels
//! irradiance = [3, 3, 3]
//! ```

use super::select::Reach;
use super::{LightModel, LightSample};
use crate::geometry::Prim;
use glam::{Vec2, Vec3A};
use std::f32::consts::PI;

#[derive(Clone, Debug)]
pub struct Distant {
    /// Unit direction the light travels in (towards the scene).
    pub dir: Vec3A,
}

impl LightModel for Distant {
    fn sample(&self, color: Vec3A, _: Vec3A, _: Vec2, _: &[Prim]) -> Option<LightSample> {
        Some(LightSample {
            wi: -self.dir,
            dist: f32::INFINITY,
            radiance: color,
            pdf: 1.0,
            delta: true,
        })
    }
    fn power(&self, c: f32, scene_radius: f32) -> f32 {
        let r2 = scene_radius * scene_radius;
        c * PI * r2
    }
    /// Beside the tree: its irradiance, scaled by the receiver's cosine.
    fn reach(&self, c: f32, _: &[Prim]) -> Reach {
        if c > 0.0 {
            Reach::Infinite {
                irradiance: c,
                dir: self.dir,
            }
        } else {
            Reach::Nowhere
        }
    }
    fn is_delta(&self) -> bool {
        true
    }
}
