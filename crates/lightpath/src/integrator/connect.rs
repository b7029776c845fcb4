//! Bidirectional path tracing: Veach and Guibas 1995, "Optimally Combining Sampling
//! Techniques for Monte Carlo Rendering" (Veach's thesis, 1997, ch. 10), with the
//! recursive form of its MIS weights of Georgiev et al. 2012, "Light Transport
//! Simulation with Vertex Connection and Merging" (tech. report, §4–5). Each camera
//! sample also traces a light subpath from an area, point or spot light (the light
//! chosen by power; a point uniform in its area and a cosine-distributed direction, or a
//! direction uniform over the sphere or the spot's outer cone; then BSDF sampling at each
//! surface it lands on: y1, y2, …), and every scattering vertex x of the camera path is
//! joined to every light vertex by a shadow ray, and every light vertex from y2 on to the
//! camera (light tracing: light_tracing.rs). A path of n ≥ 2 scattering vertices is then
//! made n + 2 ways: a BSDF ray that finds the light, light sampling, a join of a camera
//! subpath of k ≥ 1 vertices to a light subpath of n − k, and the light subpath of n
//! vertices joined to the camera; the power heuristic weighs them by their pdfs of the
//! whole path. Direct light (n = 1) is made by the first two alone.
//!
//! A room lit only by light off a ceiling or a baffle is where this pays: path tracing
//! must find the small bright patch of ceiling, and the light trapped above the baffle,
//! with BSDF rays from every surface, while light subpaths carry that light out to
//! where the camera's vertices are, and light tracing lands it on the patch itself.
//!
//! **The weights.** Each subpath carries two sums of pdf ratios (squared: the power
//! heuristic), `dvcm` and `dvc` in the report's notation, updated at each vertex from
//! local quantities alone: the area pdf of the vertex from the one before (forward), and
//! the pdf of the reverse direction as the other subpath would sample it. A join of x to
//! y weighs `1 / (1 + wLight + wCamera)`, each term one subpath's sum times the other's
//! pdf of reaching across. The camera path's sums live in `PathState::dvc`/`dvcm` (before
//! the vertex the ray finds) and `Vertex::dvc`/`dvcm` (at it); light sampling and BSDF
//! rays that find a light add the camera's term to their two-way weights. Light
//! sampling's pdf at y1 depends on the shading normal there (the light tree's
//! probabilities), so y1's `dvcm` is worked out where it is used.
//!
//! **Where a subpath may go.** Light subpaths pass through a lone delta lobe (smooth
//! glass, a mirror: `delta_step`), where nothing is joined, so light tracing
//! makes caustics through them, even of point and spot lights, which no BSDF ray finds.
//! They stop at the delta lobes of several-lobed materials, subsurface walks and
//! materials regularised after a diffuse bounce (`[render] regularize`: which Bsdf the
//! path tracer uses there depends on the camera's side of the path); such a vertex is
//! still joined to. Camera vertices there carry no `dvc` (no strategy scatters a light
//! subpath through them), and such a delta lobe or a walk clears both sums; a lone
//! delta lobe clears `dvcm` and keeps `dvc` (the pdfs both ways cancel). A BSDF ray
//! that finds a light through a delta lobe is then weighted against light tracing
//! (`Via::Hit` with `light_sampled`, routing.rs). Textures at light vertices are
//! filtered with the light subpath's own ray cone.
//!
//! **Where it applies.** Scenes without media, cut-outs, holdouts, a guide, or objects
//! that indirect rays see but shadow rays do not (the light subpath's rays and the path
//! tracer's shadow rays must find the same surfaces): `Connect::new` returns `None`
//! otherwise and the render is path tracing's alone. Lights that emit subpaths: the
//! declared triangle lights (rect, quad, disk), sphere, point, spot and distant lights
//! and domes without portals, that are not shadow-linked; the others (cylinders, domes
//! sampled through portals, whose pdfs depend on the shading point, glowing objects) keep
//! two-way weights, as no subpath starts on them (their `density` is 0). Point and spot lights are Georgiev et
//! al.'s delta lights: no ray finds them, so y1 carries no `dvc`, light sampling's
//! density of such a light is 1 in its own measure (over a subpath's area density at y1
//! the squared distance stays: `light_pdf_at`, and `light_sample_weight`'s `dist`), and
//! a light sample's weight has no BSDF term. A distant light's or a dome's subpath
//! starts as the report's companion code (SmallVCM) starts a background light's: a
//! direction as its light sample picks one, and a point uniform on a disc round the scene
//! (`Connect::disc`) facing it, so its density is over the disc's area times the
//! direction's pdf (`direction_pdf`: a dome's map varies it), and no distance converts
//! either pdf at y1 (`LightPath::at_infinity`); a distant light without a disc (one
//! direction) is delta as a point is, and BSDF rays that leave the scene find the others.

mod light_tracing;

pub(super) use light_tracing::outside_pixels;
pub use light_tracing::traces_to_camera;

use super::direct::weight_over;
use super::path::{PathState, Vertex};
use super::routing::{Origin, Via};
use super::{Sink, Tracer};
use crate::geometry::{Hit, Prim, Ray, Visibility};
use crate::light::LightShape;
use crate::material::{AtWo, Bsdf, Shading};
use crate::sampler::Sampler;
use crate::sampling::{
    cosine_hemisphere, square_to_disk, uniform_cone, uniform_cone_pdf, uniform_sphere,
    uniform_triangle, Distribution1D, Frame,
};
use crate::scene::{Material, Scene};
use glam::{Vec2, Vec3A};
use lpe::{ClassId, ScatterClass};
use std::cell::Cell;
use std::f32::consts::{FRAC_1_PI, PI};

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
    /// emitting sides, or over the solid angle a point or spot light emits into (the
    /// connection's pdf, module doc); 0 where no subpath starts. For a light at infinity
    /// (`at_infinity`), over the disc's area alone: a start's density is that times the
    /// light's pdf of its direction (`direction_pdf`), which a dome's map varies.
    pub density: Vec<f32>,
    /// Per light of the scene: whether it is at infinity (a distant light or a dome).
    at_infinity: Vec<bool>,
    /// The disc distant lights' subpaths start on: the centre and radius of a sphere
    /// round the scene, the disc facing the light through its centre.
    disc: (Vec3A, f32),
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
        // Each light's index, power, and the measure its start is uniform in (module
        // doc): area × π × emitting sides, or the solid angle a point or spot emits into.
        let disc = (scene.scene_center, scene.scene_radius);
        let mut chosen = Vec::new();
        for (li, light) in scene.lights[..scene.first_glow_light as usize]
            .iter()
            .enumerate()
        {
            let spread = match &light.shape {
                LightShape::Triangles(t) if light.object.is_some() => {
                    t.area * PI * if t.two_sided { 2.0 } else { 1.0 }
                }
                LightShape::Sphere(s) if light.object.is_some() => 4.0 * PI * sq(s.radius) * PI,
                LightShape::Point(_) => 4.0 * PI,
                LightShape::Spot(s) => 1.0 / uniform_cone_pdf(s.cos_outer),
                // The disc's area; the direction's pdf is the light's (`direction_pdf`).
                // A dome with portals samples directions by the shading point: it starts
                // no subpaths.
                LightShape::Distant(_) => PI * sq(disc.1),
                LightShape::Dome(d) if d.portals.is_empty() => PI * sq(disc.1),
                _ => continue,
            };
            let p = light.power(scene.scene_radius);
            if light.shadow_linked || !(spread > 0.0 && spread.is_finite() && p > 0.0) {
                continue;
            }
            chosen.push((li as u32, p, spread));
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
        let at_infinity = scene
            .lights
            .iter()
            .map(|l| matches!(l.shape, LightShape::Distant(_) | LightShape::Dome(_)))
            .collect();
        let lights = chosen.iter().map(|c| c.0).collect();
        Some(Connect {
            lights,
            choice,
            density,
            at_infinity,
            disc,
        })
    }
}

/// x².
#[inline(always)]
fn sq(x: f32) -> f32 {
    x * x
}

/// A light at infinity's pdf of direction `wi` (towards it) as its light sample picks
/// directions: 1 for one direction (delta).
#[inline]
fn direction_pdf(light: &crate::light::Light, wi: Vec3A) -> f32 {
    if light.is_delta() {
        1.0
    } else {
        light.pdf_hit(Vec3A::ZERO, Vec3A::ZERO, wi, f32::INFINITY, Vec3A::ZERO)
    }
}

/// The throughput's step through a lone delta lobe `bs` sampled from the light's side
/// (`sh` shaded with `wo` towards the light; `Bsdf::lone_lobe`): what the camera's sample
/// of the reverse direction weighs, the tint, without the 1/η² radiance compression the
/// light's side sample carries (flux is not compressed: the compression cancels the
/// étendue's η² between the two directions' deltas), and the shading normal's cosines as
/// a non-delta lobe's adjoint takes them; `None` where the outgoing direction grazes.
fn delta_step(
    sh: &Shading,
    bs: &crate::material::BsdfSample,
    cos_next: f32,
    cos_prev: f32,
) -> Option<Vec3A> {
    let cos_s_out = sh.frame.n.dot(bs.wi).abs();
    (cos_s_out > 0.0)
        .then(|| bs.weight * (bs.eta * bs.eta * sh.wo.z.abs() / cos_s_out) * (cos_next / cos_prev))
}

/// One vertex of the sample's light subpath, y_j.
pub(super) struct LightVertex {
    hit: Hit,
    /// Towards the vertex before (y_{j−1}; for y1 the point on the light), its distance,
    /// and |cos| between the geometric normal and it.
    to_prev: Vec3A,
    dist_prev: f32,
    cos_prev: f32,
    /// The subpath's throughput here: Le and every BSDF, G and pdf from the light.
    beta: Vec3A,
    /// The shading normal, and whether the Bsdf only reflects (`Bsdf::reflects_only`).
    ns: Vec3A,
    reflects: bool,
    /// Whether anything joins here: a lobe that is not delta (or a regularised material,
    /// rough after a diffuse bounce). Smooth glass and mirrors are passed through only.
    joinable: bool,
    /// The sums of the weights here (module doc); y1's `dvcm` depends on the normal it
    /// is shaded with and is worked out where used (`Tracer::first_dvcm`).
    dvcm: f32,
    dvc: f32,
    /// The Bsdf seen from the light's side (`wo` towards the vertex before), if the
    /// subpath may scatter here (module doc).
    light_side: Option<Turned>,
    /// This vertex's textured Bsdf, by index into `LightPath::textured`.
    textured: Option<u32>,
    /// The event of the lobe the subpath scattered through here, once it goes on.
    class_out: Option<ClassId>,
    /// Diffuse and specular lobes the subpath scattered through at y2 … y_{j−1} (the
    /// path tracer counts every lobe but the last one before the light).
    diffuse: u32,
    specular: u32,
}

/// A light subpath between two vertices: its ray, where it left, its throughput, and
/// the sums before the distance and cosine where it lands count (y2 on).
struct Walk {
    ray: Ray,
    prev_p: Vec3A,
    beta: Vec3A,
    dvcm_pre: f32,
    dvc_pre: f32,
    /// Length so far (the ray cone that filters textures), and the diffuse and specular
    /// lobes scattered through at y2 on.
    travelled: f32,
    diffuse: u32,
    specular: u32,
}

impl Walk {
    /// A subpath's first ray, from `origin` (the light's point `p0`, or a hair off it)
    /// along `dir`, carrying `beta`.
    fn start(origin: Vec3A, p0: Vec3A, dir: Vec3A, beta: Vec3A) -> Walk {
        Walk {
            ray: Ray {
                origin,
                dir,
                tmax: f32::INFINITY,
            },
            prev_p: p0,
            beta,
            dvcm_pre: 0.0,
            dvc_pre: 0.0,
            travelled: 0.0,
            diffuse: 0,
            specular: 0,
        }
    }
}

/// The sample's light subpath: traced at the first camera vertex that joins; kept by the
/// worker between samples (`Sink::light_path`) so that its buffers are reused.
#[derive(Default)]
pub(super) struct LightPath {
    traced: bool,
    li: u32,
    /// The light's normal at the subpath's start (zero for a point or spot light), and
    /// `Connect::density` of the light.
    light_ng: Vec3A,
    density: f32,
    /// Whether the light is a point or one direction (a point, spot or distant light
    /// without a disc: no ray finds it).
    delta: bool,
    /// Whether the light is at infinity (a distant light): its light samples' pdfs are
    /// of directions alone, with no distance to convert them by.
    at_infinity: bool,
    vertices: Vec<LightVertex>,
    textured: Vec<(Bsdf, Vec3A)>,
    /// Light sampling's pdf at y1 for the start (selection included), by shading normal:
    /// the same for every vertex joined to y1 from one side (the spherical rectangle's
    /// solid angle was ~15 % of a connected render).
    light_pdfs: [Cell<Option<(Vec3A, f32)>>; 2],
}

impl LightPath {
    /// The automaton's state from `from` (the camera's side) through `class` (the event
    /// of a lobe at vertex `s`), the events the subpath scattered through before `s`
    /// back to the light, and the light's `light` event.
    pub(super) fn state_to_light(
        &self,
        a: &lpe::Automaton,
        from: lpe::StateId,
        class: ClassId,
        s: usize,
        light: ClassId,
    ) -> lpe::StateId {
        let mut state = a.step(from, class);
        for before in self.vertices[..s].iter().rev() {
            if a.is_dead(state) {
                break;
            }
            state = before.class_out.map_or(state, |c| a.step(state, c));
        }
        a.step(state, light)
    }

    /// The subpath starts at light `li` (its normal there, zero for a point, a spot or a
    /// light at infinity; its start's density; whether it is delta; whether at infinity).
    fn begin(&mut self, li: u32, light_ng: Vec3A, density: f32, delta: bool, at_infinity: bool) {
        self.li = li;
        self.light_ng = light_ng;
        self.density = density;
        self.delta = delta;
        self.at_infinity = at_infinity;
    }

    /// A new camera path: the subpath is traced again when first joined.
    #[inline(always)]
    pub(super) fn reset(&mut self) {
        self.traced = false;
    }
}

/// A Bsdf shaded with `wo` along some direction: what it does for other directions (a
/// subpath's pdf of a vertex as the other subpath would sample it).
#[derive(Clone, Copy)]
pub(super) enum Turned {
    /// A lone Lambert lobe (`Bsdf::lone_lambert`): its albedo and the normal turned as
    /// `Shading::new` turns it, without the frame (~80 instructions a use on the
    /// indirect box).
    Lambert {
        albedo: Vec3A,
        n: Vec3A,
        cos_o: f32,
    },
    Shaded {
        sh: Shading,
        at: Option<AtWo>,
    },
}

impl Turned {
    /// A lone Lambert lobe of `albedo` (shading normal `ns`, geometric `ng`) shaded with
    /// `wo`, its normal turned as `Shading::new` turns a two-sided Bsdf's; `None` where
    /// `wo` grazes it.
    #[inline]
    fn lambert(albedo: Vec3A, ns: Vec3A, ng: Vec3A, wo: Vec3A) -> Option<Turned> {
        let n = if wo.dot(ng) < 0.0 { -ns } else { ns };
        let cos_o = n.dot(wo);
        (cos_o != 0.0).then_some(Turned::Lambert { albedo, n, cos_o })
    }

    /// Lobe `k`'s value (with |cos θi|) and pdf for the world direction `wi`; `bsdf` is
    /// the one shaded.
    #[inline]
    fn eval(&self, bsdf: &Bsdf, k: usize, wi: Vec3A) -> (Vec3A, f32) {
        match self {
            Turned::Lambert { albedo, n, cos_o } => {
                let cos_i = n.dot(wi);
                if *cos_o <= 0.0 || cos_i <= 0.0 {
                    (Vec3A::ZERO, 0.0)
                } else {
                    (*albedo * (FRAC_1_PI * cos_i), cos_i * FRAC_1_PI)
                }
            }
            Turned::Shaded { sh, at } => {
                bsdf.eval_lobe_at(k, sh, at.as_ref(), sh.frame.to_local(wi))
            }
        }
    }

    /// Lobe `k`'s pdf of the world direction `wi`.
    #[inline]
    fn pdf(&self, bsdf: &Bsdf, k: usize, wi: Vec3A) -> f32 {
        self.eval(bsdf, k, wi).1
    }

    /// The shading normal, turned as the frame turns it.
    #[inline]
    fn normal(&self) -> Vec3A {
        match self {
            Turned::Lambert { n, .. } => *n,
            Turned::Shaded { sh, .. } => sh.frame.n,
        }
    }
}

/// The camera subpath's side of the weight of a path through vertex `v` (module doc):
/// its sums, and the Bsdf there turned towards where the path goes next, for the reverse
/// pdfs `dvc` is multiplied by.
pub(super) struct CameraSide {
    dvcm: f32,
    dvc: f32,
    turned: Option<Turned>,
}

impl CameraSide {
    /// The sum for a path leaving `v` through lobe `k` (`back`: towards the vertex
    /// before v).
    #[inline]
    pub(super) fn sum(&self, bsdf: &Bsdf, k: usize, back: Vec3A) -> f32 {
        let p = self.turned.as_ref().map_or(0.0, |t| t.pdf(bsdf, k, back));
        self.dvcm + self.dvc * sq(p)
    }
}

impl PathState {
    /// The camera subpath's sums at `hit`, if the path `joins`, reached along `dir` from
    /// the vertex the path scattered at last, on `material`: none scatter a light subpath
    /// through a material regularised after a diffuse bounce (module doc).
    #[inline(always)]
    pub(super) fn sums_at(
        &self,
        joins: bool,
        hit: &Hit,
        dir: Vec3A,
        material: &Material,
    ) -> (f32, f32) {
        if !joins {
            return (0.0, 0.0);
        }
        let c = hit.ng.dot(dir).abs();
        if c == 0.0 || (self.dvcm == 0.0 && self.dvc == 0.0) {
            return (0.0, 0.0);
        }
        let d2 = self.prev_p.distance_squared(hit.p);
        let dvc = if material.regularized.is_some() {
            0.0
        } else {
            self.dvc / sq(c)
        };
        (self.dvcm * sq(d2 / c), dvc)
    }
}

impl Tracer<'_> {
    /// `bsdf` at `hit` with shading normal `ns` (of `material`), shaded with `wo`
    /// (world, away from the surface); `None` where `wo` grazes it.
    #[inline]
    fn turned(
        &self,
        bsdf: &Bsdf,
        material: &Material,
        hit: &Hit,
        ns: Vec3A,
        wo: Vec3A,
    ) -> Option<Turned> {
        if let Some(albedo) = bsdf.lone_lambert() {
            return Turned::lambert(albedo, ns, hit.ng, wo);
        }
        let sh = self.oriented(Shading::new(bsdf, ns, hit.ng, wo), material, hit);
        (sh.wo.z != 0.0).then(|| Turned::Shaded {
            sh,
            at: bsdf.at_wo(sh.wo),
        })
    }

    /// The camera side at `v` for a path going on towards `w` (world); `None` where no
    /// light subpath makes any such path.
    #[inline]
    pub(super) fn camera_side(&self, v: &Vertex, w: Vec3A) -> Option<CameraSide> {
        if v.dvcm == 0.0 && v.dvc == 0.0 {
            return None;
        }
        let turned = if v.dvc > 0.0 {
            self.turned(v.bsdf, v.material, v.hit, v.ns, w)
        } else {
            None
        };
        Some(CameraSide {
            dvcm: v.dvcm,
            dvc: v.dvc,
            turned,
        })
    }

    /// The camera subpath's sums after scattering at `v` through lobe `lobe` towards
    /// `wi` with pdf `pdf` (non-delta, no walk), before the vertex the ray finds.
    #[inline]
    pub(super) fn sums_after(&self, v: &Vertex, lobe: usize, wi: Vec3A, pdf: f32) -> (f32, f32) {
        let p_rev = if v.dvc > 0.0 {
            self.turned(v.bsdf, v.material, v.hit, v.ns, wi)
                .map_or(0.0, |t| t.pdf(v.bsdf, lobe, -v.dir))
        } else {
            0.0
        };
        let cos_out = v.hit.ng.dot(wi).abs();
        (
            1.0 / sq(pdf),
            sq(cos_out / pdf) * (v.dvc * sq(p_rev) + v.dvcm),
        )
    }

    /// The weight of a BSDF-sampled ray of `path` that found light `li`, light sampling's
    /// pdf being `light_pdf`, with the light subpaths that make the same path; `None`
    /// where none does.
    #[inline]
    pub(super) fn found_light_weight(
        &self,
        path: &PathState,
        li: u32,
        light_pdf: f32,
        direction_pdf: impl FnOnce() -> f32,
    ) -> Option<f32> {
        let conn = self.connect.as_ref()?;
        let mut e = conn.density[li as usize];
        if conn.at_infinity[li as usize] && e > 0.0 {
            e *= direction_pdf();
        }
        // After one vertex only light tracing would make the path, and it leaves direct
        // light alone (connect/light_tracing.rs). Light sampling makes none through a
        // delta lobe (`light_pdf` 0).
        let sampled = if light_pdf > 0.0 {
            sq(light_pdf / path.prev_pdf)
        } else {
            0.0
        };
        (path.dvc > 0.0 && e > 0.0 && path.depth >= 2)
            .then(|| weight_over(sampled + sq(e) * path.dvc))
    }

    /// Light sampling's weight at `v` for light `li` towards `wi` through lobe `k` (pdf
    /// `lobe_pdf`; the light's `light_pdf`; for a point or spot light, `dist`: its
    /// distance), with the light subpaths that make the same path (`camera`:
    /// `camera_side` towards `wi`).
    #[inline]
    pub(super) fn light_sample_weight(
        &self,
        v: &Vertex,
        camera: &CameraSide,
        (li, wi, light_pdf, dist): (u32, Vec3A, f32, Option<f32>),
        (k, lobe_pdf): (usize, f32),
    ) -> Option<f32> {
        let conn = self.connect.as_ref()?;
        let mut e = conn.density[li as usize];
        if e == 0.0 || v.bsdf.subsurface(k).is_some() {
            return None;
        }
        if conn.at_infinity[li as usize] {
            e *= direction_pdf(&self.scene.lights[li as usize], wi);
        }
        let cos_x = v.hit.ng.dot(wi).abs();
        // A point's sample: density 1 in its own measure, and no BSDF ray finds it; one
        // direction's the same, with no distance to convert by.
        let (light_pdf, bsdf_ratio) = match dist {
            Some(d) if d.is_finite() => (light_pdf * d * d, 0.0),
            Some(_) => (light_pdf, 0.0),
            None => (light_pdf, sq(lobe_pdf / light_pdf)),
        };
        let w_camera = sq(e * cos_x / light_pdf) * camera.sum(v.bsdf, k, -v.dir);
        Some(weight_over(bsdf_ratio + w_camera))
    }

    /// Joins the path's vertex `v` to every vertex of the sample's light subpath, tracing
    /// that at the first vertex that asks for it. Connections apply only where `RICH`
    /// (path.rs) is off: `Connect::new`.
    #[inline(always)]
    pub(super) fn join<S: Sampler, const RICH: bool>(
        &self,
        out: &mut Sink,
        path: &PathState,
        v: &Vertex,
        sampler: &mut S,
    ) {
        let Some(conn) = self.connect.as_ref().filter(|_| !RICH) else {
            return;
        };
        // The worker's subpath, out of the sink while the joins add to it.
        let mut lp = std::mem::take(&mut out.light_path);
        self.join_with(out, path, v, sampler, conn, &mut lp);
        out.light_path = lp;
    }

    fn join_with<S: Sampler>(
        &self,
        out: &mut Sink,
        path: &PathState,
        v: &Vertex,
        sampler: &mut S,
        conn: &Connect,
        lp: &mut LightPath,
    ) {
        // The joined path scatters at v and at y1 … y_s: all within the depth limit.
        let max_depth = self.scene.settings.max_depth;
        if path.depth + 2 >= max_depth {
            return;
        }
        if !lp.traced {
            lp.traced = true;
            self.trace_light_path(out, conn, sampler, lp);
        }
        for s in 0..lp.vertices.len() {
            if path.depth + 2 + s as u32 >= max_depth {
                break;
            }
            self.connect(out, path, v, lp, s);
        }
    }

    /// Traces the sample's light subpath into `lp` (module doc), up to the depth limit
    /// less the camera's first vertex.
    fn trace_light_path<S: Sampler>(
        &self,
        out: &mut Sink,
        conn: &Connect,
        sampler: &mut S,
        lp: &mut LightPath,
    ) {
        lp.vertices.clear();
        lp.textured.clear();
        lp.light_pdfs = Default::default();
        // The shortest join has one camera vertex; light tracing's has none.
        let camera_vertices = if self.splats.is_some() { 1 } else { 2 };
        let max_vertices = self
            .scene
            .settings
            .max_depth
            .saturating_sub(camera_vertices);
        if max_vertices == 0 {
            return;
        }
        let Some(mut walk) = self.light_start(conn, sampler, lp) else {
            return;
        };
        for j in 1..=max_vertices {
            out.rays += 1;
            if !self.land(lp, &mut walk, j) || j == max_vertices {
                break;
            }
            if !self.scatter_light(lp, &mut walk, j, sampler) {
                break;
            }
        }
    }

    /// The subpath's start: a light chosen by power, a point uniform on it, a
    /// cosine-distributed direction from its emitting side (or one of two).
    fn light_start<S: Sampler>(
        &self,
        conn: &Connect,
        sampler: &mut S,
        lp: &mut LightPath,
    ) -> Option<Walk> {
        let scene = self.scene;
        let (u_choice, u_point, u_dir) = sampler.light_path();
        let (k, pmf, _) = conn.choice.sample(u_choice);
        let li = conn.lights[k];
        let light = &scene.lights[li as usize];
        // A point uniform in the light's area, its normal, whether both sides emit, and
        // the area.
        let (p0, n, two_sided, area) = match &light.shape {
            LightShape::Triangles(t) => {
                let (p0, n) = point_on(t, scene.accel.prims(), u_point)?;
                (p0, n, t.two_sided, t.area)
            }
            LightShape::Sphere(s) => {
                let n = uniform_sphere(u_point);
                (s.center + n * s.radius, n, false, 4.0 * PI * sq(s.radius))
            }
            LightShape::Point(_) | LightShape::Spot(_) => {
                return self.point_start(conn, lp, li, u_dir);
            }
            LightShape::Distant(_) | LightShape::Dome(_) => {
                return self.infinite_start(conn, lp, li, u_point, u_dir);
            }
            _ => return None,
        };
        let (side, u_dir) = if two_sided {
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
        lp.begin(li, n, conn.density[li as usize], false, false);
        // pdf_area = 1 / area, pdf_dir = cos θ0 / (π · sides): the cosines cancel.
        let sides = if two_sided { 2.0 } else { 1.0 };
        Some(Walk::start(
            p0 + ns * scene.epsilon,
            p0,
            dir,
            le * (area * PI * sides / pmf),
        ))
    }

    /// The start from point or spot light `li`: a direction uniform over the sphere, or
    /// over the spot's outer cone, the intensity in it over the start's density
    /// (`Connect::density`: the light's choice over the solid angle it emits into).
    fn point_start(
        &self,
        conn: &Connect,
        lp: &mut LightPath,
        li: u32,
        u_dir: Vec2,
    ) -> Option<Walk> {
        let light = &self.scene.lights[li as usize];
        let (p0, dir) = match &light.shape {
            LightShape::Point(p) => (p.position, uniform_sphere(u_dir)),
            LightShape::Spot(s) => (
                s.position,
                Frame::new(s.axis).to_world(uniform_cone(u_dir, s.cos_outer)),
            ),
            _ => return None,
        };
        // The intensity towards `dir`: what light sampling gets one unit along it.
        let intensity = light
            .sample(p0 + dir, Vec3A::ZERO, Vec2::ZERO, self.scene.accel.prims())
            .map_or(Vec3A::ZERO, |ls| ls.radiance);
        if intensity == Vec3A::ZERO {
            return None;
        }
        lp.begin(li, Vec3A::ZERO, conn.density[li as usize], true, false);
        Some(Walk::start(p0, p0, dir, intensity / lp.density))
    }

    /// The start from distant light or dome `li`: a direction as its light sample picks
    /// one (uniform over a distant light's disc, or its one direction; by a dome's map),
    /// and a point uniform on the disc of `Connect::disc` facing it, outside the scene;
    /// the radiance over the start's density (`Connect::density`: the choice over the
    /// disc's area, times the direction's pdf), as Georgiev et al.'s SmallVCM starts a
    /// background light's subpath.
    fn infinite_start(
        &self,
        conn: &Connect,
        lp: &mut LightPath,
        li: u32,
        u_point: Vec2,
        u_dir: Vec2,
    ) -> Option<Walk> {
        let light = &self.scene.lights[li as usize];
        let (center, radius) = conn.disc;
        let ls = light.sample(center, Vec3A::ZERO, u_dir, &[])?;
        if ls.radiance == Vec3A::ZERO || ls.pdf.is_nan() || ls.pdf <= 0.0 {
            return None;
        }
        let dir = -ls.wi;
        let d = square_to_disk(u_point);
        let frame = Frame::new(dir);
        let p0 = center - dir * (radius * 1.01 + self.scene.epsilon)
            + (frame.s * d.x + frame.t * d.y) * radius;
        lp.begin(
            li,
            Vec3A::ZERO,
            conn.density[li as usize] * ls.pdf,
            ls.delta,
            true,
        );
        Some(Walk::start(p0, p0, dir, ls.radiance / lp.density))
    }

    /// Where `walk`'s ray lands: light vertex `j`, kept in `lp`; `false` where the
    /// subpath ends there (nothing found, nothing that scatters, a light that does not
    /// light y1).
    fn land(&self, lp: &mut LightPath, walk: &mut Walk, j: u32) -> bool {
        let scene = self.scene;
        let Some(hit) = scene.accel.intersect(&walk.ray, 0.0, Visibility::INDIRECT) else {
            return false;
        };
        let obj = &scene.objects[hit.object as usize];
        let Some(material) = obj.material.map(|m| &scene.materials[m as usize]) else {
            return false;
        };
        // Light linking: a light that does not light y1 lights nothing through it.
        if j == 1 && !self.lit(hit.object, lp.li) {
            return false;
        }
        let back = walk.prev_p - hit.p;
        let dist = back.length();
        if !(dist > 0.0 && dist.is_finite()) {
            return false;
        }
        // From a distant light: exactly its sampled direction (its pdf is that of a
        // direction in its disc), and no distance (its rays are parallel: no cone).
        let from_infinity = j == 1 && lp.at_infinity;
        let to_prev = if from_infinity {
            -walk.ray.dir
        } else {
            back / dist
        };
        let cos_prev = hit.ng.dot(to_prev).abs();
        if cos_prev == 0.0 {
            return false;
        }
        if !from_infinity {
            walk.travelled += dist;
        }
        let (dvcm, dvc) = if j == 1 {
            // dvcm: `first_dvcm`; dvc: the BSDF ray from y1 that finds the light (none
            // finds a point).
            let dvc = if lp.delta {
                0.0
            } else {
                1.0 / sq(lp.density * cos_prev)
            };
            (0.0, dvc)
        } else {
            let d2 = dist * dist;
            (
                walk.dvcm_pre * sq(d2 / cos_prev),
                walk.dvc_pre / sq(cos_prev),
            )
        };
        let textured = material.textured.as_ref().map(|tex| {
            let width = super::shading::SCATTERED_SPREAD * walk.travelled;
            let shaded = self.textured(tex, &hit, walk.ray.dir, width);
            lp.textured.push(shaded);
            (lp.textured.len() - 1) as u32
        });
        let (bsdf, ns) = match textured {
            Some(i) => (&lp.textured[i as usize].0, lp.textured[i as usize].1),
            None => (&material.bsdf, hit.ns),
        };
        let light_side = if material.regularized.is_none() {
            self.turned(bsdf, material, &hit, ns, to_prev)
        } else {
            None
        };
        lp.vertices.push(LightVertex {
            hit,
            to_prev,
            dist_prev: dist,
            cos_prev,
            beta: walk.beta,
            ns,
            reflects: bsdf.reflects_only(),
            joinable: material.regularized.is_some()
                || bsdf
                    .lobes()
                    .iter()
                    .enumerate()
                    .any(|(k, t)| !t.delta && bsdf.subsurface(k).is_none()),
            dvcm,
            dvc,
            light_side,
            textured,
            class_out: None,
            diffuse: walk.diffuse,
            specular: walk.specular,
        });
        true
    }

    /// Scatters `walk` at `lp`'s last vertex (y_j): sampled from the light's side, valued
    /// as the camera sees it; `false` where the subpath ends (a delta lobe, a walk, no
    /// sample, the roulette).
    fn scatter_light<S: Sampler>(
        &self,
        lp: &mut LightPath,
        walk: &mut Walk,
        j: u32,
        sampler: &mut S,
    ) -> bool {
        let scene = self.scene;
        let Some(y) = lp.vertices.last() else {
            return false;
        };
        let Some(from_light) = y.light_side else {
            return false;
        };
        let hit = y.hit;
        let obj = &scene.objects[hit.object as usize];
        let Some(material) = obj.material.map(|m| &scene.materials[m as usize]) else {
            return false;
        };
        let bsdf = match y.textured {
            Some(i) => &lp.textured[i as usize].0,
            None => &material.bsdf,
        };
        let (u_lobe, u_dir, u_rr) = sampler.light_vertex(j);
        let (sh, at) = match from_light {
            Turned::Shaded { sh, at } => (sh, at),
            Turned::Lambert { .. } => {
                let sh = self.oriented(Shading::new(bsdf, y.ns, hit.ng, y.to_prev), material, &hit);
                (sh, None)
            }
        };
        let Some(bs) = bsdf.sample_at(&sh, at.as_ref(), u_lobe, u_dir) else {
            return false;
        };
        if bsdf.subsurface(bs.lobe).is_some() || bs.pdf.is_nan() || bs.pdf <= 0.0 {
            return false;
        }
        if bs.delta && !bsdf.lone_lobe() {
            return false;
        }
        let cos_next = hit.ng.dot(bs.wi).abs();
        // The throughput's step and the sums before the next vertex.
        let (step, dvc_pre, dvcm_pre) = if bs.delta {
            let Some(step) = delta_step(&sh, &bs, cos_next, y.cos_prev) else {
                return false;
            };
            // Georgiev et al.'s specular vertex: nothing is joined here and the pdfs
            // both ways cancel, so `dvcm` is 0 and `dvc` takes the outgoing cosine.
            (step, sq(cos_next) * y.dvc, 0.0)
        } else {
            let Some(seen) = self.turned(bsdf, material, &hit, y.ns, bs.wi) else {
                return false;
            };
            let (f, pdf_rev) = seen.eval(bsdf, bs.lobe, y.to_prev);
            let dvcm = if j == 1 {
                self.first_dvcm(lp, seen.normal())
            } else {
                y.dvcm
            };
            (
                f * (cos_next / (y.cos_prev * bs.pdf)),
                sq(cos_next / bs.pdf) * (y.dvc * sq(pdf_rev) + dvcm),
                1.0 / sq(bs.pdf),
            )
        };
        let mut beta = walk.beta * step;
        // Roulette by the vertex's albedo from y2 on (sooner than the camera path's:
        // a light vertex costs a join with every camera vertex; +12 % efficiency on the
        // indirect box, measured against `rr_depth`).
        if j >= scene.settings.rr_depth.min(2) {
            let q = step.max_element().min(0.95);
            if u_rr >= q || q.is_nan() {
                return false;
            }
            beta /= q;
        }
        if !(beta.max_element() > 0.0 && beta.is_finite()) {
            return false;
        }
        walk.dvc_pre = dvc_pre;
        walk.dvcm_pre = dvcm_pre;
        if j >= 2 {
            match bsdf.lobes()[bs.lobe].scatter.class {
                ScatterClass::Diffuse => walk.diffuse += 1,
                _ => walk.specular += 1,
            }
        }
        walk.beta = beta;
        walk.prev_p = hit.p;
        walk.ray = self.spawn(&hit, bs.wi, f32::INFINITY);
        if let Some(last) = lp.vertices.last_mut() {
            last.class_out = Some(obj.lobe_classes[bs.lobe]);
        }
        true
    }

    /// y1's `dvcm` shaded with normal `n`: light sampling's pdf there over the light
    /// subpath's, both of y1's segment to the light.
    fn first_dvcm(&self, lp: &LightPath, n: Vec3A) -> f32 {
        sq(self.light_pdf_at(lp, n) / (lp.density * lp.vertices[0].cos_prev))
    }

    /// Joins the camera path's vertex `v` (x) to light vertex `s` of `lp` (y): every pair
    /// of a non-delta lobe at x and one at y through their events, then the light
    /// subpath's events back to the light, then `L`, weighted by the power heuristic over
    /// every way to make that path. One shadow ray, traced once some pair counts.
    fn connect(&self, out: &mut Sink, path: &PathState, v: &Vertex, lp: &LightPath, s: usize) {
        let scene = self.scene;
        let a = &scene.automaton;
        let lv = &lp.vertices[s];
        if !lv.joinable {
            return;
        }
        let light = &scene.lights[lp.li as usize];
        let y = &lv.hit;
        let obj = &scene.objects[y.object as usize];
        let Some(material) = obj.material.map(|m| &scene.materials[m as usize]) else {
            return;
        };
        let d = y.p - v.hit.p;
        let dist2 = d.length_squared();
        if !(dist2 > 0.0 && dist2.is_finite()) {
            return;
        }
        let dist = dist2.sqrt();
        let w = d / dist;
        let cos_in = y.ng.dot(w).abs();
        let cos_x = v.hit.ng.dot(w).abs();
        if cos_in == 0.0 || cos_x == 0.0 {
            return;
        }
        // Where either end only reflects, the other end must be on its side.
        if lv.reflects && lv.ns.dot(w) * lv.ns.dot(lv.to_prev) >= 0.0 {
            return;
        }
        let wi_x = v.sh.frame.to_local(w);
        if wi_x.z <= 0.0 && v.bsdf.reflects_only() {
            return;
        }
        // The camera side towards y, once for every lobe pair.
        let mut camera_side: Option<Option<CameraSide>> = None;
        // The Bsdf at y: textured (the light subpath's), regularised after a diffuse
        // bounce, or plain (the choice trace_path makes, path.rs).
        let mut shaded: [Option<Option<YShading>>; 2] = [None, None];
        let mut visible: Option<bool> = None;
        let lobes = v.bsdf.lobes();
        for (i, tag) in lobes.iter().enumerate() {
            if tag.delta || v.bsdf.subsurface(i).is_some() {
                continue;
            }
            let diffuse_i = tag.scatter.class == ScatterClass::Diffuse;
            let s_i = a.step(path.state, v.obj.lobe_classes[i]);
            if a.is_dead(s_i) {
                continue;
            }
            let (f_i, pdf_i) = v.bsdf.eval_lobe_at(i, &v.sh, v.at_wo.as_ref(), wi_x);
            if f_i == Vec3A::ZERO {
                continue;
            }
            // The shadow ray first: most joins that get this far are either seen or
            // blocked, and a blocked one needs y shaded for nothing.
            let vis = *visible.get_or_insert_with(|| self.sees(out, v.hit, y, w));
            if !vis {
                return;
            }
            let after_diffuse = path.diffuse > 0 || diffuse_i;
            let ys = shaded[after_diffuse as usize]
                .get_or_insert_with(|| self.shade_light_vertex(lp, s, material, w, after_diffuse));
            let Some(ys) = ys.as_ref() else {
                continue;
            };
            let area_pdf = pdf_i * cos_in / dist2;
            let camera_sum = camera_side
                .get_or_insert_with(|| self.camera_side(v, w))
                .as_ref()
                .map_or(0.0, |c| c.sum(v.bsdf, i, -v.dir));
            for (j, tag_y) in ys.bsdf.lobes().iter().enumerate() {
                if tag_y.delta || ys.bsdf.subsurface(j).is_some() {
                    continue;
                }
                let at_y = (s > 0).then_some(tag_y.scatter.class);
                if self.over_depth(path, lv, diffuse_i, at_y) {
                    continue;
                }
                let s_l = lp.state_to_light(a, s_i, obj.lobe_classes[j], s, light.classes.light);
                if a.accepting(s_l).is_empty() {
                    continue;
                }
                let (f_j, pdf_j) = ys.turned.eval(ys.bsdf, j, lv.to_prev);
                if f_j == Vec3A::ZERO {
                    continue;
                }
                // The light subpath's pdf of x, had it scattered at y through lobe j.
                let p_light_x = lv
                    .light_side
                    .as_ref()
                    .map_or(0.0, |t| t.pdf(ys.bsdf, j, -w) * cos_x / dist2);
                let w_light = sq(area_pdf) * (ys.dvcm + lv.dvc * sq(pdf_j));
                let w_camera = sq(p_light_x) * camera_sum;
                let weight = weight_over(w_light + w_camera);
                let value = f_i * f_j * lv.beta * (cos_in / (dist2 * lv.cos_prev));
                let origin = Origin {
                    via: Via::LightSample { visible: true },
                    scatters: path.depth + 2 + s as u32,
                    part: light.part,
                };
                self.contribute(out, s_l, path.throughput, value, weight, origin);
            }
        }
    }

    /// Whether a joined path is over the diffuse or specular depth limit: the path
    /// tracer counts every lobe but the last before the light (y1's), so the lobes at x
    /// (`diffuse_x`), at y2 … (`lv`'s counts) and at y unless it is y1 (`at_y`).
    fn over_depth(
        &self,
        path: &PathState,
        lv: &LightVertex,
        diffuse_x: bool,
        at_y: Option<ScatterClass>,
    ) -> bool {
        let settings = &self.scene.settings;
        let diffuse_y = at_y.map(|c| (c == ScatterClass::Diffuse) as u32);
        let diffuse = path.diffuse + lv.diffuse + diffuse_x as u32 + diffuse_y.unwrap_or(0);
        let specular = path.specular + lv.specular + (!diffuse_x) as u32 + at_y.is_some() as u32
            - diffuse_y.unwrap_or(0);
        settings.max_diffuse_depth.is_some_and(|max| diffuse > max)
            || settings
                .max_specular_depth
                .is_some_and(|max| specular > max)
    }

    /// Whether `x` and `y` see each other (`w`: from x to y): one shadow ray, between
    /// points moved off both surfaces (each to the other's side), as a segment ending
    /// short of y by a fixed length would cross y's own plane at grazing angles.
    fn sees(&self, out: &mut Sink, x: &Hit, y: &Hit, w: Vec3A) -> bool {
        out.rays += 1;
        let from = self.spawn(x, w, 0.0).origin;
        let to = self.spawn(y, -w, 0.0).origin;
        let span = to - from;
        let len = span.length();
        let ray = Ray {
            origin: from,
            dir: span / len,
            tmax: len * (1.0 - 1e-4),
        };
        len.is_nan() || len <= 0.0 || !self.scene.accel.occluded(&ray, 0.0, u32::MAX)
    }

    /// Light vertex `s` shaded as the path tracer shades a vertex reached along `w`:
    /// its textured Bsdf, the regularised one after a diffuse bounce, or the plain one
    /// (the choice trace_path makes, path.rs); `None` where the path tracer would stop.
    fn shade_light_vertex<'m>(
        &self,
        lp: &'m LightPath,
        s: usize,
        material: &'m Material,
        w: Vec3A,
        after_diffuse: bool,
    ) -> Option<YShading<'m>> {
        let lv = &lp.vertices[s];
        let y = &lv.hit;
        let (bsdf, ns) = match (lv.textured, &material.regularized) {
            (Some(i), _) => (&lp.textured[i as usize].0, lp.textured[i as usize].1),
            (None, Some(rough)) if after_diffuse => (rough, y.ns),
            (None, _) => (&material.bsdf, y.ns),
        };
        let turned = self.turned(bsdf, material, y, ns, -w)?;
        let dvcm = if s == 0 {
            self.first_dvcm(lp, turned.normal())
        } else {
            lv.dvcm
        };
        Some(YShading { bsdf, turned, dvcm })
    }

    /// Light sampling's pdf at y1 with shading normal `n` for the subpath's start
    /// (selection included), kept for two normals.
    fn light_pdf_at(&self, lp: &LightPath, n: Vec3A) -> f32 {
        let mut known = lp.light_pdfs.iter().filter_map(Cell::get);
        if let Some((_, pdf)) = known.find(|&(m, _)| m == n) {
            return pdf;
        }
        let scene = self.scene;
        let y1 = &lp.vertices[0];
        let light = &scene.lights[lp.li as usize];
        let select = scene.light_select.pmf(lp.li as usize, y1.hit.p, n);
        // A point's light sample has density 1 in its own measure: over the subpath's
        // area density at y1 the squared distance stays (module doc). A distant light's
        // is of directions, as its subpath's start is over the disc: no distance.
        let pdf = if lp.at_infinity {
            select * direction_pdf(light, y1.to_prev)
        } else if lp.delta {
            select * sq(y1.dist_prev)
        } else {
            select * light.pdf_hit(y1.hit.p, n, y1.to_prev, y1.dist_prev, lp.light_ng)
        };
        if let Some(free) = lp.light_pdfs.iter().find(|slot| slot.get().is_none()) {
            free.set(Some((n, pdf)));
        }
        pdf
    }
}

/// A light vertex shaded for one connection.
struct YShading<'m> {
    bsdf: &'m Bsdf,
    turned: Turned,
    /// The vertex's `dvcm` for this shading.
    dvcm: f32,
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    fn unit(rng: &mut Rng) -> Vec3A {
        loop {
            let v = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
            let l = v.length();
            if l > 0.1 && l <= 1.0 {
                return v / l;
            }
        }
    }

    /// The frameless Lambert form gives the value and pdf the Bsdf's own evaluation in
    /// its frame gives, both sides of the surface, with shading normals off the
    /// geometric one; and only a lone two-sided Lambert lobe takes that form.
    #[test]
    fn a_lone_lambert_lobe_needs_no_frame() {
        let albedo = Vec3A::new(0.8, 0.5, 0.2);
        let bsdf = Bsdf::diffuse(albedo);
        assert_eq!(bsdf.lone_lambert(), Some(albedo));
        for other in [
            Bsdf::plastic(Vec3A::splat(0.5), 1.5, 0.3),
            Bsdf::translucent(Vec3A::splat(0.3), Vec3A::splat(0.6)),
            Bsdf::conductor(Vec3A::splat(0.9), 0.2),
        ] {
            assert_eq!(other.lone_lambert(), None);
        }
        let mut rng = Rng::for_sample(7, 0, 0);
        let mut compared = 0;
        for _ in 0..2000 {
            let ng = unit(&mut rng);
            let ns = (ng + unit(&mut rng) * 0.3).normalize();
            let (wo, wi) = (unit(&mut rng), unit(&mut rng));
            let sh = Shading::new(&bsdf, ns, ng, wo);
            let shaded = Turned::Shaded {
                sh,
                at: bsdf.at_wo(sh.wo),
            };
            let Some(fast) = Turned::lambert(albedo, ns, ng, wo) else {
                assert_eq!(sh.wo.z, 0.0);
                continue;
            };
            let ((f, p), (g, q)) = (shaded.eval(&bsdf, 0, wi), fast.eval(&bsdf, 0, wi));
            assert!((f - g).abs().max_element() <= 1e-5, "{f} {g}");
            assert!((p - q).abs() <= 1e-5, "{p} {q}");
            assert!((shaded.normal() - fast.normal()).length() <= 1e-5);
            compared += (p > 0.0) as u32;
        }
        assert!(compared > 200, "{compared} lit pairs");
    }
}
