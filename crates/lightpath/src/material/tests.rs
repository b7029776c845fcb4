use super::lobe::SampleCtx;
use super::*;
use crate::light::luminance;
use crate::sampling::{uniform_sphere, Rng};
use std::f64::consts::PI;

pub(super) fn local(wo: Vec3A) -> Shading {
    Shading {
        frame: Frame::new(Vec3A::Z),
        wo,
    }
}

/// Estimates ∫ f cos dωi by sampling: the directional albedo.
fn albedo(bsdf: &Bsdf, wo: Vec3A, n: usize) -> Vec3A {
    let sh = local(wo);
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
fn lossless_glass_conserves_energy_up_to_radiance_scaling() {
    // Smooth and rough: reflection + transmission·η² sum to one (no absorption; rough
    // glass is compensated for the energy single scattering loses, Turquin 2019, so its
    // sum is one too). Within K standard errors of the estimate, from its own samples.
    const K: f64 = 5.0;
    for alpha in [0.0, 0.3] {
        let bsdf = Bsdf::dielectric(1.5, alpha, Vec3A::ONE);
        let sh = local(Vec3A::new(0.4, 0.0, 0.9).normalize());
        let mut rng = Rng::for_sample(3, 0, 0);
        let n = 200_000;
        let (mut sum, mut squares) = (0.0f64, 0.0f64);
        for _ in 0..n {
            if let Some(s) = bsdf.sample(&sh, rng.next_f32(), rng.next_2d()) {
                let w = (s.weight.x * s.eta * s.eta) as f64;
                sum += w;
                squares += w * w;
            }
        }
        let e = sum / n as f64;
        let variance = (squares / n as f64 - e * e).max(0.0) * n as f64 / (n - 1) as f64;
        let standard_error = (variance / n as f64).sqrt();
        // Smooth glass's weights are exactly one each (no variance): f32 rounding only.
        let tol = K * standard_error + 1e-5;
        assert!(
            (e - 1.0).abs() <= tol,
            "alpha {alpha}: {e} (standard error {standard_error:.2e})"
        );
    }
}

#[test]
fn sampled_weights_match_evaluation_for_rough_lobes() {
    for bsdf in [
        Bsdf::conductor(Vec3A::splat(0.9), 0.2),
        Bsdf::plastic(Vec3A::splat(0.5), 1.5, 0.3),
        Bsdf::translucent(Vec3A::splat(0.3), Vec3A::splat(0.6)),
    ] {
        let sh = local(Vec3A::new(0.5, 0.1, 0.8).normalize());
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
    let bsdf = Bsdf::translucent(Vec3A::splat(0.3), Vec3A::splat(0.5));
    let a = albedo(&bsdf, Vec3A::new(0.0, 0.2, 0.98).normalize(), 20_000);
    assert!((a.x - 0.8).abs() < 0.02, "{a}");
}

// ---- Lobe-level harness ------------------------------------------------------------

/// A lobe sampled on its own (selection probability one, not alone so that every
/// non-delta direction goes through `eval`, as inside a multi-lobe Bsdf).
struct Drawn {
    wi: Vec3A,
    weight: Vec3A,
    eta: f32,
    delta: bool,
}

fn draw(lobe: &Lobe, wo: Vec3A, rng: &mut Rng) -> Option<Drawn> {
    let ctx = SampleCtx {
        sel: 1.0,
        u_lobe: rng.next_f32(),
        alone: false,
    };
    let s = lobe.sample(wo, ctx, rng.next_2d())?;
    if let Some((weight, _, delta)) = s.value {
        return Some(Drawn {
            wi: s.wi,
            weight,
            eta: s.eta,
            delta,
        });
    }
    let (f, pdf) = lobe.eval(s.sub, wo, s.wi, 1.0);
    if pdf <= 0.0 || f == Vec3A::ZERO {
        return None;
    }
    Some(Drawn {
        wi: s.wi,
        weight: f / pdf,
        eta: s.eta,
        delta: false,
    })
}

/// Sum over the lobe's events of (f · |cos θi|, pdf): at most one is non-zero.
fn eval_all(lobe: &Lobe, wo: Vec3A, wi: Vec3A) -> (Vec3A, f32) {
    (0..lobe.tags().len()).fold((Vec3A::ZERO, 0.0), |(f, p), sub| {
        let (fs, ps) = lobe.eval(sub, wo, wi, 1.0);
        (f + fs, p + ps)
    })
}

pub(super) fn dir(theta_deg: f32, phi_deg: f32) -> Vec3A {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    Vec3A::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

/// Every non-delta lobe kind at several roughnesses, with the outgoing directions to
/// test (glass also from inside).
/// The diffuse lobes' cases of [`rough_lobe_cases`].
fn diffuse_lobe_cases(up: &[Vec3A]) -> Vec<(String, Lobe, Vec<Vec3A>)> {
    vec![
        (
            "lambert".into(),
            Lambert {
                albedo: Vec3A::new(0.8, 0.5, 0.2),
            }
            .into(),
            up.to_vec(),
        ),
        (
            "diffuse transmission".into(),
            DiffuseTransmission {
                transmit: Vec3A::new(0.3, 0.6, 0.4),
            }
            .into(),
            up.to_vec(),
        ),
        (
            "rough diffuse (EON)".into(),
            RoughDiffuse {
                color: Vec3A::new(0.8, 0.5, 0.2),
                weight: 0.9,
                roughness: 0.7,
            }
            .into(),
            up.to_vec(),
        ),
    ]
}

fn rough_lobe_cases() -> Vec<(String, Lobe, Vec<Vec3A>)> {
    let up = vec![dir(10.0, 0.0), dir(50.0, 30.0), dir(80.0, 200.0)];
    let mut cases = diffuse_lobe_cases(&up);
    for (ax, ay) in [(0.1, 0.5), (0.6, 0.05), (1.0, 1.0)] {
        let alpha = Vec2::new(ax, ay);
        cases.push((
            format!("f82 conductor alpha {alpha}"),
            Conductor {
                f0: Vec3A::new(0.9, 0.7, 0.3),
                f82_tint: Vec3A::new(0.6, 0.9, 1.0),
                weight: 0.8,
                alpha,
                lobe: 2,
            }
            .into(),
            up.clone(),
        ));
        cases.push((
            format!("specular alpha {alpha}"),
            SpecularParams {
                eta: 1.5,
                tint: Vec3A::new(1.0, 0.8, 0.6),
                tint_f0_only: false,
                weight: 1.0,
                alpha,
                lobe: 2,
            }
            .into(),
            up.clone(),
        ));
        cases.push((
            format!("specular under a coat, eta 1/1.4, alpha {alpha}"),
            SpecularParams {
                eta: 1.0 / 1.4,
                tint: Vec3A::ONE,
                tint_f0_only: false,
                weight: 0.7,
                alpha,
                lobe: 4,
            }
            .into(),
            up.clone(),
        ));
        cases.push((
            format!("dielectric alpha {alpha}"),
            Dielectric {
                compensate: true,
                eta: 1.5,
                alpha,
                tint: Vec3A::ONE,
                reflect_tint: Vec3A::ONE,
            }
            .into(),
            up.clone(),
        ));
    }
    for alpha in [0.25, 0.5, 0.8] {
        cases.push((
            format!("conductor alpha {alpha}"),
            Conductor::schlick(Vec3A::new(0.95, 0.64, 0.54), alpha).into(),
            up.clone(),
        ));
        cases.push((
            format!("coat alpha {alpha}"),
            Coat {
                eta: 1.5,
                alpha: Vec2::splat(alpha),
                weight: 1.0,
            }
            .into(),
            up.clone(),
        ));
        cases.push((
            format!("half coat alpha {alpha}"),
            Coat {
                eta: 1.5,
                alpha: Vec2::splat(alpha),
                weight: 0.5,
            }
            .into(),
            up.clone(),
        ));
        cases.push((
            format!("anisotropic coat alpha {alpha}"),
            Coat {
                eta: 1.5,
                alpha: Vec2::new(alpha, 0.3 * alpha),
                weight: 1.0,
            }
            .into(),
            up.clone(),
        ));
        cases.push((
            format!("dielectric alpha {alpha}"),
            Dielectric {
                compensate: true,
                eta: 1.5,
                alpha: Vec2::splat(alpha),
                tint: Vec3A::ONE,
                reflect_tint: Vec3A::ONE,
            }
            .into(),
            up.clone(),
        ));
    }
    cases
}

/// Rough glass seen from inside (`wo.z < 0`).
fn rough_glass_inside_cases() -> Vec<(String, Lobe, Vec<Vec3A>)> {
    [
        Vec2::splat(0.25),
        Vec2::splat(0.5),
        Vec2::splat(0.8),
        Vec2::new(0.7, 0.1),
    ]
    .into_iter()
    .map(|alpha| {
        (
            format!("dielectric alpha {alpha}, inside"),
            Dielectric {
                compensate: true,
                eta: 1.5,
                alpha,
                tint: Vec3A::ONE,
                reflect_tint: Vec3A::ONE,
            }
            .into(),
            vec![dir(170.0, 0.0), dir(130.0, 90.0)],
        )
    })
    .collect()
}

// ---- χ² goodness of fit (after pbrt-v4's bsdfs_test.cpp) ----------------------------

pub(super) const THETA_BINS: usize = 10;
pub(super) const PHI_BINS: usize = 20;
pub(super) const CHI2_SAMPLES: usize = 200_000;

pub(super) fn bin_of(w: Vec3A) -> usize {
    let theta = (w.z.clamp(-1.0, 1.0) as f64).acos();
    let mut phi = (w.y as f64).atan2(w.x as f64);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let t = ((theta / PI * THETA_BINS as f64) as usize).min(THETA_BINS - 1);
    let p = ((phi / (2.0 * PI) * PHI_BINS as f64) as usize).min(PHI_BINS - 1);
    t * PHI_BINS + p
}

/// Expected sample counts per bin: the pdf integrated over each bin (midpoint rule on a
/// fine θ×φ grid, with the sin θ of the solid angle).
pub(super) fn expected_counts(pdf: impl Fn(Vec3A) -> f32, n: usize) -> Vec<f64> {
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
            let p = pdf(w) as f64;
            e[(i / SUB) * PHI_BINS + j / SUB] += p * theta.sin() * dt * dp * n as f64;
        }
    }
    e
}

/// ln Γ(x), Lanczos (g = 7, n = 9).
pub(super) fn ln_gamma(x: f64) -> f64 {
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

/// Upper regularised incomplete gamma Q(a, x) (series below a + 1, continued fraction
/// above; Numerical Recipes §6.2).
pub(super) fn gamma_q(a: f64, x: f64) -> f64 {
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
    // χ²(1) at 3.841: p = 0.05; χ²(10) at 23.209: p = 0.01; χ²(100) at 124.342: p = 0.05.
    for (x, k, p) in [
        (3.841, 1.0, 0.05),
        (23.209, 10.0, 0.01),
        (124.342, 100.0, 0.05),
    ] {
        let q = gamma_q(k / 2.0, x / 2.0);
        assert!((q - p).abs() < 2e-4, "χ²({k}) at {x}: {q}");
    }
}

/// p-value of observed vs expected counts; bins expecting fewer than 5 samples are
/// pooled. Err if a sample fell where the pdf integrates to zero.
pub(crate) fn chi2_p_value(observed: &[u64], expected: &[f64]) -> Result<f64, String> {
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

/// Runs the χ² test of `sample` against `pdf`; returns a failure message.
pub(crate) fn chi2_case(
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
pub(crate) fn sidak(n: usize) -> f64 {
    1.0 - 0.99f64.powf(1.0 / n as f64)
}

#[test]
fn chi2_sampled_directions_follow_each_lobe_pdf() {
    chi2_lobes(rough_lobe_cases());
}

/// Known bug, kept so that it shows: `Dielectric::sample` takes the microfacet's
/// Fresnel term with the normal flipped to `wo`'s side (as if outside), `eval` with the
/// normal up (inside: 1/η), so from inside the sampled reflect/transmit split differs
/// from the pdf. Fixing it changes renders; see notes-materials.md.
#[test]
fn chi2_rough_glass_from_inside_follows_its_pdf() {
    chi2_lobes(rough_glass_inside_cases());
}

fn chi2_lobes(cases: Vec<(String, Lobe, Vec<Vec3A>)>) {
    let n: usize = cases.iter().map(|c| c.2.len()).sum();
    let threshold = sidak(n);
    let mut failures = Vec::new();
    for (seed, (name, lobe, wos)) in cases.iter().enumerate() {
        for (i, &wo) in wos.iter().enumerate() {
            let mut rng = Rng::for_sample(11, seed as u64, i as u64);
            let mut sample = || draw(lobe, wo, &mut rng).map(|d| d.wi);
            let pdf = |wi: Vec3A| eval_all(lobe, wo, wi).1;
            failures.extend(chi2_case(
                &format!("{name}, wo {wo}"),
                &mut sample,
                &pdf,
                threshold,
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Every material through `Bsdf::sample`: the lobe selection and the pdfs `eval_lobe`
/// reports (selection included) must describe the sampled directions together.
/// Delta samples are left out; their lobes have no density.
#[test]
fn chi2_sampled_directions_follow_each_material_pdf() {
    let materials = [
        ("diffuse", Bsdf::diffuse(Vec3A::splat(0.7))),
        (
            "translucent",
            Bsdf::translucent(Vec3A::splat(0.3), Vec3A::new(0.5, 0.4, 0.3)),
        ),
        ("plastic smooth", Bsdf::plastic(Vec3A::splat(0.5), 1.5, 0.0)),
        ("plastic rough", Bsdf::plastic(Vec3A::splat(0.5), 1.5, 0.3)),
        ("conductor rough", Bsdf::conductor(Vec3A::splat(0.9), 0.4)),
        ("glass rough", Bsdf::dielectric(1.5, 0.4, Vec3A::ONE)),
        // More lobes than any built-in material: selection and `u_lobe` rescaling.
        (
            "three lobes under a rough coat",
            Bsdf::layered(
                &[
                    Lambert {
                        albedo: Vec3A::splat(0.4),
                    }
                    .into(),
                    Conductor::schlick(Vec3A::splat(0.2), 0.8).into(),
                    Conductor::schlick(Vec3A::splat(0.9), 0.5).into(),
                ],
                Some(Coat {
                    eta: 1.5,
                    alpha: Vec2::splat(0.3),
                    weight: 1.0,
                }),
                Vec3A::splat(0.5),
            ),
        ),
        ("pbr dielectric", Bsdf::pbr(&pbr(0.0, 0.3, 0.0))),
        (
            "pbr half metal under a half coat",
            Bsdf::pbr(&pbr(0.5, 0.5, 0.5)),
        ),
    ];
    let wos = [dir(20.0, 0.0), dir(70.0, 45.0)];
    let threshold = sidak(materials.len() * wos.len());
    let mut failures = Vec::new();
    for (seed, (name, bsdf)) in materials.iter().enumerate() {
        for (i, &wo) in wos.iter().enumerate() {
            let sh = local(wo);
            let mut rng = Rng::for_sample(13, seed as u64, i as u64);
            let mut sample = || {
                bsdf.sample(&sh, rng.next_f32(), rng.next_2d())
                    .filter(|s| !s.delta)
                    .map(|s| sh.frame.to_local(s.wi))
            };
            let pdf = |wi: Vec3A| {
                (0..bsdf.lobes().len())
                    .map(|k| bsdf.eval_lobe(k, &sh, wi).1)
                    .sum()
            };
            failures.extend(chi2_case(
                &format!("{name}, wo {wo}"),
                &mut sample,
                &pdf,
                threshold,
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

// ---- Energy ---------------------------------------------------------------------------

/// Mean and standard error of the mean.
pub(super) fn mean_se(values: impl Iterator<Item = f64>) -> (f64, f64) {
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

/// Where every sample has the same value the standard error is zero; what is left is
/// f32 rounding of that value and of the f64 sums.
pub(super) const ROUNDING: f64 = 1e-5;

/// Directional albedo ∫ f · |cos θi| dωi from the lobe's own samples (luminance).
fn sampled_albedo(lobe: &Lobe, wo: Vec3A, n: usize, seed: u64) -> (f64, f64) {
    let mut rng = Rng::for_sample(seed, 1, 0);
    mean_se((0..n).map(|_| draw(lobe, wo, &mut rng).map_or(0.0, |d| luminance(d.weight) as f64)))
}

/// The same integral by uniform sphere sampling of `eval`.
fn uniform_albedo(lobe: &Lobe, wo: Vec3A, n: usize, seed: u64) -> (f64, f64) {
    let mut rng = Rng::for_sample(seed, 2, 0);
    mean_se((0..n).map(|_| {
        let wi = uniform_sphere(rng.next_2d());
        luminance(eval_all(lobe, wo, wi).0) as f64 * 4.0 * PI
    }))
}

fn close(a: (f64, f64), b: (f64, f64)) -> bool {
    (a.0 - b.0).abs() <= 5.0 * (a.1 * a.1 + b.1 * b.1).sqrt() + ROUNDING
}

#[test]
fn sampled_albedo_of_each_rough_lobe_matches_uniform_integration() {
    albedo_lobes(rough_lobe_cases());
}

/// The same known bug as `chi2_rough_glass_from_inside_follows_its_pdf`.
#[test]
fn sampled_albedo_of_rough_glass_from_inside_matches_uniform_integration() {
    albedo_lobes(rough_glass_inside_cases());
}

fn albedo_lobes(cases: Vec<(String, Lobe, Vec<Vec3A>)>) {
    let mut failures = Vec::new();
    for (seed, (name, lobe, wos)) in cases.iter().enumerate() {
        for &wo in wos {
            let s = sampled_albedo(lobe, wo, 100_000, seed as u64);
            let u = uniform_albedo(lobe, wo, 400_000, seed as u64);
            if !close(s, u) {
                failures.push(format!("{name}, wo {wo}: sampled {s:?}, uniform {u:?}"));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn diffuse_lobes_reflect_and_transmit_their_albedo() {
    let albedo = Vec3A::new(0.8, 0.5, 0.2);
    let transmit = Vec3A::new(0.3, 0.6, 0.4);
    for wo in [dir(10.0, 0.0), dir(60.0, 100.0), dir(85.0, 300.0)] {
        for (lobe, want) in [
            (Lobe::from(Lambert { albedo }), albedo),
            (DiffuseTransmission { transmit }.into(), transmit),
        ] {
            let want = (luminance(want) as f64, 0.0);
            let s = sampled_albedo(&lobe, wo, 20_000, 3);
            let u = uniform_albedo(&lobe, wo, 400_000, 3);
            assert!(close(s, want), "{lobe:?} sampled {s:?}, want {want:?}");
            assert!(close(u, want), "{lobe:?} uniform {u:?}, want {want:?}");
        }
        // The Bsdf's fast path (the lone diffuse lobe) returns the albedo exactly.
        let bsdf = Bsdf::diffuse(albedo);
        let mut rng = Rng::for_sample(4, 0, 0);
        for _ in 0..1000 {
            if let Some(s) = bsdf.sample(&local(wo), rng.next_f32(), rng.next_2d()) {
                assert_eq!(s.weight, albedo);
            }
        }
    }
}

#[test]
fn smooth_lobes_reflect_their_fresnel_and_glass_conserves_energy() {
    for wo in [dir(5.0, 0.0), dir(45.0, 60.0), dir(80.0, 200.0)] {
        let f0 = Vec3A::new(0.95, 0.64, 0.54);
        let mirror = Lobe::from(Conductor::schlick(f0, 0.0));
        let want = (luminance(fresnel::schlick(f0, wo.z)) as f64, 0.0);
        let got = sampled_albedo(&mirror, wo, 10_000, 5);
        assert!(close(got, want), "mirror at {wo}: {got:?} vs {want:?}");

        let coat = Lobe::from(Coat {
            eta: 1.5,
            alpha: Vec2::ZERO,
            weight: 1.0,
        });
        let want = (fresnel_dielectric(wo.z, 1.5) as f64, 0.0);
        let got = sampled_albedo(&coat, wo, 10_000, 6);
        assert!(close(got, want), "coat at {wo}: {got:?} vs {want:?}");
    }
    // Reflection + transmission · η² = 1 for clear glass, from either side (the η²
    // undoes the 1/η² radiance compression of transmission).
    let glass = Lobe::from(Dielectric {
        compensate: true,
        eta: 1.5,
        alpha: Vec2::splat(0.0),
        tint: Vec3A::ONE,
        reflect_tint: Vec3A::ONE,
    });
    for wo in [
        dir(10.0, 0.0),
        dir(60.0, 30.0),
        dir(170.0, 0.0),
        dir(120.0, 0.0),
    ] {
        let mut rng = Rng::for_sample(8, 0, 0);
        let got = mean_se((0..50_000).map(|_| {
            draw(&glass, wo, &mut rng).map_or(0.0, |d| {
                assert!(d.delta);
                (d.weight.x * d.eta * d.eta) as f64
            })
        }));
        assert!(close(got, (1.0, 0.0)), "glass at {wo}: {got:?}");
    }
}

#[test]
fn eval_pdf_equals_sample_pdf_for_every_material() {
    let materials = [
        Bsdf::diffuse(Vec3A::new(0.8, 0.5, 0.2)),
        Bsdf::translucent(Vec3A::splat(0.3), Vec3A::new(0.5, 0.4, 0.3)),
        Bsdf::plastic(Vec3A::splat(0.5), 1.5, 0.0),
        Bsdf::plastic(Vec3A::splat(0.5), 1.5, 0.4),
        Bsdf::conductor(Vec3A::splat(0.9), 0.3),
        Bsdf::dielectric(1.5, 0.3, Vec3A::new(0.9, 0.8, 0.7)),
        Bsdf::pbr(&pbr(0.0, 0.4, 0.0)),
        Bsdf::pbr(&pbr(0.7, 0.2, 1.0)),
    ];
    let mut rng = Rng::for_sample(9, 0, 0);
    for bsdf in &materials {
        let mut checked = 0;
        for _ in 0..50 {
            let mut wo = uniform_sphere(rng.next_2d());
            // Shading flips two-sided materials' frames towards wo.
            if bsdf.two_sided {
                wo.z = wo.z.abs();
            }
            let sh = local(wo);
            for _ in 0..20 {
                let Some(s) = bsdf.sample(&sh, rng.next_f32(), rng.next_2d()) else {
                    continue;
                };
                if s.delta {
                    continue;
                }
                let (f, pdf) = bsdf.eval_lobe(s.lobe, &sh, sh.frame.to_local(s.wi));
                let rel = |a: f32, b: f32| (a - b).abs() <= 1e-4 * a.abs().max(b.abs());
                assert!(rel(pdf, s.pdf), "{bsdf:?} wo {wo}: {pdf} vs {}", s.pdf);
                let w = f / pdf;
                assert!(
                    (0..3).all(|c| rel(w[c], s.weight[c])),
                    "{bsdf:?} wo {wo}: {w} vs {}",
                    s.weight
                );
                checked += 1;
            }
        }
        assert!(checked > 100, "{bsdf:?}: only {checked} samples");
    }
}

/// A metallic-roughness material of base colour (0.8, 0.6, 0.4).
fn pbr(metallic: f32, alpha: f32, clearcoat: f32) -> crate::material::PbrParams {
    crate::material::PbrParams {
        base: Vec3A::new(0.8, 0.6, 0.4),
        metallic,
        alpha,
        ior: 1.5,
        glass: false,
        clearcoat,
        clearcoat_alpha: 0.1,
    }
}

/// The metallic-roughness material conserves energy for a white base at any metallic
/// and coat, and a full metal reflects exactly as the conductor of its base colour.
#[test]
fn pbr_material_conserves_energy_and_full_metal_is_the_conductor() {
    let albedo = |bsdf: &Bsdf, wo: Vec3A, seed: u64| {
        let sh = local(wo);
        let mut rng = Rng::for_sample(17, seed, 0);
        mean_se((0..20_000).map(|_| {
            bsdf.sample(&sh, rng.next_f32(), rng.next_2d())
                .map_or(0.0, |s| luminance(s.weight) as f64)
        }))
    };
    for (i, metallic) in [0.0, 0.5, 1.0].into_iter().enumerate() {
        for (j, coat) in [0.0, 1.0].into_iter().enumerate() {
            let p = crate::material::PbrParams {
                base: Vec3A::ONE,
                ..pbr(metallic, 0.3, coat)
            };
            let wo = dir(40.0, 0.0);
            let (mean, se) = albedo(&Bsdf::pbr(&p), wo, (3 * i + j) as u64);
            assert!(
                mean <= 1.0 + 5.0 * se + ROUNDING,
                "metallic {metallic} coat {coat}: {mean} ± {se}"
            );
            assert!(mean > 0.5, "metallic {metallic} coat {coat}: {mean}");
        }
    }
    let metal = Bsdf::pbr(&pbr(1.0, 0.3, 0.0));
    let conductor = Bsdf::conductor(Vec3A::new(0.8, 0.6, 0.4), 0.3);
    let sh = local(dir(30.0, 10.0));
    let wi = dir(50.0, 200.0);
    let spec = metal.lobes().len() - 1;
    assert_eq!(
        metal.eval_lobe(spec, &sh, wi).0,
        conductor.eval_lobe(0, &sh, wi).0
    );
    assert_eq!(metal.eval_lobe(0, &sh, wi).0, Vec3A::ZERO);
}

// ---- Albedo tables ----------------------------------------------------------------------

/// Rewrites `albedo_tables.rs` (slow; run after changing the GGX code or the axes).
#[test]
#[ignore]
fn generate_albedo_tables() {
    let text = super::albedo::generator::generate(64);
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/src/material/albedo_tables.rs");
    std::fs::write(path, text).unwrap();
}

/// Single-scattering albedo of an interface, integrated by uniform sphere sampling of
/// Walter et al.'s BRDF and BTDF written out here in f64 (independent of the generator's
/// visible-normal estimator): reflection only, or reflection plus transmission with the
/// 1/η² radiance compression left out. `eta` 0: F = 1 (reflection).
fn walter_albedo(mu: f64, alpha: f64, eta: f64, glass: bool, n: usize, seed: u64) -> (f64, f64) {
    use glam::DVec3;
    let wo = DVec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let lambda =
        |w: DVec3| ((1.0 + alpha * alpha * (1.0 - w.z * w.z) / (w.z * w.z)).sqrt() - 1.0) / 2.0;
    let d = |m: DVec3| {
        let t = (m.x * m.x + m.y * m.y) / (alpha * alpha) + m.z * m.z;
        1.0 / (PI * alpha * alpha * t * t)
    };
    let fresnel = |c: f64| {
        if eta == 0.0 {
            1.0
        } else {
            fresnel_dielectric(c as f32, eta as f32) as f64
        }
    };
    let mut rng = Rng::for_sample(seed, 3, 0);
    mean_se((0..n).map(|_| {
        let u = uniform_sphere(rng.next_2d());
        let wi = DVec3::new(u.x as f64, u.y as f64, u.z as f64);
        if wi.z == 0.0 {
            return 0.0;
        }
        let g = 1.0 / (1.0 + lambda(wo) + lambda(wi));
        let v = if wi.z > 0.0 {
            let m = (wo + wi).normalize();
            fresnel(wo.dot(m)) * d(m) * g / (4.0 * mu)
        } else if glass {
            let mut m = (wo + wi * eta).normalize();
            if m.z < 0.0 {
                m = -m;
            }
            let (om, im) = (wo.dot(m), wi.dot(m));
            if om <= 0.0 || im >= 0.0 {
                return 0.0;
            }
            let denom = (im + om / eta).powi(2);
            (1.0 - fresnel(om)) * d(m) * g * (im * om).abs() / (denom * mu)
        } else {
            0.0
        };
        v * 4.0 * PI
    }))
}

#[test]
fn albedo_tables_match_fresh_integration() {
    use super::albedo::{self, generator, N_2D, N_3D};
    use super::albedo_tables::GENERATOR_ERROR;
    let n = 400_000;
    // Entries at table nodes (exact lookups), rough enough for uniform sampling.
    let mut failures = Vec::new();
    let mut check = |what: String, table: f32, fresh: (f64, f64)| {
        let tol = 5.0 * fresh.1 + GENERATOR_ERROR as f64 + 2e-6;
        if (table as f64 - fresh.0).abs() > tol {
            failures.push(format!(
                "{what}: table {table}, fresh {fresh:?}, tolerance {tol}"
            ));
        }
    };
    for (seed, (i, j)) in [(31, 16), (16, 20), (4, 31), (24, 12)]
        .into_iter()
        .enumerate()
    {
        let (mu, alpha) = (generator::node_mu(i, N_2D), generator::node_alpha(j, N_2D));
        let fresh = walter_albedo(mu as f64, alpha as f64, 0.0, false, n, seed as u64);
        check(
            format!("F = 1, mu {mu} alpha {alpha}"),
            albedo::ggx_e(mu, alpha),
            fresh,
        );
    }
    for (seed, (i, j, k)) in [(15, 10, 8), (8, 15, 3), (3, 12, 15), (12, 8, 10)]
        .into_iter()
        .enumerate()
    {
        let (mu, alpha) = (generator::node_mu(i, N_3D), generator::node_alpha(j, N_3D));
        let eta = generator::node_eta(k, N_3D);
        for eta in [eta, 1.0 / eta] {
            let s = 10 + seed as u64;
            let r = walter_albedo(mu as f64, alpha as f64, eta as f64, false, n, s);
            let what = format!("mu {mu} alpha {alpha} eta {eta}");
            check(
                format!("dielectric, {what}"),
                albedo::dielectric_e(mu, alpha, eta),
                r,
            );
            let t = walter_albedo(mu as f64, alpha as f64, eta as f64, true, n, s + 100);
            check(format!("glass, {what}"), albedo::glass_e(mu, alpha, eta), t);
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
    // The generator's error bound (5 standard errors, the largest over all entries) is
    // small against the energies compensated (a few % to 60 %).
    const { assert!(GENERATOR_ERROR < 5e-3) };
}

#[test]
fn anisotropic_ggx_projects_to_unit_area_and_reduces_to_isotropic() {
    use super::microfacet::Ggx;
    // ∫ D(m) cos θm dωm = 1 (midpoint rule in θ, φ; the peak of αy 0.1 needs a fine θ).
    for g in [Ggx::new(Vec2::new(0.1, 0.4)), Ggx::new(Vec2::new(0.7, 0.3))] {
        let (nt, np) = (4000, 400);
        let mut s = 0.0;
        for i in 0..nt {
            let t = (i as f64 + 0.5) / nt as f64 * PI / 2.0;
            for j in 0..np {
                let p = (j as f64 + 0.5) / np as f64 * 2.0 * PI;
                let m = Vec3A::new(
                    (t.sin() * p.cos()) as f32,
                    (t.sin() * p.sin()) as f32,
                    t.cos() as f32,
                );
                s += g.d(m) as f64
                    * t.cos()
                    * t.sin()
                    * (PI / 2.0 / nt as f64)
                    * (2.0 * PI / np as f64);
            }
        }
        assert!((s - 1.0).abs() < 2e-3, "{g:?}: {s}");
    }
    let (a, b) = (Ggx::isotropic(0.3), Ggx::new(Vec2::new(0.3, 0.3)));
    let (wo, wi) = (dir(40.0, 20.0), dir(60.0, 250.0));
    let m = (wo + wi).normalize();
    assert_eq!((a.d(m), a.g(wo, wi)), (b.d(m), b.g(wo, wi)));
    // Stretching along x: a facet tilted along x is likelier than one tilted along y.
    let g = Ggx::new(Vec2::new(0.5, 0.1));
    assert!(g.d(dir(20.0, 0.0)) > 10.0 * g.d(dir(20.0, 90.0)));
}

/// Energy from `wo` of a lobe sampled on its own: luminance of the weight, transmission
/// with its η² (radiance compression) undone.
fn lobe_energy(lobe: &Lobe, wo: Vec3A, n: usize, seed: u64) -> (f64, f64) {
    let mut rng = Rng::for_sample(seed, 4, 0);
    mean_se((0..n).map(|_| {
        draw(lobe, wo, &mut rng).map_or(0.0, |d| (luminance(d.weight) * d.eta * d.eta) as f64)
    }))
}

/// `mean ± 5 se` within [lo, hi].
fn within(e: (f64, f64), lo: f64, hi: f64) -> bool {
    let t = 5.0 * e.1 + ROUNDING;
    e.0 >= lo - t && e.0 <= hi + t
}

const FURNACE: (f64, f64) = (0.98, 1.01);

fn furnace_dirs() -> Vec<Vec3A> {
    vec![
        dir(0.0, 0.0),
        dir(30.0, 10.0),
        dir(60.0, 100.0),
        dir(80.0, 200.0),
    ]
}

#[test]
fn white_furnace_rough_white_metal_keeps_its_energy() {
    let mut failures = Vec::new();
    for roughness in [0.2, 0.5, 1.0] {
        let alpha = Vec2::splat(roughness_to_alpha(roughness));
        let lobe = white_metal(alpha);
        for (k, wo) in furnace_dirs().into_iter().enumerate() {
            let e = lobe_energy(&lobe, wo, 100_000, k as u64);
            // Before compensation: single scattering alone.
            let ss = super::microfacet::MicrofacetReflection::single(alpha);
            let mut rng = Rng::for_sample(k as u64, 5, 0);
            let before = mean_se((0..100_000).map(|_| {
                ss.sample(wo, 1.0, rng.next_2d()).map_or(0.0, |wi| {
                    let (f, pdf) = ss.eval(wo, wi, |_| Vec3A::ONE);
                    (f.x / pdf) as f64
                })
            }));
            println!(
                "white metal roughness {roughness}, θo {:.0}°: {:.4} (single scattering {:.4})",
                wo.z.acos().to_degrees(),
                e.0,
                before.0
            );
            if !within(e, FURNACE.0, FURNACE.1) {
                failures.push(format!("roughness {roughness} wo {wo}: {e:?}"));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

fn white_metal(alpha: Vec2) -> Lobe {
    Lobe::from(Conductor {
        f0: Vec3A::ONE,
        f82_tint: Vec3A::ONE,
        weight: 1.0,
        alpha,
        lobe: 2,
    })
}

/// Anisotropic metal is compensated at its geometric-mean alpha, as Cycles and OpenPBR's
/// MaterialX reference do (albedo.rs): its white-furnace energy from `wo` is the lobe's
/// own single scattering, integrated here by the table generator's independent
/// estimator, plus the 1 − E(μo, √(αx·αy)) of the isotropic table. Printed beside it, a
/// white sphere's mean (what `benches/materials/cycles_furnace.py` renders): Cycles
/// 5.0.1 keeps 0.8975 at Blender's roughness 0.55, anisotropy 0.8, and 0.9572 at 0.4
/// (its compensation scales by 1/E where Kulla–Conty adds 1 − E; RESULTS.md).
#[test]
fn white_furnace_anisotropic_metal_is_compensated_at_the_mean_alpha() {
    use super::albedo::{self, generator};
    use super::albedo_tables::GENERATOR_ERROR;
    let mut failures = Vec::new();
    for (i, (roughness, cycles)) in [(0.55f32, 0.8975), (0.4, 0.9572)].into_iter().enumerate() {
        // Blender's Principled anisotropy: α/ρ and α·ρ, ρ = √(1 − 0.9 s).
        let a = roughness * roughness;
        let rho = (1.0f32 - 0.9 * 0.8).sqrt();
        let alpha = Vec2::new(a / rho, a * rho);
        let lobe = white_metal(alpha);
        let g = super::microfacet::Ggx::new(alpha);
        for (k, wo) in [
            dir(0.0, 0.0),
            dir(40.0, 0.0),
            dir(40.0, 90.0),
            dir(75.0, 30.0),
            dir(75.0, 80.0),
        ]
        .into_iter()
        .enumerate()
        {
            let seed = (10 * i + k) as u64;
            let e = lobe_energy(&lobe, wo, 100_000, seed);
            let single = generator::integrate_dir(generator::Kind::White, &g, wo, 128, 900 + seed);
            let expected = single.0 + 1.0 - albedo::ggx_e(wo.z, albedo::mean_alpha(&g)) as f64;
            let tol = 5.0 * (e.1 + single.1) + GENERATOR_ERROR as f64 + ROUNDING;
            println!("anisotropic white metal roughness {roughness}, wo {wo}: {e:?}, expected {expected:.4}");
            if (e.0 - expected).abs() > tol {
                failures.push(format!(
                    "roughness {roughness} wo {wo}: {e:?} against {expected}"
                ));
            }
            // Compensation only adds energy, and never beyond what arrives.
            if e.0 < single.0 - tol || e.0 > FURNACE.1 + tol {
                failures.push(format!(
                    "roughness {roughness} wo {wo}: {e:?}, single {single:?}"
                ));
            }
        }
        // The sphere's mean: view directions cosine-distributed about the normal
        // (orthographic view), tangents at every azimuth.
        let mut rng = Rng::for_sample(7, i as u64, 0);
        let sphere = mean_se((0..256).map(|k| {
            let wo = crate::sampling::cosine_hemisphere(rng.next_2d());
            lobe_energy(&lobe, wo, 4000, 1000 + k).0
        }));
        println!(
            "anisotropic white metal roughness {roughness}: sphere {sphere:?}, Cycles {cycles}"
        );
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn white_furnace_rough_glass_keeps_its_energy_from_both_sides() {
    let mut failures = Vec::new();
    for roughness in [0.2, 0.5, 1.0] {
        for alpha in [
            Vec2::splat(roughness_to_alpha(roughness)),
            super::microfacet::roughness_anisotropy_to_alpha(roughness, 0.7),
        ] {
            // Anisotropic glass is compensated at its smaller alpha: it must not gain
            // energy, and may still lose some.
            let lo = if alpha.x == alpha.y { FURNACE.0 } else { 0.0 };
            let lobe = Lobe::from(Dielectric {
                compensate: true,
                eta: 1.5,
                alpha,
                tint: Vec3A::ONE,
                reflect_tint: Vec3A::ONE,
            });
            let mut dirs = furnace_dirs();
            dirs.extend(furnace_dirs().into_iter().map(|w| -w));
            for (k, wo) in dirs.into_iter().enumerate() {
                let e = lobe_energy(&lobe, wo, 100_000, k as u64);
                let g = super::microfacet::Ggx::new(alpha);
                let etap = if wo.z > 0.0 { 1.5 } else { 1.0 / 1.5 };
                let a = super::albedo::min_alpha(&g);
                println!(
                    "rough glass roughness {roughness} alpha {alpha}, θo {:.0}°: {:.4} (single scattering {:.4})",
                    wo.z.acos().to_degrees(),
                    e.0,
                    super::albedo::glass_e(wo.z.abs(), a, etap)
                );
                if !within(e, lo, FURNACE.1) {
                    failures.push(format!(
                        "roughness {roughness} alpha {alpha} wo {wo}: {e:?}"
                    ));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Energy from `wo` of a specular layer over a white Lambertian base attenuated by
/// 1 − E(μo): the layer by its own sampling, the base (which reflects all it receives)
/// by the layer's tabulated albedo, so the sum tests the tables against the lobe.
fn specular_over_white(spec: &Specular, wo: Vec3A, n: usize, seed: u64) -> (f64, f64) {
    let lobe = Lobe::from(*spec);
    let top = lobe_energy(&lobe, wo, n, seed);
    (top.0 + spec.base_attenuation(wo) as f64, top.1)
}

#[test]
fn white_furnace_specular_over_white_lambert_keeps_its_energy() {
    let mut failures = Vec::new();
    for (i, eta) in [1.5f32, 1.33, 2.5, 1.0 / 1.3].into_iter().enumerate() {
        for (j, alpha) in [
            Vec2::ZERO,
            Vec2::splat(0.04),
            Vec2::splat(0.25),
            Vec2::splat(1.0),
            Vec2::new(0.6, 0.1),
        ]
        .into_iter()
        .enumerate()
        {
            for weight in [1.0, 0.5] {
                let spec = SpecularParams {
                    eta,
                    tint: Vec3A::ONE,
                    tint_f0_only: false,
                    weight,
                    alpha,
                    lobe: 2,
                };
                // Anisotropic under total internal reflection: the albedo is
                // overestimated on purpose (the base dims rather than brightens).
                let lo = if alpha.x != alpha.y && eta < 1.0 {
                    0.0
                } else {
                    FURNACE.0
                };
                for (k, wo) in furnace_dirs().into_iter().enumerate() {
                    let seed = (100 * i + 10 * j + k) as u64;
                    let e = specular_over_white(&Specular::new(spec), wo, 50_000, seed);
                    if alpha.x != alpha.y {
                        println!("specular eta {eta} alpha {alpha} weight {weight} over white, wo {wo}: {:.4}", e.0);
                    }
                    if !within(e, lo, FURNACE.1) {
                        failures.push(format!("{spec:?} wo {wo}: {e:?}"));
                    }
                }
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Random lobe parameters and directions: no passive lobe returns more than it receives.
#[test]
fn passive_lobes_never_create_energy() {
    let mut rng = Rng::for_sample(21, 0, 0);
    let mut failures = Vec::new();
    let n = 20_000;
    for case in 0..150 {
        let mut r = || rng.next_f32();
        let alpha = Vec2::new(r() * r(), r() * r());
        let alpha = if case % 10 == 0 { Vec2::ZERO } else { alpha };
        let colour = |r: &mut dyn FnMut() -> f32| Vec3A::new(r(), r(), r());
        let lobe: Lobe = match case % 3 {
            0 => Conductor {
                f0: colour(&mut r),
                f82_tint: colour(&mut r),
                weight: r(),
                alpha,
                lobe: 2,
            }
            .into(),
            1 => SpecularParams {
                eta: 1.0 / 3.0 + r() * 3.0,
                tint: colour(&mut r),
                tint_f0_only: false,
                weight: r(),
                alpha,
                lobe: 2,
            }
            .into(),
            _ => Dielectric {
                compensate: true,
                eta: 1.0 + 2.0 * r(),
                alpha,
                tint: colour(&mut r),
                reflect_tint: Vec3A::ONE,
            }
            .into(),
        };
        let mut wo = uniform_sphere(rng.next_2d());
        if lobe.two_sided() {
            wo.z = wo.z.abs();
        }
        let e = lobe_energy(&lobe, wo, n, case);
        // Up to the compensation's table error (the furnace's upper bound).
        if !within(e, 0.0, FURNACE.1) {
            failures.push(format!("{lobe:?} wo {wo}: {e:?}"));
        }
        if let Lobe::Specular(s) = lobe {
            let a = s.albedo(wo);
            if !(0.0..=1.0).contains(&a) {
                failures.push(format!("{s:?}: albedo {a}"));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// EON keeps a white surface white at every roughness (its Fujii albedo and average in
/// closed form against this Monte Carlo integral of the lobe), reflects less than its
/// colour otherwise, is reciprocal, and is Lambert at roughness 0.
#[test]
fn rough_diffuse_keeps_its_energy_and_is_lambert_when_smooth() {
    let mut failures = Vec::new();
    for (i, sigma) in [0.3f32, 0.7, 1.0].into_iter().enumerate() {
        let white = Lobe::from(RoughDiffuse {
            color: Vec3A::ONE,
            weight: 1.0,
            roughness: sigma,
        });
        for (k, wo) in furnace_dirs().into_iter().enumerate() {
            let e = lobe_energy(&white, wo, 100_000, (10 * i + k) as u64);
            println!(
                "white EON σ {sigma}, θo {:.0}°: {:.4}",
                wo.z.acos().to_degrees(),
                e.0
            );
            if !within(e, 1.0, 1.0) {
                failures.push(format!("white σ {sigma} wo {wo}: {e:?}"));
            }
            let grey = Lobe::from(RoughDiffuse {
                color: Vec3A::splat(0.5),
                weight: 1.0,
                roughness: sigma,
            });
            let e = lobe_energy(&grey, wo, 100_000, (10 * i + k) as u64);
            if !within(e, 0.0, 0.5) {
                failures.push(format!("grey σ {sigma} wo {wo}: {e:?}"));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
    let mut rng = Rng::for_sample(29, 0, 0);
    let rough = Lobe::from(RoughDiffuse {
        color: Vec3A::new(0.9, 0.4, 0.1),
        weight: 0.8,
        roughness: 0.6,
    });
    let smooth = Lobe::from(RoughDiffuse {
        color: Vec3A::new(0.9, 0.4, 0.1),
        weight: 0.8,
        roughness: 0.0,
    });
    let lambert = Lobe::from(Lambert {
        albedo: Vec3A::new(0.9, 0.4, 0.1) * 0.8,
    });
    for _ in 0..500 {
        let mut wo = uniform_sphere(rng.next_2d());
        let mut wi = uniform_sphere(rng.next_2d());
        wo.z = wo.z.abs();
        wi.z = wi.z.abs();
        let a = rough.eval(0, wo, wi, 1.0).0 / wi.z;
        let b = rough.eval(0, wi, wo, 1.0).0 / wo.z;
        assert!(
            (a - b).abs().max_element() <= 1e-4 * a.max_element().max(1e-6),
            "{wo} {wi}: {a} vs {b}"
        );
        let (s, l) = (smooth.eval(0, wo, wi, 1.0), lambert.eval(0, wo, wi, 1.0));
        assert!(
            (s.0 - l.0).abs().max_element() <= 1e-5 && s.1 == l.1,
            "{wo} {wi}: {s:?} vs {l:?}"
        );
    }
}

#[test]
fn conductor_and_specular_are_reciprocal() {
    let mut rng = Rng::for_sample(23, 0, 0);
    let lobes: [Lobe; 4] = [
        Conductor {
            f0: Vec3A::new(0.9, 0.6, 0.3),
            f82_tint: Vec3A::new(0.5, 0.8, 1.0),
            weight: 0.9,
            alpha: Vec2::new(0.5, 0.2),
            lobe: 2,
        }
        .into(),
        Conductor::schlick(Vec3A::ONE, 1.0).into(),
        SpecularParams {
            eta: 1.5,
            tint: Vec3A::new(1.0, 0.9, 0.7),
            tint_f0_only: false,
            weight: 1.0,
            alpha: Vec2::new(0.3, 0.7),
            lobe: 4,
        }
        .into(),
        SpecularParams {
            eta: 1.0 / 1.3,
            tint: Vec3A::ONE,
            tint_f0_only: false,
            weight: 0.6,
            alpha: Vec2::splat(0.8),
            lobe: 2,
        }
        .into(),
    ];
    for lobe in &lobes {
        for _ in 0..500 {
            let mut wo = uniform_sphere(rng.next_2d());
            let mut wi = uniform_sphere(rng.next_2d());
            wo.z = wo.z.abs();
            wi.z = wi.z.abs();
            // f · cos θi / cos θi against f · cos θo / cos θo with the roles swapped.
            let a = lobe.eval(0, wo, wi, 1.0).0 / wi.z;
            let b = lobe.eval(0, wi, wo, 1.0).0 / wo.z;
            let scale = a.max_element().max(b.max_element()).max(1e-6);
            assert!(
                (a - b).abs().max_element() <= 1e-4 * scale,
                "{lobe:?} wo {wo} wi {wi}: {a} vs {b}"
            );
        }
    }
}

/// A tint on F0 only (glTF, Blender): the tint at normal incidence, white at grazing, and
/// per channel the tabulated albedo equals the lobe's own energy; over a white base the
/// brightest channel keeps all its energy and no channel makes any.
#[test]
fn specular_tinted_at_f0_only() {
    let tint = Vec3A::new(2.0, 1.0, 0.4);
    let smooth = SpecularParams {
        eta: 1.5,
        tint,
        tint_f0_only: true,
        weight: 1.0,
        alpha: Vec2::ZERO,
        lobe: 2,
    };
    let f0 = 0.04;
    let at_normal = Specular::new(smooth).albedo_rgb(Vec3A::Z);
    assert!(
        (at_normal - tint * f0).abs().max_element() < 1e-5,
        "{at_normal}"
    );
    // Near grazing the real Fresnel is ~0.99 and the tint has faded out.
    let grazing = Specular::new(smooth).albedo_rgb(dir(89.9, 0.0));
    assert!(grazing.min_element() > 0.98, "{grazing}");
    assert!(
        grazing.max_element() - grazing.min_element() < 2e-3,
        "{grazing}"
    );
    for (k, alpha) in [Vec2::splat(0.09), Vec2::splat(0.5), Vec2::new(0.4, 0.1)]
        .into_iter()
        .enumerate()
    {
        let spec = Specular::new(SpecularParams { alpha, ..smooth });
        let lobe = Lobe::from(spec);
        for (j, wo) in furnace_dirs().into_iter().enumerate() {
            let mut rng = Rng::for_sample(40 + (10 * k + j) as u64, 4, 0);
            let n = 50_000;
            let draws: Vec<Vec3A> = (0..n)
                .map(|_| draw(&lobe, wo, &mut rng).map_or(Vec3A::ZERO, |d| d.weight))
                .collect();
            let table = spec.albedo_rgb(wo);
            for c in 0..3 {
                let e = mean_se(draws.iter().map(|w| w[c] as f64));
                // The tables' own accuracy (the furnace tests' band) plus the noise.
                let tol = 0.01 + 5.0 * e.1;
                assert!(
                    (e.0 - table[c] as f64).abs() <= tol,
                    "alpha {alpha} wo {wo} channel {c}: lobe {e:?}, table {}",
                    table[c]
                );
                let over_white = e.0 + spec.base_attenuation(wo) as f64;
                assert!(over_white <= 1.01 + 5.0 * e.1, "{over_white}");
            }
            assert_eq!(spec.albedo(wo), table.max_element().min(1.0));
        }
    }
}

#[test]
fn specular_lobes_carry_their_lobe_number() {
    use lpe::Scatter;
    for n in [2u8, 4, 5] {
        for alpha in [Vec2::ZERO, Vec2::splat(0.3)] {
            let c = Lobe::from(Conductor {
                lobe: n,
                alpha,
                ..Conductor::schlick(Vec3A::ONE, 0.0)
            });
            let s = Lobe::from(SpecularParams {
                eta: 1.5,
                tint: Vec3A::ONE,
                tint_f0_only: false,
                weight: 1.0,
                alpha,
                lobe: n,
            });
            for l in [c, s] {
                let t = l.tags();
                assert_eq!(t.len(), 1);
                assert_eq!(t[0].scatter, Scatter::specular(n));
                assert!(!t[0].transmit);
                assert_eq!(t[0].delta, alpha == Vec2::ZERO);
            }
        }
    }
    // A rough metal is primary specular, as a mirror is.
    let b = Bsdf::conductor(Vec3A::ONE, 0.3);
    assert_eq!(b.lobes()[0].scatter, lpe::Scatter::specular(2));
}

#[test]
fn f82_tint_is_schlick_at_tint_one_and_tints_near_82_degrees() {
    let f0 = Vec3A::new(0.9, 0.6, 0.3);
    for c in [0.0, 0.1, 0.5, 1.0] {
        assert!(
            (fresnel::f82_tint(f0, Vec3A::ONE, c) - fresnel::schlick(f0, c))
                .abs()
                .max_element()
                < 1e-6
        );
    }
    let tint = Vec3A::new(0.5, 0.8, 1.0);
    let at = fresnel::f82_tint(f0, tint, 1.0 / 7.0);
    let want = fresnel::schlick(f0, 1.0 / 7.0) * tint;
    assert!((at - want).abs().max_element() < 1e-5, "{at} vs {want}");
    // The closed-form average against the midpoint rule.
    let n = 20_000;
    let mut avg = Vec3A::ZERO;
    for i in 0..n {
        let mu = (i as f32 + 0.5) / n as f32;
        avg += fresnel::f82_tint(f0, tint, mu) * (2.0 * mu / n as f32);
    }
    let closed = fresnel::f82_tint_avg(f0, tint);
    assert!(
        (avg - closed).abs().max_element() < 1e-4,
        "{avg} vs {closed}"
    );
}

/// Glass tints what it transmits (at each crossing) and not what it reflects, smooth or
/// rough, as glTF, Cycles and OpenPBR define it.
#[test]
fn glass_tints_what_it_transmits_and_not_what_it_reflects() {
    let tint = Vec3A::new(0.9, 0.5, 0.2);
    for alpha in [Vec2::ZERO, Vec2::splat(0.3)] {
        let lobe = Lobe::from(Dielectric {
            eta: 1.5,
            alpha,
            tint,
            reflect_tint: Vec3A::ONE,
            compensate: true,
        });
        let mut rng = Rng::for_sample(77, 0, 0);
        let (mut reflected, mut transmitted) = (0, 0);
        for _ in 0..4000 {
            let Some(d) = draw(&lobe, dir(70.0, 0.0), &mut rng) else {
                continue;
            };
            // The colour of the weight, whatever its size.
            let hue = d.weight / d.weight.max_element();
            let want = if d.wi.z > 0.0 {
                reflected += 1;
                Vec3A::ONE
            } else {
                transmitted += 1;
                tint / tint.max_element()
            };
            assert!(
                (hue - want).abs().max_element() < 1e-4,
                "{alpha} {}",
                d.weight
            );
        }
        assert!(
            reflected > 100 && transmitted > 100,
            "{reflected} {transmitted}"
        );
    }
}

/// With its terms at `wo` worked out once (`Bsdf::at_wo`, what the integrator does at
/// each vertex) every material evaluates and samples bit for bit as when each use works
/// them out: an OpenPBR stack of fuzz over coat over specular
/// over diffuse and metal, the layered and glTF materials, and a single lobe.
#[test]
fn terms_worked_out_once_a_vertex_change_nothing() {
    use crate::material::openpbr::{LobeSet, OpenPbr};
    let stack = OpenPbr {
        base_metalness: 0.3,
        specular_roughness: 0.4,
        coat_weight: 0.6,
        coat_roughness: 0.2,
        coat_color: Vec3A::new(0.9, 0.7, 0.6),
        fuzz_weight: 0.7,
        fuzz_roughness: 0.4,
        ..Default::default()
    };
    let materials = [
        Bsdf::openpbr(&stack, &LobeSet::of(&stack, |_| false)),
        Bsdf::plastic(Vec3A::splat(0.5), 1.5, 0.4),
        Bsdf::pbr(&pbr(0.7, 0.2, 1.0)),
        Bsdf::pbr(&pbr(0.0, 0.5, 0.0)),
        Bsdf::diffuse(Vec3A::splat(0.6)),
    ];
    let mut rng = Rng::for_sample(21, 0, 0);
    for bsdf in &materials {
        for _ in 0..40 {
            let mut wo = uniform_sphere(rng.next_2d());
            wo.z = wo.z.abs();
            let sh = local(wo);
            let at = bsdf.at_wo(wo);
            for _ in 0..20 {
                let wi = uniform_sphere(rng.next_2d());
                for k in 0..bsdf.lobes().len() {
                    let (a, b) = (
                        bsdf.eval_lobe(k, &sh, wi),
                        bsdf.eval_lobe_at(k, &sh, at.as_ref(), wi),
                    );
                    assert!(a.0.to_array().map(f32::to_bits) == b.0.to_array().map(f32::to_bits));
                    assert_eq!(a.1.to_bits(), b.1.to_bits(), "{bsdf:?} {wo} {wi}");
                }
                let (u, uv) = (rng.next_f32(), rng.next_2d());
                let (a, b) = (
                    bsdf.sample(&sh, u, uv),
                    bsdf.sample_at(&sh, at.as_ref(), u, uv),
                );
                assert_eq!(a.is_some(), b.is_some());
                if let (Some(a), Some(b)) = (a, b) {
                    assert_eq!((a.lobe, a.pdf.to_bits()), (b.lobe, b.pdf.to_bits()));
                    assert!(
                        a.weight.to_array().map(f32::to_bits)
                            == b.weight.to_array().map(f32::to_bits)
                    );
                }
            }
        }
    }
}
