//! Area lights made of triangles: a rectangle, a quad or a disk (`type = "rect"`,
//! `"quad"`, `"disk"`), sampled uniformly by area (directly on the parallelogram when the
//! triangles form one), or in solid angle, warped by the receiver's cosine, when they
//! form a rectangle and the shading point is close to it (`spherical_rect.rs` says when,
//! and why). They emit on the side of their normal unless `two_sided`. A [`Shaping`]
//! (UsdLux's ShapingAPI on rect and disk lights) narrows their emission about the normal.
//!
//! ```toml
//! [[lights]]
//! type = "rect"            # the unit square in z = 0, facing +z, placed by its transform
//! radiance = [17, 12, 4]
//! translate = [0, 0.99, 0]
//! rotate = [90, 0, 0]
//! scale = [0.25, 0.25, 1]
//! ```

use super::select::{Cone, LightBounds, Reach};
use super::spherical_rect::Rect;
use super::{LightModel, LightSample};
use crate::geometry::{Prim, Ray};
use crate::sampling::{uniform_triangle, Distribution1D};
use glam::{Vec2, Vec3A};
use std::f32::consts::PI;

#[derive(Clone, Debug)]
pub struct Triangles {
    /// The triangles, as indices into the scene's primitive list (`Accel::prims`).
    pub prims: Vec<u32>,
    /// Unit normal of each triangle, precomputed for sampling.
    pub normals: Vec<Vec3A>,
    /// Corner and edges when the triangles form one parallelogram (rectangle and most
    /// quad lights): sampled directly, uniformly in area.
    pub parallelogram: Option<[Vec3A; 3]>,
    /// The parallelogram when it is a rectangle: sampled in solid angle from close by.
    pub rect: Option<Rect>,
    pub by_area: Distribution1D,
    pub area: f32,
    pub two_sided: bool,
    pub shaping: Option<Shaping>,
}

/// UsdLux ShapingAPI's emission profile about the normal (the schema's `shaping:focus`,
/// `shaping:focusTint` and `shaping:cone:*` formulas): at θ off the normal, with
/// focusFactor = |cos θ|^focus, emission times
/// lerp(focusFactor, focusTint, white) · (1 − smoothstep(θ; start, cutoff)), zero beyond
/// `cutoff`. A black tint (the schema's default) makes the focus a plain cosine power; a
/// white one disables it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shaping {
    /// Cutoff angle in radians.
    pub cutoff: f32,
    /// Where the fade to the cutoff starts, in radians (at most `cutoff`).
    pub start: f32,
    pub focus: f32,
    /// The colour emission fades to off the axis, per channel.
    pub tint: Vec3A,
}

impl Shaping {
    /// The factor, per channel, at cosine `cos` off the normal.
    pub fn factor(&self, cos: f32) -> Vec3A {
        let c = cos.abs().min(1.0);
        let theta = c.acos();
        if theta > self.cutoff {
            return Vec3A::ZERO;
        }
        let cone = if self.start < self.cutoff && theta > self.start {
            let t = (theta - self.start) / (self.cutoff - self.start);
            1.0 - t * t * (3.0 - 2.0 * t)
        } else {
            1.0
        };
        // The schema ignores a focus below zero; at zero the factor is 1 (no tint).
        if self.focus > 0.0 {
            let f = c.powf(self.focus);
            (self.tint + (Vec3A::ONE - self.tint) * f) * cone
        } else {
            Vec3A::splat(cone)
        }
    }
}

impl Triangles {
    /// A rectangle's sample: in solid angle (warped by the cosine at a receiver with
    /// normal `ns`) when `rect.seen` says so, else by area.
    #[inline(always)]
    fn sample_rect(
        &self,
        rect: &Rect,
        color: Vec3A,
        p: Vec3A,
        ns: Vec3A,
        u: Vec2,
    ) -> Option<LightSample> {
        let n = self.normals[0];
        let [p0, e1, e2] = self.parallelogram?;
        // Behind a one-sided light (or in its plane) no point of it is seen. In its plane
        // up to rounding too: a point of the light's own surface (a light with a
        // material, hit) rounded to a hair in front would see the whole light as a
        // hemisphere and light itself.
        let height = (p - p0).dot(n);
        let on_plane =
            1e-5 * (p0.abs().max_element() + e1.abs().max_element() + e2.abs().max_element());
        if height <= 0.0 && !self.two_sided || height.abs() <= on_plane {
            return None;
        }
        let (q, pdf_of) = match rect.seen(p, ns) {
            Some(seen) => {
                let (q, pdf) = seen.sample(u);
                (q, Some(pdf))
            }
            None => (p0 + e1 * u.x + e2 * u.y, None),
        };
        let d = q - p;
        let dist2 = d.length_squared();
        let dist = dist2.sqrt();
        let wi = d / dist;
        let cos_l = -wi.dot(n);
        if cos_l == 0.0 || !dist.is_finite() || dist == 0.0 {
            return None;
        }
        let pdf = pdf_of.unwrap_or(dist2 / (cos_l.abs() * self.area));
        self.shaped_sample(color, wi, dist, cos_l, pdf)
    }

    /// The sample towards a point seen at `cos_l` off the light's normal, its radiance
    /// shaped (focus, tint, cone), or None where the shaping gives none.
    #[inline(always)]
    fn shaped_sample(
        &self,
        color: Vec3A,
        wi: Vec3A,
        dist: f32,
        cos_l: f32,
        pdf: f32,
    ) -> Option<LightSample> {
        let shaped = match &self.shaping {
            Some(s) => s.factor(cos_l),
            None => Vec3A::ONE,
        };
        if shaped.max_element() <= 0.0 {
            return None;
        }
        Some(LightSample {
            wi,
            dist,
            radiance: color * shaped,
            pdf,
            delta: false,
        })
    }
}

impl LightModel for Triangles {
    /// A point on the triangles (directly on the parallelogram when they are one), in
    /// solid angle.
    #[inline(always)]
    fn sample(
        &self,
        color: Vec3A,
        p: Vec3A,
        ns: Vec3A,
        u: Vec2,
        prims: &[Prim],
    ) -> Option<LightSample> {
        if let Some(rect) = &self.rect {
            return self.sample_rect(rect, color, p, ns, u);
        }
        let (q, n) = match self.parallelogram {
            Some([p0, e1, e2]) => (p0 + e1 * u.x + e2 * u.y, self.normals[0]),
            None => {
                let (i, _, ux) = self.by_area.sample(u.x);
                let Prim::Triangle { p0, e1, e2, .. } = prims[self.prims[i] as usize] else {
                    return None;
                };
                let (b1, b2) = uniform_triangle(Vec2::new(ux, u.y));
                (p0 + e1 * b1 + e2 * b2, self.normals[i])
            }
        };
        let d = q - p;
        let dist2 = d.length_squared();
        let dist = dist2.sqrt();
        let wi = d / dist;
        let cos_l = -wi.dot(n);
        if cos_l <= 0.0 && !self.two_sided || cos_l == 0.0 {
            return None;
        }
        self.shaped_sample(color, wi, dist, cos_l, dist2 / (cos_l.abs() * self.area))
    }

    fn pdf(&self, p: Vec3A, ns: Vec3A, dir: Vec3A, t: f32, ng: Vec3A) -> f32 {
        // The same choice as `sample_rect`'s, by `p` and `ns` alone.
        if let Some(seen) = self.rect.as_ref().and_then(|r| r.seen(p, ns)) {
            return seen.pdf(p + dir * t);
        }
        let cos_l = ng.dot(dir).abs();
        if cos_l == 0.0 {
            0.0
        } else {
            t * t / (cos_l * self.area)
        }
    }
    fn emitted(&self, color: Vec3A, ng: Vec3A, dir: Vec3A) -> Vec3A {
        if self.two_sided || ng.dot(dir) < 0.0 {
            match &self.shaping {
                Some(s) => color * s.factor(ng.dot(dir)),
                None => color,
            }
        } else {
            Vec3A::ZERO
        }
    }
    fn power(&self, c: f32, _: f32) -> f32 {
        c * self.area * PI * if self.two_sided { 2.0 } else { 1.0 }
    }
    fn reach(&self, c: f32, prims: &[Prim]) -> Reach {
        let mut min = Vec3A::splat(f32::INFINITY);
        let mut max = Vec3A::splat(f32::NEG_INFINITY);
        for &i in &self.prims {
            if let Prim::Triangle { p0, e1, e2, .. } = prims[i as usize] {
                for q in [p0, p0 + e1, p0 + e2] {
                    min = min.min(q);
                    max = max.max(q);
                }
            }
        }
        let mut cone: Option<Cone> = None;
        for n in &self.normals {
            let one = Cone {
                w: *n,
                cos_theta: 1.0,
            };
            cone = Some(cone.map_or(one, |c| Cone::union(c, one)));
        }
        if min.x > max.x {
            return Reach::Nowhere;
        }
        Reach::Bounded(LightBounds {
            min,
            max,
            phi: c * self.area,
            normals: cone.unwrap_or(Cone::SPHERE),
            cos_e: 0.0,
            two_sided: self.two_sided,
        })
    }
    /// The nearest of its triangles, one by one (an area light has few).
    fn intersect(&self, ray: &Ray, tmax: f32, prims: &[Prim]) -> Option<(f32, Vec3A)> {
        let mut nearest = None;
        let mut tmax = tmax;
        for (&i, n) in self.prims.iter().zip(&self.normals) {
            let t = prims[i as usize].intersect(ray.origin, ray.dir, 0.0, tmax);
            if t < tmax {
                tmax = t;
                nearest = Some((t, *n));
            }
        }
        nearest
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::shapes;
    use crate::sampling::{uniform_cone, uniform_cone_pdf, Frame, Rng};

    /// The UsdLux schema's ShapingAPI formulas, written out separately in f64:
    /// focusFactor = |cos θ|^focus, focusColor = lerp(focusFactor, focusTint, white),
    /// times 1 − smoothstep(θ; lerp(softness, cutoff, 0), cutoff), zero past the cutoff.
    fn schema(theta: f64, focus: f64, tint: [f64; 3], cone: f64, softness: f64) -> [f64; 3] {
        let cutoff = cone.to_radians();
        let smooth_start = cutoff + softness * (0.0 - cutoff);
        let scalar = if theta > cutoff {
            0.0
        } else if theta <= smooth_start {
            1.0
        } else {
            let t = (theta - smooth_start) / (cutoff - smooth_start);
            1.0 - t * t * (3.0 - 2.0 * t)
        };
        let ff = if focus > 0.0 {
            theta.cos().abs().powf(focus)
        } else {
            1.0
        };
        tint.map(|t| (t + ff * (1.0 - t)) * scalar)
    }

    /// A one-sided unit square facing +z with the given shaping.
    fn panel(shaping: Shaping) -> Triangles {
        Triangles {
            prims: Vec::new(),
            normals: vec![Vec3A::Z],
            parallelogram: Some([Vec3A::new(-0.5, -0.5, 0.0), Vec3A::X, Vec3A::Y]),
            rect: None,
            by_area: Distribution1D::new(&[1.0]),
            area: 1.0,
            two_sided: false,
            shaping: Some(shaping),
        }
    }

    #[test]
    fn emitted_radiance_against_angle_is_the_schemas_focus_tint_and_cone() {
        let color = Vec3A::new(2.0, 3.0, 5.0);
        let cases: [(f32, [f32; 3], f32, f32); 5] = [
            (3.0, [0.0; 3], 90.0, 0.0),
            (3.0, [0.9, 0.2, 0.0], 90.0, 0.0),
            (8.0, [0.1, 0.5, 1.0], 60.0, 0.4),
            (1.5, [1.0; 3], 45.0, 1.0),
            (0.0, [0.3, 0.6, 0.9], 70.0, 0.25),
        ];
        for (focus, tint, cone, softness) in cases {
            let cutoff = cone.to_radians();
            let light = panel(Shaping {
                cutoff,
                start: cutoff * (1.0 - softness),
                focus,
                tint: Vec3A::from(tint),
            });
            for deg in (0..90).step_by(3) {
                let theta = (deg as f32).to_radians();
                // A ray arriving at the light from θ off its normal.
                let dir = -Vec3A::new(theta.sin(), 0.0, theta.cos());
                let got = light.emitted(color, Vec3A::Z, dir);
                let want = schema(
                    theta as f64,
                    focus as f64,
                    tint.map(f64::from),
                    cone as f64,
                    softness as f64,
                );
                for k in 0..3 {
                    let w = want[k] * color[k] as f64;
                    assert!(
                        (got[k] as f64 - w).abs() <= 1e-5 * (1.0 + w),
                        "focus {focus} tint {tint:?} cone {cone}/{softness} at {deg}°: \
                         {got} against {want:?}"
                    );
                }
                // Sampled from a point along that direction: the same radiance.
                let p = -dir * 10.0;
                if let Some(s) = light.sample(color, p, Vec3A::ZERO, Vec2::splat(0.5), &[]) {
                    let cos = (-s.wi).dot(Vec3A::Z);
                    let again = schema(
                        cos.acos() as f64,
                        focus as f64,
                        tint.map(f64::from),
                        cone as f64,
                        softness as f64,
                    );
                    for k in 0..3 {
                        let w = again[k] * color[k] as f64;
                        assert!((s.radiance[k] as f64 - w).abs() <= 1e-5 * (1.0 + w));
                    }
                } else {
                    assert!(want.iter().all(|&w| w == 0.0), "{deg}°: {want:?}");
                }
            }
        }
    }

    /// The indirect box's lamp (benches/guiding/indirect_box.toml): 0.46 × 0.38 at
    /// y = 0.8, facing the ceiling 0.2 above it; `solid_angle: false` keeps area
    /// sampling everywhere.
    fn lamp(two_sided: bool, solid_angle: bool) -> (Triangles, Vec<Prim>) {
        let c = [
            Vec3A::new(-0.23, 0.8, -0.18),
            Vec3A::new(-0.23, 0.8, 0.2),
            Vec3A::new(0.23, 0.8, 0.2),
            Vec3A::new(0.23, 0.8, -0.18),
        ];
        let prims = shapes::quad(c).prims;
        let (p0, e1, e2) = (c[0], c[1] - c[0], c[3] - c[0]);
        let areas: Vec<f32> = prims.iter().map(Prim::area).collect();
        let light = Triangles {
            prims: vec![0, 1],
            normals: prims.iter().map(Prim::face_normal).collect(),
            parallelogram: Some([p0, e1, e2]),
            rect: if solid_angle {
                Rect::new(p0, e1, e2)
            } else {
                None
            },
            by_area: Distribution1D::new(&areas),
            area: areas.iter().sum(),
            two_sided,
            shaping: None,
        };
        assert!(light.normals[0].y > 0.999, "the lamp faces +y");
        (light, prims)
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

    /// Shading points: on the ceiling right above the lamp, beside it at a grazing
    /// angle, below it (two-sided only), and two far enough to be sampled by area.
    const POINTS: [Vec3A; 6] = [
        Vec3A::new(0.0, 1.0, 0.0),
        Vec3A::new(0.4, 0.98, -0.3),
        Vec3A::new(0.5, 0.81, 0.1),
        Vec3A::new(0.1, 0.5, 0.2),
        Vec3A::new(0.5, 1.0, 0.6),
        Vec3A::new(1.5, 4.0, 2.0),
    ];

    /// Shading normals to take at every point: none (a point in a medium: no warp), a
    /// ceiling's, and a tilted one that sees part of the lamp from behind.
    const NORMALS: [Vec3A; 3] = [
        Vec3A::ZERO,
        Vec3A::new(0.0, -1.0, 0.0),
        Vec3A::new(0.8, 0.0, 0.6),
    ];

    /// The pdf is a density over directions, with either sampling: from each point,
    /// ∫ pdf dω over directions drawn in a cone around the lamp (found by `intersect`)
    /// is 1 within 5 standard errors.
    #[test]
    fn the_pdf_integrates_to_one() {
        let mut rng = Rng::for_sample(11, 3, 5);
        for two_sided in [false, true] {
            let (light, prims) = lamp(two_sided, true);
            let rect = light.rect.unwrap();
            for (p, ns) in POINTS.into_iter().flat_map(|p| NORMALS.map(|n| (p, n))) {
                if !two_sided && p.y < 0.8 {
                    continue;
                }
                let centre = Vec3A::new(0.0, 0.8, 0.01);
                let radius = 0.5 * (0.46f32.hypot(0.38));
                let to = centre - p;
                let cos_max = (1.0 - (radius / to.length()).powi(2)).max(-1.0).sqrt();
                let cos_max = if to.length() > radius { cos_max } else { -1.0 };
                let frame = Frame::new(to.normalize());
                let pdf_dir = uniform_cone_pdf(cos_max);
                let (mean, se) = estimate(200_000, || {
                    let dir = frame.to_world(uniform_cone(rng.next_2d(), cos_max));
                    let ray = Ray {
                        origin: p,
                        dir,
                        tmax: f32::INFINITY,
                    };
                    match light.intersect(&ray, f32::INFINITY, &prims) {
                        Some((t, n)) if light.emitted(Vec3A::ONE, n, dir) != Vec3A::ZERO => {
                            f64::from(light.pdf(p, ns, dir, t, n) / pdf_dir)
                        }
                        _ => 0.0,
                    }
                });
                let how = if rect.seen(p, ns).is_some() {
                    "solid angle"
                } else {
                    "area"
                };
                assert!(se < 0.03, "at {p}, n {ns} ({how}): {mean} ± {se}");
                assert!(
                    (mean - 1.0).abs() <= 5.0 * se,
                    "at {p}, n {ns} ({how}): {mean} ± {se}"
                );
            }
        }
    }

    #[test]
    fn a_white_tint_disables_the_focus_and_a_negative_focus_is_none() {
        let s = |focus: f32, tint: f32| Shaping {
            cutoff: PI / 2.0,
            start: PI / 2.0,
            focus,
            tint: Vec3A::splat(tint),
        };
        for cos in [1.0, 0.7, 0.2, 0.01] {
            assert_eq!(s(20.0, 1.0).factor(cos), Vec3A::ONE);
            assert_eq!(s(-2.0, 0.0).factor(cos), Vec3A::ONE);
        }
    }

    /// What `sample` returns is what `pdf` says for the ray that finds the sampled
    /// point (MIS weighs BSDF rays that hit the light with `pdf`), with and without the
    /// receiver's normal (the cosine warp and its inverse).
    #[test]
    fn sample_and_pdf_agree() {
        let (light, prims) = lamp(true, true);
        let mut rng = Rng::for_sample(2, 7, 1);
        for (p, ns) in POINTS.into_iter().flat_map(|p| NORMALS.map(|n| (p, n))) {
            for _ in 0..2000 {
                let Some(s) = light.sample(Vec3A::ONE, p, ns, rng.next_2d(), &prims) else {
                    continue;
                };
                let ray = Ray {
                    origin: p,
                    dir: s.wi,
                    tmax: f32::INFINITY,
                };
                let Some((t, n)) = light.intersect(&ray, s.dist * 1.001, &prims) else {
                    // The sample may sit on the lamp's very edge, where the ray misses.
                    continue;
                };
                assert!(
                    (t - s.dist).abs() <= 1e-4 * s.dist,
                    "at {p}: {t} vs {}",
                    s.dist
                );
                let pdf = light.pdf(p, ns, s.wi, t, n);
                assert!(
                    (pdf - s.pdf).abs() <= 2e-3 * s.pdf,
                    "at {p}, n {ns}: pdf {pdf}, sample's {}",
                    s.pdf
                );
            }
        }
    }

    /// Irradiance from a polygon of uniform radiance L (Lambert 1760): E = L/2 ·
    /// Σᵢ γᵢ (uᵢ × uᵢ₊₁)/|uᵢ × uᵢ₊₁| · N, γᵢ the angle between the unit directions uᵢ,
    /// uᵢ₊₁ to consecutive corners. In f64, over the whole lamp (which every point
    /// below sees entirely in front of its tangent plane).
    fn lambert(corners: &[Vec3A; 4], p: Vec3A, n: Vec3A, radiance: f64) -> f64 {
        let u: Vec<_> = corners
            .iter()
            .map(|c| (*c - p).as_dvec3().normalize())
            .collect();
        let mut sum = glam::DVec3::ZERO;
        for i in 0..4 {
            let (a, b) = (u[i], u[(i + 1) % 4]);
            sum += a.cross(b).normalize() * a.dot(b).clamp(-1.0, 1.0).acos();
        }
        0.5 * radiance * sum.dot(n.as_dvec3()).abs()
    }

    /// Light samples estimate the analytic irradiance within 5 standard errors, with
    /// solid-angle sampling warped by the receiver's cosine, unwarped, and with area
    /// sampling; on the ceiling solid-angle sampling beats area sampling, and the warp
    /// beats uniform solid angle where the cosine falls across the lamp.
    #[test]
    fn irradiance_matches_lamberts_formula() {
        let corners = [
            Vec3A::new(-0.23, 0.8, -0.18),
            Vec3A::new(-0.23, 0.8, 0.2),
            Vec3A::new(0.23, 0.8, 0.2),
            Vec3A::new(0.23, 0.8, -0.18),
        ];
        let radiance = 4.0f32;
        // Points whose tangent plane has the whole lamp in front of it.
        let receivers = [
            (Vec3A::new(0.0, 1.0, 0.0), -Vec3A::Y),
            (Vec3A::new(0.35, 1.0, 0.3), -Vec3A::Y),
            (Vec3A::new(0.6, 0.9, 0.0), Vec3A::new(-1.0, 0.0, 0.0)),
            (
                Vec3A::new(1.5, 4.0, 2.0),
                Vec3A::new(-1.5, -3.2, -2.0).normalize(),
            ),
        ];
        for (i, (p, n)) in receivers.into_iter().enumerate() {
            let exact = lambert(&corners, p, n, f64::from(radiance));
            let mut errors = [0.0; 3];
            for (k, (solid_angle, ns)) in [(true, n), (true, Vec3A::ZERO), (false, n)]
                .into_iter()
                .enumerate()
            {
                let (light, prims) = lamp(false, solid_angle);
                let mut rng = Rng::for_sample(4, i as u64, k as u64);
                let (mean, se) = estimate(200_000, || {
                    match light.sample(Vec3A::splat(radiance), p, ns, rng.next_2d(), &prims) {
                        Some(s) => f64::from(s.radiance.x * s.wi.dot(n).max(0.0) / s.pdf),
                        None => 0.0,
                    }
                });
                assert!(se < 0.01 * exact, "at {p}: {mean} ± {se}");
                assert!(
                    (mean - exact).abs() <= 5.0 * se,
                    "at {p} (solid angle {solid_angle}, n {ns}): {mean} ± {se}, exact {exact}"
                );
                errors[k] = se;
            }
            // Right above the lamp the cosine peaks inside it, which a bilinear warp of
            // the corners cannot follow (it is nearly uniform there); beyond its edge it
            // falls monotonically across it and the warp follows it.
            let [warped, uniform, area] = errors;
            match i {
                0 => assert!(
                    uniform < 0.5 * area,
                    "solid angle ± {uniform}, area ± {area}"
                ),
                1 => assert!(
                    warped < 0.5 * uniform,
                    "warped ± {warped}, unwarped ± {uniform}"
                ),
                _ => {}
            }
        }
    }
}
