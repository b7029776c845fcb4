//! Thin-film interference (iridescence) on a Fresnel reflectance: Belcour & Barla 2017,
//! "A Practical Extension to Microfacet Theory for the Modeling of Varying Iridescence".
//!
//! A film of index η₂ and thickness d lies between the outside (η₁) and a base, a
//! dielectric or a conductor (complex index η₃ + iκ₃). Per polarisation, the Airy
//! reflectance is a Fourier series in the optical path difference OPD = 2 η₂ d cos θ₂
//! (the paper's equation 10): R = C₀ + 2 Σₘ Cₘ cos(m (2π OPD ν + φ)), ν the wavenumber.
//! Integrating it against a colour-matching function is then analytic: the paper fits
//! CIE 1931 XYZ by Gaussians in ν, whose Fourier transforms are closed form
//! ([`sensitivity`]). The series is cut after m = 3 as in the paper's code (the terms
//! fall as (R₁₂R₂₃)^(m/2)). XYZ is normalised so a flat reflectance R gives (R, R, R)
//! (illuminant E), scaled to the D65 white and converted to linear Rec.709 — as Blender
//! Cycles does — then clamped to [0, 1] (interference colours can leave the gamut).
//!
//! Below 30 nm the film's index blends towards the outside's, as Cycles and glTF's
//! `KHR_materials_iridescence` do, so a vanishing film is no film.
//!
//! A conductor's index differs per RGB channel: each channel runs the spectral
//! integration with its own index and keeps its own component. A metal given by
//! colours gets its index from [`conductor_ior_from_colors`] (Gulbrandsen 2014).

use glam::Vec3A;
use std::f32::consts::PI;

/// What lies under the film.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FilmBase {
    /// A dielectric of (absolute) index `eta`.
    Dielectric { eta: f32 },
    /// A conductor of complex index `eta + i·kappa` per RGB channel.
    Conductor { eta: Vec3A, kappa: Vec3A },
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
            let xyz =
                Film::new(cos1, outside, eta2, d).map_or(Vec3A::ONE, |f| f.xyz(C::real(under)));
            Vec3A::new(
                XYZ_TO_RGB[0].dot(xyz),
                XYZ_TO_RGB[1].dot(xyz),
                XYZ_TO_RGB[2].dot(xyz),
            )
        }
        FilmBase::Conductor { eta, kappa } => match Film::new(cos1, eta1, eta2, d) {
            None => Vec3A::ONE,
            Some(film) => {
                let mut out = [0.0; 3];
                for (c, o) in out.iter_mut().enumerate() {
                    let n3 = C {
                        re: positive_or(eta[c], 1e-4).max(1e-4),
                        im: if kappa[c] > 0.0 { kappa[c] } else { 0.0 },
                    };
                    *o = XYZ_TO_RGB[c].dot(film.xyz(n3));
                }
                Vec3A::from(out)
            }
        },
    };
    Vec3A::new(unit(rgb.x), unit(rgb.y), unit(rgb.z))
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

/// The paper's Gaussian fit of the CIE XYZ curves in wavenumber, as its code evaluates
/// their Fourier transforms: `val · √(2π var) · cos(pos·t + shift) · exp(−var·t²)` at
/// t = 2π·OPD, for X (two lobes), Y and Z. Here `pos` and `var` are per nanometre
/// (the paper's per-metre values × 10⁻⁹ and × 10⁻¹⁸), and `val · √(2π var)` is
/// normalised per channel so that t = 0 gives 1: (weight, pos, var, channel).
const LOBES: [(f32, f32, f32, usize); 4] = [
    (0.846_202_2, 1.6810e-3, 4.3278e-9, 0),
    (0.153_797_8, 2.2399e-3, 4.5282e-9, 0),
    (1.0, 1.7953e-3, 9.3046e-9, 1),
    (1.0, 2.2084e-3, 6.6121e-9, 2),
];

/// The paper's raw fit (val, pos, var in metres), from which [`LOBES`] follows.
#[cfg(test)]
pub(super) const PAPER_FIT: [(f64, f64, f64, usize); 4] = [
    (5.4856e-13, 1.6810e+06, 4.3278e+09, 0),
    (9.7470e-14, 2.2399e+06, 4.5282e+09, 0),
    (4.4201e-13, 1.7953e+06, 9.3046e+09, 1),
    (5.2481e-13, 2.2084e+06, 6.6121e+09, 2),
];

/// XYZ of illuminant E (flat, normalised to (1, 1, 1)) to linear Rec.709: the sRGB
/// matrix (primaries and D65 white of IEC 61966-2-1) times diag(D65 white), so E white
/// maps to RGB white (rows sum to one).
pub(super) const XYZ_TO_RGB: [Vec3A; 3] = [
    Vec3A::new(3.080_399, -1.537_383, -0.543_016),
    Vec3A::new(-0.921_223_4, 1.875_968, 0.045_255_86),
    Vec3A::new(0.052_873_94, -0.203_977, 1.151_103),
];

/// The normalised sensitivities' Fourier transform at optical path difference `opd`
/// (nm), split so that any phase shift is cheap: S(opd, shift) = A cos(shift) −
/// B sin(shift), returned as (A, B) (cos(x + s) = cos x cos s − sin x sin s).
fn sensitivity(opd: f32) -> (Vec3A, Vec3A) {
    let t = 2.0 * PI * opd;
    let mut a = [0.0f32; 3];
    let mut b = [0.0f32; 3];
    for (w, pos, var, c) in LOBES {
        let g = w * (-var * t * t).exp();
        let (sin, cos) = (pos * t).sin_cos();
        a[c] += g * cos;
        b[c] += g * sin;
    }
    (Vec3A::from(a), Vec3A::from(b))
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
        Some(Film {
            eta2,
            cos2,
            r12,
            orders: [1.0, 2.0, 3.0].map(|m| sensitivity(m * opd)),
        })
    }

    /// Spectrally integrated reflectance (XYZ, flat reflectance R → (R, R, R)) over a
    /// base of index `n3`.
    fn xyz(&self, n3: C) -> Vec3A {
        let Some((r23, _)) = amplitudes(self.eta2, n3, self.cos2) else {
            return Vec3A::ONE;
        };
        let mut sum = Vec3A::ZERO;
        for (a12, a23) in self.r12.into_iter().zip(r23) {
            sum += 0.5 * self.airy_sum(a12, a23);
        }
        sum
    }

    /// Equation 10 for one polarisation: amplitudes r₁₂ (outside → film) and r₂₃
    /// (film → base); r₂₁ = −r₁₂ gives the phase π − φ₁₂ + φ₂₃ of each round trip.
    fn airy_sum(&self, r12: C, r23: C) -> Vec3A {
        let big_r12 = r12.norm_sqr().min(1.0);
        let big_r23 = r23.norm_sqr().min(1.0);
        let r123 = big_r12 * big_r23;
        if r123 >= 1.0 || big_r23 >= 1.0 {
            // Total reflection at the base: a lossless film sends everything back.
            return Vec3A::ONE;
        }
        let t121 = 1.0 - big_r12;
        let rs = t121 * t121 * big_r23 / (1.0 - r123);
        let phi = PI - r12.arg() + r23.arg();
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
