//! The Blackman–Harris pixel filter, Cycles' default (Film > Pixel Filter, width 1.5 px),
//! by filter importance sampling: each sample is offset from its pixel centre with the
//! filter as its density and counts for that pixel alone (Ernst et al., "Filter
//! importance sampling", 2006).
//!
//! ```toml
//! [film]
//! filter = "blackman-harris"
//! filter_width = 1.5       # pixels; the window reaches ±width from the pixel centre
//! ```
//!
//! The filter is separable, a product of two 1-D windows (Harris, "On the use of windows
//! for harmonic analysis with the discrete Fourier transform", 1978, the 4-term
//! window). Cycles' `filter_func_blackman_harris` spans twice the width it is given, so
//! its "width 1.5" window reaches ±1.5 px; here `width` means the same. On t = d / width
//! in [−1, 1] the window is q(t) = a0 + a1 cos πt + a2 cos 2πt + a3 cos 3πt, whose
//! integral is 2 a0, so its CDF has a closed form. A sample inverts it by a 256-interval
//! table of the inverse (built once by safeguarded Newton steps in f64) and one Newton
//! step from the table's linear interpolation (Cycles uses the interpolated table
//! alone). Newton steps from a plain first guess cost ~0.4 µs a camera sample, 15 % of
//! the held-out real shot's CPU time (benches/peer/real_scenes.py); the table and one
//! step cost ~18 ns an axis (the tail, 3 % of the offsets, ~0.3 µs).

use glam::Vec2;
use std::f64::consts::PI;
use std::sync::OnceLock;

/// The 4-term window's coefficients, signs folded for a window centred on t = 0.
const A: [f64; 4] = [0.35875, 0.48829, 0.14128, 0.01168];

/// The window at t in [−1, 1] (1 at the centre, 6·10⁻⁵ at the ends).
pub fn window(t: f64) -> f64 {
    A[0] + A[1] * (PI * t).cos() + A[2] * (2.0 * PI * t).cos() + A[3] * (3.0 * PI * t).cos()
}

/// The density of a 2-D offset (in pixels) among those `offset` makes: the product of
/// the two axes' windows over their integrals, 2 a0 · width each.
pub fn pdf(offset: Vec2, width: f32) -> f32 {
    let axis = |d: f32| {
        let t = (d / width) as f64;
        if t.abs() > 1.0 {
            0.0
        } else {
            window(t) / (2.0 * A[0] * width as f64)
        }
    };
    (axis(offset.x) * axis(offset.y)) as f32
}

/// The window's CDF from −1 to t, minus ½: odd in t, 0 at the centre, ±½ at the ends.
pub fn half_cdf(t: f64) -> f64 {
    let sines: f64 = (1..4)
        .map(|k| A[k] * (k as f64 * PI * t).sin() / (k as f64 * PI))
        .sum();
    (A[0] * t + sines) / (2.0 * A[0])
}

/// t in [0, 1] with `half_cdf(t) = g`, for g in [0, ½]: Newton steps kept inside a
/// shrinking bracket (the density nearly vanishes at t = 1, where a bare Newton step
/// would leave the interval).
fn invert_half(g: f64) -> f64 {
    // The density at the centre is 1 / (2 a0): a first guess good for most of the mass.
    invert_half_within(g, 0.0, 1.0, (g * 2.0 * A[0]).min(1.0))
}

/// `invert_half` from `t` inside a bracket [`lo`, `hi`] known to hold the answer.
fn invert_half_within(g: f64, mut lo: f64, mut hi: f64, mut t: f64) -> f64 {
    for _ in 0..32 {
        let err = half_cdf(t) - g;
        if err.abs() < 1e-9 {
            break;
        }
        if err > 0.0 {
            hi = t;
        } else {
            lo = t;
        }
        let next = t - err * 2.0 * A[0] / window(t);
        t = if next > lo && next < hi {
            next
        } else {
            0.5 * (lo + hi)
        };
    }
    t
}

/// Intervals of the inverse-CDF table over g in [0, ½].
const TABLE: usize = 256;
/// The table's last intervals, inverted without it.
const TAIL: usize = 8;

/// `invert_half` at g = ½ i / TABLE, i = 0..=TABLE.
fn table() -> &'static [f32; TABLE + 1] {
    static INVERSE: OnceLock<[f32; TABLE + 1]> = OnceLock::new();
    INVERSE
        .get_or_init(|| std::array::from_fn(|i| invert_half(0.5 * i as f64 / TABLE as f64) as f32))
}

/// `invert_half` in f32: the table's interpolation, then one Newton step kept inside
/// the table's interval (its sines and cosines of 2πt and 3πt from those of πt).
fn invert_half_fast(g: f32) -> f32 {
    let inverse = table();
    let x = g * (2 * TABLE) as f32;
    let i = (x as usize).min(TABLE - 1);
    if i + TAIL >= TABLE {
        // The last intervals hold 3 % of the offsets (both signs) over t > 0.59, where
        // the window falls to 6·10⁻⁵ and flattens: one interpolation step is off by up
        // to 0.19 there, so the full inversion.
        let (lo, hi) = (inverse[i] as f64, inverse[i + 1] as f64);
        return invert_half_within(g as f64, lo, hi, 0.5 * (lo + hi)) as f32;
    }
    let (lo, hi) = (inverse[i], inverse[i + 1]);
    let t = lo + (hi - lo) * (x - i as f32);
    let (s1, c1) = (std::f32::consts::PI * t).sin_cos();
    let (s2, c2) = (2.0 * s1 * c1, 2.0 * c1 * c1 - 1.0);
    let (s3, c3) = (s1 * (3.0 - 4.0 * s1 * s1), c1 * (4.0 * c1 * c1 - 3.0));
    let a = A.map(|a| a as f32);
    let pi = std::f32::consts::PI;
    let cdf = (a[0] * t + a[1] * s1 / pi + a[2] * s2 / (2.0 * pi) + a[3] * s3 / (3.0 * pi))
        / (2.0 * a[0]);
    let density = (a[0] + a[1] * c1 + a[2] * c2 + a[3] * c3) / (2.0 * a[0]);
    (t - (cdf - g) / density).clamp(lo, hi)
}

/// Offset from the pixel centre in pixels for two uniform numbers, each axis by the
/// inverse CDF (monotone in u, so the sampler's stratification carries over).
pub fn offset(u: Vec2, width: f32) -> Vec2 {
    let axis = |u: f32| {
        let g = u - 0.5;
        invert_half_fast(g.abs()).copysign(g) * width
    };
    Vec2::new(axis(u.x), axis(u.y))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::tests::chi2_p_value;
    use crate::sampling::Rng;

    /// The window is Cycles' formula, `filter_func_blackman_harris(v, 2 * width)`.
    #[test]
    fn window_is_cycles_blackman_harris() {
        let width = 1.5f64;
        for d in [-1.5, -1.0, -0.3, 0.0, 0.2, 0.75, 1.49] {
            let v = 2.0 * PI * (d / (2.0 * width) + 0.5);
            let cycles =
                0.35875 - 0.48829 * v.cos() + 0.14128 * (2.0 * v).cos() - 0.01168 * (3.0 * v).cos();
            assert!((window(d / width) - cycles).abs() < 1e-12, "{d}");
        }
    }

    #[test]
    fn inverse_cdf_inverts_the_cdf() {
        for i in 0..=1000 {
            let g = 0.5 * i as f64 / 1000.0;
            let t = invert_half(g);
            assert!((0.0..=1.0).contains(&t), "{g}: {t}");
            assert!((half_cdf(t) - g).abs() < 1e-8, "{g}: {t}");
        }
        // The sampling path (the table and one f32 Newton step, or the tail's own
        // inversion, which stops within 1e-9 of g where the density is ~1e-4) agrees.
        for i in 0..=1_000_000 {
            let g = 0.5 * i as f32 / 1_000_000.0;
            let t = invert_half_fast(g);
            assert!((t as f64 - invert_half(g as f64)).abs() < 2e-5, "{g}: {t}");
        }
        assert_eq!(offset(Vec2::splat(0.5), 1.5), Vec2::ZERO);
        assert!((offset(Vec2::ZERO, 1.5) + Vec2::splat(1.5)).length() < 1e-6);
    }

    /// χ² of 200 000 offsets in a 24 × 24 grid over the support against each cell's
    /// mass, integrated from the window itself (Simpson's rule, not the CDF above).
    #[test]
    fn chi2_offsets_follow_the_window() {
        const BINS: usize = 24;
        const N: u64 = 200_000;
        for width in [0.5f32, 1.5, 2.0] {
            let mut rng = Rng::for_sample(7, 29, width.to_bits() as u64);
            let mut observed = vec![0u64; BINS * BINS];
            let cell = |d: f32| {
                let t = (d / width + 1.0) * 0.5;
                ((t * BINS as f32) as usize).min(BINS - 1)
            };
            for _ in 0..N {
                let o = offset(rng.next_2d(), width);
                assert!(o.abs().max_element() <= width * (1.0 + 1e-6), "{o}");
                observed[cell(o.y) * BINS + cell(o.x)] += 1;
            }
            let mass: Vec<f64> = (0..BINS)
                .map(|i| {
                    let (t0, t1) = (
                        -1.0 + 2.0 * i as f64 / BINS as f64,
                        -1.0 + 2.0 * (i + 1) as f64 / BINS as f64,
                    );
                    let m = 0.5 * (t0 + t1);
                    (t1 - t0) / 6.0 * (window(t0) + 4.0 * window(m) + window(t1)) / (2.0 * A[0])
                })
                .collect();
            let expected: Vec<f64> = (0..BINS * BINS)
                .map(|c| mass[c / BINS] * mass[c % BINS] * N as f64)
                .collect();
            let p = chi2_p_value(&observed, &expected).unwrap();
            assert!(p > 0.01 / 3.0, "width {width}: p = {p:e}");
        }
    }

    /// The offsets' mean is 0 and their second moment per axis is the window's,
    /// width² (1/3 + 2/π² (−a1 + a2/4 − a3/9) / a0), within 5 standard errors.
    #[test]
    fn offset_moments_match_the_window() {
        let width = 1.5f64;
        let second = width
            * width
            * (1.0 / 3.0 + 2.0 / (PI * PI) * (-A[1] + A[2] / 4.0 - A[3] / 9.0) / A[0]);
        let n = 100_000;
        let mut rng = Rng::for_sample(3, 1, 2);
        let (mut sum, mut sum2, mut sum4) = (0.0f64, 0.0f64, 0.0f64);
        for _ in 0..n {
            let o = offset(rng.next_2d(), width as f32);
            for d in [o.x as f64, o.y as f64] {
                sum += d;
                sum2 += d * d;
                sum4 += d * d * d * d;
            }
        }
        let m = 2.0 * n as f64;
        let (mean, mean2) = (sum / m, sum2 / m);
        let se2 = ((sum4 / m - mean2 * mean2) / m).sqrt();
        assert!(mean.abs() < 5.0 * (mean2 / m).sqrt(), "mean {mean}");
        assert!((mean2 - second).abs() < 5.0 * se2, "{mean2} vs {second}");
        // About a third of a pixel: Blackman-Harris 1.5 is about a Gaussian of σ 0.42 px.
        assert!((second.sqrt() - 0.42).abs() < 0.01, "{}", second.sqrt());
    }
}
