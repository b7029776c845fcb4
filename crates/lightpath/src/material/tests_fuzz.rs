//! Tests of the fuzz lobe: χ² of its sampling, its albedo against the table, energy,
//! and the white furnace of fuzz over a diffuse base. The χ² harness follows the one
//! in `tests.rs` (pbrt-v4's bsdfs_test.cpp), kept here so the two files merge freely.

use super::lobe::SampleCtx;
use super::tests::{chi2_case, dir, local, mean_se, sidak, ROUNDING};
use super::*;
use crate::light::luminance;
use crate::sampling::{cosine_hemisphere, cosine_hemisphere_pdf, Rng};

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

// ---- χ² goodness of fit --------------------------------------------------------------

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
