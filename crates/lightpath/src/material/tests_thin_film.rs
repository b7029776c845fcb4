//! Tests of the thin-film Fresnel against exact Fresnel equations written here, an
//! independent spectral integration, and the Gulbrandsen conductor mapping.

use super::thin_film::{PAPER_FIT, XYZ_TO_RGB};
use super::*;

/// Exact unpolarised Fresnel reflectance between real indices (s and p amplitudes).
fn dielectric(cos_i: f64, n1: f64, n2: f64) -> f64 {
    let sin2_t = (n1 / n2).powi(2) * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    let rp = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t);
    0.5 * (rs * rs + rp * rp)
}

/// Exact unpolarised Fresnel reflectance of a conductor η + iκ seen from a dielectric
/// of index `n1` (the closed form of pbrt-v3's `FrConductor`, for η/n1 and κ/n1).
fn conductor(cos_i: f64, n1: f64, eta: f64, kappa: f64) -> f64 {
    let (eta, k) = (eta / n1, kappa / n1);
    let c2 = cos_i * cos_i;
    let s2 = 1.0 - c2;
    let t0 = eta * eta - k * k - s2;
    let a2b2 = (t0 * t0 + 4.0 * eta * eta * k * k).sqrt();
    let t1 = a2b2 + c2;
    let a = (0.5 * (a2b2 + t0)).max(0.0).sqrt();
    let t2 = 2.0 * cos_i * a;
    let rs = (t1 - t2) / (t1 + t2);
    let t3 = c2 * a2b2 + s2 * s2;
    let t4 = t2 * s2;
    let rp = rs * (t3 - t4) / (t3 + t4);
    0.5 * (rp + rs)
}

const COSINES: [f32; 6] = [1.0, 0.9, 0.7, 0.5, 0.25, 0.05];

fn assert_close(got: Vec3A, want: [f64; 3], tol: f64, what: &str) {
    for c in 0..3 {
        assert!(
            (got[c] as f64 - want[c]).abs() <= tol,
            "{what}: channel {c}: {got} vs {want:?}"
        );
    }
}

/// A film of no thickness, or of the outside's index, is no film: the base's own
/// Fresnel reflectance, dielectric or conductor, in every channel.
#[test]
fn no_film_is_the_plain_fresnel_of_the_base() {
    let metals = [
        // Gold-like and silver-like colours, and a dark grey.
        (Vec3A::new(1.0, 0.78, 0.34), Vec3A::new(0.9, 0.8, 0.6)),
        (Vec3A::new(0.97, 0.96, 0.91), Vec3A::new(0.98, 0.97, 0.95)),
        (Vec3A::splat(0.3), Vec3A::splat(0.1)),
    ];
    for cos in COSINES {
        for outside in [1.0f32, 1.5] {
            for (film, thickness) in [(1.7f32, 0.0f32), (outside, 400.0), (1.3, -5.0)] {
                for eta in [1.2f32, 1.5, 2.4] {
                    let got = thin_film_fresnel(
                        cos,
                        outside,
                        film,
                        thickness,
                        FilmBase::Dielectric { eta },
                    );
                    let want = dielectric(cos as f64, outside as f64, eta as f64);
                    assert_close(
                        got,
                        [want; 3],
                        2e-5,
                        &format!("dielectric {eta}, cos {cos}, outside {outside}, film {film}/{thickness}"),
                    );
                }
                for (f0, tint) in metals {
                    let (eta, kappa) = conductor_ior_from_colors(f0, tint);
                    let got = thin_film_fresnel(
                        cos,
                        outside,
                        film,
                        thickness,
                        FilmBase::Conductor { eta, kappa },
                    );
                    let want: [f64; 3] = std::array::from_fn(|c| {
                        conductor(cos as f64, outside as f64, eta[c] as f64, kappa[c] as f64)
                    });
                    assert_close(
                        got,
                        want,
                        2e-5,
                        &format!(
                            "metal {f0}, cos {cos}, outside {outside}, film {film}/{thickness}"
                        ),
                    );
                }
            }
        }
    }
}

/// Every channel stays within [0, 1] and finite over angles, thicknesses 0–2000 nm and
/// indices 1–3, on dielectrics and conductors, from either side.
#[test]
fn reflectance_stays_within_zero_and_one() {
    let mut n = 0;
    for i in 0..=20 {
        let cos = i as f32 / 20.0;
        for t in 0..=40 {
            let thickness = t as f32 * 50.0;
            for film in [1.0f32, 1.3, 1.6, 2.0, 2.5, 3.0] {
                for outside in [1.0f32, 1.5] {
                    let mut bases = vec![];
                    for eta in [1.0f32, 1.5, 2.2, 3.0] {
                        bases.push(FilmBase::Dielectric { eta });
                    }
                    bases.push(FilmBase::Conductor {
                        eta: Vec3A::new(0.18, 0.42, 1.37),
                        kappa: Vec3A::new(3.42, 2.35, 1.77),
                    });
                    bases.push(FilmBase::Conductor {
                        eta: Vec3A::new(1.5, 2.0, 3.0),
                        kappa: Vec3A::ZERO,
                    });
                    for base in bases {
                        for sign in [1.0f32, -1.0] {
                            let r = thin_film_fresnel(sign * cos, outside, film, thickness, base);
                            assert!(
                                r.is_finite() && r.min_element() >= 0.0 && r.max_element() <= 1.0,
                                "cos {}, film {film}/{thickness}, outside {outside}, {base:?}: {r}",
                                sign * cos
                            );
                            n += 1;
                        }
                    }
                }
            }
        }
    }
    assert!(n > 50_000);
}

/// Against an independent computation, `tests_thin_film_reference.py` (f64): the exact
/// Airy reflectance |(r₁₂ + r₂₃ e^{iδ}) / (1 + r₁₂ r₂₃ e^{iδ})|² per polarisation,
/// integrated by quadrature over wavenumber against the paper's Gaussian sensitivities
/// (the densities whose Fourier transforms its code evaluates), converted like the
/// renderer. Differences: the series cut after m = 3 (at most 1.2e-4 in these cases, the
/// conductor's red; 1e-6 or less on dielectrics) and f32 rounding; tolerance 3e-4.
#[test]
fn matches_an_independent_spectral_integration() {
    let cases: [(f32, f32, f32, f32, FilmBase, [f64; 3]); 5] = [
        (
            0.8,
            1.0,
            1.33,
            300.0,
            FilmBase::Dielectric { eta: 1.5 },
            [0.045626, 0.018670, 0.010897],
        ),
        (
            0.3,
            1.0,
            1.8,
            500.0,
            FilmBase::Dielectric { eta: 1.5 },
            [0.318395, 0.234407, 0.272527],
        ),
        (
            0.6,
            1.0,
            1.4,
            400.0,
            FilmBase::Conductor {
                eta: Vec3A::new(0.2, 0.9, 1.1),
                kappa: Vec3A::new(3.0, 2.5, 2.2),
            },
            [0.872400, 0.624510, 0.512878],
        ),
        (
            0.9,
            1.5,
            2.0,
            250.0,
            FilmBase::Dielectric { eta: 1.3 },
            [0.156482, 0.062921, 0.018678],
        ),
        (
            1.0,
            1.0,
            1.3,
            650.0,
            FilmBase::Conductor {
                eta: Vec3A::new(0.18, 0.42, 1.37),
                kappa: Vec3A::new(3.42, 2.35, 1.77),
            },
            [0.954059, 0.726917, 0.354274],
        ),
    ];
    for (cos, outside, film, thickness, base, want) in cases {
        let got = thin_film_fresnel(cos, outside, film, thickness, base);
        assert_close(
            got,
            want,
            3e-4,
            &format!("cos {cos}, outside {outside}, film {film}/{thickness}, {base:?}"),
        );
    }
}

/// Interference colours: the reflected colour changes with thickness (a titania-like
/// film on glass at normal incidence goes through hues), unlike the plain Fresnel.
#[test]
fn colour_changes_with_thickness() {
    let base = FilmBase::Dielectric { eta: 1.5 };
    let mut red_wins = 0;
    let mut blue_wins = 0;
    let mut lo = Vec3A::ONE;
    let mut hi = Vec3A::ZERO;
    for t in 1..=40 {
        let r = thin_film_fresnel(1.0, 1.0, 2.0, t as f32 * 25.0, base);
        lo = lo.min(r);
        hi = hi.max(r);
        if r.x > 1.2 * r.z {
            red_wins += 1;
        }
        if r.z > 1.2 * r.x {
            blue_wins += 1;
        }
    }
    assert!(
        red_wins >= 3 && blue_wins >= 3,
        "red {red_wins}, blue {blue_wins}"
    );
    // Without the film every channel reflects 0.04 at normal incidence, whatever the
    // thickness; R₁₂ = 1/9 and R₂₃ ≈ 0.02 swing the film's ±2√(R₁₂R₂₃) ≈ ±0.1.
    assert!((hi - lo).min_element() > 0.1, "range {lo} .. {hi}");
}

/// Gulbrandsen's mapping reproduces the normal-incidence colour exactly, and the edge
/// tint changes the grazing colour.
#[test]
fn conductor_from_colours_reflects_f0_at_normal_incidence() {
    for f0 in [0.02f32, 0.2, 0.5, 0.9, 0.99] {
        for g in [0.0f32, 0.3, 0.7, 1.0] {
            let (eta, kappa) = conductor_ior_from_colors(Vec3A::splat(f0), Vec3A::splat(g));
            let r = conductor(1.0, 1.0, eta.x as f64, kappa.x as f64);
            assert!(
                (r - f0 as f64).abs() < 1e-4,
                "f0 {f0}, tint {g}: η {eta}, κ {kappa}: {r}"
            );
            assert!(eta.is_finite() && kappa.is_finite() && kappa.min_element() >= 0.0);
        }
    }
    let at = |g: f32| {
        let (eta, kappa) = conductor_ior_from_colors(Vec3A::splat(0.5), Vec3A::splat(g));
        conductor(0.2, 1.0, eta.x as f64, kappa.x as f64)
    };
    assert!(at(1.0) > at(0.0) + 0.02, "{} vs {}", at(1.0), at(0.0));
}

/// Nonsense input never gives NaN.
#[test]
fn bad_input_is_harmless() {
    let bases = [
        FilmBase::Dielectric { eta: f32::NAN },
        FilmBase::Dielectric { eta: -1.0 },
        FilmBase::Conductor {
            eta: Vec3A::new(0.0, -1.0, f32::NAN),
            kappa: Vec3A::new(-1.0, f32::INFINITY, 0.0),
        },
    ];
    for base in bases {
        for cos in [f32::NAN, 0.0, -0.0, 2.0, -3.0] {
            for (outside, film, thickness) in [
                (f32::NAN, 1.5, 300.0),
                (1.0, f32::NAN, 300.0),
                (1.0, 1.5, f32::NAN),
                (0.0, 0.0, f32::INFINITY),
                (1.0, 1.5, 1e9),
            ] {
                let r = thin_film_fresnel(cos, outside, film, thickness, base);
                assert!(
                    r.is_finite() && r.min_element() >= 0.0 && r.max_element() <= 1.0,
                    "{cos} {outside} {film} {thickness} {base:?}: {r}"
                );
            }
        }
    }
    let (eta, kappa) = conductor_ior_from_colors(Vec3A::splat(f32::NAN), Vec3A::splat(2.0));
    assert!(eta.is_finite() && kappa.is_finite());
}

/// The constants follow from the paper's fit and the sRGB standard.
#[test]
fn constants_follow_from_their_sources() {
    // Per channel, val·√(2π var) normalised to sum to one: X's two lobes.
    let w = |i: usize| PAPER_FIT[i].0 * (2.0 * std::f64::consts::PI * PAPER_FIT[i].2).sqrt();
    let x0 = w(0) / (w(0) + w(1));
    assert!((x0 - 0.846_202_2).abs() < 1e-6, "{x0}");
    // E white to RGB white; times diag(1/D65) it is IEC 61966-2-1's XYZ → sRGB matrix.
    let d65 = [0.3127 / 0.3290, 1.0, (1.0 - 0.3127 - 0.3290) / 0.3290];
    let srgb = [
        [3.2406, -1.5372, -0.4986],
        [-0.9689, 1.8758, 0.0415],
        [0.0557, -0.2040, 1.0570],
    ];
    for r in 0..3 {
        let row = XYZ_TO_RGB[r];
        assert!((row.x + row.y + row.z - 1.0).abs() < 1e-5, "row {r}: {row}");
        for c in 0..3 {
            assert!(
                (row[c] as f64 / d65[c] - srgb[r][c]).abs() < 1e-3,
                "({r}, {c}): {}",
                row[c] as f64 / d65[c]
            );
        }
    }
}

/// A film on a metal given by colours (OpenPBR's base colour and F82 tint) lies on the
/// complex index Gulbrandsen's mapping gives for f0 and the F82 model's reflectance at
/// 82° (as Blender Cycles maps a Principled metal under a thin film): for f0 0.05, tint 1
/// that is η 1.2474, κ 0.4488, and a 400 nm film of index 1.33 at normal incidence
/// reflects what the independent integration (`tests_thin_film_reference.py`, last case)
/// gives for that index. The tint itself as the mapping's colour (η 0.905) gave
/// (0.19, 0.06, 0.07), outside the tolerance.
#[test]
fn metal_film_follows_the_f82_reflectance() {
    use super::iridescence::Iridescence;
    let ir = Iridescence::on_metal(
        Vec3A::splat(0.05),
        Vec3A::ONE,
        1.33,
        400.0,
        1.0,
        glam::Vec2::splat(0.1),
    );
    let FilmBase::Conductor { eta, kappa } = ir.base else {
        panic!("a metal's film base is a conductor: {:?}", ir.base);
    };
    assert!((eta.x - 1.2474).abs() < 1e-3, "eta {eta}");
    assert!((kappa.x - 0.4488).abs() < 1e-3, "kappa {kappa}");
    let got = thin_film_fresnel(1.0, 1.0, 1.33, 400.0, ir.base);
    assert_close(
        got,
        [0.123877, 0.053547, 0.014913],
        3e-4,
        "f0 0.05 under 400 nm",
    );
}
