//! A cylinder light (UsdLux's `CylinderLight`): the side of a cylinder of `radius` and
//! `length`, centred at the origin with its axis along local X, emits outwards; its
//! open ends emit nothing. Placed by its transform like the other lights (a scale along
//! X stretches it, equal scales along Y and Z widen it; the cross-section must stay a
//! circle).
//!
//! Sampling is uniform in area over the part of the side a shading point can see: from
//! a point at distance `d` from the axis, the outward side faces it over the arc of
//! half-angle acos(r/d) around the direction towards it, along the whole length (the
//! normals lie across the axis), so no sample is wasted on the far side.
//!
//! ```toml
//! [[lights]]
//! type = "cylinder"
//! radius = 0.05
//! length = 1.5
//! radiance = [10, 9, 8]
//! translate = [0, 1.8, 0]
//! rotate = [0, 30, 0]
//! ```

use super::select::{Cone, LightBounds, Reach};
use super::{LightModel, LightSample};
use crate::geometry::shapes::ShapePrims;
use crate::geometry::{Prim, Ray};
use crate::scene::desc::Origin;
use crate::scene::SceneError;
use glam::{Affine3A, Vec2, Vec3A};
use std::f32::consts::PI;

#[derive(Clone, Debug)]
pub struct Cylinder {
    pub center: Vec3A,
    /// Unit direction of the axis.
    pub axis: Vec3A,
    pub radius: f32,
    pub half_length: f32,
}

/// The arc of the side a point sees: the unit vector from the axis towards the point,
/// the one completing the frame, and the arc's half-angle.
struct VisibleArc {
    towards: Vec3A,
    sideways: Vec3A,
    half_angle: f32,
}

impl Cylinder {
    /// The cylinder of `radius` and `length` along local X, placed by `xf` (whose
    /// numbers are finite). An error when its size is not positive and finite, or the
    /// transform would make the cross-section an ellipse.
    pub fn placed(
        radius: f32,
        length: f32,
        xf: &Affine3A,
        origin: &Origin,
    ) -> Result<Cylinder, SceneError> {
        if !(radius > 0.0 && radius.is_finite() && length > 0.0 && length.is_finite()) {
            return Err(origin.error(format!(
                "a cylinder light needs a positive radius and length, got radius {radius} and \
                 length {length}"
            )));
        }
        let [along, across_y, across_z] =
            [Vec3A::X, Vec3A::Y, Vec3A::Z].map(|v| xf.transform_vector3a(v));
        let (sy, sz) = (across_y.length(), across_z.length());
        let round = (sy - sz).abs() <= 1e-4 * sy.max(sz)
            && across_y.dot(across_z).abs() <= 1e-4 * sy * sz
            && along.dot(across_y).abs() <= 1e-4 * along.length() * sy
            && along.dot(across_z).abs() <= 1e-4 * along.length() * sz;
        if !round {
            return Err(origin.error(
                "a cylinder light's transform must keep its cross-section a circle: scale Y \
                 and Z alike, and no shear",
            ));
        }
        let light = Cylinder {
            center: xf.translation,
            axis: along.normalize_or_zero(),
            radius: radius * sy,
            half_length: 0.5 * length * along.length(),
        };
        let size = [light.radius, light.half_length];
        if light.axis == Vec3A::ZERO || size.iter().any(|s| !(*s > 0.0 && s.is_finite())) {
            return Err(origin.error(
                "a cylinder light's transform makes it empty or too large for 32-bit floats",
            ));
        }
        Ok(light)
    }

    pub fn prim(&self) -> Prim {
        Prim::Cylinder {
            center: self.center,
            axis: self.axis,
            radius: self.radius,
            half_length: self.half_length,
        }
    }

    /// Its surface, for the scene's geometry.
    pub fn surface(&self) -> ShapePrims {
        ShapePrims {
            prims: vec![self.prim()],
            ..ShapePrims::default()
        }
    }

    /// The part of the side `p` sees, or `None` from within the cylinder's radius of the
    /// axis (there only the inside, which does not emit, faces `p`).
    #[inline]
    fn visible_arc(&self, p: Vec3A) -> Option<VisibleArc> {
        let q = p - self.center;
        let across = q - self.axis * q.dot(self.axis);
        let d = across.length();
        if d.is_nan() || d <= self.radius {
            return None;
        }
        let towards = across / d;
        Some(VisibleArc {
            towards,
            sideways: self.axis.cross(towards),
            half_angle: (self.radius / d).acos(),
        })
    }

    /// The area of the visible part of the side.
    #[inline]
    fn visible_area(&self, arc: &VisibleArc) -> f32 {
        2.0 * arc.half_angle * self.radius * 2.0 * self.half_length
    }
}

impl LightModel for Cylinder {
    fn sample(&self, color: Vec3A, p: Vec3A, _: Vec3A, u: Vec2, _: &[Prim]) -> Option<LightSample> {
        let arc = self.visible_arc(p)?;
        let angle = arc.half_angle * (2.0 * u.x - 1.0);
        let n = arc.towards * angle.cos() + arc.sideways * angle.sin();
        let along = self.half_length * (2.0 * u.y - 1.0);
        let q = self.center + self.axis * along + n * self.radius;
        let d = q - p;
        let dist2 = d.length_squared();
        let dist = dist2.sqrt();
        let wi = d / dist;
        let cos_l = -wi.dot(n);
        if cos_l.is_nan() || cos_l <= 0.0 {
            return None;
        }
        Some(LightSample {
            wi,
            dist,
            radiance: color,
            pdf: dist2 / (cos_l * self.visible_area(&arc)),
            delta: false,
        })
    }
    fn pdf(&self, p: Vec3A, _: Vec3A, dir: Vec3A, t: f32, ng: Vec3A) -> f32 {
        let Some(arc) = self.visible_arc(p) else {
            return 0.0;
        };
        let cos_l = ng.dot(dir).abs();
        if cos_l == 0.0 {
            0.0
        } else {
            t * t / (cos_l * self.visible_area(&arc))
        }
    }
    fn emitted(&self, color: Vec3A, ng: Vec3A, dir: Vec3A) -> Vec3A {
        if ng.dot(dir) < 0.0 {
            color
        } else {
            Vec3A::ZERO
        }
    }
    /// Radiance × area × π, the side's area 2πr × length.
    fn power(&self, c: f32, _: f32) -> f32 {
        c * 2.0 * PI * self.radius * 2.0 * self.half_length * PI
    }
    /// Seen across its axis it shows its largest projected area, 2r × length.
    fn reach(&self, c: f32, _: &[Prim]) -> Reach {
        let (min, max) = self.prim().bounds();
        Reach::Bounded(LightBounds {
            min,
            max,
            phi: c * 2.0 * self.radius * 2.0 * self.half_length,
            normals: Cone::SPHERE,
            cos_e: 0.0,
            two_sided: false,
        })
    }
    fn intersect(&self, ray: &Ray, tmax: f32, _: &[Prim]) -> Option<(f32, Vec3A)> {
        let prim = self.prim();
        let t = prim.intersect(ray.origin, ray.dir, 0.0, tmax);
        t.is_finite()
            .then(|| (t, prim.curved_normal(ray.origin + ray.dir * t)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{uniform_sphere, Rng};

    fn tilted() -> Cylinder {
        let xf = Affine3A::from_translation(glam::Vec3::new(0.3, 1.0, -0.2))
            * Affine3A::from_rotation_y(0.6)
            * Affine3A::from_rotation_z(0.4);
        Cylinder::placed(0.2, 1.5, &xf, &Origin::file("test")).unwrap()
    }

    /// Mean and standard error of `n` draws of `f`.
    fn estimate(n: usize, mut f: impl FnMut() -> f64) -> (f64, f64) {
        let (mut sum, mut sum2) = (0.0, 0.0);
        for _ in 0..n {
            let x = f();
            sum += x;
            sum2 += x * x;
        }
        let mean = sum / n as f64;
        let var = (sum2 / n as f64 - mean * mean).max(0.0);
        (mean, (var / n as f64).sqrt())
    }

    /// Every watt the side emits leaves through a sphere around it (the side is convex,
    /// so nothing it emits meets it again): the flux through the sphere estimated with
    /// light samples from uniform points on it (radiance × |cos| / pdf) is the analytic
    /// power 2πr·L·π·radiance, within 5 standard errors of the estimate.
    #[test]
    fn light_samples_carry_the_analytic_power() {
        let light = tilted();
        let radiance = 3.0;
        let color = Vec3A::splat(radiance);
        let big = 2.0;
        let mut rng = Rng::for_sample(7, 1, 2);
        let area = 4.0 * PI as f64 * (big * big) as f64;
        let (flux, se) = estimate(400_000, || {
            let n = uniform_sphere(rng.next_2d());
            let x = light.center + n * big;
            match light.sample(color, x, Vec3A::ZERO, rng.next_2d(), &[]) {
                Some(s) => (s.radiance.x * s.wi.dot(n).abs() / s.pdf) as f64 * area,
                None => 0.0,
            }
        });
        let power = 2.0 * PI * light.radius * 2.0 * light.half_length * PI * radiance;
        assert!(se > 0.0 && se < 0.01 * flux, "{flux} ± {se}");
        assert!(
            (flux - power as f64).abs() <= 5.0 * se,
            "flux {flux} ± {se}, power {power}"
        );
        let c = color.max_element();
        assert!((light.power(c, 1.0) - power).abs() <= 1e-5 * power);
    }

    /// The pdf is a density over directions: from points around the light, ∫ pdf dω over
    /// uniformly sampled directions (found by `intersect`) is 1 within 5 standard errors.
    #[test]
    fn the_pdf_integrates_to_one() {
        let light = tilted();
        let mut rng = Rng::for_sample(3, 9, 4);
        for p in [
            Vec3A::new(1.2, 0.4, 0.5),
            Vec3A::new(-0.2, 2.5, 0.1),
            light.center + light.axis * 1.5 + Vec3A::new(0.0, 0.3, 0.0),
        ] {
            let (mean, se) = estimate(400_000, || {
                let dir = uniform_sphere(rng.next_2d());
                let ray = Ray {
                    origin: p,
                    dir,
                    tmax: f32::INFINITY,
                };
                match light.intersect(&ray, f32::INFINITY, &[]) {
                    Some((t, n)) if light.emitted(Vec3A::ONE, n, dir) != Vec3A::ZERO => {
                        (light.pdf(p, Vec3A::ZERO, dir, t, n) * 4.0 * PI) as f64
                    }
                    _ => 0.0,
                }
            });
            assert!((mean - 1.0).abs() <= 5.0 * se, "at {p}: {mean} ± {se}");
        }
    }

    /// A sampled point is where a ray along the sample's direction meets the light, and
    /// `pdf` there is the pdf the sample reported; the light emits towards the point.
    #[test]
    fn intersect_and_pdf_agree_with_sample() {
        let light = tilted();
        let mut rng = Rng::for_sample(1, 2, 3);
        let mut samples = 0;
        for _ in 0..2000 {
            let p = light.center + Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 4.0
                - 2.0;
            let Some(s) = light.sample(Vec3A::ONE, p, Vec3A::ZERO, rng.next_2d(), &[]) else {
                continue;
            };
            samples += 1;
            let ray = Ray {
                origin: p,
                dir: s.wi,
                tmax: f32::INFINITY,
            };
            let (t, n) = light.intersect(&ray, f32::INFINITY, &[]).expect("hits");
            // The root's error: the quadratic's constant (|o|² − r², |o| ≲ 3.5 here) is
            // rounded by ~1e-7 × 12, over its slope 2r·cos: ~3e-6 / cos (tolerance 1e-5 / cos).
            let q = p + s.wi * s.dist;
            let cos = light.prim().curved_normal(q).dot(s.wi).abs();
            assert!(
                (t - s.dist).abs() <= 1e-5 * s.dist + 1e-5 / cos,
                "{t} vs {} (cos {cos})",
                s.dist
            );
            assert_eq!(light.emitted(Vec3A::ONE, n, s.wi), Vec3A::ONE);
            // `pdf` at the sampled point is the pdf the sample reported, within rounding:
            // the point p + wi·dist is off by ~1e-7 of its distance from the origin, which
            // turns the normal by ~1e-6 rad here, a relative error of ~1e-6 / cos in the
            // pdf (tolerance ten times that). Where the ray found it, at a grazing angle
            // the two roots of the quadratic are close and the hit moves along the surface
            // by up to ~1e-4 of the distance, so that pdf is only checked to be a density.
            let normal = light.prim().curved_normal(q);
            let pdf = light.pdf(p, Vec3A::ZERO, s.wi, s.dist, normal);
            let tolerance = 1e-4 + 1e-5 / normal.dot(s.wi).abs();
            assert!(
                (pdf - s.pdf).abs() <= tolerance * s.pdf,
                "{pdf} vs {}",
                s.pdf
            );
            let found = light.pdf(p, Vec3A::ZERO, s.wi, t, n);
            assert!(found > 0.0 && found.is_finite(), "{found}");
        }
        assert!(samples > 1000, "{samples}");
        // From inside its radius, beyond an end, nothing emits towards the point.
        let inside = light.center + light.axis * 2.0;
        assert!(light
            .sample(Vec3A::ONE, inside, Vec3A::ZERO, Vec2::splat(0.5), &[])
            .is_none());
    }

    /// An elliptic cross-section is refused, naming the problem.
    #[test]
    fn a_squashed_cylinder_is_an_error() {
        let xf = Affine3A::from_scale(glam::Vec3::new(1.0, 2.0, 1.0));
        let e = Cylinder::placed(0.2, 1.0, &xf, &Origin::file("a.toml")).unwrap_err();
        assert!(e.to_string().contains("circle"), "{e}");
        let bad = Cylinder::placed(-1.0, 1.0, &Affine3A::IDENTITY, &Origin::file("a.toml"));
        assert!(bad.is_err());
    }
}
