//! Tests of the fuzz lobe: χ² of its sampling, its albedo against the table, energy,
//! and the white furnace of fuzz over a diffuse base. The χ² harness follows the one
//! in `tests.rs` (pbrt-v4's bsdfs_test.cpp), kept here so the two files merge freely.

use super::lobe::SampleCtx;
use super::*;
use crate::light::luminance;
use crate::sampling::{cosine_hemisphere, cosine_hemisphere_pdf, Rng};
use std::f64::consts::PI;

fn dir(theta_deg: f32, phi_deg: f32) -> Vec3A {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    Vec3A::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

fn local(wo: Vec3A) -> Shading {
    Shading {
        frame: Frame::new(Vec3A::Z),
        wo,
    }
}

fn fuzz(roughness: f32) -> Fuzz {
    Fuzz {
        color: Vec3A::new(0.9, 0.6, 0.3),
        weight: 0.8,
        roughness,
    }
}

/// The lobe sampled alone with selection probability one; the weight is `f / pdf` from
/// `eval`, as inside a multi-lobe Bsdf.
fn draw(lobe: &Lobe, wo: Vec3A, rng: &mut Rng) -> Option<(Vec3A, Vec3A)> {
    let ctx = SampleCtx {
        sel: 1.0,
        u_lobe: rng.next_f32(),
        alone: false,
    };
    let s = lobe.sample(wo, ctx, rng.next_2d())?;
    assert!(s.value.is_none(), "fuzz is evaluated by the Bsdf");
    let (f, pdf) = lobe.eval(s.sub, wo, s.wi, 1.0);
    if pdf <= 0.0 {
        return None;
    }
    Some((s.wi, f / pdf))
}

/// Mean and standard error of the mean.
fn mean_se(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut n, mut s, mut s2) = (0.0, 0.0, 0.0);
    for v in values {
        n += 1.0;
        s += v;
        s2 += v * v;
    }
    let mean = s / n;
    let var = (s2 / n - mean * mean).max(0.0) * n / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// f32 rounding of values that every sample shares (their standard error is zero).
const ROUNDING: f64 = 1e-5;

// ---- χ² goodness of fit --------------------------------------------------------------

const THETA_BINS: usize = 10;
const PHI_BINS: usize = 20;
const CHI2_SAMPLES: usize = 200_000;

fn bin_of(w: Vec3A) -> usize {
    let theta = (w.z.clamp(-1.0, 1.0) as f64).acos();
    let mut phi = (w.y as f64).atan2(w.x as f64);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let t = ((theta / PI * THETA_BINS as f64) as usize).min(THETA_BINS - 1);
    let p = ((phi / (2.0 * PI) * PHI_BINS as f64) as usize).min(PHI_BINS - 1);
    t * PHI_BINS + p
}

/// The pdf integrated over each bin (midpoint rule on a fine θ×φ grid).
fn expected_counts(pdf: impl Fn(Vec3A) -> f32, n: usize) -> Vec<f64> {
    const SUB: usize = 32;
    let (dt, dp) = (
        PI / (THETA_BINS * SUB) as f64,
        2.0 * PI / (PHI_BINS * SUB) as f64,
    );
    let mut e = vec![0.0; THETA_BINS * PHI_BINS];
    for i in 0..THETA_BINS * SUB {
        let theta = (i as f64 + 0.5) * dt;
        for j in 0..PHI_BINS * SUB {
            let phi = (j as f64 + 0.5) * dp;
            let w = Vec3A::new(
                (theta.sin() * phi.cos()) as f32,
                (theta.sin() * phi.sin()) as f32,
                theta.cos() as f32,
            );
            e[(i / SUB) * PHI_BINS + j / SUB] += pdf(w) as f64 * theta.sin() * dt * dp * n as f64;
        }
    }
    e
}

/// ln Γ(x), Lanczos (g = 7, n = 9).
fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    let x = x - 1.0;
    let t = x + 7.5;
    let s = C[1..]
        .iter()
        .enumerate()
        .fold(C[0], |s, (i, c)| s + c / (x + i as f64 + 1.0));
    0.5 * (2.0 * PI).ln() + (x + 0.5) * t.ln() - t + s.ln()
}

/// Upper regularised incomplete gamma Q(a, x) (Numerical Recipes §6.2).
fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let front = (-x + a * x.ln() - ln_gamma(a)).exp();
    if x < a + 1.0 {
        let (mut ap, mut del, mut sum) = (a, 1.0 / a, 1.0 / a);
        for _ in 0..10_000 {
            ap += 1.0;
            del *= x / ap;
            sum += del;
            if del.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        1.0 - sum * front
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-15 {
                break;
            }
        }
        front * h
    }
}

#[test]
fn chi2_survival_matches_known_values() {
    for (x, k, p) in [
        (3.841, 1.0, 0.05),
        (23.209, 10.0, 0.01),
        (124.342, 100.0, 0.05),
    ] {
        let q = gamma_q(k / 2.0, x / 2.0);
        assert!((q - p).abs() < 2e-4, "χ²({k}) at {x}: {q}");
    }
}

/// p-value of observed vs expected counts (bins expecting fewer than 5 pooled); Err if
/// a sample fell where the pdf integrates to zero.
fn chi2_p_value(observed: &[u64], expected: &[f64]) -> Result<f64, String> {
    let mut order: Vec<usize> = (0..expected.len()).collect();
    order.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let (mut chi2, mut dof) = (0.0, 0usize);
    let (mut pool_obs, mut pool_exp) = (0.0, 0.0);
    for i in order {
        let (o, e) = (observed[i] as f64, expected[i]);
        if e == 0.0 {
            if o > 0.0 {
                return Err(format!("{o} samples in bin {i} where the pdf is zero"));
            }
        } else if e < 5.0 || (pool_exp > 0.0 && pool_exp < 5.0) {
            pool_obs += o;
            pool_exp += e;
        } else {
            chi2 += (o - e) * (o - e) / e;
            dof += 1;
        }
    }
    if pool_exp > 0.0 || pool_obs > 0.0 {
        chi2 += (pool_obs - pool_exp) * (pool_obs - pool_exp) / pool_exp;
        dof += 1;
    }
    let dof = dof.saturating_sub(1).max(1);
    Ok(gamma_q(dof as f64 / 2.0, chi2 / 2.0))
}

fn chi2_case(
    what: &str,
    sample: &mut dyn FnMut() -> Option<Vec3A>,
    pdf: &dyn Fn(Vec3A) -> f32,
    threshold: f64,
) -> Option<String> {
    let mut observed = vec![0u64; THETA_BINS * PHI_BINS];
    for _ in 0..CHI2_SAMPLES {
        if let Some(wi) = sample() {
            observed[bin_of(wi)] += 1;
        }
    }
    let expected = expected_counts(pdf, CHI2_SAMPLES);
    match chi2_p_value(&observed, &expected) {
        Ok(p) if p >= threshold => None,
        Ok(p) => Some(format!("{what}: p = {p:e} < {threshold:e}")),
        Err(e) => Some(format!("{what}: {e}")),
    }
}

/// Šidák-corrected significance for `n` tests at overall level 0.01.
fn sidak(n: usize) -> f64 {
    1.0 - 0.99f64.powf(1.0 / n as f64)
}

const ROUGHNESSES: [f32; 3] = [0.3, 0.6, 1.0];

fn wos() -> [Vec3A; 3] {
    [dir(10.0, 0.0), dir(50.0, 130.0), dir(80.0, 250.0)]
}

#[test]
fn chi2_fuzz_samples_follow_its_pdf() {
    let threshold = sidak(ROUGHNESSES.len() * wos().len());
    let mut failures = Vec::new();
    for (i, &r) in ROUGHNESSES.iter().enumerate() {
        let lobe = Lobe::from(fuzz(r));
        for (j, wo) in wos().into_iter().enumerate() {
            let mut rng = Rng::for_sample(21, i as u64, j as u64);
            let mut sample = || draw(&lobe, wo, &mut rng).map(|d| d.0);
            let pdf = |wi: Vec3A| lobe.eval(0, wo, wi, 1.0).1;
            failures.extend(chi2_case(
                &format!("fuzz roughness {r}, wo {wo}"),
                &mut sample,
                &pdf,
                threshold,
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Fuzz beside a diffuse lobe through `Bsdf::sample`: selection and pdfs together.
#[test]
fn chi2_fuzz_over_diffuse_follows_the_bsdf_pdf() {
    let bsdf = Bsdf::layered(
        &[
            Lambert {
                albedo: Vec3A::splat(0.5),
            }
            .into(),
            fuzz(0.5).into(),
        ],
        None,
        Vec3A::splat(0.5),
    );
    let threshold = sidak(wos().len());
    let mut failures = Vec::new();
    for (i, wo) in wos().into_iter().enumerate() {
        let sh = local(wo);
        let mut rng = Rng::for_sample(22, i as u64, 0);
        let mut sample = || {
            bsdf.sample(&sh, rng.next_f32(), rng.next_2d())
                .map(|s| sh.frame.to_local(s.wi))
        };
        let pdf = |wi: Vec3A| {
            (0..bsdf.lobes().len())
                .map(|k| bsdf.eval_lobe(k, &sh, wi).1)
                .sum()
        };
        failures.extend(chi2_case(
            &format!("diffuse + fuzz, wo {wo}"),
            &mut sample,
            &pdf,
            threshold,
        ));
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn fuzz_emits_rs6_and_no_delta() {
    let t = Lobe::from(fuzz(0.5)).tags();
    assert_eq!(t.len(), 1);
    assert!(!t[0].transmit && !t[0].delta);
    assert_eq!(t[0].scatter, lpe::Scatter::specular(6));
}

// ---- Albedo and energy -------------------------------------------------------------------

/// Every sample weighs colour · weight · R(μo): the LTC is sampled exactly.
#[test]
fn sampled_weight_is_the_table_albedo_times_colour() {
    for &r in &ROUGHNESSES {
        let f = fuzz(r);
        let lobe = Lobe::from(f);
        for wo in wos() {
            let want = f.color * f.albedo(wo.z);
            let mut rng = Rng::for_sample(23, 0, 0);
            let mut n = 0;
            for _ in 0..2000 {
                if let Some((_, w)) = draw(&lobe, wo, &mut rng) {
                    assert!(
                        (w - want).abs().max_element() <= 1e-4 * want.max_element(),
                        "roughness {r}, wo {wo}: {w} vs {want}"
                    );
                    n += 1;
                }
            }
            assert!(n > 1990, "roughness {r}, wo {wo}: only {n} samples");
        }
    }
}

/// ∫ f · cos dωi by cosine-weighted sampling of `eval` (independent of the lobe's own
/// sampling) equals colour · weight · R(μo) from the table, within 5 standard errors.
#[test]
fn integrated_eval_equals_the_table_albedo() {
    let mut failures = Vec::new();
    for (i, &r) in [0.1, 0.3, 0.6, 1.0].iter().enumerate() {
        let f = fuzz(r);
        let lobe = Lobe::from(f);
        for (j, wo) in [
            dir(0.0, 0.0),
            dir(30.0, 40.0),
            dir(60.0, 200.0),
            dir(85.0, 300.0),
        ]
        .into_iter()
        .enumerate()
        {
            let mut rng = Rng::for_sample(24, i as u64, j as u64);
            let got = mean_se((0..400_000).map(|_| {
                let wi = cosine_hemisphere(rng.next_2d());
                let pdf = cosine_hemisphere_pdf(wi.z);
                if pdf <= 0.0 {
                    return 0.0;
                }
                (luminance(lobe.eval(0, wo, wi, 1.0).0) / pdf) as f64
            }));
            let want = (luminance(f.color) * f.albedo(wo.z)) as f64;
            assert!(want > 0.0, "roughness {r}, wo {wo}: no albedo");
            if (got.0 - want).abs() > 5.0 * got.1 + ROUNDING {
                failures.push(format!("roughness {r}, wo {wo}: {got:?} vs table {want}"));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// White fuzz of full weight reflects at most all the light, at any angle and roughness
/// (the table's largest albedo is 0.75), and nothing from below the horizon.
#[test]
fn white_fuzz_never_reflects_more_than_it_receives() {
    let mut max: f32 = 0.0;
    for i in 0..=40 {
        for j in 0..=40 {
            let f = Fuzz {
                color: Vec3A::ONE,
                weight: 1.0,
                roughness: i as f32 / 40.0,
            };
            let a = f.albedo(j as f32 / 40.0);
            assert!(
                (0.0..=1.0).contains(&a),
                "{f:?} at μ {}: {a}",
                j as f32 / 40.0
            );
            max = max.max(a);
            assert_eq!(f.albedo(-(j as f32) / 40.0), 0.0);
        }
    }
    assert!(max > 0.7, "largest albedo {max}");
}

/// The table's shape (which a transposed or misread table would break): the fuzz
/// reflects more towards grazing at every roughness, and more with roughness away
/// from grazing.
#[test]
fn albedo_grows_with_roughness_and_towards_grazing() {
    let albedo = |r: f32, mu: f32| {
        Fuzz {
            color: Vec3A::ONE,
            weight: 1.0,
            roughness: r,
        }
        .albedo(mu)
    };
    for i in 0..=50 {
        for j in 2..=50 {
            let (r, mu) = (i as f32 / 50.0, j as f32 / 50.0);
            assert!(
                albedo(r, mu) <= albedo(r, mu - 0.02) + 1e-6,
                "α {r}, μ {mu}"
            );
            if i > 0 {
                assert!(
                    albedo(r, mu) + 1e-6 >= albedo(r - 0.02, mu),
                    "α {r}, μ {mu}"
                );
            }
        }
    }
    assert!(albedo(1.0, 0.02) > 0.7 && albedo(1.0, 1.0) < 0.4);
    assert!(albedo(0.2, 1.0) < 1e-3);
}

/// Fuzz over a white Lambertian scaled by 1 − weight · R(μo), as the layering does,
/// keeps a white furnace white.
#[test]
fn white_furnace_of_fuzz_over_white_diffuse() {
    let mut failures = Vec::new();
    for (i, &(r, weight)) in [(0.2, 1.0), (0.5, 1.0), (1.0, 1.0), (0.7, 0.5)]
        .iter()
        .enumerate()
    {
        for (j, wo) in [
            dir(5.0, 0.0),
            dir(45.0, 60.0),
            dir(80.0, 200.0),
            dir(89.0, 10.0),
        ]
        .into_iter()
        .enumerate()
        {
            let f = Fuzz {
                color: Vec3A::ONE,
                weight,
                roughness: r,
            };
            let base = Lambert {
                albedo: Vec3A::splat(1.0 - f.albedo(wo.z)),
            };
            let bsdf = Bsdf::layered(&[base.into(), f.into()], None, Vec3A::ONE);
            let sh = local(wo);
            let mut rng = Rng::for_sample(25, i as u64, j as u64);
            // As the renderer sees it (lobe selection, each lobe's own sampling) …
            let sampled = mean_se((0..100_000).map(|_| {
                bsdf.sample(&sh, rng.next_f32(), rng.next_2d())
                    .map_or(0.0, |s| luminance(s.weight) as f64)
            }));
            // … and by cosine sampling of every lobe's `eval`, which checks the fuzz's
            // integral against the table albedo that scaled the base.
            let integrated = mean_se((0..400_000).map(|_| {
                let wi = cosine_hemisphere(rng.next_2d());
                let pdf = cosine_hemisphere_pdf(wi.z);
                if pdf <= 0.0 {
                    return 0.0;
                }
                let f: Vec3A = (0..bsdf.lobes().len())
                    .map(|k| bsdf.eval_lobe(k, &sh, wi).0)
                    .sum();
                (luminance(f) / pdf) as f64
            }));
            for (how, (mean, se)) in [("sampled", sampled), ("integrated", integrated)] {
                let within =
                    (0.98..=1.01).contains(&mean) && (mean - 1.0).abs() <= 5.0 * se + ROUNDING;
                if !within {
                    failures.push(format!(
                        "roughness {r} weight {weight}, wo {wo}, {how}: {mean} ± {se}"
                    ));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Nonsense parameters and directions give zeros, never NaN or a panic.
#[test]
fn bad_input_is_harmless() {
    let cases = [
        Fuzz {
            color: Vec3A::ONE,
            weight: 1.0,
            roughness: f32::NAN,
        },
        Fuzz {
            color: Vec3A::ONE,
            weight: -1.0,
            roughness: 2.0,
        },
        Fuzz {
            color: Vec3A::ONE,
            weight: 1.0,
            roughness: 0.0,
        },
    ];
    let mut rng = Rng::for_sample(26, 0, 0);
    for f in cases {
        let lobe = Lobe::from(f);
        for wo in [dir(0.0, 0.0), dir(90.0, 0.0), dir(120.0, 0.0), Vec3A::ZERO] {
            assert!(f.albedo(wo.z).is_finite());
            assert!(lobe.selection_weight(wo).is_finite());
            let (v, p) = lobe.eval(0, wo, dir(40.0, 10.0), 1.0);
            assert!(v.is_finite() && p.is_finite(), "{f:?} {wo}: {v} {p}");
            let ctx = SampleCtx {
                sel: 1.0,
                u_lobe: 0.5,
                alone: true,
            };
            if let Some(s) = lobe.sample(wo, ctx, rng.next_2d()) {
                assert!(s.wi.is_finite() && s.wi.z > 0.0, "{f:?} {wo}: {}", s.wi);
            }
        }
    }
}
