//! A homogeneous medium: constant absorption and scattering coefficients per colour
//! channel. Free-flight distances are sampled in closed form from the exponential
//! distribution of one channel, chosen with probabilities proportional to the path's
//! throughput; the estimator divides by the mixture of all channels' densities (spectral
//! MIS with the balance heuristic, the one-sample model of Veach & Guibas 1995, as
//! Cycles and Mitsuba 3's `volpath` handle chromatic media), so it is unbiased in every
//! channel whose throughput is not zero. A medium that does not scatter attenuates by
//! its exact transmittance instead.

use super::{channel_pmf, pick_channel, Collision};
use crate::sampling::Rng;
use glam::Vec3A;

/// Coefficients per scene unit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Homogeneous {
    pub sigma_a: Vec3A,
    pub sigma_s: Vec3A,
    pub sigma_t: Vec3A,
}

/// e^(−σ t) per channel, with e^(−0·∞) = 1 (a channel that does not attenuate lets an
/// infinite segment through).
#[inline]
pub fn beer(sigma: Vec3A, t: f32) -> Vec3A {
    let f = |s: f32| if s == 0.0 { 1.0 } else { (-s * t).exp() };
    Vec3A::new(f(sigma.x), f(sigma.y), f(sigma.z))
}

impl Homogeneous {
    pub fn new(sigma_a: Vec3A, sigma_s: Vec3A) -> Homogeneous {
        Homogeneous {
            sigma_a,
            sigma_s,
            sigma_t: sigma_a + sigma_s,
        }
    }

    /// A real collision before `tmax` (weight σs·T/pdf) or none (weight T/P), where the
    /// channel mixture with probabilities from `throughput` gives pdf and P.
    pub fn sample(&self, tmax: f32, throughput: Vec3A, rng: &mut Rng) -> Collision {
        let st = self.sigma_t;
        // A medium that only absorbs has no real collision to sample: its transmittance
        // is the exact weight (absorbing glass costs no noise).
        if self.sigma_s == Vec3A::ZERO {
            return Collision::Pass {
                weight: beer(st, tmax),
            };
        }
        let p = channel_pmf(throughput);
        let c = pick_channel(p, rng.next_f32());
        let u = rng.next_f32();
        let t = if st[c] > 0.0 {
            -(1.0 - u).ln() / st[c]
        } else {
            f32::INFINITY
        };
        if t < tmax {
            let tr = beer(st, t);
            let pdf = (p * st * tr).element_sum();
            if pdf > 0.0 {
                return Collision::Scatter {
                    t,
                    weight: self.sigma_s * tr / pdf,
                };
            }
        }
        let tr = beer(st, tmax);
        let prob = (p * tr).element_sum();
        Collision::Pass {
            weight: if prob > 0.0 { tr / prob } else { Vec3A::ZERO },
        }
    }

    /// σs, the transmittance to `t` and the density with which `sample` (steered by
    /// `throughput`) returns a collision at `t`; `None` for a medium that does not
    /// scatter (it has no collisions to weigh).
    pub fn collision_terms(&self, t: f32, throughput: Vec3A) -> Option<(Vec3A, Vec3A, f32)> {
        if self.sigma_s == Vec3A::ZERO {
            return None;
        }
        let tr = beer(self.sigma_t, t);
        let pdf = (channel_pmf(throughput) * self.sigma_t * tr).element_sum();
        Some((self.sigma_s, tr, pdf))
    }

    /// Transmittance over `[0, t]`, exactly.
    #[inline]
    pub fn transmittance(&self, t: f32) -> Vec3A {
        beer(self.sigma_t, t)
    }

    /// ∫₀ᵗ T(s) ds per channel: what a constant emission per unit length adds up to
    /// along a segment of length `t` (∞ allowed).
    pub fn optical_integral(&self, t: f32) -> Vec3A {
        let f = |s: f32| {
            if s > 0.0 {
                -(-s * t).exp_m1() / s
            } else {
                t
            }
        };
        Vec3A::new(f(self.sigma_t.x), f(self.sigma_t.y), f(self.sigma_t.z))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The estimator of transmittance from distance sampling (pass weight when it
    /// passes, zero when it scatters) averages to Beer–Lambert in every channel, for a
    /// chromatic medium and a skewed throughput; tolerance 5 standard errors.
    #[test]
    fn pass_weights_average_to_beer_lambert() {
        let m = Homogeneous::new(Vec3A::new(0.1, 0.5, 2.0), Vec3A::new(0.4, 0.2, 0.0));
        let d = 1.3;
        let throughput = Vec3A::new(1.0, 0.2, 0.05);
        let mut rng = Rng::for_sample(5, 1, 2);
        let n = 200_000;
        let (mut s, mut s2) = (glam::DVec3::ZERO, glam::DVec3::ZERO);
        for _ in 0..n {
            let w = match m.sample(d, throughput, &mut rng) {
                Collision::Pass { weight } => weight,
                Collision::Scatter { .. } => Vec3A::ZERO,
            };
            let w = glam::DVec3::new(w.x.into(), w.y.into(), w.z.into());
            s += w;
            s2 += w * w;
        }
        let mean = s / n as f64;
        let se = ((s2 / n as f64 - mean * mean) / n as f64).abs().powf(0.5);
        let exact = m.transmittance(d);
        for c in 0..3 {
            let e = f64::from(exact[c]);
            assert!(
                (mean[c] - e).abs() <= 5.0 * se[c] + 1e-6,
                "channel {c}: {} vs {e} (se {})",
                mean[c],
                se[c]
            );
        }
    }

    /// Scatter weights integrate the in-scattering kernel: E[weight · 1{t < d}] per
    /// channel is ∫₀ᵈ σs e^(−σt s) ds = σs/σt (1 − e^(−σt d)).
    #[test]
    fn scatter_weights_average_to_the_collision_integral() {
        let m = Homogeneous::new(Vec3A::new(0.05, 0.3, 0.0), Vec3A::new(0.6, 0.1, 0.9));
        let d = 2.0;
        let throughput = Vec3A::new(0.3, 1.0, 0.6);
        let mut rng = Rng::for_sample(9, 3, 4);
        let n = 200_000;
        let (mut s, mut s2) = (glam::DVec3::ZERO, glam::DVec3::ZERO);
        for _ in 0..n {
            let w = match m.sample(d, throughput, &mut rng) {
                Collision::Scatter { weight, t } => {
                    assert!(t < d);
                    weight
                }
                Collision::Pass { .. } => Vec3A::ZERO,
            };
            let w = glam::DVec3::new(w.x.into(), w.y.into(), w.z.into());
            s += w;
            s2 += w * w;
        }
        let mean = s / n as f64;
        let se = ((s2 / n as f64 - mean * mean) / n as f64).abs().powf(0.5);
        let exact = m.sigma_s * m.optical_integral(d);
        for c in 0..3 {
            let e = f64::from(exact[c]);
            assert!(
                (mean[c] - e).abs() <= 5.0 * se[c] + 1e-6,
                "channel {c}: {} vs {e} (se {})",
                mean[c],
                se[c]
            );
        }
    }
}
