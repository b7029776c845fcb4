//! A spot light: a point light whose intensity falls off smoothly (smoothstep in the
//! cosine) from the inner to the outer cone around its axis. `cone_angle` is the full
//! angle of the outer cone, `cone_softness` the width of the soft edge, in degrees.
//!
//! ```toml
//! [[lights]]
//! type = "spot"
//! position = [0, 3, 0]
//! direction = [0, -1, 0]
//! cone_angle = 60
//! cone_softness = 10
//! intensity = [30, 30, 30]
//! ```

use super::select::{Cone, LightBounds, Reach};
use super::{LightModel, LightSample};
use crate::geometry::Prim;
use glam::{Vec2, Vec3A};
use std::f32::consts::PI;

#[derive(Clone, Debug)]
pub struct Spot {
    pub position: Vec3A,
    /// Unit direction the spot points in.
    pub axis: Vec3A,
    pub cos_inner: f32,
    pub cos_outer: f32,
}

impl LightModel for Spot {
    fn sample(&self, color: Vec3A, p: Vec3A, _: Vec3A, _: Vec2, _: &[Prim]) -> Option<LightSample> {
        let d = self.position - p;
        let dist2 = d.length_squared();
        let dist = dist2.sqrt();
        let wi = d / dist;
        let cos = (-wi).dot(self.axis);
        let falloff = smoothstep(self.cos_outer, self.cos_inner, cos);
        if falloff <= 0.0 {
            return None;
        }
        Some(LightSample {
            wi,
            dist,
            radiance: color * falloff / dist2,
            pdf: 1.0,
            delta: true,
        })
    }
    fn power(&self, c: f32, _: f32) -> f32 {
        c * 2.0 * PI * (1.0 - 0.5 * (self.cos_inner + self.cos_outer))
    }
    /// Normals within the inner cone, emission falling to nothing by the outer one.
    fn reach(&self, c: f32, _: &[Prim]) -> Reach {
        let theta_e = (self.cos_outer.clamp(-1.0, 1.0).acos()
            - self.cos_inner.clamp(-1.0, 1.0).acos())
        .max(0.0);
        Reach::Bounded(LightBounds {
            min: self.position,
            max: self.position,
            phi: c,
            normals: Cone {
                w: self.axis,
                cos_theta: self.cos_inner,
            },
            cos_e: theta_e.cos(),
            two_sided: false,
        })
    }
    fn is_delta(&self) -> bool {
        true
    }
}

fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    if e1 <= e0 {
        return if x >= e0 { 1.0 } else { 0.0 };
    }
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}
