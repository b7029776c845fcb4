//! Light tracing: every vertex of a sample's light subpath joined to the camera, the
//! bidirectional strategy with one camera vertex (Veach's t = 1; the weights are
//! Georgiev et al.'s, as in the parent module, with the camera's "light subpath count"
//! the frame's pixels: each camera sample traces one subpath, so a frame of `spp`
//! samples a pixel traces `width × height × spp`). What a join adds lands in the pixels
//! whose filter reaches the light vertex's film position, not in the sample's own; it
//! goes to the window's splat film (film/splats.rs), which the render adds to its film
//! at the end.
//!
//! This is the strategy that finds small bright patches lit indirectly: a patch of
//! ceiling over a lamp that camera rays reach through a few bounces, but onto which
//! many light subpaths land.
//!
//! **Not y1.** Joined to the camera, y1 would be direct light, and there the power
//! heuristic's pdfs mislead: many subpaths land on a ceiling right above a lamp, so
//! their density beats a light sample's, but where each lands is random while a
//! solid-angle light sample of a diffuse ceiling is nearly exact. With y1 joined the
//! test room's error doubled (`benches/guiding/connections.py`); so light tracing starts
//! at y2, and the camera side leaves the strategy out of direct light's weights (light
//! sampling at the camera's first vertex, and a BSDF ray from it that finds a light).
//!
//! **Where it applies.** Where light subpaths are traced (the parent module), from a
//! pinhole camera (a thin lens would need its lens sampled from each vertex), where
//! every surface that camera rays see casts shadows and none else (the join's shadow ray
//! must find what a camera ray would), and without adaptive sampling: a camera sample's
//! weight holds its pixel's count of camera samples, which adaptive sampling knows only
//! after the sample is taken. A window (`--crop`) keeps the splats that land in it, and
//! traces the subpaths of the frame's other pixels too (`Tracer::splat_outside`), so its
//! pixels are the whole frame's.
//!
//! **Pixel filters.** A camera sample places its ray at an offset from its pixel centre
//! with the filter as its density (filter importance sampling), so the camera's density
//! of a film position, for pixel q, is the filter's density at the position's offset
//! from q's centre; a join adds to every pixel q whose filter reaches it, each with its
//! own weight. A Gaussian's offsets truncated onto its 3σ ring have no density there:
//! light tracing leaves them to the camera (`PixelFilter::pdf`).

use super::super::routing::{Origin, Via};
use super::super::{Sink, Tracer};
use super::{sq, LightPath};
use crate::film::splats::Splats;
use crate::film::PixelWindow;
use crate::sampler::Sampler;
use glam::Vec3A;
use lpe::ScatterClass;

/// Whether a render that traces light subpaths also joins them to the camera (module
/// doc): a pinhole, shadows that match camera rays, no adaptive sampling.
pub fn traces_to_camera(scene: &crate::scene::Scene) -> bool {
    scene.camera.aperture_radius <= 0.0
        && scene.settings.noise_threshold <= 0.0
        && scene.accel.shadows_match_camera()
}

/// The frame pixels outside `window` whose light subpaths row `row` of the window
/// traces (module doc): the outside pixels, numbered row by row through the frame,
/// shared out evenly over the window's rows.
pub(in crate::integrator) fn outside_pixels(
    frame: [u32; 2],
    window: PixelWindow,
    row: usize,
) -> impl Iterator<Item = (u32, u32)> {
    let [fw, fh] = frame.map(u64::from);
    let (w, h) = (u64::from(window.width()), u64::from(window.height()));
    let outside = fw * fh - w * h;
    let row = row as u64;
    let share = match (
        (outside * row).checked_div(h),
        (outside * (row + 1)).checked_div(h),
    ) {
        (Some(a), Some(b)) => a..b,
        _ => 0..0,
    };
    let above = u64::from(window.y0) * fw;
    let beside = fw - w;
    share.map(move |k| {
        let (x, y) = if k < above {
            (k % fw, k / fw)
        } else if k < above + h * beside {
            let k = k - above;
            let (x, y) = (k % beside, u64::from(window.y0) + k / beside);
            (if x < u64::from(window.x0) { x } else { x + w }, y)
        } else {
            let k = k - above - h * beside;
            (k % fw, u64::from(window.y1) + k / fw)
        };
        (x as u32, y as u32)
    })
}

impl Tracer<'_> {
    /// The camera subpath's `dvcm` at the camera for a ray along `dir` whose offset in
    /// its pixel had filter density `film_pdf`: the light subpaths' count per camera
    /// sample over the camera's solid-angle pdf of the ray (0 without light tracing, or
    /// where no light subpath can make the ray's film position).
    #[inline]
    pub(in crate::integrator) fn camera_dvcm(&self, film_pdf: f32, dir: Vec3A) -> f32 {
        if self.splats.is_none() || film_pdf <= 0.0 {
            return 0.0;
        }
        let cam = &self.scene.camera;
        let pdf_w = film_pdf * cam.to_solid_angle(cam.cos_off_axis(dir));
        let ratio = self.light_subpaths_per_sample() / pdf_w;
        if ratio.is_finite() {
            sq(ratio)
        } else {
            0.0
        }
    }

    /// Light subpaths per camera sample of a pixel: the frame's pixel count.
    fn light_subpaths_per_sample(&self) -> f32 {
        let cam = &self.scene.camera;
        cam.width as f32 * cam.height as f32
    }

    /// Joins every vertex of the sample's light subpath to the camera, tracing the
    /// subpath first if no camera vertex did.
    pub(in crate::integrator) fn splat<S: Sampler>(&self, out: &mut Sink, sampler: &mut S) {
        let (Some(conn), Some(splats)) = (self.connect.as_ref(), self.splats) else {
            return;
        };
        let aovs = self.scene.aovs.len();
        if out.splat_acc.aovs() != aovs {
            out.splat_acc = crate::film::SampleAccumulator::new(aovs);
        }
        let mut lp = std::mem::take(&mut out.light_path);
        if !lp.traced {
            lp.traced = true;
            self.trace_light_path(out, conn, sampler, &mut lp);
        }
        // From y2 on: y1 joined to the camera is direct light, which light sampling
        // estimates far better than the heuristic's pdfs say (module doc).
        for s in 1..lp.vertices.len() {
            self.to_camera(out, &lp, s, splats);
        }
        out.light_path = lp;
    }

    /// Joins light vertex `s` of `lp` to the camera: each non-delta lobe there through
    /// its event, the subpath's events back to the light and `L`, into every pixel whose
    /// filter reaches where the camera sees the vertex.
    fn to_camera(&self, out: &mut Sink, lp: &LightPath, s: usize, splats: &Splats) {
        let scene = self.scene;
        // s + 1 scattering vertices, s + 2 segments (`max_depth` counts segments).
        if s as u32 + 2 > scene.settings.max_depth {
            return;
        }
        let a = &scene.automaton;
        let cam = &scene.camera;
        let lv = &lp.vertices[s];
        let y = &lv.hit;
        if !lv.joinable {
            return;
        }
        let Some(proj) = cam.project(y.p) else {
            return;
        };
        let r = scene.filter.radius();
        let (w, h) = (cam.width as f32, cam.height as f32);
        let f = proj.film;
        if f.x + r <= 0.0 || f.y + r <= 0.0 || f.x - r >= w || f.y - r >= h {
            return;
        }
        let obj = &scene.objects[y.object as usize];
        let Some(material) = obj.material.map(|m| &scene.materials[m as usize]) else {
            return;
        };
        // `dir` runs from the camera to y, as a join's `w` from x to y.
        let dir = proj.dir;
        let cos_in = y.ng.dot(dir).abs();
        if cos_in == 0.0 {
            return;
        }
        if lv.reflects && lv.ns.dot(dir) * lv.ns.dot(lv.to_prev) >= 0.0 {
            return;
        }
        let mut visible: Option<bool> = None;
        // Seen straight from the camera: no diffuse bounce before it, so not regularised.
        let Some(ys) = self.shade_light_vertex(lp, s, material, dir, false) else {
            return;
        };
        let light = &scene.lights[lp.li as usize];
        let camera_state = a.step(a.start(), scene.camera_class);
        let geometry = proj.to_solid_angle * cos_in / sq(proj.dist);
        let n_light = self.light_subpaths_per_sample();
        for (j, tag) in ys.bsdf.lobes().iter().enumerate() {
            if tag.delta || ys.bsdf.subsurface(j).is_some() {
                continue;
            }
            let diffuse_j = tag.scatter.class == ScatterClass::Diffuse;
            // The path tracer counts every lobe but y1's (the last before the light).
            let at_y = (s > 0) as u32;
            let diffuse = lv.diffuse + at_y * diffuse_j as u32;
            let specular = lv.specular + at_y * (!diffuse_j) as u32;
            let settings = &scene.settings;
            if settings.max_diffuse_depth.is_some_and(|m| diffuse > m)
                || settings.max_specular_depth.is_some_and(|m| specular > m)
            {
                continue;
            }
            let s_l =
                lp.state_to_light(a, camera_state, obj.lobe_classes[j], s, light.classes.light);
            if a.accepting(s_l).is_empty() {
                continue;
            }
            let (f_j, pdf_j) = ys.turned.eval(ys.bsdf, j, lv.to_prev);
            if f_j == Vec3A::ZERO {
                continue;
            }
            if !*visible.get_or_insert_with(|| self.sees_camera(out, y, dir)) {
                return;
            }
            let light_sum = ys.dvcm + lv.dvc * sq(pdf_j);
            let value = f_j * lv.beta * (geometry / (lv.cos_prev * n_light));
            let origin = Origin {
                via: Via::LightSample { visible: true },
                scatters: s as u32 + 1,
                part: light.part,
            };
            self.splat_into_pixels(
                out,
                splats,
                f,
                s_l,
                value,
                light_sum * sq(geometry / n_light),
                origin,
            );
        }
    }

    /// Adds `value` (per unit film density) to every pixel whose filter reaches film
    /// position `f`, times the filter's density there, weighted against the camera's
    /// strategies (`w_per_density` × density² is the light tracer's weight term).
    #[allow(clippy::too_many_arguments)]
    fn splat_into_pixels(
        &self,
        out: &mut Sink,
        splats: &Splats,
        f: glam::Vec2,
        state: lpe::StateId,
        value: Vec3A,
        w_per_density: f32,
        origin: Origin,
    ) {
        let scene = self.scene;
        let cam = &scene.camera;
        let r = scene.filter.radius();
        let first = |c: f32| (c - 0.5 - r).ceil().max(0.0) as u32;
        let last = |c: f32, n: u32| ((c - 0.5 + r).floor().max(-1.0) as i64).min(n as i64 - 1);
        let (x0, x1) = (first(f.x), last(f.x, cam.width));
        let (y0, y1) = (first(f.y), last(f.y, cam.height));
        // The routing adds to `out.acc`: for the splats it holds the splat accumulator's
        // buffers, drained into the splat film after each pixel.
        std::mem::swap(out.acc, &mut out.splat_acc);
        for qy in y0 as i64..=y1 {
            for qx in x0 as i64..=x1 {
                let centre = glam::Vec2::new(qx as f32 + 0.5, qy as f32 + 0.5);
                let density = scene.filter.pdf(f - centre);
                if density <= 0.0 {
                    continue;
                }
                let weight = 1.0 / (1.0 + w_per_density * sq(density));
                self.contribute(out, state, Vec3A::ONE, value * density, weight, origin);
                out.acc.drain(|k, v| splats.add(qx as u32, qy as u32, k, v));
            }
        }
        std::mem::swap(out.acc, &mut out.splat_acc);
    }

    /// Whether the camera sees `y` along `dir` (from the camera) at `dist`: one shadow
    /// ray from y, moved off its surface, to the camera.
    fn sees_camera(&self, out: &mut Sink, y: &crate::geometry::Hit, dir: Vec3A) -> bool {
        out.rays += 1;
        let from = self.spawn(y, -dir, 0.0).origin;
        let span = self.scene.camera.position - from;
        let len = span.length();
        if !(len > 0.0 && len.is_finite()) {
            return false;
        }
        let ray = crate::geometry::Ray {
            origin: from,
            dir: span / len,
            tmax: len * (1.0 - 1e-4),
        };
        !self.scene.accel.occluded(&ray, 0.0, u32::MAX)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rows of a window share out every pixel outside it once, and none inside.
    #[test]
    fn a_windows_rows_share_the_outside_pixels_once() {
        let frame = [7, 5];
        for window in [
            PixelWindow {
                x0: 2,
                y0: 1,
                x1: 5,
                y1: 3,
            },
            PixelWindow {
                x0: 0,
                y0: 0,
                x1: 7,
                y1: 2,
            },
            PixelWindow {
                x0: 0,
                y0: 4,
                x1: 3,
                y1: 5,
            },
            PixelWindow::full(7, 5),
        ] {
            let mut seen = [0; 35];
            for row in 0..window.height() as usize {
                for (x, y) in outside_pixels(frame, window, row) {
                    seen[(y * 7 + x) as usize] += 1;
                }
            }
            for y in 0..5 {
                for x in 0..7 {
                    let inside =
                        (window.x0..window.x1).contains(&x) && (window.y0..window.y1).contains(&y);
                    assert_eq!(
                        seen[(y * 7 + x) as usize],
                        !inside as u32,
                        "{window:?} ({x}, {y})"
                    );
                }
            }
        }
    }
}
