//! A dielectric clear coat (RS4) over base lobes: its specular reflection, and the
//! Fresnel transmittance that attenuates what lies beneath. A `weight` below one is a
//! partial coat (glTF's `clearcoatFactor`): reflection × w, the base × (1 − w·F).

use super::fresnel::{fresnel_dielectric, reflect};
use super::lobe::{tag, LobeModel, LobeSample, LobeTag, SampleCtx};
use super::microfacet::Ggx;
use glam::{Vec2, Vec3A};
use lpe::Scatter;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coat {
    pub eta: f32,
    /// GGX alphas along the shading frame's tangent and bitangent (OpenPBR's
    /// `coat_roughness_anisotropy` stretches them as the specular's); zero is a smooth coat.
    pub alpha: Vec2,
    /// How much of the surface the coat covers, in [0, 1].
    pub weight: f32,
}

impl Coat {
    /// The factor on a base lobe's `f`: light crosses the coat going in and coming out.
    pub fn transmittance(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        (1.0 - self.weight * fresnel_dielectric(wo.z, self.eta))
            * (1.0 - self.weight * fresnel_dielectric(wi.z, self.eta))
    }
}

impl LobeModel for Coat {
    fn tags(&self) -> &'static [LobeTag] {
        const SMOOTH: [LobeTag; 1] = [tag(false, Scatter::specular(4), true)];
        const ROUGH: [LobeTag; 1] = [tag(false, Scatter::specular(4), false)];
        if self.alpha == Vec2::ZERO {
            &SMOOTH
        } else {
            &ROUGH
        }
    }
    fn eval(&self, _: usize, wo: Vec3A, wi: Vec3A, sel: f32) -> (Vec3A, f32) {
        if self.alpha == Vec2::ZERO || wo.z <= 0.0 || wi.z <= 0.0 {
            return (Vec3A::ZERO, 0.0);
        }
        let g = Ggx::new(self.alpha);
        let m = (wo + wi).normalize();
        let f = self.weight * fresnel_dielectric(wi.dot(m), self.eta) * g.d(m) * g.g(wo, wi)
            / (4.0 * wo.z);
        (
            Vec3A::splat(f),
            sel * g.pdf_visible(wo, m) / (4.0 * wo.dot(m)),
        )
    }
    fn sample(&self, wo: Vec3A, ctx: SampleCtx, u: Vec2) -> Option<LobeSample> {
        if wo.z <= 0.0 {
            return None;
        }
        if self.alpha == Vec2::ZERO {
            let f = self.weight * fresnel_dielectric(wo.z, self.eta);
            return Some(LobeSample {
                sub: 0,
                wi: Vec3A::new(-wo.x, -wo.y, wo.z),
                eta: 1.0,
                value: Some((Vec3A::splat(f / ctx.sel), ctx.sel, true)),
            });
        }
        let m = Ggx::new(self.alpha).sample_visible(wo, u);
        let wi = reflect(wo, m);
        if wi.z <= 0.0 {
            return None;
        }
        LobeSample::direction(0, wi)
    }
    /// What it reflects towards `wo`.
    fn selection_weight(&self, wo: Vec3A) -> f32 {
        self.weight * fresnel_dielectric(wo.z.abs(), self.eta)
    }
}
