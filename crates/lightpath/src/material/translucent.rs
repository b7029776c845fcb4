//! Diffuse transmission (TD2): the far side of a thin translucent sheet. RenderMan
//! numbers translucency `D2` like diffuse reflection; `D3` is subsurface
//! (material/subsurface.rs).

use super::lobe::{tag, LobeModel, LobeSample, LobeTag, SampleCtx};
use crate::light::luminance;
use crate::sampling::{cosine_hemisphere, cosine_hemisphere_pdf};
use glam::{Vec2, Vec3A};
use lpe::Scatter;
use std::f32::consts::FRAC_1_PI;

pub const TD2: LobeTag = tag(true, Scatter::diffuse(2), false);

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiffuseTransmission {
    pub transmit: Vec3A,
}

impl LobeModel for DiffuseTransmission {
    fn tags(&self) -> &'static [LobeTag] {
        &[TD2]
    }
    fn eval(&self, _: usize, wo: Vec3A, wi: Vec3A, sel: f32) -> (Vec3A, f32) {
        if wo.z <= 0.0 || wi.z >= 0.0 {
            return (Vec3A::ZERO, 0.0);
        }
        (
            self.transmit * FRAC_1_PI * wi.z.abs(),
            sel * cosine_hemisphere_pdf(wi.z.abs()),
        )
    }
    fn sample(&self, _: Vec3A, _: SampleCtx, u: Vec2) -> Option<LobeSample> {
        let mut wi = cosine_hemisphere(u);
        wi.z = -wi.z;
        LobeSample::direction(0, wi)
    }
    fn selection_weight(&self, _: Vec3A) -> f32 {
        luminance(self.transmit)
    }
}
