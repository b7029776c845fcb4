//! A heterogeneous medium: σa and σs are a density grid's value (media/grid.rs, from
//! an OpenVDB file) times RGB coefficients, placed in the scene by the grid's own
//! transform and then the transform of the object that bounds it.
//!
//! Free flights are null-collision tracking against the grid's per-cell majorants. When
//! σt is the same in every channel (grey smoke, coloured only by σs/σt), all channels
//! share one free-flight distribution: the grid's decomposition tracking (Kutz et al.
//! 2017, "Spectral and decomposition tracking for rendering heterogeneous volumes", §4)
//! samples it exactly and a collision's weight is the albedo σs/σt. With a chromatic σt,
//! spectral tracking (Kutz et al. 2017, §3.3) with history-aware collision
//! probabilities: one majorant for all channels (the cell's maximum density times the
//! largest σt), and at each tentative collision a real or null event chosen with
//! probabilities proportional to the path's throughput times σt or σn = μ̄ − σt, the
//! weights dividing by them, so every channel stays unbiased. That is the heterogeneous
//! counterpart of the homogeneous medium's throughput-steered channel mixture
//! (media/homogeneous.rs): the same weights when the medium is in fact constant.
//!
//! Shadow rays attenuate by residual ratio tracking (Novák et al. 2014), unbiased per
//! channel. Emission, `emission` times the density per unit length, is estimated at one
//! uniformly chosen point of the ray's stretch through the grid, with the ratio-tracked
//! transmittance to it.

use super::grid::{ratio_tracking, GridDensity};
use super::{channel_pmf, Collision};
use crate::geometry::Ray;
use crate::sampling::Rng;
use glam::{Affine3A, Vec3, Vec3A};
use std::sync::Arc;

/// Coefficients per scene unit at density 1, and the density where it is.
#[derive(Clone, Debug)]
pub struct Heterogeneous {
    pub grid: Arc<GridDensity>,
    /// Scene space to the grid's world space (the inverse of the bounding object's
    /// transform).
    pub to_grid: Affine3A,
    pub sigma_a: Vec3A,
    pub sigma_s: Vec3A,
    pub sigma_t: Vec3A,
}

impl PartialEq for Heterogeneous {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.grid, &other.grid)
            && self.to_grid == other.to_grid
            && self.sigma_a == other.sigma_a
            && self.sigma_s == other.sigma_s
    }
}

impl Heterogeneous {
    pub fn new(
        grid: Arc<GridDensity>,
        object_to_world: Affine3A,
        sigma_a: Vec3A,
        sigma_s: Vec3A,
    ) -> Heterogeneous {
        Heterogeneous {
            grid,
            to_grid: object_to_world.inverse(),
            sigma_a,
            sigma_s,
            sigma_t: sigma_a + sigma_s,
        }
    }

    /// The ray in the grid's world space. Its direction keeps the scene's length per
    /// unit of `t`, so distances and σ stay per scene unit under a scaling transform.
    #[inline]
    fn local(&self, ray: &Ray) -> (Vec3, Vec3) {
        (
            self.to_grid.transform_point3(ray.origin.into()),
            self.to_grid.transform_vector3(ray.dir.into()),
        )
    }

    /// The density at distance `t` along a ray already in the grid's index space.
    #[inline]
    fn density_at(&self, qo: Vec3, qd: Vec3, t: f32) -> f32 {
        self.grid.grid.density_index(qo + qd * t)
    }

    #[inline]
    fn index_ray(&self, o: Vec3, d: Vec3) -> (Vec3, Vec3) {
        let w2i = self.grid.grid.world_to_index();
        (w2i.transform_point3(o), w2i.transform_vector3(d))
    }

    /// A free flight along `ray` up to `ray.tmax`: a real collision (weight σs/σt when
    /// σt is grey, the spectral-tracking weight otherwise) or none (weight 1 for a grey
    /// σt). A medium that does not scatter attenuates by its ratio-tracked
    /// transmittance instead, as the homogeneous one does by Beer–Lambert.
    pub fn sample(&self, ray: &Ray, throughput: Vec3A, rng: &mut Rng) -> Collision {
        if self.sigma_s == Vec3A::ZERO {
            return Collision::Pass {
                weight: self.transmittance(ray, rng),
            };
        }
        let (o, d) = self.local(ray);
        let st = self.sigma_t;
        if st.x == st.y && st.y == st.z {
            let mut u = || rng.next_f32();
            return match self.grid.sample_distance(o, d, ray.tmax, st.x, &mut u) {
                Some(t) => Collision::Scatter {
                    t,
                    weight: self.sigma_s / st,
                },
                None => Collision::Pass { weight: Vec3A::ONE },
            };
        }
        self.spectral_tracking(o, d, ray.tmax, throughput, rng)
    }

    /// Spectral tracking (Kutz et al. 2017, Algorithm 4, with history-aware
    /// probabilities; absorption is carried in the real collision's weight, as the
    /// homogeneous medium's σs/σt, rather than ending the path).
    fn spectral_tracking(
        &self,
        o: Vec3,
        d: Vec3,
        tmax: f32,
        throughput: Vec3A,
        rng: &mut Rng,
    ) -> Collision {
        let st = self.sigma_t;
        let st_max = st.max_element();
        let (qo, qd) = self.index_ray(o, d);
        let mut w = Vec3A::ONE;
        for seg in self.grid.majorants.segments(o, d, 0.0, tmax) {
            let mu = seg.max * st_max;
            if mu.is_nan() || mu <= 0.0 {
                continue;
            }
            let mut t = seg.t0;
            loop {
                t += -(1.0 - rng.next_f32()).ln() / mu;
                if t >= seg.t1 {
                    break;
                }
                let rho = self.density_at(qo, qd, t);
                let sigma_t = st * rho;
                // The majorant bounds the density (media/grid.rs); the clamp only
                // guards against rounding.
                let sigma_n = (Vec3A::splat(mu) - sigma_t).max(Vec3A::ZERO);
                // History-aware: the path's throughput times this flight's weight.
                let h = channel_pmf(throughput * w);
                let p_real = (h * sigma_t).element_sum() / mu;
                if rng.next_f32() < p_real {
                    return Collision::Scatter {
                        t,
                        weight: w * self.sigma_s * rho / (mu * p_real),
                    };
                }
                let p_null = 1.0 - p_real;
                if p_null <= 0.0 {
                    return Collision::Pass {
                        weight: Vec3A::ZERO,
                    };
                }
                w *= sigma_n / (mu * p_null);
                if w == Vec3A::ZERO {
                    return Collision::Pass { weight: w };
                }
            }
        }
        Collision::Pass { weight: w }
    }

    /// Transmittance along `ray` up to `ray.tmax` by residual ratio tracking (unbiased
    /// per channel).
    pub fn transmittance(&self, ray: &Ray, rng: &mut Rng) -> Vec3A {
        if self.sigma_t == Vec3A::ZERO {
            return Vec3A::ONE;
        }
        let (o, d) = self.local(ray);
        let mut u = || rng.next_f32();
        Vec3A::from(
            self.grid
                .transmittance(o, d, ray.tmax, self.sigma_t.into(), &mut u),
        )
    }

    /// σs at the scene point `p`: the coefficients times the density there.
    #[inline]
    pub fn sigma_s_at(&self, p: Vec3A) -> Vec3A {
        let q = self.to_grid.transform_point3(p.into());
        self.sigma_s * self.grid.grid.density(q)
    }

    /// An upper bound on the optical depth along `ray` up to `ray.tmax` in the densest
    /// channel: the majorants' integral over the cells it crosses (e^(−bound) is a lower
    /// bound on its transmittance).
    pub fn majorant_depth(&self, ray: &Ray) -> f32 {
        let (o, d) = self.local(ray);
        let st = self.sigma_t.max_element();
        self.grid
            .majorants
            .segments(o, d, 0.0, ray.tmax)
            .map(|s| s.max * st * (s.t1 - s.t0))
            .sum()
    }

    /// An unbiased estimate of ∫ ρ(s) T(s) ds along `ray` up to `ray.tmax` (what an
    /// emission of one per unit length at density 1 adds up to): one point chosen
    /// uniformly on the ray's stretch through the grid's box, its density times the
    /// ratio-tracked transmittance to it, over its density of choice.
    pub fn emission_integral(&self, ray: &Ray, rng: &mut Rng) -> Vec3A {
        let (o, d) = self.local(ray);
        let (qo, qd) = self.index_ray(o, d);
        let (lo, hi) = self.grid.grid.index_bounds();
        let (mut t0, mut t1) = (0.0f32, ray.tmax);
        for a in 0..3 {
            if qd[a] == 0.0 {
                if !(qo[a] >= lo[a] && qo[a] <= hi[a]) {
                    return Vec3A::ZERO;
                }
                continue;
            }
            let (mut near, mut far) = ((lo[a] - qo[a]) / qd[a], (hi[a] - qo[a]) / qd[a]);
            if near > far {
                std::mem::swap(&mut near, &mut far);
            }
            t0 = t0.max(near);
            t1 = t1.min(far);
        }
        if t0.partial_cmp(&t1) != Some(std::cmp::Ordering::Less) || !t1.is_finite() {
            return Vec3A::ZERO;
        }
        let t = t0 + (t1 - t0) * rng.next_f32();
        let rho = self.density_at(qo, qd, t);
        if rho <= 0.0 {
            return Vec3A::ZERO;
        }
        let tr = if self.sigma_t == Vec3A::ZERO {
            Vec3A::ONE
        } else {
            let segs = self.grid.majorants.segments(o, d, 0.0, t);
            let mut u = || rng.next_f32();
            Vec3A::from(ratio_tracking(
                segs,
                self.sigma_t.into(),
                |s| self.density_at(qo, qd, s),
                &mut u,
            ))
        };
        tr * (rho * (t1 - t0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::media::grid::DensityGrid;
    use glam::{DVec3, IVec3, Quat};

    /// A smooth blob with a hole and a floor on a 20×16×12 grid, rotated and scaled.
    fn blob() -> Arc<GridDensity> {
        let size = IVec3::new(20, 16, 12);
        let mut values = Vec::new();
        for k in 0..size.z {
            for j in 0..size.y {
                for i in 0..size.x {
                    let p = Vec3::new(i as f32, j as f32, k as f32);
                    let r2 = (p - Vec3::new(10.0, 8.0, 6.0)).length_squared();
                    let hole = if (i + j) % 7 == 0 { 0.0 } else { 1.0 };
                    values.push(0.2 + hole * 2.5 * (-r2 / 20.0).exp());
                }
            }
        }
        let to_world = Affine3A::from_scale_rotation_translation(
            Vec3::splat(0.1),
            Quat::from_rotation_z(0.4),
            Vec3::new(-1.0, -0.8, -0.6),
        );
        let g = DensityGrid::from_dense(size, &values, to_world, 1.0).unwrap();
        Arc::new(GridDensity::new(g, 4).unwrap())
    }

    /// The medium under an object transform with a non-uniform scale, and rays in scene
    /// space from outside through its middle.
    fn medium(sigma_a: Vec3A, sigma_s: Vec3A) -> Heterogeneous {
        let object = Affine3A::from_scale_rotation_translation(
            Vec3::new(1.5, 1.0, 0.8),
            Quat::from_rotation_x(0.3),
            Vec3::new(0.5, 0.0, 0.2),
        );
        Heterogeneous::new(blob(), object, sigma_a, sigma_s)
    }

    fn ray(k: usize) -> Ray {
        let a = k as f32 * 2.399;
        let dir = Vec3A::new(a.cos(), a.sin() * 0.8, 0.6 - 0.1 * k as f32).normalize();
        let target = Vec3A::new(0.5, 0.0, 0.2) + Vec3A::new(0.1, -0.05, 0.03) * k as f32;
        Ray {
            origin: target - dir * 4.0,
            dir,
            tmax: 8.0,
        }
    }

    /// ∫₀ᵗ ρ by midpoint steps in scene space (brute force: no majorants, no DDA).
    fn march(m: &Heterogeneous, r: &Ray, t: f32, n: usize) -> f64 {
        let h = t as f64 / n as f64;
        (0..n)
            .map(|i| {
                let p = r.origin + r.dir * ((i as f64 + 0.5) * h) as f32;
                m.grid.grid.density(m.to_grid.transform_point3(p.into())) as f64 * h
            })
            .sum()
    }

    /// Mean and standard error per channel of `n` estimates.
    fn stats(n: usize, mut f: impl FnMut() -> Vec3A) -> (DVec3, DVec3) {
        let (mut s, mut s2) = (DVec3::ZERO, DVec3::ZERO);
        for _ in 0..n {
            let v = f().as_dvec3();
            s += v;
            s2 += v * v;
        }
        let mean = s / n as f64;
        let var = (s2 / n as f64 - mean * mean).max(DVec3::ZERO) / (n - 1) as f64;
        (mean, var.powf(0.5))
    }

    fn check(what: &str, (mean, se): (DVec3, DVec3), want: DVec3) {
        for c in 0..3 {
            assert!(
                (mean[c] - want[c]).abs() <= 5.0 * se[c] + 1e-6,
                "{what}, channel {c}: {} ± {} vs {}",
                mean[c],
                se[c],
                want[c]
            );
        }
    }

    /// Shadow-ray transmittance and the pass weight of free flights (grey and chromatic
    /// σt) both average to exp(−σt ∫ρ) from brute-force marching, per channel.
    #[test]
    fn tracked_transmittance_matches_ray_marching() {
        for (sa, ss) in [
            (Vec3A::new(0.5, 0.5, 0.5), Vec3A::new(2.0, 2.0, 2.0)),
            (Vec3A::new(0.2, 1.0, 3.0), Vec3A::new(2.0, 0.5, 0.0)),
        ] {
            let m = medium(sa, ss);
            let mut rng = Rng::for_sample(1, 2, 3);
            for k in 0..6 {
                let r = ray(k);
                let tau = march(&m, &r, r.tmax, 20_000);
                assert!((tau - march(&m, &r, r.tmax, 40_000)).abs() < 1e-4 * tau.max(1.0));
                let want = (-(m.sigma_t.as_dvec3()) * tau).exp();
                let shadow = stats(20_000, || m.transmittance(&r, &mut rng));
                check(&format!("ray {k} ratio tracking"), shadow, want);
                let throughput = Vec3A::new(1.0, 0.3, 0.6);
                let pass = stats(20_000, || match m.sample(&r, throughput, &mut rng) {
                    Collision::Pass { weight } => weight,
                    Collision::Scatter { .. } => Vec3A::ZERO,
                });
                check(&format!("ray {k} free-flight pass"), pass, want);
            }
        }
    }

    /// The scatter weights integrate the single-scattering kernel: E[weight · f(t)] is
    /// ∫ σs ρ(t) T(t) f(t) dt, here with f(t) = cos(t) + 1.5 so the distances' placement
    /// matters, against quadrature on the marched optical depth.
    #[test]
    fn free_flight_collisions_integrate_the_scattering_kernel() {
        for (sa, ss) in [
            (Vec3A::new(0.3, 0.3, 0.3), Vec3A::new(1.5, 1.0, 0.6)),
            (Vec3A::new(0.1, 0.8, 2.0), Vec3A::new(1.5, 0.7, 0.2)),
        ] {
            let m = medium(sa, ss);
            let f = |t: f64| t.cos() + 1.5;
            let mut rng = Rng::for_sample(4, 5, 6);
            for k in 0..4 {
                let r = ray(k);
                let n = 8192;
                let h = r.tmax as f64 / n as f64;
                let (mut tau, mut want) = (0.0f64, DVec3::ZERO);
                for i in 0..n {
                    let t = (i as f64 + 0.5) * h;
                    let p = r.origin + r.dir * t as f32;
                    let rho = m.grid.grid.density(m.to_grid.transform_point3(p.into())) as f64;
                    // Midpoint rule with the optical depth up to the midpoint.
                    let tau_mid = tau + rho * h / 2.0;
                    want += m.sigma_s.as_dvec3()
                        * rho
                        * (-(m.sigma_t.as_dvec3()) * tau_mid).exp()
                        * f(t)
                        * h;
                    tau += rho * h;
                }
                let throughput = Vec3A::new(0.4, 1.0, 0.7);
                let got = stats(40_000, || match m.sample(&r, throughput, &mut rng) {
                    Collision::Scatter { t, weight } => {
                        assert!(t < r.tmax);
                        weight * f(t as f64) as f32
                    }
                    Collision::Pass { .. } => Vec3A::ZERO,
                });
                check(&format!("ray {k} collisions"), got, want);
            }
        }
    }

    /// The emission estimate averages to ∫ ρ T by quadrature.
    #[test]
    fn emission_integral_matches_quadrature() {
        let m = medium(Vec3A::new(0.4, 1.2, 0.1), Vec3A::new(0.5, 0.5, 0.5));
        let mut rng = Rng::for_sample(7, 8, 9);
        for k in 0..4 {
            let r = ray(k);
            let n = 8192;
            let h = r.tmax as f64 / n as f64;
            let (mut tau, mut want) = (0.0f64, DVec3::ZERO);
            for i in 0..n {
                let p = r.origin + r.dir * ((i as f64 + 0.5) * h) as f32;
                let rho = m.grid.grid.density(m.to_grid.transform_point3(p.into())) as f64;
                want += rho * (-(m.sigma_t.as_dvec3()) * (tau + rho * h / 2.0)).exp() * h;
                tau += rho * h;
            }
            let got = stats(40_000, || m.emission_integral(&r, &mut rng));
            check(&format!("ray {k} emission"), got, want);
        }
    }
}
