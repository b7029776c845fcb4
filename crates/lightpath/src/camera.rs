//! A perspective camera with an optional thin lens, and the pixel filter that places
//! samples in the pixel.
//!
//! ```toml
//! [camera]
//! position = [0, 0, 3.9]
//! look_at = [0, 0, 0]
//! up = [0, 1, 0]
//! fov = 39.3077            # degrees, along fov_axis
//! fov_axis = "smaller"     # x | y | smaller | larger
//! aperture_radius = 0.0    # thin lens; 0 is a pinhole
//! focus_distance = 3.9
//! ```

use crate::geometry::Ray;
use crate::sampling::square_to_disk;
use glam::{Vec2, Vec3A};

mod blackman_harris;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PixelFilter {
    /// Uniform over the pixel (each sample counts only for its own pixel).
    Box,
    /// Samples offset by a Gaussian of this standard deviation in pixels (filter
    /// importance sampling, so samples still land in one pixel each).
    Gaussian { stddev: f32 },
    /// Samples offset by a Blackman–Harris window reaching ±`width` pixels (Cycles'
    /// default pixel filter at width 1.5).
    BlackmanHarris { width: f32 },
}

/// The pixel filter a scene names (`[film] filter`); a Gaussian's width is a setting of
/// its own (`filter_stddev`), as is a Blackman–Harris window's (`filter_width`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FilterKind {
    #[default]
    Box,
    Gaussian,
    BlackmanHarris,
}

impl FilterKind {
    pub const NAMES: [&'static str; 3] = ["box", "gaussian", "blackman-harris"];

    pub fn parse(s: &str) -> Option<FilterKind> {
        match s {
            "box" => Some(FilterKind::Box),
            "gaussian" => Some(FilterKind::Gaussian),
            "blackman-harris" => Some(FilterKind::BlackmanHarris),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            FilterKind::Box => "box",
            FilterKind::Gaussian => "gaussian",
            FilterKind::BlackmanHarris => "blackman-harris",
        }
    }
}

impl PixelFilter {
    /// The filter of a kind, with the Gaussian's standard deviation and the
    /// Blackman–Harris window's half-width in pixels.
    pub fn new(kind: FilterKind, stddev: f32, width: f32) -> PixelFilter {
        match kind {
            FilterKind::Box => PixelFilter::Box,
            FilterKind::Gaussian => PixelFilter::Gaussian { stddev },
            FilterKind::BlackmanHarris => PixelFilter::BlackmanHarris { width },
        }
    }

    /// Offset from the pixel centre for two uniform numbers.
    pub fn offset(&self, u: Vec2) -> Vec2 {
        match *self {
            PixelFilter::Box => u - Vec2::splat(0.5),
            PixelFilter::Gaussian { stddev } => {
                // Box–Muller, truncated at 3σ.
                let r = (-2.0 * (1.0 - u.x).max(1e-12).ln()).sqrt().min(3.0) * stddev;
                let (sin, cos) = crate::sampling::sin_cos_turns(u.y);
                Vec2::new(r * cos, r * sin)
            }
            PixelFilter::BlackmanHarris { width } => blackman_harris::offset(u, width),
        }
    }

    /// The density of `offset` from the pixel centre (per pixel area) among the offsets
    /// `offset` makes; 0 on a Gaussian's 3σ ring, where the truncation piles the tail up
    /// with no density (light tracing leaves those offsets to camera rays, connect.rs).
    pub fn pdf(&self, offset: Vec2) -> f32 {
        match *self {
            PixelFilter::Box => (offset.x.abs() <= 0.5 && offset.y.abs() <= 0.5) as u32 as f32,
            PixelFilter::Gaussian { stddev } => {
                let var = stddev * stddev;
                let r2 = offset.length_squared();
                if r2 < 9.0 * var * (1.0 - 1e-4) {
                    (-r2 / (2.0 * var)).exp() / (2.0 * std::f32::consts::PI * var)
                } else {
                    0.0
                }
            }
            PixelFilter::BlackmanHarris { width } => blackman_harris::pdf(offset, width),
        }
    }

    /// How far from its pixel centre an offset may reach, in pixels along each axis.
    pub fn radius(&self) -> f32 {
        match *self {
            PixelFilter::Box => 0.5,
            PixelFilter::Gaussian { stddev } => 3.0 * stddev,
            PixelFilter::BlackmanHarris { width } => width,
        }
    }
}

/// Where a pinhole camera sees a point (light tracing, connect.rs).
#[derive(Clone, Copy, Debug)]
pub struct Projection {
    /// The film position in pixels (origin top-left), as `Camera::ray` takes it.
    pub film: Vec2,
    /// The unit direction from the camera to the point, and the distance.
    pub dir: Vec3A,
    pub dist: f32,
    /// The solid-angle density of camera rays there per unit film density: d² / cos³,
    /// d being the distance of the image plane on which a pixel has unit area and cos
    /// the angle off the view axis.
    pub to_solid_angle: f32,
}

#[derive(Clone, Debug)]
pub struct Camera {
    pub position: Vec3A,
    forward: Vec3A,
    right: Vec3A,
    up: Vec3A,
    tan_half: Vec2,
    pub aperture_radius: f32,
    pub focus_distance: f32,
    pub width: u32,
    pub height: u32,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FovAxis {
    X,
    Y,
    Smaller,
    Larger,
}

impl Camera {
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        position: Vec3A,
        look_at: Vec3A,
        up: Vec3A,
        fov_deg: f32,
        axis: FovAxis,
        width: u32,
        height: u32,
        aperture_radius: f32,
        focus_distance: f32,
    ) -> Camera {
        let forward = (look_at - position).normalize();
        let right = forward.cross(up).normalize();
        let up = right.cross(forward);
        let aspect = width as f32 / height as f32;
        let t = (fov_deg.to_radians() * 0.5).tan();
        let along_x = match axis {
            FovAxis::X => true,
            FovAxis::Y => false,
            FovAxis::Smaller => width <= height,
            FovAxis::Larger => width >= height,
        };
        let tan_half = if along_x {
            Vec2::new(t, t / aspect)
        } else {
            Vec2::new(t * aspect, t)
        };
        Camera {
            position,
            forward,
            right,
            up,
            tan_half,
            aperture_radius,
            focus_distance,
            width,
            height,
        }
    }

    /// The angle one pixel subtends at the image centre (radians): the spread of the
    /// ray cones that choose texture mip levels.
    pub fn pixel_spread(&self) -> f32 {
        2.0 * self.tan_half.y / self.height as f32
    }

    /// OpenEXR's `worldToCamera` as a column-vector matrix: camera space has x right, y
    /// up and z along the view direction (left-handed; what the camera sees has z > 0).
    pub fn world_to_camera(&self) -> glam::Mat4 {
        let (r, u, f, p) = (self.right, self.up, self.forward, self.position);
        glam::Mat4::from_cols_array(&[
            r.x,
            u.x,
            f.x,
            0.0,
            r.y,
            u.y,
            f.y,
            0.0,
            r.z,
            u.z,
            f.z,
            0.0,
            -r.dot(p),
            -u.dot(p),
            -f.dot(p),
            1.0,
        ])
    }

    /// OpenEXR's `worldToNDC` as a column-vector matrix: after the divide by w, x and y
    /// run from (0, 0) at the frame's top-left corner to (1, 1) at its bottom-right, as
    /// the pixel at film position (fx, fy) has (fx / width, fy / height); z is 1 − 1/depth.
    pub fn world_to_ndc(&self) -> glam::Mat4 {
        let (tx, ty) = (self.tan_half.x, self.tan_half.y);
        let projection = glam::Mat4::from_cols_array(&[
            0.5 / tx,
            0.0,
            0.0,
            0.0,
            0.0,
            -0.5 / ty,
            0.0,
            0.0,
            0.5,
            0.5,
            1.0,
            1.0,
            0.0,
            0.0,
            -1.0,
            0.0,
        ]);
        projection * self.world_to_camera()
    }

    /// Where the camera sees `p`, if it is a pinhole and `p` is in front of it (film
    /// positions off the frame included: a pixel filter reaches past the edge).
    pub fn project(&self, p: Vec3A) -> Option<Projection> {
        if self.aperture_radius > 0.0 {
            return None;
        }
        let d = p - self.position;
        let dist = d.length();
        if !(dist > 0.0 && dist.is_finite()) {
            return None;
        }
        let dir = d / dist;
        let cos = dir.dot(self.forward);
        if cos <= 0.0 {
            return None;
        }
        let x = dir.dot(self.right) / (cos * self.tan_half.x);
        let y = dir.dot(self.up) / (cos * self.tan_half.y);
        let (w, h) = (self.width as f32, self.height as f32);
        Some(Projection {
            film: Vec2::new((x + 1.0) * 0.5 * w, (1.0 - y) * 0.5 * h),
            dir,
            dist,
            to_solid_angle: self.to_solid_angle(cos),
        })
    }

    /// `Projection::to_solid_angle` at `cos` off the view axis.
    pub fn to_solid_angle(&self, cos: f32) -> f32 {
        let image = self.width as f32 / (2.0 * self.tan_half.x);
        image * image / (cos * cos * cos)
    }

    /// The cosine between a direction from the camera and the view axis.
    pub fn cos_off_axis(&self, dir: Vec3A) -> f32 {
        dir.dot(self.forward)
    }

    /// Camera-space depth of `p`: its distance from the camera along the view axis
    /// (what compositors call Z).
    pub fn depth(&self, p: Vec3A) -> f32 {
        (p - self.position).dot(self.forward)
    }

    /// The primary ray through film position `film` (in pixels, origin top-left).
    pub fn ray(&self, film: Vec2, lens: Vec2) -> Ray {
        let ndc = Vec2::new(
            2.0 * film.x / self.width as f32 - 1.0,
            1.0 - 2.0 * film.y / self.height as f32,
        );
        let dir = (self.forward
            + self.right * (ndc.x * self.tan_half.x)
            + self.up * (ndc.y * self.tan_half.y))
            .normalize();
        if self.aperture_radius <= 0.0 {
            return Ray {
                origin: self.position,
                dir,
                tmax: f32::INFINITY,
            };
        }
        // Thin lens: every ray through the lens meets the chief ray on the focal plane.
        let focus = self.position + dir * (self.focus_distance / dir.dot(self.forward));
        let d = square_to_disk(lens) * self.aperture_radius;
        let origin = self.position + self.right * d.x + self.up * d.y;
        Ray {
            origin,
            dir: (focus - origin).normalize(),
            tmax: f32::INFINITY,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Light tracing's projection undoes `ray`: a point on the ray through a film
    /// position (off the frame too) lands back there, and the solid angle a small patch of
    /// film subtends is its area over `to_solid_angle` (finite differences).
    #[test]
    fn a_point_projects_to_the_film_position_of_its_ray() {
        let c = Camera::new(
            Vec3A::new(0.3, -0.2, 3.9),
            Vec3A::new(0.1, 0.0, 0.0),
            Vec3A::Y,
            50.0,
            FovAxis::Larger,
            64,
            48,
            0.0,
            1.0,
        );
        for film in [
            Vec2::new(32.0, 24.0),
            Vec2::new(0.25, 47.5),
            Vec2::new(63.0, 3.0),
            Vec2::new(-1.2, 50.0),
        ] {
            let ray = c.ray(film, Vec2::ZERO);
            for t in [0.5, 7.0] {
                let p = c.project(ray.origin + ray.dir * t).unwrap();
                assert!((p.film - film).length() < 1e-3, "{film} {}", p.film);
                assert!((p.dist - t).abs() < 1e-4 && (p.dir - ray.dir).length() < 1e-5);
                let d = 1e-2;
                let (dx, dy) = (
                    c.ray(film + Vec2::new(d, 0.0), Vec2::ZERO).dir - ray.dir,
                    c.ray(film + Vec2::new(0.0, d), Vec2::ZERO).dir - ray.dir,
                );
                let solid_angle = dx.cross(dy).length() / (d * d);
                assert!((solid_angle * p.to_solid_angle - 1.0).abs() < 1e-2);
            }
        }
        assert!(
            c.project(Vec3A::new(0.3, -0.2, 5.0)).is_none(),
            "behind the camera"
        );
        let lens = Camera {
            aperture_radius: 0.1,
            ..c
        };
        assert!(
            lens.project(Vec3A::ZERO).is_none(),
            "a thin lens is not a pinhole"
        );
    }

    /// Each filter's `pdf` is the density of the offsets `offset` makes: χ² of 20 000
    /// offsets' histogram over 16 × 16 cells against the density integrated over each
    /// (the Gaussian's truncated tail, on its 3σ ring, has none and is left out).
    #[test]
    fn a_filters_pdf_is_the_density_of_its_offsets() {
        let mut rng = crate::sampling::Rng::for_sample(7, 0, 0);
        for filter in [
            PixelFilter::Box,
            PixelFilter::Gaussian { stddev: 0.5 },
            PixelFilter::BlackmanHarris { width: 1.5 },
        ] {
            let (n, cells) = (20_000, 16);
            let r = filter.radius();
            let cell = 2.0 * r / cells as f32;
            let mut seen = vec![0.0f64; cells * cells];
            for _ in 0..n {
                let o = filter.offset(rng.next_2d());
                if filter.pdf(o) == 0.0 {
                    continue;
                }
                let (i, j) = (((o.x + r) / cell) as usize, ((o.y + r) / cell) as usize);
                seen[j.min(cells - 1) * cells + i.min(cells - 1)] += 1.0;
            }
            let (mut chi2, mut dof) = (0.0, 0);
            for j in 0..cells {
                for i in 0..cells {
                    // The density integrated over the cell by an 8 × 8 midpoint rule.
                    let mut mass = 0.0;
                    for b in 0..8 {
                        for a in 0..8 {
                            let o = Vec2::new(
                                -r + (i as f32 + (a as f32 + 0.5) / 8.0) * cell,
                                -r + (j as f32 + (b as f32 + 0.5) / 8.0) * cell,
                            );
                            mass += filter.pdf(o) as f64 * (cell * cell) as f64 / 64.0;
                        }
                    }
                    let expected = mass * n as f64;
                    if expected >= 10.0 {
                        chi2 += (seen[j * cells + i] - expected).powi(2) / expected;
                        dof += 1;
                    }
                }
            }
            let bound = dof as f64 + 5.0 * (2.0 * dof as f64).sqrt();
            assert!(chi2 < bound, "{filter:?}: χ² {chi2} over {dof} cells");
        }
    }

    #[test]
    fn image_x_is_world_right_and_row_zero_is_top() {
        let c = Camera::new(
            Vec3A::new(0.0, 0.0, 3.9),
            Vec3A::ZERO,
            Vec3A::Y,
            40.0,
            FovAxis::Smaller,
            100,
            50,
            0.0,
            1.0,
        );
        let centre = c.ray(Vec2::new(50.0, 25.0), Vec2::ZERO);
        assert!((centre.dir - (-Vec3A::Z)).length() < 1e-6);
        assert!(c.ray(Vec2::new(99.0, 25.0), Vec2::ZERO).dir.x > 0.0);
        assert!(c.ray(Vec2::new(50.0, 0.0), Vec2::ZERO).dir.y > 0.0);
        // The smaller axis (y here) spans the field of view.
        let top = c.ray(Vec2::new(50.0, 0.0), Vec2::ZERO).dir;
        assert!((top.y.atan2(-top.z).to_degrees() - 20.0).abs() < 1e-3);
    }

    #[test]
    fn world_to_ndc_maps_a_point_on_a_pixels_ray_to_that_pixel() {
        let c = Camera::new(
            Vec3A::new(1.0, 2.0, 3.9),
            Vec3A::new(0.2, -0.3, 0.0),
            Vec3A::Y,
            50.0,
            FovAxis::X,
            64,
            48,
            0.0,
            1.0,
        );
        let (w2c, w2n) = (c.world_to_camera(), c.world_to_ndc());
        for (fx, fy) in [(0.0, 0.0), (64.0, 48.0), (10.5, 40.25), (32.0, 24.0)] {
            let ray = c.ray(Vec2::new(fx, fy), Vec2::ZERO);
            for t in [0.5, 3.0] {
                let p = glam::Vec3::from(ray.origin + ray.dir * t);
                let cam = w2c.transform_point3(p);
                assert!((cam.z - t * ray.dir.dot(c.forward)).abs() < 1e-4, "{cam}");
                let ndc = w2n.project_point3(p);
                assert!((ndc.x - fx / 64.0).abs() < 1e-5, "{ndc} for ({fx}, {fy})");
                assert!((ndc.y - fy / 48.0).abs() < 1e-5, "{ndc} for ({fx}, {fy})");
            }
        }
        // The camera sits at the origin of camera space.
        let origin = w2c.transform_point3(glam::Vec3::from(c.position));
        assert!(origin.length() < 1e-5);
    }
}
