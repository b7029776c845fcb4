//! Glass (RS8 + TS8): exact dielectric Fresnel; smooth, or rough (anisotropic GGX,
//! Walter et al. 2007, as pbrt-v4's DielectricBxDF). One lobe with two events, because
//! rough glass chooses reflection or transmission per sampled microfacet. The
//! transmission colour tints each crossing; the reflection has its own (untinted in
//! OpenPBR's and glTF's glass).
//!
//! Rough glass compensates the energy single scattering loses as Turquin 2019
//! ("Practical multiple scattering compensation for microfacet models") does for
//! dielectrics: reflection and transmission are both scaled by 1/E(μo), E the albedo
//! of single scattering (reflection + transmission, radiance compression left out)
//! from `wo`'s side, tabulated entering and exiting ([`albedo::glass_e`]). A lossless
//! interface then keeps all the energy from either side; the scale is not reciprocal,
//! as in the paper. The tables are isotropic: anisotropic glass reads them at its
//! smaller alpha, which undercompensates (see the furnace test) but never adds energy.

use super::albedo;
use super::fresnel::{fresnel_dielectric, reflect, refract};
use super::lobe::{tag, LobeModel, LobeSample, LobeTag, SampleCtx};
use super::microfacet::{is_smooth, Ggx};
use glam::{Vec2, Vec3A};
use lpe::Scatter;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dielectric {
    /// Inside / outside index of refraction.
    pub eta: f32,
    /// GGX (αx along the tangent, αy); both 0 is smooth.
    pub alpha: Vec2,
    /// Colour of transmitted light, at each crossing.
    pub tint: Vec3A,
    /// Colour (and weight) of the reflection: glTF, Cycles and OpenPBR leave a glass's
    /// reflection untinted by its transmission colour.
    pub reflect_tint: Vec3A,
    /// Turquin's compensation on (false only for a regularised glass: see
    /// `Bsdf::regularized_glass`).
    pub compensate: bool,
}

impl Dielectric {
    /// Index crossed leaving along `wo`'s side into the other one.
    fn etap(&self, wo: Vec3A) -> f32 {
        if wo.z > 0.0 {
            self.eta
        } else {
            1.0 / self.eta
        }
    }

    fn tints(&self) -> (Vec3A, Vec3A) {
        (self.reflect_tint, self.tint)
    }

    /// Turquin's energy scale 1/E(μo) for rough glass seen from `wo`.
    fn compensation(&self, g: &Ggx, wo: Vec3A) -> f32 {
        if !self.compensate {
            return 1.0;
        }
        // Anisotropic glass reads the isotropic table at its smaller alpha: it then
        // loses some energy, but never gains any.
        let a = albedo::min_alpha(g);
        let e = albedo::glass_e(wo.z.abs(), a, self.etap(wo));
        // Exiting at α = 1 keeps 0.4 for η = 1.5, less for denser glass; the floor
        // only guards against a broken table.
        1.0 / e.max(0.02)
    }
}

impl LobeModel for Dielectric {
    fn tags(&self) -> &'static [LobeTag] {
        const GLASS: [LobeTag; 2] = [
            tag(false, Scatter::specular(8), true),
            tag(true, Scatter::specular(8), true),
        ];
        const ROUGH_GLASS: [LobeTag; 2] = [
            tag(false, Scatter::specular(8), false),
            tag(true, Scatter::specular(8), false),
        ];
        if is_smooth(self.alpha) {
            &GLASS
        } else {
            &ROUGH_GLASS
        }
    }
    /// The per-microfacet Fresnel choice is part of the pdf, so `sel` (always 1: glass
    /// is never layered) is not applied.
    fn eval(&self, sub: usize, wo: Vec3A, wi: Vec3A, _sel: f32) -> (Vec3A, f32) {
        if is_smooth(self.alpha) || wo.z == 0.0 || wi.z == 0.0 {
            return (Vec3A::ZERO, 0.0);
        }
        let g = Ggx::new(self.alpha);
        let (f, pdf) = rough_eval(sub, self.eta, g, self.tints(), wo, wi);
        (f * self.compensation(&g, wo), pdf)
    }
    fn sample(&self, wo: Vec3A, ctx: SampleCtx, u: Vec2) -> Option<LobeSample> {
        if wo.z == 0.0 {
            return None;
        }
        let eta = self.eta;
        if is_smooth(self.alpha) {
            let f = fresnel_dielectric(wo.z, eta);
            let n = if wo.z > 0.0 { Vec3A::Z } else { -Vec3A::Z };
            let etap = self.etap(wo);
            if ctx.u_lobe < f {
                // f / pdf = F / F.
                return Some(LobeSample {
                    sub: 0,
                    wi: Vec3A::new(-wo.x, -wo.y, wo.z),
                    eta: 1.0,
                    value: Some((self.reflect_tint, f, true)),
                });
            }
            let wi = refract(wo, n, etap)?;
            // Radiance is compressed by 1/η² entering a denser medium.
            return Some(LobeSample {
                sub: 1,
                wi,
                eta: etap,
                value: Some((self.tint / (etap * etap), 1.0 - f, true)),
            });
        }
        let g = Ggx::new(self.alpha);
        let flipz = if wo.z < 0.0 { -1.0 } else { 1.0 };
        let wo_up = wo * flipz;
        let m = g.sample_visible(wo_up, u) * flipz;
        // Fresnel of the up-facing microfacet, as `rough_eval` takes it: from inside, cos < 0
        // selects the inside-to-outside ratio.
        let f = fresnel_dielectric(wo.dot(m) * flipz, eta);
        let (k, wi) = if ctx.u_lobe < f {
            (0, reflect(wo, m))
        } else {
            let n = if wo.dot(m) > 0.0 { m } else { -m };
            (1, refract(wo, n, self.etap(wo))?)
        };
        let (fv, pdf) = rough_eval(k, eta, g, self.tints(), wo, wi);
        if pdf <= 0.0 || fv == Vec3A::ZERO {
            return None;
        }
        Some(LobeSample {
            sub: k,
            wi,
            eta: if k == 1 { self.etap(wo) } else { 1.0 },
            value: Some((fv * (self.compensation(&g, wo) / pdf), pdf, false)),
        })
    }
    fn selection_weight(&self, _: Vec3A) -> f32 {
        1.0
    }
    fn two_sided(&self) -> bool {
        false
    }
}

/// Rough dielectric event `k` (0 reflection, 1 transmission): `f · |cos θi|` and pdf,
/// both including the per-microfacet Fresnel choice.
/// `tints` are (reflection, transmission).
fn rough_eval(
    k: usize,
    eta: f32,
    g: Ggx,
    tints: (Vec3A, Vec3A),
    wo: Vec3A,
    wi: Vec3A,
) -> (Vec3A, f32) {
    let (cos_o, cos_i) = (wo.z, wi.z);
    let reflect = cos_o * cos_i > 0.0;
    if reflect != (k == 0) {
        return (Vec3A::ZERO, 0.0);
    }
    let etap = if reflect {
        1.0
    } else if cos_o > 0.0 {
        eta
    } else {
        1.0 / eta
    };
    let mut m = wi * etap + wo;
    if m.length_squared() == 0.0 {
        return (Vec3A::ZERO, 0.0);
    }
    m = m.normalize();
    if m.z < 0.0 {
        m = -m;
    }
    // Back-facing microfacets carry no light.
    if m.dot(wi) * cos_i < 0.0 || m.dot(wo) * cos_o < 0.0 {
        return (Vec3A::ZERO, 0.0);
    }
    let f = fresnel_dielectric(wo.dot(m), eta);
    // Sample pdfs are over the hemisphere of wo.
    let wo_up = if cos_o < 0.0 { -wo } else { wo };
    let m_up = if cos_o < 0.0 { -m } else { m };
    let pdf_m = g.pdf_visible(wo_up, m_up);
    if reflect {
        let val = g.d(m) * g.g(wo, wi) * f / (4.0 * cos_o.abs());
        let pdf = pdf_m / (4.0 * wo.dot(m).abs()) * f;
        (tints.0 * val, pdf)
    } else {
        let denom = (wi.dot(m) + wo.dot(m) / etap).powi(2);
        let val = (1.0 - f) * g.d(m) * g.g(wo, wi) * (wi.dot(m) * wo.dot(m)).abs()
            / (denom * cos_o.abs())
            / (etap * etap);
        let pdf = pdf_m * wi.dot(m).abs() / denom * (1.0 - f);
        (tints.1 * val, pdf)
    }
}
