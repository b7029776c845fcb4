//! Rough diffuse reflection (RD2): OpenPBR's `base_diffuse_roughness`, the
//! energy-preserving Oren–Nayar model "EON" of Portsmouth, Kutz & Hill 2025 ("EON: A
//! practical energy-preserving rough diffuse BRDF", JCGT 14(1)), as OpenPBR 1.1 and
//! Blender Cycles' Principled BSDF (`bsdf_oren_nayar.h`) define it.
//!
//! Fujii's Oren–Nayar single scattering
//! `f_ss = ρ/π · A (1 + σ s/t)`, A = 1/(1 + (½ − 2/(3π)) σ), s = ωi·ωo − μi μo,
//! t = max(μi, μo) where s > 0 (else 1), plus a Kulla–Conty lobe
//! `f_ms = ρ_ms/π · (1 − E(μo)) (1 − E(μi)) / (1 − E_avg)` with Fujii's directional
//! albedo E in closed form (the paper's "exact" one, which Cycles uses) and
//! ρ_ms = ρ² E_avg / (1 − ρ (1 − E_avg)): a white surface reflects all it receives at
//! every roughness, and σ = 0 is Lambert. Sampled by the cosine, as Cycles does.

use super::lambert::RD2;
use super::lobe::{LobeModel, LobeSample, LobeTag, SampleCtx};
use crate::light::luminance;
use crate::sampling::{cosine_hemisphere, cosine_hemisphere_pdf};
use glam::{Vec2, Vec3A};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_2, PI};

/// ½ − 2/(3π): Fujii's A = 1/(1 + this · σ).
const FON_A: f32 = 0.5 - 2.0 / (3.0 * PI);
/// 2/3 − 28/(15π): E_avg = A (1 + this · σ).
const FON_AVG: f32 = 2.0 / 3.0 - 28.0 / (15.0 * PI);

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughDiffuse {
    /// ρ, the single-scattering albedo (OpenPBR's base colour): the multiple scattering
    /// grows with it, so it is kept apart from the mixing weight.
    pub color: Vec3A,
    /// The lobe's share of the material (base weight and the mix of the dielectric base).
    pub weight: f32,
    /// σ in [0, 1] (`base_diffuse_roughness`).
    pub roughness: f32,
}

/// Fujii's G(μ), E(μ) = A (1 + σ G(μ)/π); near grazing its series, where tan θ is unstable.
fn fon_g(mu: f32) -> f32 {
    if mu < 1e-6 {
        return (FRAC_PI_2 - 2.0 / 3.0) - mu;
    }
    let s = (1.0 - mu * mu).max(0.0).sqrt();
    s * (mu.clamp(-1.0, 1.0).acos() - s * mu) + 2.0 / 3.0 * ((s / mu) * (1.0 - s * s * s) - s)
}

impl RoughDiffuse {
    fn sigma(&self) -> f32 {
        if self.roughness.is_nan() {
            0.0
        } else {
            self.roughness.clamp(0.0, 1.0)
        }
    }

    /// Fujii's directional albedo E(μ) for white ρ (EON's `E_FON_exact`).
    pub fn fon_albedo(mu: f32, sigma: f32) -> f32 {
        (1.0 + sigma * fon_g(mu) * FRAC_1_PI) / (1.0 + FON_A * sigma)
    }

    /// f for `wo`, `wi` in the upper hemisphere.
    fn f(&self, wo: Vec3A, wi: Vec3A) -> Vec3A {
        let sigma = self.sigma();
        let (mu_i, mu_o) = (wi.z, wo.z);
        let s = wi.dot(wo) - mu_i * mu_o;
        let s_over_t = if s > 0.0 { s / mu_i.max(mu_o) } else { s };
        let a = 1.0 / (1.0 + FON_A * sigma);
        let single = a * (1.0 + sigma * s_over_t);
        let e_avg = a * (1.0 + FON_AVG * sigma);
        // The paper's ε keeps σ = 0 (E = 1 everywhere) finite.
        const EPS: f32 = 1e-7;
        let ms = (1.0 - Self::fon_albedo(mu_o, sigma)).max(EPS)
            * (1.0 - Self::fon_albedo(mu_i, sigma)).max(EPS)
            / (1.0 - e_avg).max(EPS);
        let rho = self.color.clamp(Vec3A::ZERO, Vec3A::ONE);
        let rho_ms = rho * rho * e_avg / (Vec3A::ONE - rho * (1.0 - e_avg));
        (self.color * single + rho_ms * ms) * (self.weight * FRAC_1_PI)
    }
}

impl LobeModel for RoughDiffuse {
    fn tags(&self) -> &'static [LobeTag] {
        &[RD2]
    }
    fn eval(&self, _: usize, wo: Vec3A, wi: Vec3A, sel: f32) -> (Vec3A, f32) {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return (Vec3A::ZERO, 0.0);
        }
        (self.f(wo, wi) * wi.z, sel * cosine_hemisphere_pdf(wi.z))
    }
    fn sample(&self, wo: Vec3A, ctx: SampleCtx, u: Vec2) -> Option<LobeSample> {
        let wi = cosine_hemisphere(u);
        if !ctx.alone {
            return LobeSample::direction(0, wi);
        }
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return None;
        }
        // Cosine sampling: f·cos/pdf is π f.
        Some(LobeSample {
            sub: 0,
            wi,
            eta: 1.0,
            value: Some((self.f(wo, wi) * PI, cosine_hemisphere_pdf(wi.z), false)),
        })
    }
    fn selection_weight(&self, _: Vec3A) -> f32 {
        luminance(self.color) * self.weight
    }
}
