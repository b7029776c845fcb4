use super::*;
use crate::sampling::Rng;

fn local(wo: Vec3A) -> Shading {
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
    // Smooth and rough: reflection + transmission·η² sum to one (no absorption).
    for alpha in [0.0, 0.3] {
        let bsdf = Bsdf::dielectric(1.5, alpha, Vec3A::ONE);
        let sh = local(Vec3A::new(0.4, 0.0, 0.9).normalize());
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
