//! Dielectric specular reflection over an opaque base (OpenPBR's specular layer on its
//! diffuse or subsurface base): GGX reflection, anisotropic, with exact unpolarised
//! Fresnel and Kulla–Conty multiple scattering (Kulla & Conty 2017, "Revisiting
//! Physically Based Shading at Imageworks"), the dielectric's mean Fresnel F_avg(η)
//! in their F_ms. Reflection only: what it does not reflect towards the viewer enters
//! the base, which the material attenuates by 1 − E(μo) with [`Specular::albedo`]
//! (albedo scaling at the outgoing direction, as OpenPBR's MaterialX reference and
//! Cycles' Principled BSDF layer it; for a white base the layer and the base then
//! reflect all the energy, up to the tables' accuracy: within 1 % in the furnace
//! tests; anisotropic lobes under total internal reflection, η < 1, overestimate E on
//! purpose and lose up to 45 % there). Kulla–Conty's reciprocal form
//! (1 − E(μo))(1 − E(μi)) / (1 − E_avg) was measured 3–5 % brighter than Cycles on
//! every layered object (benches/materials/RESULTS.md).
//!
//! The tint either scales the whole lobe (OpenPBR's `specular_color`) or only the
//! reflectance at normal incidence, F = mix(tint·F0, 1, s(μ)) with s the real Fresnel
//! remapped from [F0, 1] to [0, 1] (glTF's `KHR_materials_specular`, Blender's
//! Principled BSDF: [`Specular::tint_f0_only`]).
//!
//! Its event is `RS2` (primary specular), or the lobe number it is given.

use super::albedo;
use super::fresnel::fresnel_dielectric;
use super::lobe::{LobeModel, LobeSample, LobeTag, SampleCtx};
use super::microfacet::{
    clamp_weight, is_smooth, reflection_eval_with, reflection_sample_with, reflection_tags, Ggx,
    MicrofacetReflection,
};
use crate::light::luminance;
use glam::{Vec2, Vec3A};

/// The specular layer's parameters; [`Specular::new`] makes the lobe of them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpecularParams {
    /// Relative index of refraction, below / above the surface (below 1: the denser
    /// medium is above, e.g. under a coat of higher index).
    pub eta: f32,
    /// Colour of the reflection (OpenPBR: specular colour). Over the whole lobe it does
    /// not change what the base receives; on F0 only, the base receives 1 − the largest
    /// channel's albedo (as Cycles' `closure_layering_weight`).
    pub tint: Vec3A,
    /// The tint applies to F0 only, fading to white at grazing (glTF, Blender).
    pub tint_f0_only: bool,
    /// Mixing weight in [0, 1].
    pub weight: f32,
    /// GGX (αx along the tangent, αy); both 0 is smooth, a delta lobe.
    pub alpha: Vec2,
    /// RenderMan lobe number: 2 primary specular, 4 coat, 5 iridescence.
    pub lobe: u8,
}

/// The lobe: its parameters and what it looks up in the tables once, when it is made
/// (the mean Fresnel and E_avg were looked up again at every evaluation, ~3 % of a glTF
/// shot's instructions: docs/performance.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Specular {
    p: SpecularParams,
    /// The dielectric's cosine-weighted mean Fresnel, untinted.
    f_avg_white: f32,
    /// The GGX distribution with the multiple scattering of the tinted mean Fresnel.
    reflection: MicrofacetReflection,
}

impl From<SpecularParams> for Specular {
    fn from(p: SpecularParams) -> Specular {
        Specular::new(p)
    }
}

impl From<SpecularParams> for super::lobe::Lobe {
    fn from(p: SpecularParams) -> super::lobe::Lobe {
        Specular::new(p).into()
    }
}

impl Specular {
    pub fn new(p: SpecularParams) -> Specular {
        let mut s = Specular {
            p,
            f_avg_white: 0.0,
            reflection: MicrofacetReflection::single(p.alpha),
        };
        s.f_avg_white = albedo::dielectric_f_avg(s.eta());
        s.reflection = MicrofacetReflection::new(p.alpha, s.f_avg());
        s
    }

    pub fn params(&self) -> &SpecularParams {
        &self.p
    }

    /// The same lobe at another mixing weight (nothing it looked up depends on it).
    pub fn with_weight(self, weight: f32) -> Specular {
        Specular {
            p: SpecularParams { weight, ..self.p },
            ..self
        }
    }

    fn eta(&self) -> f32 {
        if self.p.eta > 0.0 {
            self.p.eta
        } else {
            1.0
        }
    }

    /// Reflectance at normal incidence, from both sides alike.
    fn f0(&self) -> f32 {
        let e = self.eta();
        ((e - 1.0) / (e + 1.0)).powi(2)
    }

    /// The cosine-weighted mean of [`Specular::fresnel`], the tint included (the
    /// multiple scattering takes the tint as the single scattering does).
    fn f_avg(&self) -> Vec3A {
        self.tinted(self.f_avg_white)
    }

    /// A reflectance `f` of the untinted interface (or a mean of them), tinted: scaled,
    /// or with the tint on F0 only mix(tint·F0, 1, s), s = (f − F0) / (1 − F0).
    fn tinted(&self, f: f32) -> Vec3A {
        if self.p.tint_f0_only {
            let f0 = self.f0();
            let s = ((f - f0) / (1.0 - f0)).clamp(0.0, 1.0);
            self.p.tint * (f0 * (1.0 - s)) + Vec3A::splat(s)
        } else {
            self.p.tint * f
        }
    }

    /// Directional albedo E(ωo): weight × (single scattering with the exact Fresnel +
    /// multiple scattering), towards `wo` in the local frame (`wo.z` taken as positive;
    /// the azimuth matters only when anisotropic), with a white tint over the whole
    /// lobe and the largest channel's with the tint on F0 only. Below 1; what the base
    /// beneath receives is 1 − E.
    pub fn albedo(&self, wo: Vec3A) -> f32 {
        if self.p.tint_f0_only {
            self.albedo_rgb(wo).max_element().min(1.0)
        } else {
            let white = Specular {
                p: SpecularParams {
                    tint: Vec3A::ONE,
                    ..self.p
                },
                reflection: self.reflection.with_f_avg(Vec3A::splat(self.f_avg_white)),
                ..*self
            };
            white.albedo_rgb(wo).x
        }
    }

    /// Directional albedo per channel, the tint included.
    pub fn albedo_rgb(&self, wo: Vec3A) -> Vec3A {
        let wo = Vec3A::new(wo.x, wo.y, wo.z.abs());
        let w = clamp_weight(self.p.weight);
        if is_smooth(self.p.alpha) {
            return (w * self.fresnel(wo.z)).min(Vec3A::ONE);
        }
        let r = &self.reflection;
        let g = Ggx::new(self.p.alpha);
        let a = self.table_alpha(&g, wo);
        let e_fresnel = albedo::dielectric_e(wo.z, a, self.eta());
        let ss = if self.p.tint_f0_only {
            // Linear in the Fresnel term: mix(tint·F0, 1, s) integrates to
            // tint·F0·(E₁ − E_s) + E_s, E₁ the albedo with F = 1 and E_s that with
            // F = s = (F − F0) / (1 − F0).
            let f0 = self.f0();
            let e_one = albedo::ggx_e(wo.z, a);
            let e_s = ((e_fresnel - f0 * e_one) / (1.0 - f0)).max(0.0);
            let ss = self.p.tint * (f0 * (e_one - e_s)) + Vec3A::splat(e_s);
            // Isotropic, the multiple scattering's E(μo) is the same lookup.
            if g.alpha_x == g.alpha_y {
                return (w * (ss + r.ms_albedo_given(e_one))).min(Vec3A::ONE);
            }
            ss
        } else {
            self.p.tint * e_fresnel
        };
        (w * (ss + r.ms_albedo(wo))).min(Vec3A::ONE)
    }

    /// The factor on a base lobe beneath for light leaving towards `wo`: 1 − E(μo).
    pub fn base_attenuation(&self, wo: Vec3A) -> f32 {
        (1.0 - self.albedo(wo)).max(0.0)
    }

    /// The isotropic tables' alpha for anisotropic `g` towards `wo`: the roughness in
    /// `wo`'s plane of incidence; under total internal reflection (η < 1), where the
    /// albedo is not monotonic in the roughness, whichever of the smallest and largest
    /// alpha gives the larger albedo, so that the base beneath is dimmed a little too
    /// much rather than brightened.
    fn table_alpha(&self, g: &Ggx, wo: Vec3A) -> f32 {
        let eta = self.eta();
        if eta >= 1.0 || g.alpha_x == g.alpha_y {
            return albedo::directional_alpha(g, wo);
        }
        let (lo, hi) = (g.alpha_x.min(g.alpha_y), g.alpha_x.max(g.alpha_y));
        if albedo::dielectric_e(wo.z, lo, eta) >= albedo::dielectric_e(wo.z, hi, eta) {
            lo
        } else {
            hi
        }
    }

    fn fresnel(&self, cos: f32) -> Vec3A {
        self.tinted(fresnel_dielectric(cos, self.eta()))
    }
}

impl LobeModel for Specular {
    fn tags(&self) -> &'static [LobeTag] {
        reflection_tags(self.p.lobe, is_smooth(self.p.alpha))
    }
    fn eval(&self, _: usize, wo: Vec3A, wi: Vec3A, sel: f32) -> (Vec3A, f32) {
        let p = &self.p;
        reflection_eval_with(&self.reflection, p.alpha, p.weight, wo, wi, sel, |c| {
            self.fresnel(c)
        })
    }
    fn sample(&self, wo: Vec3A, ctx: SampleCtx, u: Vec2) -> Option<LobeSample> {
        let p = &self.p;
        reflection_sample_with(&self.reflection, p.alpha, p.weight, wo, ctx, u, |c| {
            self.fresnel(c)
        })
    }
    fn selection_weight(&self, wo: Vec3A) -> f32 {
        clamp_weight(self.p.weight) * luminance(self.fresnel(wo.z.abs()))
    }
}
