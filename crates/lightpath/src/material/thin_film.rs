//! Thin-film interference (iridescence) on a Fresnel reflectance: Belcour & Barla 2017,
//! "A Practical Extension to Microfacet Theory for the Modeling of Varying Iridescence".
//!
//! A film of index η₂ and thickness d lies between the outside (η₁) and a base, a
//! dielectric or a conductor (complex index η₃ + iκ₃). Per polarisation, the Airy
//! reflectance is a Fourier series in the optical path difference OPD = 2 η₂ d cos θ₂
//! (the paper's equation 10): R = C₀ + 2 Σₘ Cₘ cos(m (2π OPD ν + φ)), ν the wavenumber.
//! Integrating it against a sensitivity curve then needs only the curve's Fourier
//! transform at m·OPD ([`Sensitivity`]). The series is cut after m = 3 as in the paper's
//! code (the terms fall as (R₁₂R₂₃)^(m/2)).
//!
//! The sensitivities are the CIE 1931 colour-matching functions (`cie1931_2deg.csv`)
//! turned into linear Rec.709 ones by the XYZ → RGB matrix, each normalised to unit area,
//! so a flat reflectance R gives (R, R, R): an equal-energy spectrum white-balanced per RGB
//! channel. That is what Blender Cycles 5.0 integrates, from a table of the
//! same functions' transform; the paper's Gaussian fit of XYZ, white-balanced in XYZ,
//! which Lightpath used before, differs from it by up to 13 % per channel on a dark
//! metal under a film (benches/materials/RESULTS.md). Interference colours can leave the
//! gamut: the result is clamped to [0, 1].
//!
//! Below 30 nm the film's index blends towards the outside's, as glTF's
//! `KHR_materials_iridescence` sample renderer does, so a vanishing film is no film.
//!
//! A conductor's index differs per RGB channel: each channel runs the spectral
//! integration with its own index and keeps its own component. A metal given by
//! colours gets its index from [`conductor_ior_from_colors`] (Gulbrandsen 2014).

use glam::Vec3A;
use std::f32::consts::PI;
use std::sync::OnceLock;

use super::fresnel::{f82_tint, MU_BAR};

/// What lies under the film.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FilmBase {
    /// A dielectric of (absolute) index `eta`.
    Dielectric { eta: f32 },
    /// A conductor of complex index `eta + i·kappa` per RGB channel.
    Conductor { eta: Vec3A, kappa: Vec3A },
    /// A metal given as the F82 model's colours, as OpenPBR and Blender's Principled BSDF
    /// describe one: `f0` at normal incidence and `f82`, its reflectance at μ̄ = 1/7
    /// (about 82°). Under the film it reflects as Blender Cycles 5.0 has it:
    /// the phase of a complex index from the two colours ([`conductor_ior_from_colors`]),
    /// the strength (s and p alike) of the F82 model with the same `f82` and the F0 of
    /// that index seen from the film. As the film's index goes to the outside's this is
    /// the bare F82 lobe, which a thin-film weight below one mixes with; the complex
    /// index's own Fresnel would depart from it towards grazing.
    F82 { f0: Vec3A, f82: Vec3A },
}

/// Reflectance of a film of index `film_ior` and thickness `thickness_nm` on `base`,
/// seen from a medium of index `eta_outside` at `cos_i` (the cosine of the angle of
/// incidence, for microfacets `wi·m`), per linear Rec.709 channel, in [0, 1].
///
/// A negative `cos_i` arrives from inside: under a dielectric the two sides swap (a
/// lossless stack reflects alike from both sides); a conductor is two-sided.
/// Nonsense indices fall back to no interface, a non-positive or NaN thickness to no
/// film; the result is never NaN.
pub fn thin_film_fresnel(
    cos_i: f32,
    eta_outside: f32,
    film_ior: f32,
    thickness_nm: f32,
    base: FilmBase,
) -> Vec3A {
    let eta1 = positive_or(eta_outside, 1.0);
    let mut cos1 = cos_i.abs();
    if cos1.is_nan() {
        cos1 = 1.0;
    }
    let cos1 = cos1.min(1.0);
    let d = if thickness_nm > 0.0 {
        thickness_nm
    } else {
        0.0
    };
    let mut eta2 = positive_or(film_ior, eta1);
    if d < 30.0 {
        eta2 = eta1 + (eta2 - eta1) * smoothstep(d / 30.0);
    }
    let rgb = match base {
        FilmBase::Dielectric { eta } => {
            let eta3 = positive_or(eta, eta1);
            let (outside, under) = if cos_i < 0.0 {
                (eta3, eta1)
            } else {
                (eta1, eta3)
            };
            Film::new(cos1, outside, eta2, d).map_or(Vec3A::ONE, |f| f.rgb(C::real(under), None))
        }
        FilmBase::Conductor { eta, kappa } => {
            per_channel(cos1, eta1, eta2, d, |c| (conductor(eta[c], kappa[c]), None))
        }
        FilmBase::F82 { f0, f82 } => {
            let (eta, kappa) = conductor_ior_from_colors(f0, f82);
            per_channel(cos1, eta1, eta2, d, |c| {
                let n3 = conductor(eta[c], kappa[c]);
                // F0 of the metal under the film; the F82 colour as given (Cycles does
                // the same, so that a film of the outside's index is the bare lobe).
                let f0 = n3.sub(C::real(eta2)).div(n3.add(C::real(eta2))).norm_sqr();
                let f82 = unit(f82[c]);
                let tint = f82_tint(Vec3A::splat(f0), Vec3A::ONE, MU_BAR).x;
                let tint = if tint > 0.0 { f82 / tint } else { 1.0 };
                (n3, Some((f0, tint)))
            })
        }
    };
    Vec3A::new(unit(rgb.x), unit(rgb.y), unit(rgb.z))
}

/// A conductor's reflectance per channel: channel `c` integrates the film over the
/// base `base(c)` gives (its index and, for an F82 metal, the F82 model's F0 and tint
/// for the strength of the reflection under the film) and keeps its own component.
fn per_channel(
    cos1: f32,
    eta1: f32,
    eta2: f32,
    d: f32,
    base: impl Fn(usize) -> (C, Option<(f32, f32)>),
) -> Vec3A {
    let Some(film) = Film::new(cos1, eta1, eta2, d) else {
        return Vec3A::ONE;
    };
    let mut out = [0.0; 3];
    for (c, o) in out.iter_mut().enumerate() {
        let (n3, f82) = base(c);
        *o = film.rgb(n3, f82)[c];
    }
    Vec3A::from(out)
}

/// A complex index from a conductor's (η, κ), nonsense replaced by a harmless index.
fn conductor(eta: f32, kappa: f32) -> C {
    C {
        re: positive_or(eta, 1e-4).max(1e-4),
        im: if kappa > 0.0 { kappa } else { 0.0 },
    }
}

/// A conductor's complex index (η, κ) per channel from its normal-incidence colour `f0`
/// and its edge tint (Gulbrandsen 2014, "Artist Friendly Metallic Fresnel"): the
/// conductor Fresnel of the result is `f0` at normal incidence, and the tint steers
/// the colour towards grazing. `f0` is clamped to [0, 0.99], the tint to [0, 1].
pub fn conductor_ior_from_colors(f0: Vec3A, edge_tint: Vec3A) -> (Vec3A, Vec3A) {
    let mut eta = [0.0; 3];
    let mut kappa = [0.0; 3];
    for c in 0..3 {
        let r = if f0[c] > 0.0 { f0[c].min(0.99) } else { 0.0 };
        let g = unit(edge_tint[c]);
        let sr = r.sqrt();
        let n = g * (1.0 - r) / (1.0 + r) + (1.0 - g) * (1.0 + sr) / (1.0 - sr);
        let k2 = (r * (n + 1.0) * (n + 1.0) - (n - 1.0) * (n - 1.0)) / (1.0 - r);
        eta[c] = n;
        kappa[c] = k2.max(0.0).sqrt();
    }
    (Vec3A::from(eta), Vec3A::from(kappa))
}

fn positive_or(x: f32, fallback: f32) -> f32 {
    if x > 0.0 && x.is_finite() {
        x
    } else {
        fallback
    }
}

/// Clamps to [0, 1], NaN to 0.
fn unit(x: f32) -> f32 {
    if x > 0.0 {
        x.min(1.0)
    } else {
        0.0
    }
}

fn smoothstep(t: f32) -> f32 {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// CIE XYZ (D65 white at Y = 1) to linear Rec.709: the inverse of the matrix whose columns
/// are the Rec.709 primaries scaled so that they sum to the D65 white, from IEC
/// 61966-2-1's chromaticities (the test `constants_follow_from_their_sources` derives it).
pub(super) const XYZ_TO_RGB: [[f64; 3]; 3] = [
    [3.240_969_942, -1.537_383_178, -0.498_610_760],
    [-0.969_243_636, 1.875_967_502, 0.041_555_057],
    [0.055_630_080, -0.203_976_959, 1.056_971_514],
];

/// The CIE 1931 colour-matching functions, 1 nm steps from 360 nm: (nm, x̄, ȳ, z̄).
pub(super) fn cie1931() -> Vec<[f64; 4]> {
    include_str!("cie1931_2deg.csv")
        .lines()
        .filter(|l| l.starts_with(|c: char| c.is_ascii_digit()))
        .map(|l| {
            let mut v = [0.0; 4];
            for (x, f) in v.iter_mut().zip(l.split(',')) {
                *x = f.trim().parse().expect("cie1931_2deg.csv: a number");
            }
            v
        })
        .collect()
}

/// Spacing and extent of the tabulated transform, in nm of optical path difference.
/// Beyond `OPD_MAX` the transform is about 10⁻⁴ and taken as zero (a film whose path
/// difference is tens of µm looks white: its colours average out within each channel).
const OPD_STEP: f64 = 5.0;
const OPD_MAX: f64 = 40_000.0;

/// The normalised RGB sensitivities' Fourier transform S(x) = ∫ s(ν) e^{2πiνx} dν over
/// the wavenumber ν, per channel, tabulated in x (nm of optical path difference). Each
/// channel is stored as its slowly varying envelope S(x)·e^{−2πiν̄x} about its mean
/// wavenumber ν̄, which linear interpolation follows closely at 5 nm steps (the
/// transform itself turns by 2πν̄·5 nm ≈ 0.06 rad a step, the envelope by less).
pub(super) struct Sensitivity {
    /// Mean wavenumber per channel, 1/nm.
    nu: [f64; 3],
    /// Envelope (re, im) per channel at x = i·OPD_STEP.
    envelope: Vec<[[f32; 2]; 3]>,
}

impl Sensitivity {
    /// The table, built on first use from the CIE data (a few milliseconds).
    pub(super) fn get() -> &'static Sensitivity {
        static TABLE: OnceLock<Sensitivity> = OnceLock::new();
        TABLE.get_or_init(Sensitivity::build)
    }

    fn build() -> Sensitivity {
        // s_c(λ) dλ = (XYZ_TO_RGB · x̄ȳz̄(λ))_c dλ, per 1 nm sample, normalised so
        // that each sums to one; ν = 1/λ.
        let cmf = cie1931();
        let mut weight = vec![[0.0f64; 3]; cmf.len()];
        let mut total = [0.0f64; 3];
        for (w, row) in weight.iter_mut().zip(&cmf) {
            for c in 0..3 {
                w[c] = (0..3).map(|j| XYZ_TO_RGB[c][j] * row[j + 1]).sum();
                total[c] += w[c];
            }
        }
        let mut nu = [0.0f64; 3];
        for (w, row) in weight.iter_mut().zip(&cmf) {
            for c in 0..3 {
                w[c] /= total[c];
                nu[c] += w[c] / row[0];
            }
        }
        // Each sample's phasor about the channel's ν̄, turned one step at a time.
        let steps = (OPD_MAX / OPD_STEP) as usize + 1;
        let mut envelope = vec![[[0.0f32; 2]; 3]; steps];
        for (w, row) in weight.iter().zip(&cmf) {
            for c in 0..3 {
                let turn = 2.0 * std::f64::consts::PI * (1.0 / row[0] - nu[c]) * OPD_STEP;
                let (sin, cos) = turn.sin_cos();
                let (mut re, mut im) = (w[c], 0.0f64);
                for e in envelope.iter_mut() {
                    e[c][0] += re as f32;
                    e[c][1] += im as f32;
                    (re, im) = (re * cos - im * sin, re * sin + im * cos);
                }
            }
        }
        Sensitivity { nu, envelope }
    }

    /// The transform at path difference `opd` (nm, ≥ 0) as (Re, Im) per channel: the
    /// sensitivity-weighted mean of cos and sin of 2πν·opd.
    pub(super) fn at(&self, opd: f32) -> (Vec3A, Vec3A) {
        let x = opd as f64 / OPD_STEP;
        if !(x >= 0.0 && x < (self.envelope.len() - 1) as f64) {
            return (Vec3A::ZERO, Vec3A::ZERO);
        }
        let i = x as usize;
        let t = (x - i as f64) as f32;
        let (e0, e1) = (self.envelope[i], self.envelope[i + 1]);
        let mut re = [0.0f32; 3];
        let mut im = [0.0f32; 3];
        for c in 0..3 {
            let a = e0[c][0] + t * (e1[c][0] - e0[c][0]);
            let b = e0[c][1] + t * (e1[c][1] - e0[c][1]);
            // The carrier in f64: ν̄·opd reaches hundreds of turns.
            let turn = self.nu[c] * opd as f64;
            let (sin, cos) = (2.0 * std::f64::consts::PI * turn.fract()).sin_cos();
            let (sin, cos) = (sin as f32, cos as f32);
            re[c] = a * cos - b * sin;
            im[c] = a * sin + b * cos;
        }
        (Vec3A::from(re), Vec3A::from(im))
    }
}

/// The film seen at one angle: the top interface and the sensitivities at the first
/// three path differences, shared by both polarisations and every base channel.
struct Film {
    eta2: f32,
    cos2: f32,
    r12: [C; 2],
    orders: [(Vec3A, Vec3A); 3],
}

impl Film {
    /// The film η₂ of thickness `d` nm under η₁, at cos θ₁ = `cos1` in [0, 1]; `None`
    /// on total reflection at the top (a film optically thinner than the outside).
    fn new(cos1: f32, eta1: f32, eta2: f32, d: f32) -> Option<Film> {
        let (r12, cos2) = amplitudes(eta1, C::real(eta2), cos1)?;
        let cos2 = cos2.real_part()?;
        let opd = 2.0 * eta2 * d * cos2;
        let sensitivity = Sensitivity::get();
        Some(Film {
            eta2,
            cos2,
            r12,
            orders: [1.0, 2.0, 3.0].map(|m| sensitivity.at(m * opd)),
        })
    }

    /// Spectrally integrated reflectance (linear Rec.709, flat reflectance R → (R, R, R))
    /// over a base of index `n3`; with `f82` = (F0, tint) the base reflects with the
    /// strength of the F82 model at θ₂ (see [`FilmBase::F82`]) and the phase of `n3`.
    fn rgb(&self, n3: C, f82: Option<(f32, f32)>) -> Vec3A {
        let Some((r23, _)) = amplitudes(self.eta2, n3, self.cos2) else {
            return Vec3A::ONE;
        };
        let strength =
            f82.map(|(f0, tint)| f82_tint(Vec3A::splat(f0), Vec3A::splat(tint), self.cos2).x);
        let mut sum = Vec3A::ZERO;
        for (a12, a23) in self.r12.into_iter().zip(r23) {
            let big_r23 = strength.unwrap_or_else(|| a23.norm_sqr());
            sum += 0.5 * self.airy_sum(a12, big_r23, a23.arg());
        }
        sum
    }

    /// Equation 10 for one polarisation: amplitude r₁₂ (outside → film), reflectance
    /// R₂₃ and phase φ₂₃ (film → base); r₂₁ = −r₁₂ gives the phase π − φ₁₂ + φ₂₃ of each
    /// round trip.
    fn airy_sum(&self, r12: C, big_r23: f32, phi23: f32) -> Vec3A {
        let big_r12 = r12.norm_sqr().min(1.0);
        let big_r23 = big_r23.min(1.0);
        let r123 = big_r12 * big_r23;
        if r123 >= 1.0 || big_r23 >= 1.0 {
            // Total reflection at the base: a lossless film sends everything back.
            return Vec3A::ONE;
        }
        let t121 = 1.0 - big_r12;
        let rs = t121 * t121 * big_r23 / (1.0 - r123);
        let phi = PI - r12.arg() + phi23;
        let mut out = Vec3A::splat(big_r12 + rs);
        let mut cm = rs - t121;
        let root = r123.sqrt();
        for (m, (a, b)) in self.orders.iter().enumerate() {
            cm *= root;
            let (sin, cos) = ((m + 1) as f32 * phi).sin_cos();
            out += 2.0 * cm * (*a * cos - *b * sin);
        }
        out
    }
}

/// Fresnel amplitudes (s, p) from a real index `n1` into `n2` at cos θ₁ = `cos1`, and
/// the (complex) cosine in `n2`; `None` on total internal reflection into a lossless
/// medium.
fn amplitudes(n1: f32, n2: C, cos1: f32) -> Option<([C; 2], C)> {
    let sin2 = (1.0 - cos1 * cos1).max(0.0);
    let ratio2 = C::real(n1 * n1).div(n2.mul(n2));
    let cos2_sq = C::real(1.0).sub(ratio2.scale(sin2));
    if n2.im == 0.0 && cos2_sq.re <= 0.0 {
        return None;
    }
    let mut cos2 = cos2_sq.sqrt();
    // The transmitted wave decays into an absorbing medium: Im(n₂ cos θ₂) ≥ 0.
    if n2.mul(cos2).im < 0.0 {
        cos2 = cos2.scale(-1.0);
    }
    let a = C::real(n1 * cos1);
    let b = n2.mul(cos2);
    let rs = a.sub(b).div(a.add(b));
    let c = n2.scale(cos1);
    let e = cos2.scale(n1);
    let rp = c.sub(e).div(c.add(e));
    Some(([rs, rp], cos2))
}

/// A complex number, just what the Fresnel amplitudes need.
#[derive(Clone, Copy, Debug)]
struct C {
    re: f32,
    im: f32,
}

impl C {
    fn real(re: f32) -> C {
        C { re, im: 0.0 }
    }
    fn add(self, o: C) -> C {
        C {
            re: self.re + o.re,
            im: self.im + o.im,
        }
    }
    fn sub(self, o: C) -> C {
        C {
            re: self.re - o.re,
            im: self.im - o.im,
        }
    }
    fn mul(self, o: C) -> C {
        C {
            re: self.re * o.re - self.im * o.im,
            im: self.re * o.im + self.im * o.re,
        }
    }
    fn scale(self, s: f32) -> C {
        C {
            re: self.re * s,
            im: self.im * s,
        }
    }
    fn div(self, o: C) -> C {
        let d = o.norm_sqr();
        if d == 0.0 {
            return C::real(0.0);
        }
        C {
            re: (self.re * o.re + self.im * o.im) / d,
            im: (self.im * o.re - self.re * o.im) / d,
        }
    }
    fn norm_sqr(self) -> f32 {
        self.re * self.re + self.im * self.im
    }
    fn arg(self) -> f32 {
        self.im.atan2(self.re)
    }
    /// Principal square root.
    fn sqrt(self) -> C {
        let r = self.norm_sqr().sqrt();
        let re = ((r + self.re) * 0.5).max(0.0).sqrt();
        let im = ((r - self.re) * 0.5).max(0.0).sqrt();
        C {
            re,
            im: if self.im < 0.0 { -im } else { im },
        }
    }
    /// The real value of a cosine into a lossless medium (no evanescent part).
    fn real_part(self) -> Option<f32> {
        (self.im == 0.0 && self.re > 0.0).then_some(self.re)
    }
}
