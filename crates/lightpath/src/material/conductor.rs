//! Metal (OpenPBR's "metal" lobe): GGX reflection, anisotropic, with the F82-tint
//! Fresnel ([`f82_tint`]) and Kulla–Conty multiple scattering
//! ([`MicrofacetReflection`]); a mirror (a delta lobe) when both alphas are 0. Its
//! event is `RS2` (primary specular) whether rough or smooth, or the lobe number it is
//! given (docs/lpe.md#paths-and-events).

use super::fresnel::{f82_tint, f82_tint_avg};
use super::lobe::{LobeModel, LobeSample, LobeTag, SampleCtx};
use super::microfacet::{
    clamp_weight, is_smooth, reflection_eval, reflection_sample, reflection_tags,
};
use crate::light::luminance;
use glam::{Vec2, Vec3A};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conductor {
    /// Reflectance at normal incidence (OpenPBR: base colour × base weight).
    pub f0: Vec3A,
    /// Reflectance near grazing (about 82°) relative to Schlick's (OpenPBR: specular
    /// colour); 1 is plain Schlick.
    pub f82_tint: Vec3A,
    /// Mixing weight of the whole lobe in [0, 1] (OpenPBR: specular weight).
    pub weight: f32,
    /// GGX (αx along the tangent, αy); both 0 is a perfect mirror.
    pub alpha: Vec2,
    /// RenderMan lobe number of its event: 2 primary specular, 4 coat, 5 iridescence.
    pub lobe: u8,
}

impl Conductor {
    /// An isotropic metal with Schlick Fresnel (F82 tint 1), weight 1, event `RS2`.
    pub fn schlick(f0: Vec3A, alpha: f32) -> Conductor {
        Conductor {
            f0,
            f82_tint: Vec3A::ONE,
            weight: 1.0,
            alpha: Vec2::splat(alpha),
            lobe: 2,
        }
    }

    fn fresnel(&self, cos: f32) -> Vec3A {
        f82_tint(self.f0, self.f82_tint, cos)
    }
}

impl LobeModel for Conductor {
    fn tags(&self) -> &'static [LobeTag] {
        reflection_tags(self.lobe, is_smooth(self.alpha))
    }
    fn eval(&self, _: usize, wo: Vec3A, wi: Vec3A, sel: f32) -> (Vec3A, f32) {
        let f_avg = f82_tint_avg(self.f0, self.f82_tint);
        reflection_eval(self.alpha, self.weight, f_avg, wo, wi, sel, |c| {
            self.fresnel(c)
        })
    }
    fn sample(&self, wo: Vec3A, ctx: SampleCtx, u: Vec2) -> Option<LobeSample> {
        let f_avg = f82_tint_avg(self.f0, self.f82_tint);
        reflection_sample(self.alpha, self.weight, f_avg, wo, ctx, u, |c| {
            self.fresnel(c)
        })
    }
    /// Its Fresnel reflectance towards `wo`: beside a diffuse lobe, a dielectric's
    /// specular (f0 ≈ 0.04) gets few samples, a metal's most. (Alone, a lobe's weight
    /// is never read.)
    fn selection_weight(&self, wo: Vec3A) -> f32 {
        clamp_weight(self.weight) * luminance(self.fresnel(wo.z.abs()))
    }
}
