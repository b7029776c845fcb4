//! Materials as lists of lobes. Each lobe is reflection or transmission, diffuse or
//! specular, with RenderMan's lobe number (LPE.md §1), so that light sampling can send
//! every lobe's contribution through its own LPE event.
//!
//! ```toml
//! [materials.white]
//! type = "diffuse"          # diffuse | translucent | conductor | dielectric | plastic
//! albedo = [0.8, 0.8, 0.8]
//! ```
//!
//! Conventions: directions point away from the surface; `f` values include the cosine
//! of the incoming direction (`f · |cos θi|`); every pdf is in solid angle and includes
//! the probability of choosing the lobe.

use crate::sampling::{cosine_hemisphere, cosine_hemisphere_pdf, Frame};
use glam::{Vec2, Vec3A};
use lpe::Scatter;
use std::f32::consts::{FRAC_1_PI, PI};

/// How a lobe reads as an LPE event.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LobeTag {
    pub transmit: bool,
    pub scatter: Scatter,
    /// A Dirac lobe (smooth mirror or glass): never light-sampled.
    pub delta: bool,
}

const fn tag(transmit: bool, scatter: Scatter, delta: bool) -> LobeTag {
    LobeTag {
        transmit,
        scatter,
        delta,
    }
}

#[derive(Clone, Debug, PartialEq)]
pub enum Bsdf {
    /// Lambertian reflection (RD2).
    Diffuse { albedo: Vec3A },
    /// Diffuse reflection (RD2) and diffuse transmission (TD3): thin translucent sheets,
    /// RenderMan's subsurface-like lobe.
    Translucent { reflect: Vec3A, transmit: Vec3A },
    /// Metal: a mirror (RS2) when smooth, GGX (RS3) when rough; Schlick Fresnel from `f0`.
    Conductor { f0: Vec3A, alpha: f32 },
    /// Glass (RS8 + TS8): exact dielectric Fresnel; smooth or rough (GGX, Walter 2007).
    Dielectric { eta: f32, alpha: f32, tint: Vec3A },
    /// A diffuse base (RD2) under a dielectric clear coat (RS4).
    Plastic { albedo: Vec3A, eta: f32, alpha: f32 },
}

pub struct BsdfSample {
    pub lobe: usize,
    pub wi: Vec3A,
    /// `f · |cos θi| / pdf`.
    pub weight: Vec3A,
    pub pdf: f32,
    pub delta: bool,
    /// Relative index of refraction crossed (1 for reflection), for Russian roulette.
    pub eta: f32,
}

/// Where and how a surface is shaded.
#[derive(Clone, Copy, Debug)]
pub struct Shading {
    pub frame: Frame,
    /// The outgoing direction in the local frame.
    pub wo: Vec3A,
}

impl Shading {
    /// A frame around the shading normal. Two-sided materials (all but glass) flip it
    /// towards `wo`, so reflection is `wi.z > 0` and transmission `wi.z < 0`; dielectrics keep the geometric orientation (it tells inside from outside).
    pub fn new(bsdf: &Bsdf, ns: Vec3A, ng: Vec3A, wo_world: Vec3A) -> Shading {
        let n = match bsdf {
            Bsdf::Dielectric { .. } => ns,
            _ => {
                if wo_world.dot(ng) < 0.0 {
                    -ns
                } else {
                    ns
                }
            }
        };
        let frame = Frame::new(n);
        Shading {
            frame,
            wo: frame.to_local(wo_world),
        }
    }
}

fn luminance(c: Vec3A) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// Unpolarised Fresnel reflectance of a dielectric; `eta` = inside / outside, `cos_i`
/// signed (negative: arriving from inside).
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let (cos_i, eta) = if cos_i < 0.0 {
        (-cos_i, 1.0 / eta)
    } else {
        (cos_i, eta)
    };
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    0.5 * (rs * rs + rp * rp)
}

fn schlick(f0: Vec3A, cos: f32) -> Vec3A {
    let m = (1.0 - cos.clamp(0.0, 1.0)).powi(5);
    f0 + (Vec3A::ONE - f0) * m
}

/// Refracts `wi` about `n` (same side as `wi`) with relative index `eta`; None on total
/// internal reflection.
fn refract(wi: Vec3A, n: Vec3A, eta: f32) -> Option<Vec3A> {
    let cos_i = wi.dot(n);
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(-wi / eta + n * (cos_i / eta - cos_t))
}

/// The GGX (Trowbridge–Reitz) microfacet distribution with Smith shadowing.
#[derive(Clone, Copy)]
struct Ggx {
    alpha: f32,
}

impl Ggx {
    fn d(&self, m: Vec3A) -> f32 {
        let a2 = self.alpha * self.alpha;
        let c2 = m.z * m.z;
        let t = c2 * (a2 - 1.0) + 1.0;
        a2 / (PI * t * t)
    }
    fn lambda(&self, w: Vec3A) -> f32 {
        let c2 = w.z * w.z;
        if c2 == 0.0 {
            return f32::INFINITY;
        }
        let tan2 = (1.0 - c2).max(0.0) / c2;
        ((1.0 + self.alpha * self.alpha * tan2).sqrt() - 1.0) / 2.0
    }
    fn g1(&self, w: Vec3A) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }
    fn g(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }
    /// Density of visible normals from `wo` (Heitz 2018), per solid angle of `m`.
    fn pdf_visible(&self, wo: Vec3A, m: Vec3A) -> f32 {
        if wo.z == 0.0 {
            return 0.0;
        }
        self.g1(wo) * wo.dot(m).abs() * self.d(m) / wo.z.abs()
    }
    /// Samples a visible normal (Heitz 2018, "Sampling the GGX Distribution of Visible
    /// Normals"), for `wo` in the upper hemisphere.
    fn sample_visible(&self, wo: Vec3A, u: Vec2) -> Vec3A {
        let wo = if wo.z < 0.0 { -wo } else { wo };
        let vh = Vec3A::new(self.alpha * wo.x, self.alpha * wo.y, wo.z).normalize();
        let len2 = vh.x * vh.x + vh.y * vh.y;
        let t1 = if len2 > 0.0 {
            Vec3A::new(-vh.y, vh.x, 0.0) / len2.sqrt()
        } else {
            Vec3A::X
        };
        let t2 = vh.cross(t1);
        let r = u.x.sqrt();
        let (sin_phi, cos_phi) = crate::sampling::sin_cos_turns(u.y);
        let p1 = r * cos_phi;
        let s = 0.5 * (1.0 + vh.z);
        let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * sin_phi;
        let nh = t1 * p1 + t2 * p2 + vh * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
        Vec3A::new(self.alpha * nh.x, self.alpha * nh.y, nh.z.max(1e-6)).normalize()
    }
}

/// Roughness as artists write it (0 smooth … 1 rough) to GGX alpha.
pub fn roughness_to_alpha(r: f32) -> f32 {
    let r = r.clamp(0.0, 1.0);
    if r < 1e-3 {
        0.0
    } else {
        r * r
    }
}

const RD2: LobeTag = tag(false, Scatter::diffuse(2), false);
const TD3: LobeTag = tag(true, Scatter::diffuse(3), false);

impl Bsdf {
    pub fn lobes(&self) -> &'static [LobeTag] {
        const DIFFUSE: [LobeTag; 1] = [RD2];
        const TRANSLUCENT: [LobeTag; 2] = [RD2, TD3];
        const MIRROR: [LobeTag; 1] = [tag(false, Scatter::specular(2), true)];
        const METAL: [LobeTag; 1] = [tag(false, Scatter::specular(3), false)];
        const GLASS: [LobeTag; 2] = [
            tag(false, Scatter::specular(8), true),
            tag(true, Scatter::specular(8), true),
        ];
        const ROUGH_GLASS: [LobeTag; 2] = [
            tag(false, Scatter::specular(8), false),
            tag(true, Scatter::specular(8), false),
        ];
        const PLASTIC: [LobeTag; 2] = [RD2, tag(false, Scatter::specular(4), true)];
        const ROUGH_PLASTIC: [LobeTag; 2] = [RD2, tag(false, Scatter::specular(4), false)];
        match self {
            Bsdf::Diffuse { .. } => &DIFFUSE,
            Bsdf::Translucent { .. } => &TRANSLUCENT,
            Bsdf::Conductor { alpha, .. } if *alpha == 0.0 => &MIRROR,
            Bsdf::Conductor { .. } => &METAL,
            Bsdf::Dielectric { alpha, .. } if *alpha == 0.0 => &GLASS,
            Bsdf::Dielectric { .. } => &ROUGH_GLASS,
            Bsdf::Plastic { alpha, .. } if *alpha == 0.0 => &PLASTIC,
            Bsdf::Plastic { .. } => &ROUGH_PLASTIC,
        }
    }

    /// The colour the `U2` albedo lobe reports.
    pub fn albedo(&self) -> Vec3A {
        match self {
            Bsdf::Diffuse { albedo } | Bsdf::Plastic { albedo, .. } => *albedo,
            Bsdf::Translucent { reflect, transmit } => *reflect + *transmit,
            Bsdf::Conductor { f0, .. } => *f0,
            Bsdf::Dielectric { tint, .. } => *tint,
        }
    }

    /// Probability of choosing each lobe when sampling (at most two lobes).
    fn selection(&self, wo: Vec3A) -> [f32; 2] {
        match self {
            Bsdf::Diffuse { .. } | Bsdf::Conductor { .. } => [1.0, 0.0],
            Bsdf::Translucent { reflect, transmit } => {
                let (r, t) = (luminance(*reflect), luminance(*transmit));
                if r + t <= 0.0 {
                    [0.5, 0.5]
                } else {
                    [r / (r + t), t / (r + t)]
                }
            }
            // Rough glass chooses per microfacet inside its pdfs; smooth glass by Fresnel.
            Bsdf::Dielectric { eta, .. } => {
                let f = fresnel_dielectric(wo.z, *eta);
                [f, 1.0 - f]
            }
            Bsdf::Plastic { albedo, eta, .. } => {
                let f = fresnel_dielectric(wo.z.abs(), *eta);
                let d = (1.0 - f) * luminance(*albedo);
                let spec = (f / (f + d).max(1e-6)).clamp(0.1, 0.9);
                [1.0 - spec, spec]
            }
        }
    }

    /// `f · |cos θi|` of lobe `k` for the local directions, and its pdf (selection
    /// included). Delta lobes evaluate to zero.
    pub fn eval_lobe(&self, k: usize, sh: &Shading, wi: Vec3A) -> (Vec3A, f32) {
        let wo = sh.wo;
        let sel = self.selection(wo);
        match (self, k) {
            (Bsdf::Diffuse { albedo }, _)
            | (
                Bsdf::Translucent {
                    reflect: albedo, ..
                },
                0,
            )
            | (Bsdf::Plastic { albedo, .. }, 0) => {
                if wo.z <= 0.0 || wi.z <= 0.0 {
                    return (Vec3A::ZERO, 0.0);
                }
                let mut f = *albedo * FRAC_1_PI * wi.z;
                if let Bsdf::Plastic { eta, .. } = self {
                    f *= (1.0 - fresnel_dielectric(wo.z, *eta))
                        * (1.0 - fresnel_dielectric(wi.z, *eta));
                }
                (f, sel[0] * cosine_hemisphere_pdf(wi.z))
            }
            (Bsdf::Translucent { transmit, .. }, _) => {
                if wo.z <= 0.0 || wi.z >= 0.0 {
                    return (Vec3A::ZERO, 0.0);
                }
                (
                    *transmit * FRAC_1_PI * wi.z.abs(),
                    sel[1] * cosine_hemisphere_pdf(wi.z.abs()),
                )
            }
            (Bsdf::Conductor { f0, alpha }, _) => {
                if *alpha == 0.0 || wo.z <= 0.0 || wi.z <= 0.0 {
                    return (Vec3A::ZERO, 0.0);
                }
                let g = Ggx { alpha: *alpha };
                let m = (wo + wi).normalize();
                let f = schlick(*f0, wi.dot(m)) * (g.d(m) * g.g(wo, wi) / (4.0 * wo.z));
                (f, g.pdf_visible(wo, m) / (4.0 * wo.dot(m)))
            }
            (Bsdf::Plastic { eta, alpha, .. }, _) => {
                if *alpha == 0.0 || wo.z <= 0.0 || wi.z <= 0.0 {
                    return (Vec3A::ZERO, 0.0);
                }
                let g = Ggx { alpha: *alpha };
                let m = (wo + wi).normalize();
                let f = fresnel_dielectric(wi.dot(m), *eta) * g.d(m) * g.g(wo, wi) / (4.0 * wo.z);
                (
                    Vec3A::splat(f),
                    sel[1] * g.pdf_visible(wo, m) / (4.0 * wo.dot(m)),
                )
            }
            (Bsdf::Dielectric { eta, alpha, tint }, k) => {
                if *alpha == 0.0 || wo.z == 0.0 || wi.z == 0.0 {
                    return (Vec3A::ZERO, 0.0);
                }
                rough_dielectric_eval(k, *eta, Ggx { alpha: *alpha }, *tint, wo, wi)
            }
        }
    }

    /// Samples a lobe and a direction. `u_lobe` chooses the lobe.
    pub fn sample(&self, sh: &Shading, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        let wo = sh.wo;
        let sel = self.selection(wo);
        let lobe = if u_lobe < sel[0] { 0 } else { 1 };
        let sample = |lobe: usize,
                      wi: Vec3A,
                      delta_weight: Option<(Vec3A, f32)>,
                      eta: f32|
         -> Option<BsdfSample> {
            if let Some((weight, pdf)) = delta_weight {
                return Some(BsdfSample {
                    lobe,
                    wi: sh.frame.to_world(wi),
                    weight,
                    pdf,
                    delta: true,
                    eta,
                });
            }
            let (f, pdf) = self.eval_lobe(lobe, sh, wi);
            if pdf <= 0.0 || f == Vec3A::ZERO {
                return None;
            }
            Some(BsdfSample {
                lobe,
                wi: sh.frame.to_world(wi),
                weight: f / pdf,
                pdf,
                delta: false,
                eta,
            })
        };
        match self {
            // Cosine sampling: f·cos/pdf is the albedo itself.
            Bsdf::Diffuse { albedo } => {
                if wo.z <= 0.0 {
                    return None;
                }
                let wi = cosine_hemisphere(u);
                if wi.z <= 0.0 {
                    return None;
                }
                Some(BsdfSample {
                    lobe: 0,
                    wi: sh.frame.to_world(wi),
                    weight: *albedo,
                    pdf: cosine_hemisphere_pdf(wi.z),
                    delta: false,
                    eta: 1.0,
                })
            }
            Bsdf::Translucent { .. } => {
                let mut wi = cosine_hemisphere(u);
                if lobe == 1 {
                    wi.z = -wi.z;
                }
                sample(lobe, wi, None, 1.0)
            }
            Bsdf::Conductor { f0, alpha } => {
                if wo.z <= 0.0 {
                    return None;
                }
                if *alpha == 0.0 {
                    let wi = Vec3A::new(-wo.x, -wo.y, wo.z);
                    return sample(0, wi, Some((schlick(*f0, wo.z), 1.0)), 1.0);
                }
                let m = Ggx { alpha: *alpha }.sample_visible(wo, u);
                let wi = reflect(wo, m);
                if wi.z <= 0.0 {
                    return None;
                }
                sample(0, wi, None, 1.0)
            }
            Bsdf::Plastic { alpha, .. } => {
                if wo.z <= 0.0 {
                    return None;
                }
                if lobe == 0 {
                    return sample(0, cosine_hemisphere(u), None, 1.0);
                }
                if *alpha == 0.0 {
                    let f = fresnel_dielectric(wo.z, self.eta());
                    let wi = Vec3A::new(-wo.x, -wo.y, wo.z);
                    return sample(1, wi, Some((Vec3A::splat(f / sel[1]), sel[1])), 1.0);
                }
                let m = Ggx { alpha: *alpha }.sample_visible(wo, u);
                let wi = reflect(wo, m);
                if wi.z <= 0.0 {
                    return None;
                }
                sample(1, wi, None, 1.0)
            }
            Bsdf::Dielectric { eta, alpha, tint } => {
                if wo.z == 0.0 {
                    return None;
                }
                if *alpha == 0.0 {
                    let n = if wo.z > 0.0 { Vec3A::Z } else { -Vec3A::Z };
                    let etap = if wo.z > 0.0 { *eta } else { 1.0 / eta };
                    if lobe == 0 {
                        let wi = Vec3A::new(-wo.x, -wo.y, wo.z);
                        // f / pdf = F / F.
                        return sample(0, wi, Some((*tint, sel[0])), 1.0);
                    }
                    let wi = refract(wo, n, etap)?;
                    // Radiance is compressed by 1/η² entering a denser medium.
                    return sample(1, wi, Some((*tint / (etap * etap), sel[1])), etap);
                }
                // Rough glass: sample a visible microfacet, then reflect or refract by its
                // Fresnel term (Walter et al. 2007, as in pbrt-v4).
                let g = Ggx { alpha: *alpha };
                let flipz = if wo.z < 0.0 { -1.0 } else { 1.0 };
                let wo_up = wo * flipz;
                let m = g.sample_visible(wo_up, u) * flipz;
                let f = fresnel_dielectric(wo.dot(m), *eta);
                let (k, wi) = if u_lobe < f {
                    (0, reflect(wo, m))
                } else {
                    let etap = if wo.z > 0.0 { *eta } else { 1.0 / eta };
                    let n = if wo.dot(m) > 0.0 { m } else { -m };
                    (1, refract(wo, n, etap)?)
                };
                let (fv, pdf) = rough_dielectric_eval(k, *eta, g, *tint, wo, wi);
                if pdf <= 0.0 || fv == Vec3A::ZERO {
                    return None;
                }
                let etap = if k == 1 {
                    if wo.z > 0.0 {
                        *eta
                    } else {
                        1.0 / eta
                    }
                } else {
                    1.0
                };
                Some(BsdfSample {
                    lobe: k,
                    wi: sh.frame.to_world(wi),
                    weight: fv / pdf,
                    pdf,
                    delta: false,
                    eta: etap,
                })
            }
        }
    }

    fn eta(&self) -> f32 {
        match self {
            Bsdf::Plastic { eta, .. } | Bsdf::Dielectric { eta, .. } => *eta,
            _ => 1.0,
        }
    }
}

fn reflect(wo: Vec3A, m: Vec3A) -> Vec3A {
    -wo + m * (2.0 * wo.dot(m))
}

/// Rough dielectric lobe `k` (0 reflection, 1 transmission): `f · |cos θi|` and pdf,
/// both including the per-microfacet Fresnel choice (pbrt-v4's DielectricBxDF).
fn rough_dielectric_eval(
    k: usize,
    eta: f32,
    g: Ggx,
    tint: Vec3A,
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
    // Discard back-facing microfacets.
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
        (tint * val, pdf)
    } else {
        let denom = (wi.dot(m) + wo.dot(m) / etap).powi(2);
        let val = (1.0 - f) * g.d(m) * g.g(wo, wi) * (wi.dot(m) * wo.dot(m)).abs()
            / (denom * cos_o.abs())
            / (etap * etap);
        let pdf = pdf_m * wi.dot(m).abs() / denom * (1.0 - f);
        (tint * val, pdf)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    /// Estimates ∫ f cos dωi by sampling: the directional albedo, and checks that
    /// sampling weights agree with eval / pdf.
    fn albedo(bsdf: &Bsdf, wo: Vec3A, n: usize) -> Vec3A {
        let sh = Shading {
            frame: Frame::new(Vec3A::Z),
            wo,
        };
        let mut rng = Rng::for_sample(7, 0, 0);
        let mut sum = Vec3A::ZERO;
        for _ in 0..n {
            if let Some(s) = bsdf.sample(&sh, rng.next_f32(), rng.next_2d()) {
                sum += s.weight;
            }
        }
        sum / n as f32
    }

    #[test]
    fn white_diffuse_reflects_everything() {
        let a = albedo(
            &Bsdf::Diffuse { albedo: Vec3A::ONE },
            Vec3A::new(0.3, 0.0, 0.95).normalize(),
            1000,
        );
        assert!((a - Vec3A::ONE).abs().max_element() < 1e-4, "{a}");
    }

    #[test]
    fn lossless_glass_conserves_energy_up_to_radiance_scaling() {
        // Smooth and rough: reflection + transmission·η² sum to one (no absorption).
        for alpha in [0.0, 0.3] {
            let bsdf = Bsdf::Dielectric {
                eta: 1.5,
                alpha,
                tint: Vec3A::ONE,
            };
            let sh = Shading {
                frame: Frame::new(Vec3A::Z),
                wo: Vec3A::new(0.4, 0.0, 0.9).normalize(),
            };
            let mut rng = Rng::for_sample(3, 0, 0);
            let n = 200_000;
            let mut total = 0.0;
            for _ in 0..n {
                if let Some(s) = bsdf.sample(&sh, rng.next_f32(), rng.next_2d()) {
                    total += s.weight.x * s.eta * s.eta;
                }
            }
            let e = total / n as f32;
            // Rough GGX loses a little energy to single scattering (a few %).
            let tol = if alpha == 0.0 { 0.01 } else { 0.05 };
            assert!(e <= 1.0 + 0.01 && e > 1.0 - tol, "alpha {alpha}: {e}");
        }
    }

    #[test]
    fn sampled_weights_match_evaluation_for_rough_lobes() {
        for bsdf in [
            Bsdf::Conductor {
                f0: Vec3A::splat(0.9),
                alpha: 0.2,
            },
            Bsdf::Plastic {
                albedo: Vec3A::splat(0.5),
                eta: 1.5,
                alpha: 0.3,
            },
            Bsdf::Translucent {
                reflect: Vec3A::splat(0.3),
                transmit: Vec3A::splat(0.6),
            },
        ] {
            let sh = Shading {
                frame: Frame::new(Vec3A::Z),
                wo: Vec3A::new(0.5, 0.1, 0.8).normalize(),
            };
            let mut rng = Rng::for_sample(5, 0, 0);
            for _ in 0..200 {
                if let Some(s) = bsdf.sample(&sh, rng.next_f32(), rng.next_2d()) {
                    let (f, pdf) = bsdf.eval_lobe(s.lobe, &sh, sh.frame.to_local(s.wi));
                    assert!(
                        (pdf - s.pdf).abs() <= 1e-3 * pdf.max(1.0),
                        "{bsdf:?}: {pdf} vs {}",
                        s.pdf
                    );
                    assert!((f / pdf - s.weight).abs().max_element() < 1e-3, "{bsdf:?}");
                }
            }
        }
    }

    #[test]
    fn translucent_energy_is_reflect_plus_transmit() {
        let bsdf = Bsdf::Translucent {
            reflect: Vec3A::splat(0.3),
            transmit: Vec3A::splat(0.5),
        };
        let a = albedo(&bsdf, Vec3A::new(0.0, 0.2, 0.98).normalize(), 20_000);
        assert!((a.x - 0.8).abs() < 0.02, "{a}");
    }
}
