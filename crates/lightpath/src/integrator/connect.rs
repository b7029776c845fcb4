//! Light-vertex connections: the bidirectional strategy of Veach and Guibas 1995,
//! "Optimally Combining Sampling Techniques for Monte Carlo Rendering" (Veach's thesis,
//! 1997, ch. 10), for light subpaths of one segment. Each camera sample also traces one
//! ray from an area light (the light chosen by power, a point uniform in its area, a
//! cosine-distributed direction); where it lands, y1, is a light vertex, and every
//! scattering vertex x of the camera path is joined to it by a shadow ray: the path
//! camera … x → y1 → y0 (the light). Path tracing finds the same paths two ways (a BSDF
//! ray from x lands on y1, then light sampling or a BSDF ray at y1 finds y0), and the
//! three are weighed by the power heuristic over their pdfs of the whole path.
//!
//! A room lit only by light off a ceiling or a baffle is where this pays: path tracing
//! must find the small bright patch of ceiling with a BSDF ray from every surface, while
//! the light subpath lands on it in proportion to how bright it is.
//!
//! **The weights.** The three pdfs share the camera subpath up to x. Divided by the pdf of
//! y1 in area measure from x, `A = pdf_x(x→y1) · |cos y1| / |x − y1|²` (the BSDF ray from
//! x), the path tracer's two are its usual solid-angle pdfs at y1 — BSDF sampling's
//! `p_y1(y1→y0)` and light sampling's `p_L` — and the connection's is
//! `pmf · (1/area) · |cos θ'| / (π · sides) / A`, with θ' at y1 between the geometric
//! normal and the light (`density` below holds the part without θ' and A). A path the
//! path tracer makes carries that third term only when its vertex before y1 could have
//! been joined (`PathState::conn_x`: connections on, a surface, a non-delta lobe) and
//! the light can emit a subpath (`density` > 0); a light sample whose shadow ray is
//! blocked, which no light subpath makes, keeps its two-way weight (the lights-only test
//! likewise).
//!
//! **Where it applies.** Scenes without media, cut-outs, holdouts, a guide, or objects
//! that indirect rays see but shadow rays do not (the light subpath's ray and the path
//! tracer's shadow ray must find the same surfaces): `Connect::new` returns `None`
//! otherwise and the render is path tracing's alone. Lights that emit subpaths: the
//! declared triangle lights (rect, quad, disk) that are not shadow-linked; the others
//! keep two-way weights, as no subpath starts on them.

use super::direct::power_heuristic3;
use super::path::{PathState, Vertex};
use super::routing::{Origin, Via};
use super::{Sink, Tracer};
use crate::geometry::{Hit, Prim, Ray, Visibility};
use crate::light::LightShape;
use crate::material::{Bsdf, Shading};
use crate::sampler::Sampler;
use crate::sampling::{cosine_hemisphere, uniform_triangle, Distribution1D, Frame};
use crate::scene::Scene;
use glam::{Vec2, Vec3A};
use lpe::ScatterClass;
use std::cell::{Cell, OnceCell};
use std::f32::consts::PI;

/// Whether renders trace light subpaths and join them to camera paths
/// (`[render] light_connections`, `--light-connections`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LightConnections {
    #[default]
    Off,
    On,
}

impl LightConnections {
    pub const NAMES: [&'static str; 2] = ["off", "on"];

    pub fn parse(s: &str) -> Option<LightConnections> {
        match s {
            "off" => Some(LightConnections::Off),
            "on" => Some(LightConnections::On),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            LightConnections::Off => "off",
            LightConnections::On => "on",
        }
    }
}

/// The lights that emit subpaths, chosen by power.
pub(super) struct Connect {
    /// Their indices in `Scene::lights`, and the choice among them.
    lights: Vec<u32>,
    choice: Distribution1D,
    /// Per light of the scene: its choice's probability over its area, π and its
    /// emitting sides (the connection's pdf, module doc); 0 where no subpath starts.
    pub density: Vec<f32>,
}

impl Connect {
    /// The connections of `scene`, if they are on and apply (module doc).
    pub(super) fn new(scene: &Scene, guided: bool) -> Option<Connect> {
        if scene.settings.light_connections != LightConnections::On
            || guided
            || scene.has_media
            || scene.has_presence
            || scene.objects.iter().any(|o| o.holdout)
            || !scene.accel.shadows_match_indirect()
        {
            return None;
        }
        // Each light's index, power, and area × π × emitting sides.
        let mut chosen = Vec::new();
        for (li, light) in scene.lights[..scene.first_glow_light as usize]
            .iter()
            .enumerate()
        {
            let LightShape::Triangles(t) = &light.shape else {
                continue;
            };
            let p = light.power(scene.scene_radius);
            let emits = t.area > 0.0 && p > 0.0;
            if light.shadow_linked || light.object.is_none() || !emits {
                continue;
            }
            let sides = if t.two_sided { 2.0 } else { 1.0 };
            chosen.push((li as u32, p, t.area * PI * sides));
        }
        if chosen.is_empty() {
            return None;
        }
        let power: Vec<f32> = chosen.iter().map(|c| c.1).collect();
        let choice = Distribution1D::new(&power);
        let mut density = vec![0.0; scene.lights.len()];
        for (k, &(li, _, spread)) in chosen.iter().enumerate() {
            density[li as usize] = choice.pmf(k) / spread;
        }
        let lights = chosen.iter().map(|c| c.0).collect();
        Some(Connect {
            lights,
            choice,
            density,
        })
    }

    /// The third term of the power heuristic's sum for a path the path tracer made (module
    /// doc): `a` is A, `cos_out` |cos θ'|; 0 when `a` is (no connection could make it).
    #[inline]
    pub(super) fn pdf_over(&self, li: u32, cos_out: f32, a: f32) -> f32 {
        if a > 0.0 {
            self.density[li as usize] * cos_out / a
        } else {
            0.0
        }
    }
}

/// Where a light subpath landed: y1, and what it brings there from y0.
pub(super) struct LightVertex {
    hit: Hit,
    li: u32,
    /// From y1 to the point y0 on the light: unit direction and distance, and the
    /// light's normal there.
    to_light: Vec3A,
    dist: f32,
    light_ng: Vec3A,
    /// The subpath's throughput at y1: Le · |cos θ0| / (pmf · pdf_area · pdf_dir).
    alpha: Vec3A,
    /// |cos θ'| at y1 between the geometric normal and `to_light`.
    cos_out: f32,
    /// Light sampling's pdf at y1 for y0, by shading normal (`light_pdf_at`).
    light_pdfs: [Cell<Option<(Vec3A, f32)>>; 2],
}

impl PathState {
    /// A at `hit`, reached along `dir` from the vertex the path scattered at last: the
    /// area pdf of `hit` from there, if that vertex could have been joined; else 0.
    #[inline]
    pub(super) fn conn_a_at(&self, hit: &Hit, dir: Vec3A) -> f32 {
        if self.conn_x {
            self.prev_pdf * hit.ng.dot(dir).abs() / self.prev_p.distance_squared(hit.p)
        } else {
            0.0
        }
    }
}

impl Tracer<'_> {
    /// Joins the path's vertex `v` to the sample's light vertex, tracing that at the
    /// first vertex that asks for it (`light_vertex` keeps it for the path's others).
    /// Connections apply only where `RICH` (path.rs) is off: `Connect::new`.
    #[inline(always)]
    pub(super) fn join<S: Sampler, const RICH: bool>(
        &self,
        out: &mut Sink,
        path: &PathState,
        v: &Vertex,
        sampler: &mut S,
        light_vertex: &mut Option<Option<LightVertex>>,
    ) {
        let Some(conn) = self.connect.as_ref().filter(|_| !RICH) else {
            return;
        };
        self.join_with(out, path, v, sampler, conn, light_vertex);
    }

    fn join_with<S: Sampler>(
        &self,
        out: &mut Sink,
        path: &PathState,
        v: &Vertex,
        sampler: &mut S,
        conn: &Connect,
        light_vertex: &mut Option<Option<LightVertex>>,
    ) {
        // The joined path scatters at v and at y1: both within the depth limit.
        if path.depth + 2 >= self.scene.settings.max_depth {
            return;
        }
        if let Some(lv) = light_vertex.get_or_insert_with(|| self.light_vertex(conn, sampler)) {
            self.connect(out, path, v, conn, lv);
        }
    }

    /// The connection's term of the power heuristic for a light sample at `v` towards
    /// `wi` (world) on light `li` (module doc); 0 where no connection makes that path.
    #[inline]
    pub(super) fn conn_pdf(&self, v: &Vertex, li: u32, wi: Vec3A) -> f32 {
        match &self.connect {
            Some(conn) if v.conn_a > 0.0 => conn.pdf_over(li, v.hit.ng.dot(wi).abs(), v.conn_a),
            _ => 0.0,
        }
    }

    /// Traces the sample's light subpath: `None` where it leaves the scene or lands on
    /// nothing that scatters.
    fn light_vertex<S: Sampler>(&self, conn: &Connect, sampler: &mut S) -> Option<LightVertex> {
        let scene = self.scene;
        let (u_choice, u_point, u_dir) = sampler.light_path();
        let (k, pmf, _) = conn.choice.sample(u_choice);
        let li = conn.lights[k];
        let light = &scene.lights[li as usize];
        let LightShape::Triangles(t) = &light.shape else {
            return None;
        };
        let (p0, n) = point_on(t, scene.accel.prims(), u_point)?;
        // The emitting side, then a cosine-distributed direction about it.
        let (side, u_dir) = if t.two_sided {
            if u_dir.x < 0.5 {
                (1.0, Vec2::new(u_dir.x * 2.0, u_dir.y))
            } else {
                (-1.0, Vec2::new(u_dir.x * 2.0 - 1.0, u_dir.y))
            }
        } else {
            (1.0, u_dir)
        };
        let local = cosine_hemisphere(u_dir);
        if local.z <= 0.0 {
            return None;
        }
        let ns = n * side;
        let dir = Frame::new(ns).to_world(local);
        let le = light.emitted_at(n, -dir);
        if le == Vec3A::ZERO {
            return None;
        }
        let ray = Ray {
            origin: p0 + ns * scene.epsilon,
            dir,
            tmax: f32::INFINITY,
        };
        let hit = scene.accel.intersect(&ray, 0.0, Visibility::INDIRECT)?;
        let obj = &scene.objects[hit.object as usize];
        obj.material?;
        let back = p0 - hit.p;
        let dist = back.length();
        if !(dist > 0.0 && dist.is_finite()) {
            return None;
        }
        let to_light = back / dist;
        let cos_out = hit.ng.dot(to_light).abs();
        if cos_out == 0.0 {
            return None;
        }
        // pdf_area = 1 / area, pdf_dir = cos θ0 / (π · sides): the cosines cancel.
        let sides = if t.two_sided { 2.0 } else { 1.0 };
        let alpha = le * (t.area * PI * sides / pmf);
        Some(LightVertex {
            hit,
            li,
            to_light,
            dist,
            light_ng: n,
            alpha,
            cos_out,
            light_pdfs: Default::default(),
        })
    }

    /// Joins the camera path's vertex `v` (x) to the light vertex `lv`: every pair of a
    /// non-delta lobe at x and one at y1 through their events, then `L`, with the
    /// connection's MIS weight. One shadow ray, traced once some pair's contribution
    /// counts.
    fn connect(
        &self,
        out: &mut Sink,
        path: &PathState,
        v: &Vertex,
        conn: &Connect,
        lv: &LightVertex,
    ) {
        let scene = self.scene;
        let a = &scene.automaton;
        let settings = &scene.settings;
        let light = &scene.lights[lv.li as usize];
        let y = &lv.hit;
        let obj = &scene.objects[y.object as usize];
        let Some(material) = obj.material.map(|m| &scene.materials[m as usize]) else {
            return;
        };
        if !self.lit(y.object, lv.li) {
            return;
        }
        let d = y.p - v.hit.p;
        let dist2 = d.length_squared();
        if !(dist2 > 0.0 && dist2.is_finite()) {
            return;
        }
        let dist = dist2.sqrt();
        let w = d / dist;
        let cos_in = y.ng.dot(w).abs();
        if cos_in == 0.0 {
            return;
        }
        let wi_x = v.sh.frame.to_local(w);
        let q_conn = conn.density[lv.li as usize] * lv.cos_out;
        // y1's Bsdf as the path tracer would shade it after a diffuse bounce or not
        // (path.rs): the regularised one only after one.
        let textured = OnceCell::new();
        let mut shaded: [Option<Option<YShading>>; 2] = [None, None];
        let mut visible: Option<bool> = None;
        let lobes = v.bsdf.lobes();
        for (i, tag) in lobes.iter().enumerate() {
            if tag.delta || v.bsdf.subsurface(i).is_some() {
                continue;
            }
            let diffuse = tag.scatter.class == ScatterClass::Diffuse;
            let over = if diffuse {
                settings
                    .max_diffuse_depth
                    .is_some_and(|max| path.diffuse + 1 > max)
            } else {
                settings
                    .max_specular_depth
                    .is_some_and(|max| path.specular + 1 > max)
            };
            if over {
                continue;
            }
            let s_i = a.step(path.state, v.obj.lobe_classes[i]);
            if a.is_dead(s_i) {
                continue;
            }
            let (f_i, pdf_i) = v.bsdf.eval_lobe_at(i, &v.sh, v.at_wo.as_ref(), wi_x);
            if f_i == Vec3A::ZERO {
                continue;
            }
            let after_diffuse = path.diffuse > 0 || diffuse;
            let ys = shaded[after_diffuse as usize].get_or_insert_with(|| {
                self.shade_light_vertex(path, lv, material, (w, dist), after_diffuse, &textured)
            });
            let Some(ys) = ys.as_ref() else {
                continue;
            };
            let area_pdf = pdf_i * cos_in / dist2;
            for (j, tag_y) in ys.bsdf.lobes().iter().enumerate() {
                if tag_y.delta || ys.bsdf.subsurface(j).is_some() {
                    continue;
                }
                let s_j = a.step(s_i, obj.lobe_classes[j]);
                if a.is_dead(s_j) {
                    continue;
                }
                let s_l = a.step(s_j, light.classes.light);
                if a.accepting(s_l).is_empty() {
                    continue;
                }
                let (f_j, pdf_j) = ys
                    .bsdf
                    .eval_lobe_at(j, &ys.sh, ys.at_wo.as_ref(), ys.wi_light);
                if f_j == Vec3A::ZERO {
                    continue;
                }
                let vis = *visible.get_or_insert_with(|| {
                    out.rays += 1;
                    // Between points moved off both surfaces (each to the other's side):
                    // a segment ending short of y1 by a fixed length would cross y1's
                    // own plane when it arrives at a grazing angle.
                    let from = self.spawn(v.hit, w, 0.0).origin;
                    let to = self.spawn(y, -w, 0.0).origin;
                    let span = to - from;
                    let len = span.length();
                    let ray = Ray {
                        origin: from,
                        dir: span / len,
                        tmax: len * (1.0 - 1e-4),
                    };
                    len.is_nan() || len <= 0.0 || !scene.accel.occluded(&ray, 0.0, u32::MAX)
                });
                if !vis {
                    return;
                }
                let weight = power_heuristic3(q_conn, area_pdf * pdf_j, area_pdf * ys.light_pdf);
                let value = f_i * f_j * lv.alpha * (cos_in / (dist2 * lv.cos_out));
                let origin = Origin {
                    via: Via::LightSample { visible: true },
                    scatters: path.depth + 2,
                    part: light.part,
                };
                self.contribute(out, s_l, path.throughput, value, weight, origin);
            }
        }
    }

    /// y1 shaded as the path tracer shades a vertex reached from `v` along `w`:
    /// textured (with the ray cone the path would have there; kept in `textured`, the
    /// same for both `after_diffuse`), regularised after a diffuse bounce, or plain (the
    /// choice trace_path makes, path.rs); `None` where the path tracer would stop there.
    #[allow(clippy::too_many_arguments)]
    fn shade_light_vertex<'m>(
        &self,
        path: &PathState,
        lv: &LightVertex,
        material: &'m crate::scene::Material,
        (w, dist): (Vec3A, f32),
        after_diffuse: bool,
        textured: &'m OnceCell<(Bsdf, Vec3A)>,
    ) -> Option<YShading<'m>> {
        let y = &lv.hit;
        let (bsdf, ns) = match (&material.textured, &material.regularized) {
            (Some(t), _) => {
                let (bsdf, ns) = textured.get_or_init(|| {
                    let spread = path.cone_spread.max(super::shading::SCATTERED_SPREAD);
                    self.textured(t, y, w, path.cone_width + spread * dist)
                });
                (bsdf, *ns)
            }
            (None, Some(rough)) if after_diffuse => (rough, y.ns),
            (None, _) => (&material.bsdf, y.ns),
        };
        let sh = self.oriented(Shading::new(bsdf, ns, y.ng, -w), material, y);
        if sh.wo.z == 0.0 {
            return None;
        }
        Some(YShading {
            wi_light: sh.frame.to_local(lv.to_light),
            bsdf,
            at_wo: bsdf.at_wo(sh.wo),
            light_pdf: self.light_pdf_at(lv, sh.frame.n),
            sh,
        })
    }

    /// Light sampling's pdf at y1 with shading normal `n` for y0 (selection included):
    /// the same for every vertex joined to `lv` from the same side, so kept for two
    /// normals (the spherical rectangle's solid angle was ~15 % of a connected render).
    fn light_pdf_at(&self, lv: &LightVertex, n: Vec3A) -> f32 {
        let mut known = lv.light_pdfs.iter().filter_map(Cell::get);
        if let Some((_, pdf)) = known.find(|&(m, _)| m == n) {
            return pdf;
        }
        let scene = self.scene;
        let y = &lv.hit;
        let light = &scene.lights[lv.li as usize];
        let pdf = scene.light_select.pmf(lv.li as usize, y.p, n)
            * light.pdf_hit(y.p, n, lv.to_light, lv.dist, lv.light_ng);
        if let Some(free) = lv.light_pdfs.iter().find(|slot| slot.get().is_none()) {
            free.set(Some((n, pdf)));
        }
        pdf
    }
}

/// A light vertex shaded for one connection.
struct YShading<'m> {
    bsdf: &'m Bsdf,
    sh: Shading,
    at_wo: Option<crate::material::AtWo>,
    wi_light: Vec3A,
    /// Light sampling's solid-angle pdf at y1 for y0 (selection included).
    light_pdf: f32,
}

/// A point uniform in the area of triangle light `t`, and its unit normal.
fn point_on(t: &crate::light::Triangles, prims: &[Prim], u: Vec2) -> Option<(Vec3A, Vec3A)> {
    if let Some([p0, e1, e2]) = t.parallelogram {
        return Some((p0 + e1 * u.x + e2 * u.y, *t.normals.first()?));
    }
    let (k, _, ux) = t.by_area.sample(u.x);
    let Prim::Triangle { p0, e1, e2, .. } = prims.get(*t.prims.get(k)? as usize)? else {
        return None;
    };
    let (b1, b2) = uniform_triangle(Vec2::new(ux, u.y));
    Some((*p0 + *e1 * b1 + *e2 * b2, *t.normals.get(k)?))
}
