//! Portals: the openings (windows, doors, skylights) through which a dome lights an
//! interior. A dome with portals samples its light through them: a portal chosen
//! uniformly, a point on it (in solid angle from close by, warped by the receiver's
//! cosine, else uniformly in area, as a rectangle light: `spherical_rect.rs`), the
//! dome's radiance along that direction; its pdf of a direction is the mean over the
//! portals that direction passes through, and 0 elsewhere. Directions through no portal
//! are left to BSDF rays, which MIS weighs against that pdf (they keep their whole weight
//! there), so nothing is lost: a portal in the wrong place costs noise, never light.
//! RenderMan's PxrPortalLight and Cycles' portals do the same job.
//!
//! ```toml
//! [[lights]]
//! type = "dome"
//! radiance = [1, 1, 1]
//! portals = [[[1.5, -0.2, -1.3], [1.5, -0.2, -0.5], [1.5, 0.6, -0.5], [1.5, 0.6, -1.3]]]
//! ```

use super::spherical_rect::Rect;
use glam::{Vec2, Vec3A};

/// One portal: a parallelogram (corner, edges), its unit normal and area, and the
/// rectangle it is when its edges are perpendicular (sampled in solid angle).
#[derive(Clone, Debug)]
pub struct Portal {
    p0: Vec3A,
    e1: Vec3A,
    e2: Vec3A,
    n: Vec3A,
    area: f32,
    rect: Option<Rect>,
}

impl Portal {
    /// The portal with these four corners, in order round it; `None` unless they make a
    /// flat parallelogram of some area (the fourth corner within 10⁻⁴ of its size of
    /// where the first three put it).
    pub fn new(corners: [Vec3A; 4]) -> Option<Portal> {
        let [c0, c1, c2, c3] = corners;
        let (e1, e2) = (c1 - c0, c3 - c0);
        let cross = e1.cross(e2);
        let area = cross.length();
        let size = e1.length().max(e2.length());
        if !(area > 0.0 && area.is_finite()) || (c0 + e1 + e2 - c2).length() > 1e-4 * size {
            return None;
        }
        Some(Portal {
            p0: c0,
            e1,
            e2,
            n: cross / area,
            area,
            rect: Rect::new(c0, e1, e2),
        })
    }

    /// Where a ray from `p` along `dir` crosses the portal, if it does (ahead of `p`).
    #[inline]
    fn crossing(&self, p: Vec3A, dir: Vec3A) -> Option<(Vec3A, f32)> {
        let denom = dir.dot(self.n);
        if denom == 0.0 {
            return None;
        }
        let t = (self.p0 - p).dot(self.n) / denom;
        if !(t > 0.0 && t.is_finite()) {
            return None;
        }
        let q = p + dir * t;
        // q − p0 = a·e1 + b·e2, solved in the plane (the edges need not be square).
        let d = q - self.p0;
        let a = d.cross(self.e2).dot(self.n) / self.area;
        let b = self.e1.cross(d).dot(self.n) / self.area;
        // A sample on the edge may round to just outside it.
        const EDGE: std::ops::RangeInclusive<f32> = -1e-5..=1.0 + 1e-5;
        (EDGE.contains(&a) && EDGE.contains(&b)).then_some((q, t))
    }

    /// The solid-angle pdf with which `sample` from `p` (normal `n`) picks the point
    /// where `dir` crosses the portal; 0 where it does not.
    #[inline]
    fn pdf(&self, p: Vec3A, n: Vec3A, dir: Vec3A) -> f32 {
        let Some((q, t)) = self.crossing(p, dir) else {
            return 0.0;
        };
        // The same choice as `sample`'s, by `p` and `n` alone.
        if let Some(seen) = self.rect.as_ref().and_then(|r| r.seen(p, n)) {
            return seen.pdf(q);
        }
        let cos = self.n.dot(dir).abs();
        if cos == 0.0 {
            0.0
        } else {
            t * t / (cos * self.area)
        }
    }

    /// A direction from `p` (normal `n`) through the portal and this portal's `pdf` of
    /// it; `None` from its plane.
    #[inline]
    fn sample(&self, p: Vec3A, n: Vec3A, u: Vec2) -> Option<(Vec3A, f32)> {
        let height = (p - self.p0).dot(self.n);
        let scale = self.p0.abs().max_element() + self.e1.length() + self.e2.length();
        if height.abs() <= 1e-5 * scale {
            return None;
        }
        let (q, seen_pdf) = match self.rect.as_ref().and_then(|r| r.seen(p, n)) {
            Some(seen) => {
                let (q, pdf) = seen.sample(u);
                (q, Some(pdf))
            }
            None => (self.p0 + self.e1 * u.x + self.e2 * u.y, None),
        };
        let d = q - p;
        let len = d.length();
        if !(len > 0.0 && len.is_finite()) {
            return None;
        }
        let wi = d / len;
        // The same density `pdf` gives, without seeing the rectangle again.
        let pdf = seen_pdf.unwrap_or_else(|| {
            let cos = self.n.dot(wi).abs();
            if cos == 0.0 {
                0.0
            } else {
                len * len / (cos * self.area)
            }
        });
        Some((wi, pdf))
    }
}

/// A direction from `p` (normal `n`) through one of `portals`, chosen uniformly
/// (`u.x` reused), and its pdf (`pdf`: every portal it passes through counts).
pub fn sample(portals: &[Portal], p: Vec3A, n: Vec3A, u: Vec2) -> Option<(Vec3A, f32)> {
    let count = portals.len();
    if count == 0 {
        return None;
    }
    let x = u.x * count as f32;
    let k = (x as usize).min(count - 1);
    let u = Vec2::new((x - k as f32).clamp(0.0, 1.0 - f32::EPSILON), u.y);
    let (wi, own) = portals[k].sample(p, n, u)?;
    let others: f32 = (portals.iter().enumerate())
        .filter(|&(j, _)| j != k)
        .map(|(_, q)| q.pdf(p, n, wi))
        .sum();
    let pdf = (own + others) / count as f32;
    (pdf > 0.0 && pdf.is_finite()).then_some((wi, pdf))
}

/// The pdf of direction `dir` from `p` (normal `n`): the mean of the portals' pdfs.
pub fn pdf(portals: &[Portal], p: Vec3A, n: Vec3A, dir: Vec3A) -> f32 {
    if portals.is_empty() {
        return 0.0;
    }
    let sum: f32 = portals.iter().map(|q| q.pdf(p, n, dir)).sum();
    sum / portals.len() as f32
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::PI;

    /// Directions sampled through two portals (one a rectangle seen from close by, in
    /// solid angle with the cosine warp; one a skewed parallelogram, by area) integrate
    /// the pdf to one, and a histogram of them agrees with the pdf (χ²).
    #[test]
    fn portal_directions_follow_their_density() {
        let window = Portal::new([
            Vec3A::new(1.0, -0.3, -0.4),
            Vec3A::new(1.0, -0.3, 0.4),
            Vec3A::new(1.0, 0.5, 0.4),
            Vec3A::new(1.0, 0.5, -0.4),
        ])
        .unwrap();
        let skylight = Portal::new([
            Vec3A::new(-0.5, 2.0, -0.5),
            Vec3A::new(0.5, 2.0, -0.3),
            Vec3A::new(0.5, 2.0, 0.7),
            Vec3A::new(-0.5, 2.0, 0.5),
        ])
        .unwrap();
        let portals = [window, skylight];
        let (p, n) = (Vec3A::new(0.2, 0.0, 0.1), Vec3A::new(0.6, 0.8, 0.0));
        // Bins over the sphere in (cos θ, φ) about +z; the pdf integrated over each bin
        // by a fine midpoint rule.
        const NT: usize = 40;
        const NP: usize = 80;
        let bin = |w: Vec3A| {
            let t = (((w.z + 1.0) * 0.5 * NT as f32) as usize).min(NT - 1);
            let phi = (w.y.atan2(w.x) / (2.0 * PI) + 0.5) * NP as f32;
            t * NP + (phi as usize).min(NP - 1)
        };
        let n_samples = 200_000u32;
        let mut counts = vec![0f64; NT * NP];
        let mut rng = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            (rng >> 40) as f32 / (1u64 << 24) as f32
        };
        for _ in 0..n_samples {
            let (w, pdf) = sample(&portals, p, n, Vec2::new(next(), next())).unwrap();
            assert!((pdf - super::pdf(&portals, p, n, w)).abs() <= 1e-4 * pdf);
            counts[bin(w)] += 1.0;
        }
        let mut expected = vec![0f64; NT * NP];
        // Fine enough that the portals' edges, which cut bins, cost the rule < 1 %.
        let fine = 40;
        let mut total = 0.0;
        for i in 0..NT * fine {
            let c = -1.0 + 2.0 * (i as f32 + 0.5) / (NT * fine) as f32;
            let s = (1.0 - c * c).sqrt();
            for j in 0..NP * fine {
                let phi = ((j as f32 + 0.5) / (NP * fine) as f32 - 0.5) * 2.0 * PI;
                let w = Vec3A::new(s * phi.cos(), s * phi.sin(), c);
                let d_omega = (2.0 / (NT * fine) as f32) * (2.0 * PI / (NP * fine) as f32);
                let mass = (super::pdf(&portals, p, n, w) * d_omega) as f64;
                total += mass;
                expected[bin(w)] += mass * n_samples as f64;
            }
        }
        assert!((total - 1.0).abs() < 0.02, "the pdf integrates to {total}");
        let (mut chi2, mut dof) = (0.0, 0);
        for (o, e) in counts.iter().zip(&expected) {
            if *e > 20.0 {
                chi2 += (o - e) * (o - e) / e;
                dof += 1;
            } else {
                assert!(*o < 60.0, "{o} samples where {e} were expected");
            }
        }
        let limit = dof as f64 + 5.0 * (2.0 * dof as f64).sqrt();
        assert!(dof > 30 && chi2 < limit, "χ² {chi2:.1} over {dof} bins");
    }

    #[test]
    fn a_portal_must_be_a_flat_parallelogram() {
        let flat = [Vec3A::ZERO, Vec3A::X, Vec3A::new(1.0, 1.0, 0.0), Vec3A::Y];
        assert!(Portal::new(flat).is_some());
        let bent = [flat[0], flat[1], Vec3A::new(1.0, 1.0, 0.3), flat[3]];
        assert!(Portal::new(bent).is_none());
        assert!(Portal::new([Vec3A::ZERO; 4]).is_none());
    }
}
