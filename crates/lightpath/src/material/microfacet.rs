//! The anisotropic GGX (Trowbridge–Reitz) microfacet distribution with Smith
//! shadowing, in the shading frame (`x` the tangent, `y` the bitangent, `z` the normal),
//! and [`MicrofacetReflection`], the one GGX reflection the reflecting lobes share
//! (metal, dielectric specular; a thin-film lobe plugs in its own Fresnel): it takes
//! its Fresnel term as a closure and adds Kulla–Conty multiple scattering (see
//! [`super::albedo`]). [`reflection_eval`] and [`reflection_sample`] are a whole
//! lobe's eval and sample around it, smooth (delta) or rough.
//!
//! Visible-normal sampling: Heitz 2018, "Sampling the GGX Distribution of Visible
//! Normals" (JCGT 7(4)), which handles anisotropy by stretching the view direction.

use super::albedo;
use super::fresnel::reflect;
use super::lobe::{tag, LobeSample, LobeTag, SampleCtx};
use crate::sampling::{cosine_hemisphere, cosine_hemisphere_pdf};
use glam::{Vec2, Vec3A};
use lpe::Scatter;
use std::f32::consts::PI;

/// Alphas below this are raised to it once a lobe is rough (a lobe with both alphas 0 is
/// a delta lobe and never builds a [`Ggx`]), so that one zero alpha of an anisotropic
/// lobe cannot divide by zero.
pub const MIN_ALPHA: f32 = 1e-4;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ggx {
    /// Roughness along the tangent (`x`).
    pub alpha_x: f32,
    /// Roughness along the bitangent (`y`).
    pub alpha_y: f32,
}

impl Ggx {
    /// `alpha.x` along the tangent, `alpha.y` along the bitangent, each at least
    /// [`MIN_ALPHA`] (NaN too becomes it).
    pub fn new(alpha: Vec2) -> Ggx {
        Ggx {
            alpha_x: alpha.x.max(MIN_ALPHA),
            alpha_y: alpha.y.max(MIN_ALPHA),
        }
    }
    pub fn isotropic(alpha: f32) -> Ggx {
        Ggx::new(Vec2::splat(alpha))
    }
    pub fn d(&self, m: Vec3A) -> f32 {
        let (ax, ay) = (self.alpha_x, self.alpha_y);
        let x = m.x / ax;
        let y = m.y / ay;
        let t = x * x + y * y + m.z * m.z;
        if t == 0.0 {
            return 0.0;
        }
        1.0 / (PI * ax * ay * t * t)
    }
    fn lambda(&self, w: Vec3A) -> f32 {
        let c2 = w.z * w.z;
        if c2 == 0.0 {
            return f32::INFINITY;
        }
        let (ax, ay) = (self.alpha_x * w.x, self.alpha_y * w.y);
        ((1.0 + (ax * ax + ay * ay) / c2).sqrt() - 1.0) / 2.0
    }
    pub fn g1(&self, w: Vec3A) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }
    pub fn g(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }
    /// Density of visible normals from `wo` (Heitz 2018), per solid angle of `m`.
    pub fn pdf_visible(&self, wo: Vec3A, m: Vec3A) -> f32 {
        if wo.z == 0.0 {
            return 0.0;
        }
        self.g1(wo) * wo.dot(m).abs() * self.d(m) / wo.z.abs()
    }
    /// Samples a visible normal (Heitz 2018), for `wo` in the upper hemisphere (a `wo`
    /// below is mirrored up).
    pub fn sample_visible(&self, wo: Vec3A, u: Vec2) -> Vec3A {
        let wo = if wo.z < 0.0 { -wo } else { wo };
        let (ax, ay) = (self.alpha_x, self.alpha_y);
        let vh = Vec3A::new(ax * wo.x, ay * wo.y, wo.z).normalize();
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
        Vec3A::new(ax * nh.x, ay * nh.y, nh.z.max(1e-6)).normalize()
    }
}

/// OpenPBR's roughness and roughness anisotropy (both in [0, 1]) to (αx, αy), as its
/// specification maps them: α = r², αx = α·√(2 / (1 + (1 − a)²)), αy = (1 − a)·αx
/// (so that αx² + αy² = 2α² whatever the anisotropy). Roughness 0: both 0, smooth.
pub fn roughness_anisotropy_to_alpha(roughness: f32, anisotropy: f32) -> Vec2 {
    let alpha = super::roughness_to_alpha(roughness);
    let a = if anisotropy.is_nan() {
        0.0
    } else {
        anisotropy.clamp(0.0, 1.0)
    };
    let ax = alpha * (2.0 / (1.0 + (1.0 - a) * (1.0 - a))).sqrt();
    Vec2::new(ax, (1.0 - a) * ax)
}

/// The Fresnel factor of Kulla & Conty's multiple-scattering lobe for a surface whose
/// cosine-weighted mean Fresnel is `f_avg` and mean single-scattering albedo (F = 1)
/// `e_avg`: F_avg² E_avg / (1 − F_avg (1 − E_avg)), the energy that leaves after any
/// number of bounces, each losing 1 − F_avg.
pub fn kulla_conty_fms(f_avg: Vec3A, e_avg: f32) -> Vec3A {
    let f = f_avg.clamp(Vec3A::ZERO, Vec3A::ONE);
    f * f * e_avg / (Vec3A::ONE - f * (1.0 - e_avg)).max(Vec3A::splat(1e-6))
}

/// GGX reflection, single scattering with any Fresnel term plus Kulla & Conty's (2017)
/// multiple-scattering lobe
/// `f_ms · cos θi = F_ms (1 − E(μo)) (1 − E(μi)) μi / (π (1 − E_avg))`,
/// E the albedo with F = 1 (tables in [`super::albedo`]). That lobe is symmetric in
/// (μo, μi), so reciprocity holds, and it returns exactly the energy
/// (1 − E(μo)) · F_ms that single scattering loses; anisotropic alphas read E at their
/// geometric mean, as Cycles and OpenPBR's reference do, which returns less where the
/// view sees the rough axis.
///
/// Sampling draws a visible normal, or with probability `1 − E(μo)` (the multiple
/// scattering's share with white Fresnel) a cosine-distributed direction; the pdf is
/// that mixture.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MicrofacetReflection {
    pub ggx: Ggx,
    /// F_ms: the colour of multiple scattering ([`kulla_conty_fms`]); zero turns it off.
    pub ms: Vec3A,
    /// E_avg of the distribution, looked up once.
    e_avg: f32,
}

impl MicrofacetReflection {
    /// A rough lobe of `alpha` whose Fresnel term averages `f_avg` over the cosine-weighted
    /// hemisphere.
    pub fn new(alpha: Vec2, f_avg: Vec3A) -> MicrofacetReflection {
        let ggx = Ggx::new(alpha);
        let e_avg = albedo::ggx_e_avg_of(&ggx);
        MicrofacetReflection {
            ggx,
            ms: kulla_conty_fms(f_avg, e_avg),
            e_avg,
        }
    }

    /// The same distribution with the multiple scattering of another mean Fresnel.
    pub fn with_f_avg(self, f_avg: Vec3A) -> MicrofacetReflection {
        MicrofacetReflection {
            ms: kulla_conty_fms(f_avg, self.e_avg),
            ..self
        }
    }

    /// Single scattering only (no compensation).
    pub fn single(alpha: Vec2) -> MicrofacetReflection {
        MicrofacetReflection {
            ggx: Ggx::new(alpha),
            ms: Vec3A::ZERO,
            e_avg: 1.0,
        }
    }

    fn e(&self, w: Vec3A) -> f32 {
        albedo::ggx_e_dir(&self.ggx, w)
    }

    /// Probability of sampling the multiple-scattering lobe from `wo`.
    fn p_ms(&self, wo: Vec3A) -> f32 {
        if self.ms == Vec3A::ZERO {
            0.0
        } else {
            (1.0 - self.e(wo)).clamp(0.0, 1.0)
        }
    }

    /// `f · cos θi` and its pdf (solid angle, without lobe selection) for `wo`, `wi` in
    /// the upper hemisphere; `fresnel(cos θh)` is the single-scattering Fresnel term.
    #[inline]
    pub fn eval<F: Fn(f32) -> Vec3A>(&self, wo: Vec3A, wi: Vec3A, fresnel: F) -> (Vec3A, f32) {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return (Vec3A::ZERO, 0.0);
        }
        let h = wo + wi;
        if h.length_squared() == 0.0 {
            return (Vec3A::ZERO, 0.0);
        }
        let m = h.normalize();
        let g = &self.ggx;
        let cos_h = wi.dot(m);
        let mut f = fresnel(cos_h) * (g.d(m) * g.g(wo, wi) / (4.0 * wo.z));
        let pdf_ss = g.pdf_visible(wo, m) / (4.0 * wo.dot(m));
        if self.ms == Vec3A::ZERO {
            return (f, pdf_ss);
        }
        let (eo, ei) = (self.e(wo), self.e(wi));
        let denom = PI * (1.0 - self.e_avg);
        if denom > 1e-6 {
            f += self.ms * ((1.0 - eo) * (1.0 - ei) * wi.z / denom);
        }
        let p = (1.0 - eo).clamp(0.0, 1.0);
        (f, (1.0 - p) * pdf_ss + p * cosine_hemisphere_pdf(wi.z))
    }

    /// Draws `wi` for `wo` (upper hemisphere): `u_choice` picks single or multiple
    /// scattering, `u` the direction. None below the horizon.
    #[inline]
    pub fn sample(&self, wo: Vec3A, u_choice: f32, u: Vec2) -> Option<Vec3A> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = if u_choice < self.p_ms(wo) {
            cosine_hemisphere(u)
        } else {
            reflect(wo, self.ggx.sample_visible(wo, u))
        };
        (wi.z > 0.0).then_some(wi)
    }

    /// The multiple-scattering lobe's directional albedo from `wo`:
    /// `F_ms · (1 − E(ωo))`.
    pub fn ms_albedo(&self, wo: Vec3A) -> Vec3A {
        if self.ms == Vec3A::ZERO {
            Vec3A::ZERO
        } else {
            self.ms * (1.0 - self.e(wo))
        }
    }

    /// [`ms_albedo`](Self::ms_albedo) for a `wo` whose albedo with F = 1 the caller
    /// already looked up (`e_wo`).
    pub fn ms_albedo_given(&self, e_wo: f32) -> Vec3A {
        if self.ms == Vec3A::ZERO {
            Vec3A::ZERO
        } else {
            self.ms * (1.0 - e_wo)
        }
    }
}

/// A reflection lobe of roughness `alpha` (both 0: a smooth mirror, a delta lobe) with
/// Fresnel term `fresnel(cos θh)` (cosine-weighted mean `f_avg`, for the multiple
/// scattering) and `weight`: `f · cos θi` and pdf, the lobe's selection probability
/// `sel` included. The one evaluation the metal, dielectric-specular and thin-film
/// lobes share, whatever their Fresnel.
#[inline]
pub fn reflection_eval<F: Fn(f32) -> Vec3A>(
    alpha: Vec2,
    weight: f32,
    f_avg: Vec3A,
    wo: Vec3A,
    wi: Vec3A,
    sel: f32,
    fresnel: F,
) -> (Vec3A, f32) {
    reflection_eval_by(alpha, weight, wo, wi, sel, fresnel, || {
        MicrofacetReflection::new(alpha, f_avg)
    })
}

/// [`reflection_eval`] with the lobe's [`MicrofacetReflection`] built beforehand (a lobe
/// that keeps its own, so that no evaluation looks its tables up again).
#[inline]
pub fn reflection_eval_with<F: Fn(f32) -> Vec3A>(
    r: &MicrofacetReflection,
    alpha: Vec2,
    weight: f32,
    wo: Vec3A,
    wi: Vec3A,
    sel: f32,
    fresnel: F,
) -> (Vec3A, f32) {
    reflection_eval_by(alpha, weight, wo, wi, sel, fresnel, || *r)
}

/// The evaluation both forms share; `rough` gives the distribution, built only where
/// the lobe is rough and both directions are above the surface.
#[inline(always)]
fn reflection_eval_by<F: Fn(f32) -> Vec3A, R: FnOnce() -> MicrofacetReflection>(
    alpha: Vec2,
    weight: f32,
    wo: Vec3A,
    wi: Vec3A,
    sel: f32,
    fresnel: F,
    rough: R,
) -> (Vec3A, f32) {
    if is_smooth(alpha) || wo.z <= 0.0 || wi.z <= 0.0 {
        return (Vec3A::ZERO, 0.0);
    }
    let (f, pdf) = rough().eval(wo, wi, fresnel);
    (f * clamp_weight(weight), sel * pdf)
}

/// Samples the lobe [`reflection_eval`] evaluates: a smooth lobe returns its mirror
/// direction with its value, a rough one a direction for the Bsdf to evaluate.
#[inline]
pub fn reflection_sample<F: Fn(f32) -> Vec3A>(
    alpha: Vec2,
    weight: f32,
    f_avg: Vec3A,
    wo: Vec3A,
    ctx: SampleCtx,
    u: Vec2,
    fresnel: F,
) -> Option<LobeSample> {
    reflection_sample_by(alpha, weight, wo, ctx, u, fresnel, || {
        MicrofacetReflection::new(alpha, f_avg)
    })
}

/// [`reflection_sample`] with the lobe's [`MicrofacetReflection`] built beforehand.
#[inline]
pub fn reflection_sample_with<F: Fn(f32) -> Vec3A>(
    r: &MicrofacetReflection,
    alpha: Vec2,
    weight: f32,
    wo: Vec3A,
    ctx: SampleCtx,
    u: Vec2,
    fresnel: F,
) -> Option<LobeSample> {
    reflection_sample_by(alpha, weight, wo, ctx, u, fresnel, || *r)
}

/// The sampling both forms share; `rough` gives the rough lobe's distribution.
#[inline(always)]
fn reflection_sample_by<F: Fn(f32) -> Vec3A, R: FnOnce() -> MicrofacetReflection>(
    alpha: Vec2,
    weight: f32,
    wo: Vec3A,
    ctx: SampleCtx,
    u: Vec2,
    fresnel: F,
    rough: R,
) -> Option<LobeSample> {
    if wo.z <= 0.0 {
        return None;
    }
    if is_smooth(alpha) {
        let f = fresnel(wo.z) * clamp_weight(weight);
        return Some(LobeSample {
            sub: 0,
            wi: Vec3A::new(-wo.x, -wo.y, wo.z),
            eta: 1.0,
            value: Some((f / ctx.sel, ctx.sel, true)),
        });
    }
    let wi = rough().sample(wo, ctx.u_lobe, u)?;
    LobeSample::direction(0, wi)
}

/// A lobe whose alphas are both 0 (or not positive) is a delta lobe.
pub fn is_smooth(alpha: Vec2) -> bool {
    !(alpha.x > 0.0 || alpha.y > 0.0)
}

/// Lobe weights are mixing factors in [0, 1]; anything else (NaN too) is brought there.
pub fn clamp_weight(w: f32) -> f32 {
    if w > 0.0 {
        w.min(1.0)
    } else {
        0.0
    }
}

static REFLECT: [[LobeTag; 1]; 9] = reflect_tags(false);
static REFLECT_DELTA: [[LobeTag; 1]; 9] = reflect_tags(true);

const fn reflect_tags(delta: bool) -> [[LobeTag; 1]; 9] {
    let mut t = [[tag(false, Scatter::specular(0), delta)]; 9];
    let mut n = 0;
    while n < 9 {
        t[n] = [tag(false, Scatter::specular(n as u8), delta)];
        n += 1;
    }
    t
}

/// The LPE event of a specular reflection lobe numbered `lobe` (RenderMan's numbers:
/// 2 primary specular, 4 coat, 5 iridescence; docs/lpe.md), rough or smooth. Numbers
/// above 8 read as 8.
pub fn reflection_tags(lobe: u8, delta: bool) -> &'static [LobeTag] {
    let n = usize::from(lobe.min(8));
    if delta {
        &REFLECT_DELTA[n]
    } else {
        &REFLECT[n]
    }
}
