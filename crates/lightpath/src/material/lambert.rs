//! Lambertian reflection (RD2).

use super::lobe::{tag, LobeModel, LobeSample, LobeTag, SampleCtx};
use crate::light::luminance;
use crate::sampling::{cosine_hemisphere, cosine_hemisphere_pdf};
use glam::{Vec2, Vec3A};
use lpe::Scatter;
use std::f32::consts::FRAC_1_PI;

pub const RD2: LobeTag = tag(false, Scatter::diffuse(2), false);

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lambert {
    pub albedo: Vec3A,
}

impl LobeModel for Lambert {
    fn tags(&self) -> &'static [LobeTag] {
        &[RD2]
    }
    fn eval(&self, _: usize, wo: Vec3A, wi: Vec3A, sel: f32) -> (Vec3A, f32) {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return (Vec3A::ZERO, 0.0);
        }
        (
            self.albedo * FRAC_1_PI * wi.z,
            sel * cosine_hemisphere_pdf(wi.z),
        )
    }
    fn sample(&self, wo: Vec3A, ctx: SampleCtx, u: Vec2) -> Option<LobeSample> {
        let wi = cosine_hemisphere(u);
        if !ctx.alone {
            return LobeSample::direction(0, wi);
        }
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return None;
        }
        // Cosine sampling: f·cos/pdf is the albedo itself.
        Some(LobeSample {
            sub: 0,
            wi,
            eta: 1.0,
            value: Some((self.albedo, cosine_hemisphere_pdf(wi.z), false)),
        })
    }
    fn selection_weight(&self, _: Vec3A) -> f32 {
        luminance(self.albedo)
    }
}
