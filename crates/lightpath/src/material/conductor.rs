//! Metal: a mirror (RS2) when smooth, GGX (RS3) when rough; Schlick Fresnel from `f0`.

use super::fresnel::{reflect, schlick};
use super::lobe::{tag, LobeModel, LobeSample, LobeTag, SampleCtx};
use super::microfacet::Ggx;
use glam::{Vec2, Vec3A};
use lpe::Scatter;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conductor {
    pub f0: Vec3A,
    /// GGX alpha; 0 is a perfect mirror.
    pub alpha: f32,
}

impl LobeModel for Conductor {
    fn tags(&self) -> &'static [LobeTag] {
        const MIRROR: [LobeTag; 1] = [tag(false, Scatter::specular(2), true)];
        const METAL: [LobeTag; 1] = [tag(false, Scatter::specular(3), false)];
        if self.alpha == 0.0 {
            &MIRROR
        } else {
            &METAL
        }
    }
    fn eval(&self, _: usize, wo: Vec3A, wi: Vec3A, sel: f32) -> (Vec3A, f32) {
        if self.alpha == 0.0 || wo.z <= 0.0 || wi.z <= 0.0 {
            return (Vec3A::ZERO, 0.0);
        }
        let g = Ggx { alpha: self.alpha };
        let m = (wo + wi).normalize();
        let f = schlick(self.f0, wi.dot(m)) * (g.d(m) * g.g(wo, wi) / (4.0 * wo.z));
        (f, sel * g.pdf_visible(wo, m) / (4.0 * wo.dot(m)))
    }
    fn sample(&self, wo: Vec3A, ctx: SampleCtx, u: Vec2) -> Option<LobeSample> {
        if wo.z <= 0.0 {
            return None;
        }
        if self.alpha == 0.0 {
            return Some(LobeSample {
                sub: 0,
                wi: Vec3A::new(-wo.x, -wo.y, wo.z),
                eta: 1.0,
                value: Some((schlick(self.f0, wo.z) / ctx.sel, ctx.sel, true)),
            });
        }
        let m = Ggx { alpha: self.alpha }.sample_visible(wo, u);
        let wi = reflect(wo, m);
        if wi.z <= 0.0 {
            return None;
        }
        LobeSample::direction(0, wi)
    }
    /// Its Fresnel reflectance towards `wo`: beside a diffuse lobe, a dielectric's
    /// specular (f0 ≈ 0.04) gets few samples, a metal's most. (Alone, a lobe's weight
    /// is never read.)
    fn selection_weight(&self, wo: Vec3A) -> f32 {
        crate::light::luminance(schlick(self.f0, wo.z.abs()))
    }
}
