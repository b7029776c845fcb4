//! Equiangular sampling of a distance along a ray towards a point (Kulla & Fajardo 2012,
//! "Importance Sampling Techniques for Path Tracing in Participating Media"): the
//! density is proportional to 1/r², the inverse square falloff of a point light's
//! irradiance, so single scattering near a point or spot light is sampled where it is
//! bright instead of where the medium is dense.

use crate::geometry::Ray;

/// The distances of `ray` in `[0, ray.tmax)` as angles seen from a point.
#[derive(Clone, Copy, Debug)]
pub struct Equiangular {
    /// Distance along the ray to the point's foot, and the point's distance from it.
    foot: f32,
    dist: f32,
    theta_a: f32,
    theta_b: f32,
}

impl Equiangular {
    /// `None` when the ray passes (numerically) through the point, or has no length.
    pub fn new(ray: &Ray, point: glam::Vec3A) -> Option<Equiangular> {
        let foot = (point - ray.origin).dot(ray.dir);
        let dist = (ray.origin + ray.dir * foot - point).length();
        if !(dist > 1e-6 && ray.tmax > 0.0 && foot.is_finite()) {
            return None;
        }
        let theta_a = (-foot / dist).atan();
        let theta_b = ((ray.tmax - foot) / dist).atan();
        (theta_b > theta_a).then_some(Equiangular {
            foot,
            dist,
            theta_a,
            theta_b,
        })
    }

    /// A distance for `u` in [0, 1), and its density.
    pub fn sample(&self, u: f32) -> (f32, f32) {
        let theta = self.theta_a + u * (self.theta_b - self.theta_a);
        let t = self.foot + self.dist * theta.tan();
        (t, self.pdf(t))
    }

    /// The density of distance `t`.
    pub fn pdf(&self, t: f32) -> f32 {
        let x = t - self.foot;
        self.dist / ((self.theta_b - self.theta_a) * (self.dist * self.dist + x * x))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3A;

    /// The density integrates to one over the segment, and samples fall inside it with
    /// the density `pdf` gives (histogram in 20 bins, 4.5 standard errors each).
    #[test]
    fn equiangular_density_is_normalised_and_sampled() {
        let ray = Ray {
            origin: Vec3A::ZERO,
            dir: Vec3A::X,
            tmax: 3.0,
        };
        let e = Equiangular::new(&ray, Vec3A::new(1.0, 0.4, 0.0)).unwrap();
        let n = 100_000;
        let integral: f64 = (0..n)
            .map(|i| f64::from(e.pdf((i as f32 + 0.5) / n as f32 * 3.0)) * 3.0 / n as f64)
            .sum();
        assert!((integral - 1.0).abs() < 1e-3, "{integral}");
        let mut bins = [0u32; 20];
        let mut rng = crate::sampling::Rng::for_sample(1, 2, 3);
        for _ in 0..n {
            let (t, pdf) = e.sample(rng.next_f32());
            assert!((0.0..3.0).contains(&t) && (pdf - e.pdf(t)).abs() <= 1e-4 * pdf);
            bins[((t / 3.0 * 20.0) as usize).min(19)] += 1;
        }
        for (k, &count) in bins.iter().enumerate() {
            let m = 200;
            let p: f64 = (0..m)
                .map(|j| {
                    let t = (k as f32 + (j as f32 + 0.5) / m as f32) * 0.15;
                    f64::from(e.pdf(t)) * 0.15 / m as f64
                })
                .sum();
            let expected = p * n as f64;
            let se = (expected * (1.0 - p)).sqrt();
            assert!(
                (f64::from(count) - expected).abs() <= 4.5 * se,
                "bin {k}: {count} vs {expected}"
            );
        }
    }
}
