//! Dielectric specular reflection over an opaque base (OpenPBR's specular layer on its
//! diffuse or subsurface base): GGX reflection, anisotropic, with exact unpolarised
//! Fresnel and Kulla–Conty multiple scattering (Kulla & Conty 2017, "Revisiting
//! Physically Based Shading at Imageworks"), the dielectric's mean Fresnel F_avg(η)
//! in their F_ms. Reflection only: what it does not reflect enters the base, which the
//! material attenuates with [`Specular::albedo`] and [`Specular::albedo_avg`] as
//! base × (1 − E(μo))(1 − E(μi)) / (1 − E_avg), reciprocal, and for a white base the
//! energy the layer leaves, up to the tables' accuracy (within 1 % in the furnace
//! tests; anisotropic lobes under total internal reflection, η < 1, overestimate E on
//! purpose and lose up to 45 % there).
//!
//! Its event is `RS2` (primary specular), or the lobe number it is given.

use super::albedo;
use super::fresnel::fresnel_dielectric;
use super::lobe::{LobeModel, LobeSample, LobeTag, SampleCtx};
use super::microfacet::{
    clamp_weight, is_smooth, reflection_eval, reflection_sample, reflection_tags, Ggx,
    MicrofacetReflection,
};
use crate::light::luminance;
use glam::{Vec2, Vec3A};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Specular {
    /// Relative index of refraction, below / above the surface (below 1: the denser
    /// medium is above, e.g. under a coat of higher index).
    pub eta: f32,
    /// Colour of the reflection (OpenPBR: specular colour); it does not change what
    /// the base receives.
    pub tint: Vec3A,
    /// Mixing weight in [0, 1].
    pub weight: f32,
    /// GGX (αx along the tangent, αy); both 0 is smooth, a delta lobe.
    pub alpha: Vec2,
    /// RenderMan lobe number: 2 primary specular, 4 coat, 5 iridescence.
    pub lobe: u8,
}

impl Specular {
    fn eta(&self) -> f32 {
        if self.eta > 0.0 {
            self.eta
        } else {
            1.0
        }
    }

    fn f_avg(&self) -> Vec3A {
        Vec3A::splat(albedo::dielectric_f_avg(self.eta()))
    }

    /// Directional albedo E(ωo) with a white tint: weight × (single scattering with the
    /// exact Fresnel + multiple scattering), towards `wo` in the local frame (`wo.z`
    /// taken as positive; the azimuth matters only when anisotropic). Below 1; what
    /// the base beneath receives is 1 − E.
    pub fn albedo(&self, wo: Vec3A) -> f32 {
        let wo = Vec3A::new(wo.x, wo.y, wo.z.abs());
        let w = clamp_weight(self.weight);
        if is_smooth(self.alpha) {
            return w * fresnel_dielectric(wo.z, self.eta());
        }
        let r = MicrofacetReflection::new(self.alpha, self.f_avg());
        let g = Ggx::new(self.alpha);
        let ss = albedo::dielectric_e(wo.z, self.table_alpha(&g, wo), self.eta());
        (w * (ss + r.ms_albedo(wo).x)).min(1.0)
    }

    /// The cosine-weighted average of [`Specular::albedo`], 2∫E(μ)μ dμ.
    pub fn albedo_avg(&self) -> f32 {
        let w = clamp_weight(self.weight);
        if is_smooth(self.alpha) {
            return w * albedo::dielectric_f_avg(self.eta());
        }
        let r = MicrofacetReflection::new(self.alpha, self.f_avg());
        let g = Ggx::new(self.alpha);
        let a = if self.eta() >= 1.0 {
            albedo::rms_alpha(&g)
        } else {
            albedo::min_alpha(&g)
        };
        let ss = albedo::dielectric_e_avg(a, self.eta());
        (w * (ss + r.ms_albedo_avg().x)).min(1.0)
    }

    /// The factor on a base lobe beneath, (1 − E(μo))(1 − E(μi)) / (1 − E_avg): what
    /// enters through the layer and leaves through it again.
    pub fn base_attenuation(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        let avg = 1.0 - self.albedo_avg();
        if avg <= 0.0 {
            return 0.0;
        }
        (1.0 - self.albedo(wo)) * (1.0 - self.albedo(wi)) / avg
    }

    /// The isotropic tables' alpha for anisotropic `g` towards `wo`: the roughness in
    /// `wo`'s plane of incidence; under total internal reflection (η < 1) the smaller
    /// alpha, which overestimates the albedo, so that the base beneath is dimmed a
    /// little too much rather than brightened.
    fn table_alpha(&self, g: &Ggx, wo: Vec3A) -> f32 {
        if self.eta() >= 1.0 {
            albedo::directional_alpha(g, wo)
        } else {
            albedo::min_alpha(g)
        }
    }

    fn fresnel(&self, cos: f32) -> Vec3A {
        self.tint * fresnel_dielectric(cos, self.eta())
    }
}

impl LobeModel for Specular {
    fn tags(&self) -> &'static [LobeTag] {
        reflection_tags(self.lobe, is_smooth(self.alpha))
    }
    fn eval(&self, _: usize, wo: Vec3A, wi: Vec3A, sel: f32) -> (Vec3A, f32) {
        // The multiple scattering takes the tint as the single scattering does.
        let f_avg = self.f_avg() * self.tint;
        reflection_eval(self.alpha, self.weight, f_avg, wo, wi, sel, |c| {
            self.fresnel(c)
        })
    }
    fn sample(&self, wo: Vec3A, ctx: SampleCtx, u: Vec2) -> Option<LobeSample> {
        let f_avg = self.f_avg() * self.tint;
        reflection_sample(self.alpha, self.weight, f_avg, wo, ctx, u, |c| {
            self.fresnel(c)
        })
    }
    fn selection_weight(&self, wo: Vec3A) -> f32 {
        clamp_weight(self.weight) * luminance(self.fresnel(wo.z.abs()))
    }
}
