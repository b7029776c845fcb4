//! Lights: area (triangles of a rectangle, quad or disk; spheres), point, spot, distant
//! and dome (constant or an equirectangular EXR, importance sampled). Each carries its
//! light groups, which become the labels of its `L` and `O` events.
//!
//! ```toml
//! [[lights]]
//! type = "rect"            # rect | quad | disk | sphere | point | spot | distant | dome
//! groups = ["key"]
//! radiance = [17, 12, 4]   # area and dome lights; point/spot: intensity; distant: irradiance
//! translate = [0, 0.99, 0]
//! rotate = [90, 0, 0]
//! scale = [0.25, 0.25, 1]
//! ```

pub mod select;

use crate::geometry::Prim;
use crate::sampling::{
    uniform_cone, uniform_cone_pdf, uniform_sphere, uniform_triangle, Distribution1D, Frame,
};
use glam::{Mat3A, Vec2, Vec3A};
use std::f32::consts::PI;

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

pub fn luminance(c: Vec3A) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

#[derive(Clone, Debug)]
pub enum LightShape {
    /// Triangles (of a rectangle, quad or disk) sampled by area; emits on the side of
    /// their normal unless two-sided.
    Triangles {
        /// The triangles, as indices into the scene's primitive list (`Accel::prims`).
        prims: Vec<u32>,
        /// Unit normal of each triangle, precomputed for sampling.
        normals: Vec<Vec3A>,
        /// Corner and edges when the triangles form one parallelogram (rectangle and
        /// most quad lights): sampled directly, uniformly in area.
        parallelogram: Option<[Vec3A; 3]>,
        by_area: Distribution1D,
        area: f32,
        two_sided: bool,
        /// A mesh light (an object's own triangles): they may shadow one another, so
        /// shadow rays do not pass through its object, and the lights-only test finds
        /// them in `Scene::mesh_lights` instead of trying each.
        mesh: bool,
    },
    Sphere {
        center: Vec3A,
        radius: f32,
    },
    Point {
        position: Vec3A,
    },
    /// Intensity falls off smoothly from the inner to the outer cone.
    Spot {
        position: Vec3A,
        axis: Vec3A,
        cos_inner: f32,
        cos_outer: f32,
    },
    /// Light travelling along `dir` (towards the scene).
    Distant {
        dir: Vec3A,
    },
    Dome {
        map: Option<EnvMap>,
    },
}

#[derive(Clone, Debug)]
pub struct Light {
    pub shape: LightShape,
    /// Radiance (area, dome), intensity (point, spot) or irradiance (distant).
    pub color: Vec3A,
    pub groups: Vec<String>,
    pub camera_visible: bool,
    /// The object the light's surface belongs to (area lights), if any.
    pub object: Option<u32>,
}

/// A light sample as seen from a shading point.
pub struct LightSample {
    /// Direction to the light.
    pub wi: Vec3A,
    /// Distance to the sampled point (infinite for distant and dome lights).
    pub dist: f32,
    /// Radiance arriving along `wi` (for delta lights: intensity / d², irradiance).
    pub radiance: Vec3A,
    /// Solid-angle pdf (not including the choice of the light); 1 for delta lights.
    pub pdf: f32,
    pub delta: bool,
}

/// The fields of a triangle light that sampling reads, borrowed from its `LightShape`.
struct TriangleLight<'a> {
    ids: &'a [u32],
    normals: &'a [Vec3A],
    parallelogram: &'a Option<[Vec3A; 3]>,
    by_area: &'a Distribution1D,
    area: f32,
    two_sided: bool,
}

impl Light {
    pub fn is_delta(&self) -> bool {
        matches!(
            self.shape,
            LightShape::Point { .. } | LightShape::Spot { .. } | LightShape::Distant { .. }
        )
    }

    pub fn is_infinite(&self) -> bool {
        matches!(
            self.shape,
            LightShape::Dome { .. } | LightShape::Distant { .. }
        )
    }

    /// Samples a point of the light as seen from `p`; `prims` is the scene's primitive
    /// list, which area lights index.
    pub fn sample(&self, p: Vec3A, u: Vec2, prims: &[Prim]) -> Option<LightSample> {
        match &self.shape {
            LightShape::Triangles {
                prims: ids,
                normals,
                parallelogram,
                by_area,
                area,
                two_sided,
                ..
            } => {
                let shape = TriangleLight {
                    ids,
                    normals,
                    parallelogram,
                    by_area,
                    area: *area,
                    two_sided: *two_sided,
                };
                self.sample_triangles(&shape, p, u, prims)
            }
            LightShape::Sphere { center, radius } => self.sample_sphere(*center, *radius, p, u),
            LightShape::Point { position } => {
                let d = *position - p;
                let dist2 = d.length_squared();
                let dist = dist2.sqrt();
                Some(LightSample {
                    wi: d / dist,
                    dist,
                    radiance: self.color / dist2,
                    pdf: 1.0,
                    delta: true,
                })
            }
            LightShape::Spot {
                position,
                axis,
                cos_inner,
                cos_outer,
            } => {
                let d = *position - p;
                let dist2 = d.length_squared();
                let dist = dist2.sqrt();
                let wi = d / dist;
                let cos = (-wi).dot(*axis);
                let falloff = smoothstep(*cos_outer, *cos_inner, cos);
                if falloff <= 0.0 {
                    return None;
                }
                Some(LightSample {
                    wi,
                    dist,
                    radiance: self.color * falloff / dist2,
                    pdf: 1.0,
                    delta: true,
                })
            }
            LightShape::Distant { dir } => Some(LightSample {
                wi: -*dir,
                dist: f32::INFINITY,
                radiance: self.color,
                pdf: 1.0,
                delta: true,
            }),
            LightShape::Dome { map } => match map {
                None => {
                    let wi = uniform_sphere(u);
                    Some(LightSample {
                        wi,
                        dist: f32::INFINITY,
                        radiance: self.color,
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
                        radiance: self.color * m.lookup(wi),
                        pdf,
                        delta: false,
                    })
                }
            },
        }
    }

    /// A point on a triangle light (directly on its parallelogram when it is one), in
    /// solid angle.
    fn sample_triangles(
        &self,
        t: &TriangleLight,
        p: Vec3A,
        u: Vec2,
        prims: &[Prim],
    ) -> Option<LightSample> {
        let TriangleLight {
            ids,
            normals,
            parallelogram,
            by_area,
            area,
            two_sided,
        } = *t;
        let (q, n) = match parallelogram {
            Some([p0, e1, e2]) => (*p0 + *e1 * u.x + *e2 * u.y, normals[0]),
            None => {
                let (i, _, ux) = by_area.sample(u.x);
                let Prim::Triangle { p0, e1, e2, .. } = prims[ids[i] as usize] else {
                    return None;
                };
                let (b1, b2) = uniform_triangle(Vec2::new(ux, u.y));
                (p0 + e1 * b1 + e2 * b2, normals[i])
            }
        };
        let d = q - p;
        let dist2 = d.length_squared();
        let dist = dist2.sqrt();
        let wi = d / dist;
        let cos_l = -wi.dot(n);
        if cos_l <= 0.0 && !two_sided || cos_l == 0.0 {
            return None;
        }
        Some(LightSample {
            wi,
            dist,
            radiance: self.color,
            pdf: dist2 / (cos_l.abs() * area),
            delta: false,
        })
    }

    /// A direction in the cone the sphere subtends from `p`, uniformly.
    fn sample_sphere(&self, center: Vec3A, radius: f32, p: Vec3A, u: Vec2) -> Option<LightSample> {
        let to_c = center - p;
        let d2 = to_c.length_squared();
        if d2 <= radius * radius {
            return None;
        }
        let cos_max = (1.0 - radius * radius / d2).max(0.0).sqrt();
        let frame = Frame::new(to_c / d2.sqrt());
        let wi = frame.to_world(uniform_cone(u, cos_max));
        let dist = crate::geometry::Prim::Sphere { center, radius }
            .intersect(p, wi, 0.0, f32::INFINITY)
            // A grazing direction may miss in floating point: use its closest approach.
            .min(to_c.dot(wi));
        Some(LightSample {
            wi,
            dist,
            radiance: self.color,
            pdf: uniform_cone_pdf(cos_max),
            delta: false,
        })
    }

    /// The object a shadow ray towards this light may pass through: an area light's own
    /// surface (planar, it cannot hide itself); none for a mesh light, whose triangles
    /// can shadow one another.
    pub fn shadow_exempt(&self) -> u32 {
        match self.shape {
            LightShape::Triangles { mesh: true, .. } => u32::MAX,
            _ => self.object.unwrap_or(u32::MAX),
        }
    }

    /// Radiance leaving a point of the light's surface with normal `ng` towards `-dir`
    /// (the ray direction that hit it).
    pub fn emitted_at(&self, ng: Vec3A, dir: Vec3A) -> Vec3A {
        match &self.shape {
            LightShape::Triangles { two_sided, .. } => {
                if *two_sided || ng.dot(dir) < 0.0 {
                    self.color
                } else {
                    Vec3A::ZERO
                }
            }
            LightShape::Sphere { .. } => {
                if ng.dot(dir) < 0.0 {
                    self.color
                } else {
                    Vec3A::ZERO
                }
            }
            _ => Vec3A::ZERO,
        }
    }

    /// Radiance of a dome arriving from direction `-dir` (a ray along `dir` escaped).
    pub fn emitted_escaped(&self, dir: Vec3A) -> Vec3A {
        match &self.shape {
            LightShape::Dome { map: None } => self.color,
            LightShape::Dome { map: Some(m) } => self.color * m.lookup(dir),
            _ => Vec3A::ZERO,
        }
    }

    /// The solid-angle pdf with which `sample` from `p` would pick the point hit at
    /// distance `t` along `dir` (normal `ng`).
    pub fn pdf_hit(&self, p: Vec3A, dir: Vec3A, t: f32, ng: Vec3A) -> f32 {
        match &self.shape {
            LightShape::Triangles { area, .. } => {
                let cos_l = ng.dot(dir).abs();
                if cos_l == 0.0 {
                    0.0
                } else {
                    t * t / (cos_l * area)
                }
            }
            LightShape::Sphere { center, radius } => {
                let d2 = (*center - p).length_squared();
                if d2 <= radius * radius {
                    return 0.0;
                }
                uniform_cone_pdf((1.0 - radius * radius / d2).max(0.0).sqrt())
            }
            LightShape::Dome { map: None } => 1.0 / (4.0 * PI),
            LightShape::Dome { map: Some(m) } => m.pdf(dir),
            _ => 0.0,
        }
    }
}

fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    if e1 <= e0 {
        return if x >= e0 { 1.0 } else { 0.0 };
    }
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
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
