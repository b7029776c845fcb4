//! A dome: light from every direction at infinity, constant or an equirectangular EXR
//! (importance sampled by its texels' luminance × solid angle). Its `rotate`/`matrix`
//! turns the map; scale is divided out and the translation ignored.
//!
//! ```toml
//! [[lights]]
//! type = "dome"
//! map = "sky.exr"          # optional; without it the dome is `radiance` everywhere
//! radiance = [1, 1, 1]
//! rotate = [0, 90, 0]
//! ```

use super::portal::{self, Portal};
use super::select::Reach;
use super::{luminance, LightModel, LightSample};
use crate::geometry::Prim;
use crate::sampling::{uniform_sphere, Distribution1D};
use glam::{Mat3A, Vec2, Vec3A};
use std::f32::consts::PI;

/// A dome: `map` × the light's colour, or its colour alone; sampled through its
/// `portals` if it has any (portal.rs).
#[derive(Clone, Debug)]
pub struct Dome {
    pub map: Option<EnvMap>,
    pub portals: Vec<Portal>,
}

impl LightModel for Dome {
    fn sample(&self, color: Vec3A, p: Vec3A, n: Vec3A, u: Vec2, _: &[Prim]) -> Option<LightSample> {
        if !self.portals.is_empty() {
            let (wi, pdf) = portal::sample(&self.portals, p, n, u)?;
            let radiance = self.escaped(color, wi);
            return (radiance != Vec3A::ZERO).then_some(LightSample {
                wi,
                dist: f32::INFINITY,
                radiance,
                pdf,
                delta: false,
            });
        }
        match &self.map {
            None => {
                let wi = uniform_sphere(u);
                Some(LightSample {
                    wi,
                    dist: f32::INFINITY,
                    radiance: color,
                    pdf: 1.0 / (4.0 * PI),
                    delta: false,
                })
            }
            Some(m) => {
                let (wi, pdf) = m.sample(u);
                if pdf <= 0.0 {
                    return None;
                }
                Some(LightSample {
                    wi,
                    dist: f32::INFINITY,
                    radiance: color * m.lookup(wi),
                    pdf,
                    delta: false,
                })
            }
        }
    }
    fn pdf(&self, p: Vec3A, n: Vec3A, dir: Vec3A, _: f32, _: Vec3A) -> f32 {
        if !self.portals.is_empty() {
            return portal::pdf(&self.portals, p, n, dir);
        }
        match &self.map {
            None => 1.0 / (4.0 * PI),
            Some(m) => m.pdf(dir),
        }
    }
    fn escaped(&self, color: Vec3A, dir: Vec3A) -> Vec3A {
        match &self.map {
            None => color,
            Some(m) => color * m.lookup(dir),
        }
    }
    fn escapes(&self) -> bool {
        true
    }
    fn power(&self, c: f32, scene_radius: f32) -> f32 {
        let r2 = scene_radius * scene_radius;
        let avg = self.map.as_ref().map_or(1.0, |m| m.average().max_element());
        c * avg * PI * PI * r2
    }
    /// Beside the tree: π × its average radiance, whatever the receiver's normal.
    fn reach(&self, c: f32, _: &[Prim]) -> Reach {
        if c > 0.0 {
            Reach::Infinite {
                irradiance: c * PI * self.map.as_ref().map_or(1.0, |m| m.average().max_element()),
                dir: Vec3A::ZERO,
            }
        } else {
            Reach::Nowhere
        }
    }
}

/// An equirectangular environment map with a 2D sampling distribution.
#[derive(Clone, Debug)]
pub struct EnvMap {
    pub width: usize,
    pub height: usize,
    pub texels: Vec<Vec3A>,
    rows: Distribution1D,
    columns: Vec<Distribution1D>,
    /// The map's frame to world (a rotation, possibly with a mirror), or None: identity.
    to_world: Option<Mat3A>,
}

impl EnvMap {
    pub fn new(width: usize, height: usize, texels: Vec<Vec3A>) -> EnvMap {
        let mut columns = Vec::with_capacity(height);
        let mut row_weights = Vec::with_capacity(height);
        for y in 0..height {
            // sin θ: texels near the poles cover less solid angle.
            let sin_t = (PI * (y as f32 + 0.5) / height as f32).sin();
            let w: Vec<f32> = texels[y * width..(y + 1) * width]
                .iter()
                .map(|t| luminance(*t) * sin_t + 1e-6)
                .collect();
            let d = Distribution1D::new(&w);
            row_weights.push(d.total());
            columns.push(d);
        }
        EnvMap {
            width,
            height,
            texels,
            rows: Distribution1D::new(&row_weights),
            columns,
            to_world: None,
        }
    }

    /// The same map turned by `to_world` (orthonormal: rotations and mirrors keep solid
    /// angles, so the sampling density is unchanged).
    pub fn rotated(self, to_world: Mat3A) -> EnvMap {
        EnvMap {
            to_world: Some(to_world),
            ..self
        }
    }

    /// A world direction in the map's frame.
    #[inline]
    fn local(&self, d: Vec3A) -> Vec3A {
        match &self.to_world {
            None => d,
            Some(m) => m.transpose() * d,
        }
    }

    /// Lat-long lookup: +Y up; u runs with the azimuth from −Z towards +X.
    fn uv(d: Vec3A) -> Vec2 {
        let u = 0.5 + d.x.atan2(-d.z) / (2.0 * PI);
        let v = d.y.clamp(-1.0, 1.0).acos() / PI;
        Vec2::new(u.rem_euclid(1.0), v.clamp(0.0, 0.999_999))
    }

    fn dir(uv: Vec2) -> Vec3A {
        let phi = (uv.x - 0.5) * 2.0 * PI;
        let theta = uv.y * PI;
        Vec3A::new(
            theta.sin() * phi.sin(),
            theta.cos(),
            -theta.sin() * phi.cos(),
        )
    }

    fn lookup(&self, d: Vec3A) -> Vec3A {
        let uv = Self::uv(self.local(d));
        let x = ((uv.x * self.width as f32) as usize).min(self.width - 1);
        let y = ((uv.y * self.height as f32) as usize).min(self.height - 1);
        self.texels[y * self.width + x]
    }

    fn sample(&self, u: Vec2) -> (Vec3A, f32) {
        let (y, py, _) = self.rows.sample(u.y);
        let (x, px, rx) = self.columns[y].sample(u.x);
        let uv = Vec2::new(
            (x as f32 + rx) / self.width as f32,
            (y as f32 + 0.5) / self.height as f32,
        );
        let d = match &self.to_world {
            None => Self::dir(uv),
            Some(m) => *m * Self::dir(uv),
        };
        let sin_t = (PI * uv.y).sin().max(1e-6);
        // Texel probability over its solid angle: (2π/W)(π/H) sin θ.
        let pdf = py * px * (self.width * self.height) as f32 / (2.0 * PI * PI * sin_t);
        (d, pdf)
    }

    fn pdf(&self, d: Vec3A) -> f32 {
        let uv = Self::uv(self.local(d));
        let x = ((uv.x * self.width as f32) as usize).min(self.width - 1);
        let y = ((uv.y * self.height as f32) as usize).min(self.height - 1);
        let sin_t = (PI * (y as f32 + 0.5) / self.height as f32).sin().max(1e-6);
        self.rows.pmf(y) * self.columns[y].pmf(x) * (self.width * self.height) as f32
            / (2.0 * PI * PI * sin_t)
    }

    pub fn average(&self) -> Vec3A {
        let mut sum = Vec3A::ZERO;
        let mut wsum = 0.0;
        for y in 0..self.height {
            let sin_t = (PI * (y as f32 + 0.5) / self.height as f32).sin();
            for x in 0..self.width {
                sum += self.texels[y * self.width + x] * sin_t;
                wsum += sin_t;
            }
        }
        sum / wsum.max(1e-6)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    #[test]
    fn env_map_pdf_matches_its_sampling() {
        let (w, h) = (16, 8);
        let texels: Vec<Vec3A> = (0..w * h)
            .map(|i| Vec3A::splat(1.0 + (i % 7) as f32))
            .collect();
        let m = EnvMap::new(w, h, texels);
        let mut rng = Rng::for_sample(1, 2, 3);
        for _ in 0..100 {
            let (d, pdf) = m.sample(rng.next_2d());
            let again = m.pdf(d);
            assert!((pdf - again).abs() < 2e-2 * pdf, "{pdf} vs {again}");
        }
        // ∫ pdf dω = 1, by uniform sphere sampling.
        let n = 200_000;
        let integral: f32 = (0..n)
            .map(|_| m.pdf(uniform_sphere(rng.next_2d())) * 4.0 * PI)
            .sum::<f32>()
            / n as f32;
        assert!((integral - 1.0).abs() < 0.02, "{integral}");
    }

    /// A turned map is the same map seen through the rotation: lookups, densities and
    /// samples all move with it.
    #[test]
    fn a_rotated_env_map_moves_its_radiance_and_its_sampling() {
        let (w, h) = (16, 8);
        let texels: Vec<Vec3A> = (0..w * h)
            .map(|i| Vec3A::splat(1.0 + (i * 5 % 11) as f32))
            .collect();
        let plain = EnvMap::new(w, h, texels);
        let r = Mat3A::from_rotation_y(0.7) * Mat3A::from_rotation_x(-0.4);
        let turned = plain.clone().rotated(r);
        let mut rng = Rng::for_sample(3, 2, 1);
        for _ in 0..200 {
            let d = uniform_sphere(rng.next_2d());
            assert_eq!(turned.lookup(r * d), plain.lookup(d));
            let (p, q) = (turned.pdf(r * d), plain.pdf(d));
            assert!((p - q).abs() <= 1e-4 * q, "{p} vs {q}");
            let u = rng.next_2d();
            let ((dt, pt), (dp, pp)) = (turned.sample(u), plain.sample(u));
            assert!((dt - r * dp).length() < 1e-5, "{dt} vs {}", r * dp);
            assert_eq!(pt, pp);
        }
        // Something actually moved: the brightest direction is not where it was.
        let moved = (0..200)
            .map(|_| uniform_sphere(rng.next_2d()))
            .filter(|d| turned.lookup(*d) != plain.lookup(*d))
            .count();
        assert!(moved > 100, "{moved}");
    }
}
