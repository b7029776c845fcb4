//! Equiangular sampling of a distance along a ray towards a point (Kulla & Fajardo 2012,
//! "Importance Sampling Techniques for Path Tracing in Participating Media"): the
//! density is proportional to 1/r², the inverse square falloff of a point light's
//! irradiance, so single scattering near a point or spot light is sampled where it is
//! bright instead of where the medium is dense. An area light is aimed at by its centre
//! (the paper picks a point on the light first; one centre for every flight keeps the
//! density a function of the flight alone, which MIS needs), while the flight keeps out
//! of the sphere holding the light ([`Equiangular::towards`]). Weighed against free
//! flights by the power heuristic, aiming adds no variance where it fits badly (the
//! weighted second moment is at most the free flights' alone): it costs a sample.

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

    /// Sampling along `ray` towards a light held in the sphere of `radius` about `centre`
    /// (0: a point light), or `None` where the segment enters that sphere: the light is
    /// small for the segment when it lies to one side of all of it. Then from distance r
    /// the light lies in the sphere's cone, of solid angle 2π(1 − √(1 − R²/r²)) ≤
    /// 2πR²/r², the inverse square the density follows (within 2× for a sphere light).
    /// Inside the sphere a light's solid angle stops growing as 1/r² while the density
    /// keeps peaking at the foot. The test depends on the segment and the light alone
    /// (no scene scale), the same for every technique that asks.
    pub fn towards(ray: &Ray, centre: glam::Vec3A, radius: f32) -> Option<Equiangular> {
        let e = Equiangular::new(ray, centre)?;
        let x = e.foot.clamp(0.0, ray.tmax) - e.foot;
        (e.dist * e.dist + x * x >= radius * radius).then_some(e)
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

    /// A flight takes a light by its bounding sphere only while it stays outside it: a
    /// segment passing 0.5 from the centre takes a light of radius 0.4, not one of 0.6,
    /// unless it ends before coming that near; a point light is always taken.
    #[test]
    fn area_lights_are_aimed_at_from_outside_their_sphere() {
        let centre = Vec3A::new(2.0, 0.5, 0.0);
        let ray = |tmax| Ray {
            origin: Vec3A::ZERO,
            dir: Vec3A::X,
            tmax,
        };
        assert!(Equiangular::towards(&ray(5.0), centre, 0.0).is_some());
        assert!(Equiangular::towards(&ray(5.0), centre, 0.4).is_some());
        assert!(Equiangular::towards(&ray(5.0), centre, 0.6).is_none());
        assert!(Equiangular::towards(&ray(f32::INFINITY), centre, 0.6).is_none());
        // Ending at x = 1.5, 0.707 from the centre.
        assert!(Equiangular::towards(&ray(1.5), centre, 0.6).is_some());
        assert!(Equiangular::towards(&ray(1.5), centre, 0.8).is_none());
    }

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
