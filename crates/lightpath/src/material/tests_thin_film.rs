//! Tests of the thin-film Fresnel against exact Fresnel equations written here, an
//! independent spectral integration, and the Gulbrandsen conductor mapping.

use super::fresnel::{f82_tint, MU_BAR};
use super::thin_film::{cie1931, Sensitivity, XYZ_TO_RGB};
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
                    if outside == 1.0 {
                        // Seen from air, a metal by F82 colours is the bare F82 lobe
                        // (for f0 up to 0.99, where Gulbrandsen's mapping clamps it).
                        let f0 = f0.min(Vec3A::splat(0.99));
                        let f82 = f82_tint(f0, tint, MU_BAR);
                        let got = thin_film_fresnel(
                            cos,
                            outside,
                            film,
                            thickness,
                            FilmBase::F82 { f0, f82 },
                        );
                        let want = f82_tint(f0, tint, cos);
                        assert_close(
                            got,
                            [want.x as f64, want.y as f64, want.z as f64],
                            2e-5,
                            &format!("F82 metal {f0}, cos {cos}, film {film}/{thickness}"),
                        );
                    }
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
                    bases.push(FilmBase::F82 {
                        f0: Vec3A::new(0.05, 0.5, 0.95),
                        f82: Vec3A::new(0.2, 0.9, 1.0),
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
/// integrated by quadrature over wavelength against the CIE 1931 functions made linear
/// Rec.709 sensitivities. Differences: the series cut after m = 3 (1.7e-4 on the first
/// conductor's red, 1.5e-5 or less elsewhere), the tabulated and interpolated transform,
/// the 1 nm sums and f32 rounding; tolerance 3e-4.
#[test]
fn matches_an_independent_spectral_integration() {
    let cases: [(f32, f32, f32, f32, FilmBase, [f64; 3]); 8] = [
        (
            0.8,
            1.0,
            1.33,
            300.0,
            FilmBase::Dielectric { eta: 1.5 },
            [0.041247, 0.018883, 0.010756],
        ),
        (
            0.3,
            1.0,
            1.8,
            500.0,
            FilmBase::Dielectric { eta: 1.5 },
            [0.307654, 0.236891, 0.273385],
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
            [0.877752, 0.625614, 0.513383],
        ),
        (
            0.9,
            1.5,
            2.0,
            250.0,
            FilmBase::Dielectric { eta: 1.3 },
            [0.138701, 0.065536, 0.017971],
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
            [0.949982, 0.731937, 0.356700],
        ),
        (
            0.7,
            1.0,
            1.6,
            900.0,
            FilmBase::F82 {
                f0: Vec3A::new(0.9, 0.6, 0.3),
                f82: Vec3A::new(0.8, 0.7, 0.5),
            },
            [0.834777, 0.490332, 0.236470],
        ),
        (
            1.0,
            1.0,
            1.33,
            400.0,
            FilmBase::F82 {
                f0: Vec3A::splat(0.05),
                f82: Vec3A::splat(0.4895311),
            },
            [0.109433, 0.056429, 0.014326],
        ),
        (
            0.5,
            1.0,
            1.33,
            400.0,
            FilmBase::F82 {
                f0: Vec3A::splat(0.05),
                f82: Vec3A::splat(0.4895311),
            },
            [0.029824, 0.069242, 0.132217],
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

/// The constants follow from their sources: the matrix from IEC 61966-2-1's
/// chromaticities, the CIE table is the 1931 observer (ȳ peaks at 1 at 555 nm, and the
/// three functions have equal areas: the equal-energy white is x = y = 1/3), and the
/// tabulated transform is one at zero path difference and falls off at large ones.
#[test]
fn constants_follow_from_their_sources() {
    let xyz = |x: f64, y: f64| [x / y, 1.0, (1.0 - x - y) / y];
    let prim = [xyz(0.64, 0.33), xyz(0.30, 0.60), xyz(0.15, 0.06)];
    let white = xyz(0.3127, 0.3290);
    // RGB → XYZ has columns prim[j]·s[j], with s such that RGB (1, 1, 1) is the white.
    let m: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|j| prim[j][i]));
    let s: [f64; 3] = std::array::from_fn(|j| (0..3).map(|k| inv3(m)[j][k] * white[k]).sum());
    let rgb_to_xyz: [[f64; 3]; 3] =
        std::array::from_fn(|i| std::array::from_fn(|j| m[i][j] * s[j]));
    let want = inv3(rgb_to_xyz);
    for r in 0..3 {
        for c in 0..3 {
            assert!(
                (XYZ_TO_RGB[r][c] - want[r][c]).abs() < 1e-8,
                "({r}, {c}): {} vs {}",
                XYZ_TO_RGB[r][c],
                want[r][c]
            );
        }
        let w: f64 = (0..3).map(|c| XYZ_TO_RGB[r][c] * white[c]).sum();
        assert!((w - 1.0).abs() < 1e-8, "white row {r}: {w}");
    }

    let cmf = cie1931();
    assert_eq!(cmf.len(), 471);
    assert_eq!((cmf[0][0], cmf[470][0]), (360.0, 830.0));
    assert_eq!(cmf[195], [555.0, 0.5120501, 1.0, 0.005749999]);
    let area: [f64; 3] = std::array::from_fn(|c| cmf.iter().map(|r| r[c + 1]).sum());
    for c in 0..3 {
        assert!((area[c] / area[1] - 1.0).abs() < 1e-3, "areas {area:?}");
    }

    let (re, im) = Sensitivity::get().at(0.0);
    assert!((re - Vec3A::ONE).abs().max_element() < 1e-5, "{re}");
    assert!(im.abs().max_element() < 1e-5, "{im}");
    for opd in [20_000.0, 39_000.0, 50_000.0] {
        let (re, im) = Sensitivity::get().at(opd);
        assert!(
            re.abs().max_element() + im.abs().max_element() < 3e-3,
            "{opd}: {re} {im}"
        );
    }
}

fn inv3(m: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let [[a, b, c], [d, e, f], [g, h, i]] = m;
    let det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g);
    [
        [e * i - f * h, c * h - b * i, b * f - c * e],
        [f * g - d * i, a * i - c * g, c * d - a * f],
        [d * h - e * g, b * g - a * h, a * e - b * d],
    ]
    .map(|row| row.map(|v| v / det))
}

/// The tabulated transform against a direct sum over the CIE table at path differences
/// off the table's 5 nm grid: interpolating the envelope loses less than 2e-4.
#[test]
fn tabulated_sensitivity_matches_a_direct_sum() {
    let cmf = cie1931();
    let s: Vec<[f64; 3]> = cmf
        .iter()
        .map(|r| std::array::from_fn(|c| (0..3).map(|j| XYZ_TO_RGB[c][j] * r[j + 1]).sum()))
        .collect();
    let total: [f64; 3] = std::array::from_fn(|c| s.iter().map(|v| v[c]).sum());
    for opd in [1.0f32, 333.3, 802.7, 1999.9, 3141.6, 7777.7] {
        let (re, im) = Sensitivity::get().at(opd);
        for c in 0..3 {
            let (mut a, mut b) = (0.0, 0.0);
            for (v, r) in s.iter().zip(&cmf) {
                let t = 2.0 * std::f64::consts::PI * opd as f64 / r[0];
                a += v[c] * t.cos() / total[c];
                b += v[c] * t.sin() / total[c];
            }
            assert!(
                (re[c] as f64 - a).abs() < 2e-4 && (im[c] as f64 - b).abs() < 2e-4,
                "opd {opd}, channel {c}: ({}, {}) vs ({a}, {b})",
                re[c],
                im[c]
            );
        }
    }
}

/// A film on a metal given by colours (OpenPBR's base colour and F82 tint) lies on the
/// metal the bare lobe shows, the F82 model's reflectance at 82° passed on (for f0 0.05,
/// tint 1 that is 0.4895), and reflects as Blender Cycles 5.0.1 renders it:
/// `benches/materials/thin_film_sphere.py` renders a smooth sphere of that metal under a
/// 400 nm film of index 1.33 in a white world and prints the mean colour at each viewing
/// cosine (from the sphere's normal pass). Tolerance 1e-3 (measured: 6e-4 at most, near
/// grazing): pixels average over ±0.004 in cosine, and Cycles interpolates its own table
/// of the transform.
#[test]
fn metal_film_matches_blender_cycles() {
    use super::iridescence::Iridescence;
    let ir = Iridescence::on_metal(
        Vec3A::splat(0.05),
        Vec3A::ONE,
        1.33,
        400.0,
        1.0,
        glam::Vec2::splat(0.1),
    );
    let FilmBase::F82 { f0, f82 } = ir.base else {
        panic!("a metal's film base is an F82 metal: {:?}", ir.base);
    };
    assert_eq!(f0, Vec3A::splat(0.05));
    assert!((f82.x - 0.48953).abs() < 1e-4, "f82 {f82}");
    for (cos, cycles) in CYCLES_SPHERE {
        let got = thin_film_fresnel(cos, 1.0, 1.33, 400.0, ir.base);
        assert_close(got, cycles, 1e-3, &format!("cos {cos}"));
    }
}

/// `benches/materials/thin_film_sphere.py`'s output (Blender 5.0.1): viewing cosine and
/// the mean colour of the pixels there.
const CYCLES_SPHERE: [(f32, [f64; 3]); 11] = [
    (0.9980, [0.10901, 0.05706, 0.01395]),
    (0.9498, [0.10072, 0.07218, 0.00480]),
    (0.8999, [0.08839, 0.08518, 0.00268]),
    (0.8003, [0.05829, 0.09871, 0.02140]),
    (0.6997, [0.03125, 0.09544, 0.05990]),
    (0.6001, [0.01876, 0.08188, 0.09967]),
    (0.5005, [0.02994, 0.06934, 0.13182]),
    (0.3999, [0.07727, 0.07256, 0.15905]),
    (0.2993, [0.17513, 0.11518, 0.19698]),
    (0.2011, [0.33620, 0.23022, 0.27878]),
    (0.0985, [0.60143, 0.49151, 0.49145]),
];
