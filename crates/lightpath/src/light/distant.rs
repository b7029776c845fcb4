//! A distant light: light of irradiance `color` (on a surface facing it) arriving from
//! one direction, as from the sun; with an angular size, from a disc of that angular
//! diameter (uniform radiance), whose soft shadows are sampled uniformly over its cone.
//!
//! ```toml
//! [[lights]]
//! type = "distant"
//! direction = [0.3, -1, 0.1]   # the direction the light travels
//! irradiance = [3, 3, 3]
//! angle = 0.53                 # optional: the disc's angular diameter, in degrees
//! ```

use super::select::Reach;
use super::{LightModel, LightSample};
use crate::geometry::Prim;
use crate::sampling::{sin_cos_turns, Frame};
use glam::{Vec2, Vec3A};
use std::f32::consts::PI;

#[derive(Clone, Debug)]
pub struct Distant {
    /// Unit direction the light travels in (towards the scene).
    pub dir: Vec3A,
    /// 1 − cos of the disc's angular radius (0: a single direction, a Dirac light),
    /// kept as such so that the sun's half a degree keeps its precision in f32.
    pub one_minus_cos: f32,
}

impl Distant {
    /// A distant light travelling along `dir` from a disc of angular diameter
    /// `angle_degrees` (0: one direction).
    pub fn new(dir: Vec3A, angle_degrees: f32) -> Distant {
        let half = (angle_degrees.clamp(0.0, 180.0) * 0.5).to_radians();
        let s = (half * 0.5).sin();
        Distant {
            dir,
            one_minus_cos: 2.0 * s * s,
        }
    }

    /// The disc's radiance for irradiance `color`: E = L·π·sin²(radius).
    #[inline]
    fn radiance(&self, color: Vec3A) -> Vec3A {
        let s = self.one_minus_cos;
        color / (PI * s * (2.0 - s))
    }

    /// Uniform over the disc's cone: pdf = 1 / (2π (1 − cos radius)).
    #[inline]
    fn cone_pdf(&self) -> f32 {
        1.0 / (2.0 * PI * self.one_minus_cos)
    }

    /// Whether a ray along `d` (unit) escapes into the disc.
    #[inline]
    fn in_disc(&self, d: Vec3A) -> bool {
        // 1 − cos of the angle to the disc's centre, without cancellation.
        (d + self.dir).length_squared() * 0.5 <= self.one_minus_cos
    }
}

impl LightModel for Distant {
    fn sample(&self, color: Vec3A, _: Vec3A, _: Vec3A, u: Vec2, _: &[Prim]) -> Option<LightSample> {
        if self.one_minus_cos <= 0.0 {
            return Some(LightSample {
                wi: -self.dir,
                dist: f32::INFINITY,
                radiance: color,
                pdf: 1.0,
                delta: true,
            });
        }
        // 1 − cos θ uniform in [0, 1 − cos radius]; sin θ from it without cancellation.
        let s = u.x * self.one_minus_cos;
        let sin_t = (s * (2.0 - s)).max(0.0).sqrt();
        let (sin_p, cos_p) = sin_cos_turns(u.y);
        let local = Vec3A::new(sin_t * cos_p, sin_t * sin_p, 1.0 - s);
        Some(LightSample {
            wi: Frame::new(-self.dir).to_world(local).normalize(),
            dist: f32::INFINITY,
            radiance: self.radiance(color),
            pdf: self.cone_pdf(),
            delta: false,
        })
    }
    fn pdf(&self, _: Vec3A, _: Vec3A, dir: Vec3A, t: f32, _: Vec3A) -> f32 {
        if self.one_minus_cos > 0.0 && t == f32::INFINITY && self.in_disc(dir) {
            self.cone_pdf()
        } else {
            0.0
        }
    }
    fn escaped(&self, color: Vec3A, dir: Vec3A) -> Vec3A {
        if self.one_minus_cos > 0.0 && self.in_disc(dir) {
            self.radiance(color)
        } else {
            Vec3A::ZERO
        }
    }
    /// A disc is reached by rays that leave the scene towards it.
    fn escapes(&self) -> bool {
        self.one_minus_cos > 0.0
    }
    fn power(&self, c: f32, scene_radius: f32) -> f32 {
        let r2 = scene_radius * scene_radius;
        c * PI * r2
    }
    /// Beside the tree: its irradiance, scaled by the receiver's cosine.
    fn reach(&self, c: f32, _: &[Prim]) -> Reach {
        if c > 0.0 {
            Reach::Infinite {
                irradiance: c,
                dir: self.dir,
            }
        } else {
            Reach::Nowhere
        }
    }
    fn is_delta(&self) -> bool {
        self.one_minus_cos <= 0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_disc_gives_its_irradiance_and_its_samples_stay_in_it() {
        let dir = Vec3A::new(0.3, -1.0, 0.2).normalize();
        for angle in [0.53f32, 10.0, 60.0] {
            let light = Distant::new(dir, angle);
            let half = (angle * 0.5).to_radians();
            let e = Vec3A::splat(2.0);
            // Irradiance on a surface facing the disc: ∫ L cos θ dω estimated from the
            // samples (one value per sample of a stratified grid).
            let n = 64;
            let mut sum = 0.0f64;
            for i in 0..n {
                for j in 0..n {
                    let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                    let s = light.sample(e, Vec3A::ZERO, Vec3A::ZERO, u, &[]).unwrap();
                    let cos = s.wi.dot(-dir);
                    assert!(cos >= half.cos() - 1e-5, "{angle}: {cos}");
                    assert!(light.in_disc(s.wi) && !s.delta);
                    assert!(
                        (light.pdf(Vec3A::ZERO, Vec3A::ZERO, s.wi, f32::INFINITY, Vec3A::ZERO)
                            - s.pdf)
                            .abs()
                            < 1e-3 * s.pdf
                    );
                    sum += (s.radiance.x * cos / s.pdf) as f64;
                }
            }
            let irradiance = sum / (n * n) as f64;
            assert!((irradiance - 2.0).abs() < 2e-3, "{angle}: {irradiance}");
            // Outside the disc nothing arrives.
            let off =
                Frame::new(-dir).to_world(Vec3A::new((1.1 * half).sin(), 0.0, (1.1 * half).cos()));
            assert_eq!(light.escaped(e, off), Vec3A::ZERO);
            assert!(light.escaped(e, -dir).x > 0.0);
        }
        assert!(Distant::new(dir, 0.0).is_delta());
    }
}
