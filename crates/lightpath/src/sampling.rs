//! Random numbers and the warps that turn them into directions and points. Each warp
//! states its pdf next to it.

use glam::{Vec2, Vec3A};
use std::f32::consts::{FRAC_1_PI, PI};

/// PCG32 (O'Neill 2014): small, fast, and good enough for Monte Carlo.
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
    inc: u64,
}

/// A 64-bit mix (splitmix64's finaliser): a hash of `x`, for seeding.
pub fn splitmix64(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

impl Rng {
    /// A stream for paths that draw nothing from it: no seeding to pay for.
    pub const UNUSED: Rng = Rng { state: 0, inc: 1 };

    /// The generator of one camera sample: seeded by (seed, pixel, sample index) so a
    /// render is identical for any thread count and sample ranges merge exactly.
    pub fn for_sample(seed: u64, pixel: u64, sample: u64) -> Rng {
        let a = splitmix64(
            seed ^ splitmix64(pixel.wrapping_mul(0x2545_f491_4f6c_dd1d) ^ splitmix64(sample)),
        );
        let b = splitmix64(a ^ 0x6a09_e667_f3bc_c909);
        let mut r = Rng {
            state: 0,
            inc: (b << 1) | 1,
        };
        r.next_u32();
        r.state = r.state.wrapping_add(a);
        r.next_u32();
        r
    }

    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in [0, 1).
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    #[inline]
    pub fn next_2d(&mut self) -> Vec2 {
        Vec2::new(self.next_f32(), self.next_f32())
    }
}

/// An orthonormal basis around `n` (Duff et al. 2017, "Building an Orthonormal Basis,
/// Revisited").
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    pub s: Vec3A,
    pub t: Vec3A,
    pub n: Vec3A,
}

impl Frame {
    pub fn new(n: Vec3A) -> Frame {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3A::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3A::new(b, sign + n.y * n.y * a, -n.y);
        Frame { s, t, n }
    }
    #[inline]
    pub fn to_local(&self, v: Vec3A) -> Vec3A {
        Vec3A::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }
    #[inline]
    pub fn to_world(&self, v: Vec3A) -> Vec3A {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

/// (sin a, cos a) for |a| ≤ π/4 by Taylor polynomials, within 3e-7 of the true
/// values. libm's `sincosf` handles any argument and cost 4 % of a render; the warps
/// below only ever need an octant.
#[inline]
pub fn sin_cos_octant(a: f32) -> (f32, f32) {
    let a2 = a * a;
    let sin = a * (1.0 + a2 * (-1.0 / 6.0 + a2 * (1.0 / 120.0 + a2 * (-1.0 / 5040.0))));
    let cos = 1.0 + a2 * (-0.5 + a2 * (1.0 / 24.0 + a2 * (-1.0 / 720.0 + a2 * (1.0 / 40320.0))));
    (sin, cos)
}

/// (sin 2πt, cos 2πt) for `t` in [0, 1], within 3e-7: the quadrant's centre angle plus
/// an offset of at most π/4.
#[inline]
pub fn sin_cos_turns(t: f32) -> (f32, f32) {
    let x = t.clamp(0.0, 1.0) * 4.0;
    let quadrant = (x as u32).min(3);
    let (s, c) = sin_cos_octant((x - quadrant as f32 - 0.5) * (PI / 2.0));
    let h = std::f32::consts::FRAC_1_SQRT_2;
    // sin and cos of (centre + a), centre = π/4 + quadrant·π/2.
    let (p, m) = (h * (c + s), h * (c - s));
    match quadrant {
        0 => (p, m),
        1 => (m, -p),
        2 => (-p, -m),
        _ => (-m, p),
    }
}

/// Concentric mapping of the unit square to the unit disk (Shirley & Chiu 1997);
/// uniform in area.
pub fn square_to_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    if o.x.abs() > o.y.abs() {
        // θ = π/4 · y/x
        let (sin, cos) = sin_cos_octant(PI / 4.0 * (o.y / o.x));
        o.x * Vec2::new(cos, sin)
    } else {
        // θ = π/2 − π/4 · x/y: cos θ = sin(π/4 · x/y), sin θ = cos(π/4 · x/y).
        let (sin, cos) = sin_cos_octant(PI / 4.0 * (o.x / o.y));
        o.y * Vec2::new(sin, cos)
    }
}

/// Cosine-weighted hemisphere around +z; pdf = cos θ / π.
pub fn cosine_hemisphere(u: Vec2) -> Vec3A {
    let d = square_to_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3A::new(d.x, d.y, z)
}

pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * FRAC_1_PI
}

/// Uniform direction on the sphere; pdf = 1 / 4π.
pub fn uniform_sphere(u: Vec2) -> Vec3A {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (sin, cos) = sin_cos_turns(u.y);
    Vec3A::new(r * cos, r * sin, z)
}

/// Uniform direction in the cone of half-angle acos(`cos_max`) around +z;
/// pdf = 1 / (2π (1 − cos_max)).
pub fn uniform_cone(u: Vec2, cos_max: f32) -> Vec3A {
    let cos_t = 1.0 - u.x * (1.0 - cos_max);
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let (sin, cos) = sin_cos_turns(u.y);
    Vec3A::new(sin_t * cos, sin_t * sin, cos_t)
}

pub fn uniform_cone_pdf(cos_max: f32) -> f32 {
    1.0 / (2.0 * PI * (1.0 - cos_max))
}

/// Uniform barycentrics on a triangle (pdf = 1 / area).
pub fn uniform_triangle(u: Vec2) -> (f32, f32) {
    let su = u.x.sqrt();
    (1.0 - su, u.y * su)
}

/// A discrete distribution over items by weight, sampled by binary search.
#[derive(Clone, Debug, Default)]
pub struct Distribution1D {
    cdf: Vec<f32>,
    total: f32,
}

impl Distribution1D {
    pub fn new(weights: &[f32]) -> Distribution1D {
        let mut cdf = Vec::with_capacity(weights.len());
        let mut total = 0.0f64;
        for &w in weights {
            total += w.max(0.0) as f64;
            cdf.push(total as f32);
        }
        Distribution1D {
            cdf,
            total: total as f32,
        }
    }
    pub fn total(&self) -> f32 {
        self.total
    }
    pub fn len(&self) -> usize {
        self.cdf.len()
    }
    pub fn is_empty(&self) -> bool {
        self.cdf.is_empty()
    }
    /// Samples an index; returns it with its probability and `u` remapped to [0, 1)
    /// within the chosen item.
    pub fn sample(&self, u: f32) -> (usize, f32, f32) {
        if self.cdf.len() == 1 {
            return (0, 1.0, u);
        }
        let target = u * self.total;
        let i = self
            .cdf
            .partition_point(|&c| c <= target)
            .min(self.cdf.len() - 1);
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        let w = self.cdf[i] - lo;
        let remapped = if w > 0.0 {
            ((target - lo) / w).clamp(0.0, 0.999_999_94)
        } else {
            0.0
        };
        (i, w / self.total, remapped)
    }
    pub fn pmf(&self, i: usize) -> f32 {
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        (self.cdf[i] - lo) / self.total
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_sin_cos_match_libm() {
        let mut worst = 0.0f32;
        for i in 0..=100_000 {
            let t = i as f32 / 100_000.0;
            let (s, c) = sin_cos_turns(t);
            let a = 2.0 * std::f64::consts::PI * t as f64;
            worst = worst
                .max((s as f64 - a.sin()).abs() as f32)
                .max((c as f64 - a.cos()).abs() as f32);
            let a = (t - 0.5) * PI / 2.0;
            let (s, c) = sin_cos_octant(a);
            worst = worst
                .max((s as f64 - (a as f64).sin()).abs() as f32)
                .max((c as f64 - (a as f64).cos()).abs() as f32);
        }
        assert!(worst < 5e-7, "worst error {worst}");
    }

    #[test]
    fn generators_are_deterministic_and_distinct() {
        let mut a = Rng::for_sample(1, 2, 3);
        let mut b = Rng::for_sample(1, 2, 3);
        let mut c = Rng::for_sample(1, 2, 4);
        let va: Vec<u32> = (0..8).map(|_| a.next_u32()).collect();
        assert_eq!(va, (0..8).map(|_| b.next_u32()).collect::<Vec<_>>());
        assert_ne!(va, (0..8).map(|_| c.next_u32()).collect::<Vec<_>>());
        let mean = (0..100_000).map(|_| a.next_f32() as f64).sum::<f64>() / 100_000.0;
        // Standard error of the mean of U(0,1) over 1e5 draws is 0.0009.
        assert!((mean - 0.5).abs() < 0.005, "{mean}");
    }

    #[test]
    fn frames_are_orthonormal() {
        for n in [Vec3A::Z, -Vec3A::Z, Vec3A::new(0.3, -0.5, 0.8).normalize()] {
            let f = Frame::new(n);
            assert!(
                f.s.dot(f.t).abs() < 1e-5 && f.s.dot(n).abs() < 1e-5 && f.t.dot(n).abs() < 1e-5
            );
            let v = Vec3A::new(0.2, 0.4, -0.3);
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-5);
        }
    }

    #[test]
    fn distribution_samples_by_weight() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0]);
        assert_eq!(d.sample(0.1).0, 0);
        assert_eq!(d.sample(0.5).0, 2);
        assert!((d.pmf(2) - 0.75).abs() < 1e-6);
    }
}
