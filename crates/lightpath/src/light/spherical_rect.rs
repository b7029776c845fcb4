//! Solid-angle sampling of rectangular lights: Ureña, Fajardo and King 2013, "An
//! Area-Preserving Parametrization for Spherical Rectangles" (EGSR). Seen from a shading
//! point, a rectangle is a spherical rectangle; the paper maps the unit square onto it
//! with constant Jacobian, so uniform samples of the square are uniform in solid angle.
//!
//! Area sampling's solid-angle pdf, r² / (cos θₗ · A), varies over a light by the cube
//! of the ratio of its farthest to its nearest point (cos θₗ = |z₀| / r with z₀ the same
//! for every point of a planar light). Close to a large light (a ceiling 0.2 above a lamp
//! that size) that ratio is large and the samples near the light's edge carry huge
//! weights; from afar it is near one and the two pdfs agree. So [`Rect::seen`] chooses,
//! by the shading point alone, as `sample` and `pdf` must both choose:
//!
//! - **solid angle** when the point is within two half-diagonals of the centre (κ =
//!   [`NEAR`] = ½ of its distance), and the spherical rectangle subtends at least
//!   [`MIN_SOLID_ANGLE`]. Farther, area sampling's pdf varies over the light by at most
//!   ((1+κ)/(1−κ))³ edge-on and (1+κ²)^{3/2} ≈ 1.4 face-on, while a solid-angle sample
//!   costs far more (three atan2, a sin_cos and the square roots, in f64). κ was
//!   measured (docs/performance.md, "Solid-angle sampling of rect lights"): at κ = 0.1
//!   cornell-classic's small lamp was sampled in solid angle from everywhere, 3–5 % less
//!   error for 40–60 % more time; at 0.5 the indirect box keeps nearly all of its gain;
//! - **area** otherwise: far away, and where the spherical rectangle degenerates to an
//!   arc (the point nearly in the light's plane, where the parametrization's divisions
//!   lose their precision and the light delivers almost nothing anyway).
//!
//! **The receiver's cosine.** Uniform in solid angle still ignores cos θ at the
//! receiver, which near a large lamp varies from 1 over its middle to near 0 at its
//! far edge. As pbrt-v4 does for its rectangles (Hart, Pharr, Müller, Lopes, McGuire
//! and Shirley 2020, "Practical Product Sampling by Fitting and Composing Warps", EGSR),
//! when the shading point has a normal the unit square is first warped bilinearly by
//! |cos θ| towards the four corners (floored at [`MIN_CORNER_COSINE`], so no part of the
//! light gets a zero pdf), and the pdf is the bilinear density over Ω. `pdf` needs the
//! square's point for a direction: the parametrization's inverse ([`Seen::pdf`]), in
//! closed form because it is area-preserving: the first coordinate is the solid angle of
//! the part of the rectangle before x over Ω, the second linear in the sine of the
//! elevation along the strip. |cos θ| (not clamped at zero) keeps one choice for
//! reflection and transmission, which the pdf of a BSDF ray could not tell apart; a
//! point in a medium passes a zero normal and keeps the uniform samples.
//!
//! The parametrization is computed in f64: its solid angle is a sum of four angles
//! (less 2π), which f32 would cancel to a few digits for the small rectangles near the
//! threshold.

use glam::{DVec3, Vec2, Vec3A};
use std::f64::consts::PI;

/// A light's half-diagonal over the distance to its centre beyond which it is sampled
/// in solid angle (κ above).
pub const NEAR: f32 = 0.5;

/// Smallest subtended solid angle, in steradians, sampled as a spherical rectangle.
pub const MIN_SOLID_ANGLE: f64 = 1e-6;

/// The least corner weight of the cosine warp (pbrt-v4's): parts of the light behind or
/// edge-on to the receiver keep a pdf, which a transmissive or rough lobe may need.
pub const MIN_CORNER_COSINE: f64 = 0.01;

/// A rectangle: a corner, the unit vectors along its two edges and their lengths.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rect {
    corner: Vec3A,
    x: Vec3A,
    y: Vec3A,
    width: f32,
    height: f32,
    center: Vec3A,
    /// Squared distance from the centre within which the rectangle is sampled in solid
    /// angle: (half-diagonal / [`NEAR`])².
    near2: f32,
}

/// The rectangle as seen from a point, in the paper's local frame: x and y along the
/// edges, z towards the rectangle's plane from the point (so z₀ < 0 is its distance).
#[derive(Clone, Copy, Debug)]
pub struct Seen {
    p: Vec3A,
    x: DVec3,
    y: DVec3,
    z: DVec3,
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
    z0: f64,
    b0: f64,
    b1: f64,
    /// γ₂ + γ₃: the first coordinate's angle is u·Ω − (γ₂ + γ₃).
    g23: f64,
    /// Ω, the solid angle.
    pub solid_angle: f64,
    /// The cosine warp's corner weights (x₀y₀, x₁y₀, x₀y₁, x₁y₁), `None` without a
    /// normal.
    warp: Option<Bilinear>,
}

/// A bilinear density on the unit square with weights at its corners (00, 10, 01, 11),
/// sampled by its marginal in y and conditional in x, each linear (pbrt-v4's
/// `SampleBilinear`).
#[derive(Clone, Copy, Debug)]
struct Bilinear([f64; 4]);

impl Bilinear {
    /// The density at `(x, y)`.
    #[inline]
    fn pdf(&self, x: f64, y: f64) -> f64 {
        let [w00, w10, w01, w11] = self.0;
        4.0 * ((1.0 - x) * (1.0 - y) * w00
            + x * (1.0 - y) * w10
            + (1.0 - x) * y * w01
            + x * y * w11)
            / (w00 + w10 + w01 + w11)
    }

    /// The point `u` maps to.
    #[inline]
    fn sample(&self, u: (f64, f64)) -> (f64, f64) {
        let [w00, w10, w01, w11] = self.0;
        let y = sample_linear(u.1, w00 + w10, w01 + w11);
        let x = sample_linear(u.0, w00 + y * (w01 - w00), w10 + y * (w11 - w10));
        (x, y)
    }
}

/// The x in [0, 1] whose cdf under the density ∝ a + (b − a)·x is `u` (a, b > 0): the
/// root of the quadratic, in the form without cancellation.
#[inline]
fn sample_linear(u: f64, a: f64, b: f64) -> f64 {
    let x = u * (a + b) / (a + (a * a + u * (b * b - a * a)).sqrt());
    x.min(1.0)
}

/// F(x, y) = atan(x·y / (h·r)) at the corner (x, y) of a rectangle at height h (r the
/// corner's distance), as the complex number h·r + i·x·y whose argument it is.
#[inline]
fn corner_angle(h: f64, x: f64, y: f64) -> (f64, f64) {
    (h * (x * x + y * y + h * h).sqrt(), x * y)
}

/// The difference of two such angles (each within ±π/2), as one atan2 of a·conj(b).
#[inline]
fn angle_diff(a: (f64, f64), b: (f64, f64)) -> f64 {
    (a.1 * b.0 - a.0 * b.1).atan2(a.0 * b.0 + a.1 * b.1)
}

impl Rect {
    /// The rectangle with corner `p0` and edges `e1`, `e2`, or `None` when the edges are
    /// not perpendicular (a skewed parallelogram keeps area sampling) or are degenerate.
    pub fn new(p0: Vec3A, e1: Vec3A, e2: Vec3A) -> Option<Rect> {
        let (width, height) = (e1.length(), e2.length());
        if !(width > 0.0 && height > 0.0 && width.is_finite() && height.is_finite()) {
            return None;
        }
        if e1.dot(e2).abs() > 1e-4 * width * height {
            return None;
        }
        let half_diagonal2 = 0.25 * (width * width + height * height);
        Some(Rect {
            corner: p0,
            x: e1 / width,
            y: e2 / height,
            width,
            height,
            center: p0 + 0.5 * (e1 + e2),
            near2: half_diagonal2 / (NEAR * NEAR),
        })
    }

    /// The spherical rectangle seen from `p` when `p` is to sample it in solid angle
    /// (the module's criterion), else `None`: sample by area. A non-zero shading normal
    /// `n` warps the samples by the receiver's cosine.
    #[inline]
    pub fn seen(&self, p: Vec3A, n: Vec3A) -> Option<Seen> {
        if (p - self.center).length_squared() >= self.near2 {
            return None;
        }
        let d = self.corner - p;
        let (x, y) = (self.x.as_dvec3(), self.y.as_dvec3());
        let mut z = x.cross(y);
        let d = d.as_dvec3();
        let (x0, y0, mut z0) = (d.dot(x), d.dot(y), d.dot(z));
        if z0 > 0.0 {
            z = -z;
            z0 = -z0;
        }
        let h = -z0;
        if h.is_nan() || h <= 0.0 {
            return None;
        }
        let (x1, y1) = (x0 + f64::from(self.width), y0 + f64::from(self.height));
        // The paper's internal angles in closed form for an axis-aligned rectangle:
        // γ at the corner (x, y) is π/2 ± F(x, y), F(x, y) = atan(x·y / (h·r)) with r
        // the corner's distance, so Ω = Σγ − 2π = F₁₁ − F₀₁ + F₀₀ − F₁₀ and γ₂ + γ₃ =
        // π + F₀₀ − F₀₁. F as the argument of h·r + i·x·y; differences of two F (each
        // within ±π/2) as one atan2 of a·conj(b): three atan2 in all instead of four
        // acos of normalized cross products.
        let corner = |x: f64, y: f64| corner_angle(h, x, y);
        let (c00, c01, c10, c11) = (
            corner(x0, y0),
            corner(x0, y1),
            corner(x1, y0),
            corner(x1, y1),
        );
        let solid_angle = angle_diff(c11, c01) + angle_diff(c00, c10);
        // NaN (a degenerate frame) fails this too.
        if solid_angle.is_nan() || solid_angle < MIN_SOLID_ANGLE {
            return None;
        }
        // The z components of the planes' normals through the edges y = y₀ and y = y₁.
        let b0 = -y0 / (h * h + y0 * y0).sqrt();
        let b1 = y1 / (h * h + y1 * y1).sqrt();
        let warp = (n != Vec3A::ZERO).then(|| {
            // |cos θ| towards a corner: |n · (x, y, z₀)| / r, and r = c.0 / h.
            let n = n.as_dvec3();
            let (nx, ny, nz) = (n.dot(x), n.dot(y), n.dot(z));
            let w = |xc: f64, yc: f64, c: (f64, f64)| {
                ((xc * nx + yc * ny + z0 * nz).abs() * h / c.0).max(MIN_CORNER_COSINE)
            };
            Bilinear([
                w(x0, y0, c00),
                w(x1, y0, c10),
                w(x0, y1, c01),
                w(x1, y1, c11),
            ])
        });
        Some(Seen {
            p,
            x,
            y,
            z,
            x0,
            x1,
            y0,
            y1,
            z0,
            b0,
            b1,
            g23: PI + angle_diff(c00, c01),
            solid_angle,
            warp,
        })
    }
}

impl Seen {
    /// The point of the rectangle that `u` maps to and its solid-angle pdf: the cosine
    /// warp, then the paper's inversion (uniform in solid angle).
    #[inline]
    pub fn sample(&self, u: Vec2) -> (Vec3A, f32) {
        let u = (f64::from(u.x), f64::from(u.y));
        let (u, density) = match &self.warp {
            Some(w) => {
                let v = w.sample(u);
                (v, w.pdf(v.0, v.1))
            }
            None => (u, 1.0),
        };
        (self.point(u), (density / self.solid_angle) as f32)
    }

    /// The paper's map from the unit square onto the rectangle.
    #[inline]
    fn point(&self, (u0, u1): (f64, f64)) -> Vec3A {
        let au = u0 * self.solid_angle - self.g23;
        let (sin_au, cos_au) = au.sin_cos();
        let fu = (cos_au * self.b0 - self.b1) / sin_au;
        let cu = (1.0 / (fu * fu + self.b0 * self.b0).sqrt()).copysign(fu);
        let cu = cu.clamp(-1.0 + 1e-12, 1.0 - 1e-12);
        let xu = (-(cu * self.z0) / (1.0 - cu * cu).sqrt()).clamp(self.x0, self.x1);
        // NaN (fu = 0/0 at the very ends of u) falls back to the nearer edge.
        let xu = if xu.is_nan() { self.x0 } else { xu };
        let d2 = xu * xu + self.z0 * self.z0;
        let h0 = self.y0 / (d2 + self.y0 * self.y0).sqrt();
        let h1 = self.y1 / (d2 + self.y1 * self.y1).sqrt();
        let hv = h0 + u1 * (h1 - h0);
        let hv2 = hv * hv;
        let yv = if hv2 < 1.0 - 1e-12 {
            (hv * d2.sqrt() / (1.0 - hv2).sqrt()).clamp(self.y0, self.y1)
        } else {
            self.y1
        };
        let q = self.x * xu + self.y * yv + self.z * self.z0;
        self.p + Vec3A::from(q.as_vec3())
    }

    /// The solid-angle pdf with which [`sample`](Self::sample) picks the point `q` of the
    /// rectangle: 1 / Ω, times the warp's density at `q`'s point of the square.
    #[inline]
    pub fn pdf(&self, q: Vec3A) -> f32 {
        let density = match &self.warp {
            Some(w) => {
                let (u0, u1) = self.inverse(q);
                w.pdf(u0, u1)
            }
            None => 1.0,
        };
        (density / self.solid_angle) as f32
    }

    /// The point of the unit square that [`point`](Self::point) maps to `q`. The map is
    /// area-preserving, so u₀ is the solid angle of the rectangle's part x₀ ≤ x ≤ x_q
    /// over Ω (the same closed form as Ω's, `Rect::seen`), and u₁ is linear in the sine
    /// of the elevation along the strip at x_q, as `point` interpolates it.
    #[inline]
    fn inverse(&self, q: Vec3A) -> (f64, f64) {
        let d = (q - self.p).as_dvec3();
        let xq = d.dot(self.x).clamp(self.x0, self.x1);
        let yq = d.dot(self.y).clamp(self.y0, self.y1);
        let h = -self.z0;
        let corner = |x: f64, y: f64| corner_angle(h, x, y);
        let part = angle_diff(corner(xq, self.y1), corner(self.x0, self.y1))
            + angle_diff(corner(self.x0, self.y0), corner(xq, self.y0));
        let u0 = (part / self.solid_angle).clamp(0.0, 1.0);
        let d2 = xq * xq + self.z0 * self.z0;
        let h0 = self.y0 / (d2 + self.y0 * self.y0).sqrt();
        let h1 = self.y1 / (d2 + self.y1 * self.y1).sqrt();
        let hv = yq / (d2 + yq * yq).sqrt();
        let u1 = if h1 > h0 {
            ((hv - h0) / (h1 - h0)).clamp(0.0, 1.0)
        } else {
            0.5
        };
        (u0, u1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    fn lamp() -> Rect {
        // The indirect box's lamp: 0.46 × 0.38 at y = 0.8, facing +y.
        Rect::new(
            Vec3A::new(-0.23, 0.8, -0.18),
            Vec3A::new(0.0, 0.0, 0.38),
            Vec3A::new(0.46, 0.0, 0.0),
        )
        .unwrap()
    }

    /// The solid angle of a rectangle seen from `p`, by summing the solid angles of a
    /// fine grid of its cells (each a small flat patch: area × |cos| / r²), in f64.
    fn solid_angle_by_cells(r: &Rect, p: Vec3A, n: usize) -> f64 {
        let z = r.x.cross(r.y).as_dvec3();
        let mut sum = 0.0;
        let cell = f64::from(r.width) * f64::from(r.height) / (n * n) as f64;
        for i in 0..n {
            for j in 0..n {
                let q = r.corner.as_dvec3()
                    + r.x.as_dvec3() * (f64::from(r.width) * (i as f64 + 0.5) / n as f64)
                    + r.y.as_dvec3() * (f64::from(r.height) * (j as f64 + 0.5) / n as f64);
                let d = q - p.as_dvec3();
                let r2 = d.length_squared();
                sum += cell * d.dot(z).abs() / (r2 * r2.sqrt());
            }
        }
        sum
    }

    /// Ω from the four angles agrees with Ω summed over the rectangle's cells, near
    /// and at grazing angles.
    #[test]
    fn the_solid_angle_is_the_rectangles() {
        let r = lamp();
        for p in [
            Vec3A::new(0.0, 1.0, 0.0),
            Vec3A::new(0.3, 0.95, -0.1),
            Vec3A::new(-0.4, 0.9, 0.3),
            Vec3A::new(0.5, 0.81, 0.0),
            Vec3A::new(0.1, 0.3, 0.05),
        ] {
            let seen = r.seen(p, Vec3A::ZERO).expect("near the lamp");
            let cells = solid_angle_by_cells(&r, p, 800);
            let rel = seen.solid_angle / cells - 1.0;
            assert!(rel.abs() < 1e-4, "at {p}: {} vs {cells}", seen.solid_angle);
        }
    }

    /// Samples are on the rectangle and uniform in solid angle: a χ² test over an 8 × 8
    /// grid of cells, each expected to get n · Ω_cell / Ω samples.
    #[test]
    fn samples_are_uniform_in_solid_angle() {
        let r = lamp();
        let mut rng = Rng::for_sample(5, 2, 8);
        for p in [
            Vec3A::new(0.0, 1.0, 0.0),
            Vec3A::new(0.4, 0.9, 0.3),
            Vec3A::new(0.0, 0.805, 0.5),
        ] {
            let seen = r.seen(p, Vec3A::ZERO).unwrap();
            const K: usize = 8;
            let n = 200_000;
            let mut counts = [[0u32; K]; K];
            for _ in 0..n {
                let (q, pdf) = seen.sample(rng.next_2d());
                assert_eq!(pdf, seen.pdf(q));
                assert!((f64::from(pdf) * seen.solid_angle - 1.0).abs() < 1e-6);
                let d = q - r.corner;
                let (a, b) = (d.dot(r.x) / r.width, d.dot(r.y) / r.height);
                assert!(
                    (-1e-4..=1.0 + 1e-4).contains(&a) && (-1e-4..=1.0 + 1e-4).contains(&b),
                    "{q} off the rectangle"
                );
                assert!(d.dot(r.x.cross(r.y)).abs() < 1e-5, "{q} off the plane");
                let (i, j) = (
                    ((a * K as f32) as usize).min(K - 1),
                    ((b * K as f32) as usize).min(K - 1),
                );
                counts[i][j] += 1;
            }
            let mut chi2 = 0.0;
            for (i, row) in counts.iter().enumerate() {
                for (j, &c) in row.iter().enumerate() {
                    let (w, h) = (r.width / K as f32, r.height / K as f32);
                    let cell = Rect::new(
                        r.corner + r.x * (w * i as f32) + r.y * (h * j as f32),
                        r.x * w,
                        r.y * h,
                    )
                    .unwrap();
                    let expected = n as f64 * solid_angle_by_cells(&cell, p, 40) / seen.solid_angle;
                    chi2 += (f64::from(c) - expected).powi(2) / expected;
                }
            }
            // 63 degrees of freedom: mean 63, standard deviation √126 ≈ 11.2; 5 of them.
            assert!(chi2 < 63.0 + 5.0 * 126f64.sqrt(), "at {p}: χ² = {chi2}");
        }
    }

    /// Receivers near the lamp with their shading normals: the ceiling right above it,
    /// a wall beside it, a tilted surface below it, and one that sees some of the lamp's
    /// corners from behind (the warp takes |cos|).
    const RECEIVERS: [(Vec3A, Vec3A); 4] = [
        (Vec3A::new(0.0, 1.0, 0.0), Vec3A::new(0.0, -1.0, 0.0)),
        (Vec3A::new(0.5, 0.9, 0.0), Vec3A::new(-1.0, 0.0, 0.0)),
        (Vec3A::new(0.1, 0.5, 0.2), Vec3A::new(0.6, 0.8, 0.0)),
        (Vec3A::new(0.1, 0.95, 0.1), Vec3A::new(1.0, 0.0, 0.0)),
    ];

    /// The warped map's inverse gives back the square's point (what `pdf` relies on).
    #[test]
    fn the_inverse_undoes_the_map() {
        let r = lamp();
        let mut rng = Rng::for_sample(9, 1, 2);
        for (p, _) in RECEIVERS {
            let seen = r.seen(p, Vec3A::ZERO).unwrap();
            for _ in 0..20_000 {
                let u = rng.next_2d();
                let u = (0.005 + 0.99 * f64::from(u.x), 0.005 + 0.99 * f64::from(u.y));
                let (a, b) = seen.inverse(seen.point(u));
                assert!(
                    (a - u.0).abs() < 1e-3 && (b - u.1).abs() < 1e-3,
                    "at {p}: {u:?} came back as ({a}, {b})"
                );
            }
        }
    }

    /// Samples warped by the receiver's cosine follow the pdf `pdf` gives them: a χ²
    /// test over an 8 × 8 grid of cells, each expected to get n · ∫ pdf dω over the cell
    /// (by the midpoint rule on 24 × 24 patches of it). The expected counts add up to n
    /// only if the pdf integrates to one.
    #[test]
    fn warped_samples_follow_their_pdf() {
        let r = lamp();
        let z = r.x.cross(r.y);
        let mut rng = Rng::for_sample(6, 4, 1);
        for (p, n) in RECEIVERS {
            let seen = r.seen(p, n).unwrap();
            const K: usize = 8;
            const M: usize = 24;
            let samples = 200_000;
            let mut counts = [[0u32; K]; K];
            for _ in 0..samples {
                let (q, pdf) = seen.sample(rng.next_2d());
                let again = seen.pdf(q);
                assert!(
                    (again - pdf).abs() <= 1e-3 * pdf,
                    "at {p}: {pdf} vs {again}"
                );
                let d = q - r.corner;
                let (a, b) = (d.dot(r.x) / r.width, d.dot(r.y) / r.height);
                let (i, j) = (
                    ((a * K as f32) as usize).min(K - 1),
                    ((b * K as f32) as usize).min(K - 1),
                );
                counts[i][j] += 1;
            }
            let mut chi2 = 0.0;
            let mut total = 0.0;
            let patch = f64::from(r.width * r.height) / ((K * M) as f64).powi(2);
            for (i, row) in counts.iter().enumerate() {
                for (j, &c) in row.iter().enumerate() {
                    let mut integral = 0.0;
                    for k in 0..M {
                        for l in 0..M {
                            let (a, b) = (
                                ((i * M + k) as f32 + 0.5) / (K * M) as f32,
                                ((j * M + l) as f32 + 0.5) / (K * M) as f32,
                            );
                            let q = r.corner + r.x * (a * r.width) + r.y * (b * r.height);
                            let d = (q - p).as_dvec3();
                            let r2 = d.length_squared();
                            let d_omega = patch * d.dot(z.as_dvec3()).abs() / (r2 * r2.sqrt());
                            integral += f64::from(seen.pdf(q)) * d_omega;
                        }
                    }
                    total += integral;
                    let expected = samples as f64 * integral;
                    chi2 += (f64::from(c) - expected).powi(2) / expected;
                }
            }
            assert!((total - 1.0).abs() < 2e-3, "at {p}: ∫ pdf dω = {total}");
            // 63 degrees of freedom: mean 63, standard deviation √126 ≈ 11.2; 5 of them.
            assert!(chi2 < 63.0 + 5.0 * 126f64.sqrt(), "at {p}: χ² = {chi2}");
        }
    }

    /// The warp's corner weights are the receiver's |cos θ| towards each corner.
    #[test]
    fn the_warp_weighs_corners_by_the_receivers_cosine() {
        let r = lamp();
        for (p, n) in RECEIVERS {
            let Bilinear(w) = r.seen(p, n).unwrap().warp.unwrap();
            let corners = [
                r.corner,
                r.corner + r.x * r.width,
                r.corner + r.y * r.height,
                r.corner + r.x * r.width + r.y * r.height,
            ];
            for (k, c) in corners.into_iter().enumerate() {
                let cos = f64::from((c - p).normalize().dot(n).abs()).max(MIN_CORNER_COSINE);
                assert!(
                    (w[k] - cos).abs() < 1e-5,
                    "at {p}, corner {k}: {} vs {cos}",
                    w[k]
                );
            }
        }
    }

    /// Far away and in the plane of the light, `seen` leaves the light to area sampling.
    #[test]
    fn far_and_edge_on_points_sample_by_area() {
        let r = lamp();
        for n in [Vec3A::ZERO, Vec3A::Y] {
            assert!(r.seen(Vec3A::new(0.0, 10.0, 0.0), n).is_none());
            assert!(r.seen(Vec3A::new(0.4, 0.8, 0.0), n).is_none());
            assert!(r.seen(Vec3A::new(0.5, 1.0, 0.6), n).is_none());
            assert!(r.seen(Vec3A::new(0.0, 0.9, 0.0), n).is_some());
        }
        // A parallelogram that is not a rectangle has no spherical rectangle.
        assert!(Rect::new(Vec3A::ZERO, Vec3A::X, Vec3A::new(0.5, 1.0, 0.0)).is_none());
        assert!(Rect::new(Vec3A::ZERO, Vec3A::ZERO, Vec3A::Y).is_none());
    }
}
