//! Paths through participating media (media/): the medium a path is in, free flights
//! that end at a scattering vertex (a `V` event, light sampled there with MIS against
//! the phase function, the next direction from the phase function, or where the render
//! guides from its mixture with the guide, guided.rs), single scattering
//! towards point, spot and small sphere lights (rect, quad and disk lights too with
//! `volume_sampling = "mis-area"`) at equiangularly sampled distances (Kulla &
//! Fajardo 2012, "Importance Sampling Techniques for Path Tracing in Participating
//! Media"; media/equiangular.rs), and the transmittance of shadow rays, which pass null
//! boundaries and media and stop at any other surface.
//!
//! Single scattering towards a light along one flight has up to three techniques: a
//! free-flight vertex's light sample (A), an equiangular distance's light sample (B, the
//! same light sampling from its point), and a free-flight vertex's phase-sampled ray that
//! finds the light (C, path.rs). Light sampling takes the share λ = power heuristic of
//! (light pdf, phase pdf) against C, as at any vertex ([`light_share`]); within it, A and
//! B split by the power heuristic of their distance densities, the light sample's pdf
//! being common to both. So A weighs λ·μ_A, B λ·μ_B, C 1 − λ, summing to one for every
//! path. In a grid thin along the flight, which has no free-flight density to weigh by,
//! B takes λ whole and A gives its light samples of those lights up (`thin_grid`).
//!
//! A `V` vertex is a bounce like a surface's: it takes the same sampler dimensions of
//! its depth (light choice and point, direction, roulette), counts toward `max_depth`
//! and `rr_depth`, and not toward the diffuse or specular limits (docs/lpe.md#volumes).
//! Free-flight distances and colour-channel choices come from a generator per camera
//! sample (`PathState::rng`), seeded from the camera ray, so the sampler's layout is the
//! same with and without media.

use super::direct::power_heuristic;
use super::guided::GuideAt;
use super::path::PathState;
use super::routing::{Origin, Via};
use super::{Sink, Tracer};
use crate::geometry::{Hit, Prim, Ray, Visibility};
use crate::light::{Light, LightSample, LightShape};
use crate::material::BsdfSample;
use crate::media::equiangular::Equiangular;
use crate::media::{Collision, Medium, MediumStack, VolumeSampling};
use crate::sampler::{dim, Sampler};
use crate::sampling::{splitmix64, Rng};
use crate::scene::{MediumUse, Scene};
use glam::{Vec2, Vec3A};
use lpe::StateId;

/// The optical depth (the majorants' bound, densest channel) below which a grid medium
/// is thin along a flight: its transmittance there is at least e^(−1), so distances
/// sampled towards a light waste little on light the medium has already absorbed.
const THIN: f32 = 1.0;

/// Whether single scattering towards the lights equiangular sampling aims at along the
/// flight `seg` in `medium` is left to it alone: a grid medium, thin along it. A grid
/// has no free-flight density to weigh equiangular distances against (its tracking only
/// samples one), so the two techniques split the lights instead of weighing each sample:
/// by this test of the segment, which both sides make alike, so each light's single
/// scattering is counted exactly once. Dense grids keep light sampling at the vertices.
fn thin_grid(medium: &Medium, seg: &Ray) -> bool {
    matches!(medium, Medium::Heterogeneous(h) if h.majorant_depth(seg) < THIN)
}

/// Boundaries a ray may pass without an event before it counts as lost: a cap on the
/// work of one segment among many nested or overlapping null surfaces.
pub(super) const MAX_CROSSINGS: u32 = 256;

/// A seed for the media decisions of the camera sample whose first ray is `ray` (its
/// origin and direction come from that sample's pixel-filter and lens numbers).
pub(super) fn media_seed(ray: &Ray) -> u64 {
    let bits = |v: Vec3A| {
        u64::from(v.x.to_bits())
            ^ (u64::from(v.y.to_bits()) << 21)
            ^ (u64::from(v.z.to_bits()) << 42)
    };
    splitmix64(bits(ray.dir) ^ splitmix64(bits(ray.origin)))
}

/// A medium scattering vertex: where, the direction the path travelled, the medium,
/// and the object that bounds it (`u32::MAX`: the atmosphere).
pub(super) struct MediumVertex {
    pub p: Vec3A,
    pub dir: Vec3A,
    pub medium: MediumUse,
    pub object: u32,
    /// The flight's segment and the density of its distance (0: unknown, no MIS with
    /// equiangular sampling).
    pub seg: Ray,
    pub pdf: f32,
}

/// What equiangular sampling aims at for one light: its centre, and the radius of a
/// sphere about it that holds the whole light (0 for a point or spot light).
#[derive(Clone, Copy, Debug)]
pub(super) struct Aim {
    centre: Vec3A,
    radius: f32,
}

/// Per light of `scene`, what equiangular sampling aims at: point and spot lights, and
/// sphere lights by their bounding sphere, and with `volume_sampling = "mis-area"` rect,
/// quad and disk lights too (whether a flight takes one is [`Equiangular::towards`]'s
/// test: it stays outside that sphere). Empty, so no equiangular sampling, without
/// media or such lights or with `volume_sampling = "distance"`. Mesh lights and glows,
/// of any shape and size, are left to the vertices.
pub(super) fn aims(scene: &Scene) -> Vec<Option<Aim>> {
    let one_sided = match scene.settings.volume_sampling {
        _ if !scene.has_media => return Vec::new(),
        VolumeSampling::Distance => return Vec::new(),
        VolumeSampling::Mis => false,
        VolumeSampling::MisArea => true,
    };
    let prims = scene.accel.prims();
    let aims: Vec<_> = scene
        .lights
        .iter()
        .map(|l| aim_of(l, prims, one_sided))
        .collect();
    if aims.iter().any(Option::is_some) {
        aims
    } else {
        Vec::new()
    }
}

/// One light's aim; rect, quad and disk lights (`LightShape::Triangles`) only if
/// `one_sided`: half of the distances sampled towards them fall behind them, and at equal
/// time they lost to free flights alone (benches/media/README.md).
fn aim_of(light: &Light, prims: &[Prim], one_sided: bool) -> Option<Aim> {
    let (centre, radius) = match &light.shape {
        LightShape::Point(p) => (p.position, 0.0),
        LightShape::Spot(s) => (s.position, 0.0),
        LightShape::Sphere(s) => (s.center, s.radius),
        LightShape::Triangles(t) if one_sided => {
            let corners = || {
                t.prims
                    .iter()
                    .filter_map(|&i| match prims.get(i as usize) {
                        Some(&Prim::Triangle { p0, e1, e2, .. }) => Some([p0, p0 + e1, p0 + e2]),
                        _ => None,
                    })
                    .flatten()
            };
            let (lo, hi) = corners().fold((Vec3A::INFINITY, Vec3A::NEG_INFINITY), |b, q| {
                (b.0.min(q), b.1.max(q))
            });
            let centre = (lo + hi) * 0.5;
            let radius = corners().map(|q| q.distance(centre)).fold(0.0, f32::max);
            (centre, radius)
        }
        _ => return None,
    };
    (centre.is_finite() && radius.is_finite()).then_some(Aim { centre, radius })
}

/// The share of a light sample at a medium vertex against phase sampling finding the
/// light (`light_pdf`: its pdf with the light's choice; `f`: the phase function's value,
/// its sampling pdf), as path.rs weighs the other side: all of it for delta lights,
/// which no ray finds, and shadow-linked ones (a ray stops at what casts them no shadow).
fn light_share(light: &Light, ls: &LightSample, light_pdf: f32, f: f32) -> f32 {
    if ls.delta || light.shadow_linked {
        1.0
    } else {
        power_heuristic(light_pdf, f)
    }
}

/// What lies on a null boundary a ray passes (within `epsilon` of it, which the next
/// segment would skip): see [`Tracer::coincident`].
pub(super) enum Coincident {
    /// A real surface, found in the boundary's place.
    Surface(Hit),
    /// Another null boundary (two media sharing a face), crossed with it.
    Boundary(Hit),
}

/// How a ray's flight through the medium it is in ended.
pub(super) enum Flight {
    /// At the surface it found (or out of the scene), the throughput attenuated.
    Reached,
    /// At a scattering vertex, which sent the path on along this ray.
    Scattered(Ray),
    /// The path ended in the medium (depth limit, dead state, roulette, no throughput).
    Ended,
}

impl Tracer<'_> {
    /// The flight of `ray` up to what it `found`, in the medium the path is in (none:
    /// it reaches it): the medium's emission along it, then a free-flight distance; a
    /// real collision before the surface is a scattering vertex.
    pub(super) fn fly<S: Sampler>(
        &self,
        out: &mut Sink,
        path: &mut PathState,
        ray: &Ray,
        found: Option<&Hit>,
        sampler: &mut S,
    ) -> Flight {
        let scene = self.scene;
        let Some((m, object)) = self.medium_of(&path.media) else {
            return Flight::Reached;
        };
        let seg = Ray {
            tmax: found.map_or(f32::INFINITY, |h| h.t),
            ..*ray
        };
        self.medium_emission(out, path, m, &seg);
        if self.equiangular() {
            self.equiangular_light(out, path, m, object, &seg);
        }
        let volume = &scene.volumes[m.volume as usize];
        let throughput = path.throughput;
        match volume.medium.sample(&seg, throughput, &mut path.rng) {
            Collision::Pass { weight } => {
                path.throughput *= weight;
                if path.throughput == Vec3A::ZERO {
                    Flight::Ended
                } else {
                    Flight::Reached
                }
            }
            Collision::Scatter { t, weight } => {
                path.throughput *= weight;
                path.cone_width += path.cone_spread * t;
                // `max_depth` counts segments, as at a surface (path.rs).
                if path.depth + 1 >= scene.settings.max_depth {
                    return Flight::Ended;
                }
                let v = MediumVertex {
                    p: ray.origin + ray.dir * t,
                    dir: ray.dir,
                    medium: m,
                    object,
                    seg,
                    pdf: match self.equiangular() {
                        true => volume
                            .medium
                            .collision_terms(t, throughput)
                            .map_or(0.0, |c| c.2),
                        false => 0.0,
                    },
                };
                match self.medium_scatter(out, path, &v, sampler) {
                    Some(next) if self.roulette(path, sampler) => Flight::Scattered(next),
                    _ => Flight::Ended,
                }
            }
        }
    }

    /// Whether flights sample distances equiangularly towards some light.
    #[inline]
    fn equiangular(&self) -> bool {
        !self.aims.is_empty()
    }

    /// Equiangular sampling of the flight `seg` towards light `li`, if the flight takes
    /// that light: the one test both techniques make.
    #[inline]
    fn aim(&self, seg: &Ray, li: usize) -> Option<Equiangular> {
        let aim = self.aims.get(li)?.as_ref()?;
        Equiangular::towards(seg, aim.centre, aim.radius)
    }

    /// The medium of `stack` and the object that bounds it (`u32::MAX` for the
    /// atmosphere), if any.
    #[inline]
    pub(super) fn medium_of(&self, stack: &MediumStack) -> Option<(MediumUse, u32)> {
        let scene = self.scene;
        match stack.current() {
            Some(o) => scene.objects[o as usize].interior.map(|m| (m, o)),
            None => scene.atmosphere.map(|m| (m, u32::MAX)),
        }
    }

    /// Whether a boundary of `object` is no interface here: a medium of higher
    /// priority is around it (Schmidt & Budge's false hit), so the ray passes it.
    #[inline]
    pub(super) fn false_boundary(&self, stack: &MediumStack, object: u32) -> bool {
        let o = &self.scene.objects[object as usize];
        o.interior.is_some()
            && stack
                .top_priority_without(object)
                .is_some_and(|p| p > o.priority)
    }

    /// Whether a ray passes `hit` without an event: a null surface or a false boundary.
    #[inline]
    pub(super) fn passes(&self, stack: &MediumStack, hit: &Hit) -> bool {
        self.scene.objects[hit.object as usize].null_surface
            || self.false_boundary(stack, hit.object)
    }

    /// `stack` after a ray travelling along `dir` crosses `hit`'s surface.
    #[inline]
    pub(super) fn cross(&self, stack: &mut MediumStack, hit: &Hit, dir: Vec3A) {
        let o = &self.scene.objects[hit.object as usize];
        if o.interior.is_some() {
            stack.cross(hit.object, o.priority, dir.dot(hit.ng) < 0.0);
        }
    }

    /// The stack of a ray that leaves a surface vertex at `hit` (reached along `dir_in`)
    /// along `dir_out`: crossed when it goes through the surface.
    #[inline]
    pub(super) fn stack_after(
        &self,
        stack: &MediumStack,
        hit: &Hit,
        dir_in: Vec3A,
        dir_out: Vec3A,
    ) -> MediumStack {
        let mut s = *stack;
        if dir_in.dot(hit.ng) * dir_out.dot(hit.ng) > 0.0 {
            self.cross(&mut s, hit, dir_out);
        }
        s
    }

    /// What lies within `epsilon` of the null boundary `hit` along `ray`, other than
    /// `hit`'s own object (nothing for a surface not there for this ray: presence). A ray that passes a boundary goes on from it skipping
    /// `epsilon`, which would lose a surface the boundary rests on (a fog box on a floor:
    /// the floor's footprint seen through) or shares a face with. A real surface there
    /// takes the boundary's place: the ray meets it on the side it came from, in the
    /// medium it was in, and does not cross the boundary (a path that goes on through
    /// that surface keeps that medium: coplanar interfaces have no other order). Its `t`
    /// is from `ray`'s origin, at least the boundary's less `epsilon`.
    pub(super) fn coincident(
        &self,
        stack: &MediumStack,
        ray: &Ray,
        hit: &Hit,
        mask: u8,
    ) -> Option<Coincident> {
        let eps = self.scene.epsilon;
        let probe = Ray {
            origin: hit.p - ray.dir * eps,
            dir: ray.dir,
            tmax: 2.0 * eps,
        };
        let mut c = self
            .scene
            .accel
            .intersect_except(&probe, 0.0, mask, hit.object)?;
        c.t = (hit.t - eps + c.t).max(0.0);
        if self.passes(stack, &c) {
            Some(Coincident::Boundary(c))
        } else if self.see_through(&c, ray) {
            None
        } else {
            Some(Coincident::Surface(c))
        }
    }

    /// The transmittance of the shadow ray `ray` (up to `ray.tmax`) starting in
    /// `stack`'s medium: through null boundaries and media, zero at any other surface
    /// (`ignore`: a light's own object, which it passes; `li`: the light, whose
    /// unshadowing objects it passes too, `u32::MAX`: none).
    pub(super) fn transmittance(
        &self,
        out: &mut Sink,
        ray: &Ray,
        stack: &MediumStack,
        (ignore, li): (u32, u32),
        rng: &mut Rng,
    ) -> Vec3A {
        let scene = self.scene;
        let mut tr = Vec3A::ONE;
        let mut stack = *stack;
        let mut ray = *ray;
        // Past a boundary the ray starts on it and skips `tmin` (path.rs does the same).
        let mut tmin = 0.0;
        for _ in 0..MAX_CROSSINGS {
            out.rays += 1;
            let hit = scene.accel.intersect(&ray, tmin, Visibility::SHADOW);
            tmin = scene.epsilon;
            if let Some((m, _)) = self.medium_of(&stack) {
                let seg = Ray {
                    tmax: hit.as_ref().map_or(ray.tmax, |h| h.t),
                    ..ray
                };
                tr *= scene.volumes[m.volume as usize]
                    .medium
                    .transmittance(&seg, rng);
                if tr == Vec3A::ZERO {
                    return tr;
                }
            }
            let Some(hit) = hit else {
                return tr;
            };
            if hit.object != ignore && !self.unshadowing(hit.object, li) {
                if self.passes(&stack, &hit) {
                    // As a camera path does (`coincident`): blocked by a surface the
                    // boundary lies on, through a boundary it shares a face with.
                    match self.coincident(&stack, &ray, &hit, Visibility::SHADOW) {
                        Some(Coincident::Surface(c))
                            if c.object != ignore && !self.unshadowing(c.object, li) =>
                        {
                            return Vec3A::ZERO;
                        }
                        Some(Coincident::Boundary(c)) => self.cross(&mut stack, &c, ray.dir),
                        _ => {}
                    }
                    self.cross(&mut stack, &hit, ray.dir);
                } else if !self.see_through(&hit, &ray) {
                    return Vec3A::ZERO;
                }
            }
            ray.origin = hit.p;
            ray.tmax -= hit.t;
            if ray.tmax <= tmin {
                return tr;
            }
        }
        Vec3A::ZERO
    }

    /// A scattering vertex in a medium: the `V` event, light sampling, and the next
    /// direction from the phase function. `None`: the path ends (dead state).
    pub(super) fn medium_scatter<S: Sampler>(
        &self,
        out: &mut Sink,
        path: &mut PathState,
        v: &MediumVertex,
        sampler: &mut S,
    ) -> Option<Ray> {
        let scene = self.scene;
        let a = &scene.automaton;
        let s_v = a.step(path.state, v.medium.scatter_class);
        if a.is_dead(s_v) {
            return None;
        }
        let guide = self.guide_in_medium(v.p);
        self.medium_light(out, path, s_v, v, guide, sampler);
        let volume = &scene.volumes[v.medium.volume as usize];
        let guided = guide.filter(|g| g.alpha > 0.0 || (self.learn && g.trained));
        // A phase function has one lobe: the lobe's number picks phase or guide (read
        // before the direction: the layout's order, sampler.rs).
        let u_choice = guided.map(|_| sampler.vertex_1d(path.depth, dim::LOBE_CHOICE));
        let u_dir = sampler.vertex_2d(path.depth, dim::DIRECTION);
        let before = path.throughput;
        let (wi, pdf, weight, pdfs) = match (guided, u_choice) {
            (Some(g), Some(u_choice)) => {
                let (wi, pdf, f, pdfs) =
                    self.sample_medium_guided(g, &volume.phase, v.dir, u_choice, u_dir)?;
                (wi, pdf, f / pdf, Some(pdfs))
            }
            // The phase function is sampled exactly: its weight is one.
            _ => {
                let (wi, pdf) = volume.phase.sample(v.dir, u_dir);
                (wi, pdf, 1.0, None)
            }
        };
        path.throughput *= weight;
        path.state = s_v;
        path.prev_p = v.p;
        path.prev_n = Vec3A::ZERO;
        path.prev_pdf = pdf;
        path.prev_delta = false;
        path.prev_light_samples = 1.0;
        path.only_delta = false;
        path.prev_object = v.object;
        if let Some(g) = guide {
            let bs = BsdfSample {
                lobe: 0,
                wi,
                weight: Vec3A::splat(weight),
                pdf,
                delta: false,
                eta: 1.0,
            };
            self.record_vertex(out, path, g, &bs, pdfs, before);
        }
        path.travelled = 0.0;
        path.cone_spread = path.cone_spread.max(super::shading::SCATTERED_SPREAD);
        path.depth += 1;
        Some(Ray {
            origin: v.p,
            dir: wi,
            tmax: f32::INFINITY,
        })
    }

    /// Light sampling at a medium vertex, the path's state `s_v` past its `V`: one
    /// light, one point, the phase function's value, weighted against phase sampling;
    /// the shadow ray's transmittance splits it between plain and `shadows` AOVs.
    fn medium_light<S: Sampler>(
        &self,
        out: &mut Sink,
        path: &mut PathState,
        s_v: StateId,
        v: &MediumVertex,
        guide: Option<GuideAt>,
        sampler: &mut S,
    ) {
        let scene = self.scene;
        let a = &scene.automaton;
        let u_light = sampler.vertex_1d(path.depth, dim::LIGHT_CHOICE);
        let u_point = sampler.vertex_2d(path.depth, dim::LIGHT_POINT);
        if scene.lights.is_empty() {
            return;
        }
        let Some((li, select_pmf)) = scene.light_select.sample(u_light, v.p, Vec3A::ZERO) else {
            return;
        };
        let light = &scene.lights[li];
        if !self.lit(v.object, li as u32) {
            return;
        }
        let s_light = a.step(s_v, light.classes.light);
        if a.accepting(s_light).is_empty() {
            return;
        }
        let Some(ls) = light.sample(v.p, Vec3A::ZERO, u_point, scene.accel.prims()) else {
            return;
        };
        let volume = &scene.volumes[v.medium.volume as usize];
        let f = volume.phase.eval(v.dir, ls.wi);
        if f <= 0.0 {
            return;
        }
        let light_pdf = select_pmf * ls.pdf;
        let share = light_share(light, &ls, light_pdf, self.medium_pdf(guide, f, ls.wi));
        let w = match self.equiangular_pdf(&v.seg, li, v.p) {
            // The flight also aims at this light: the free-flight and equiangular
            // distances split light sampling's share (its pdf the same for both).
            Some(pdf_e) if v.pdf > 0.0 => share * power_heuristic(v.pdf * select_pmf, pdf_e),
            // A grid thin along the flight: equiangular sampling takes it alone.
            Some(pdf_e) if pdf_e > 0.0 && thin_grid(&volume.medium, &v.seg) => return,
            _ => share,
        };
        let tmax = if ls.dist.is_finite() {
            ls.dist - 2.0 * scene.epsilon
        } else {
            f32::INFINITY
        };
        let shadow = Ray {
            origin: v.p,
            dir: ls.wi,
            tmax,
        };
        let tr = if tmax <= 0.0 {
            Vec3A::ONE
        } else {
            self.transmittance(
                out,
                &shadow,
                &path.media,
                (light.shadow_exempt(), li as u32),
                &mut path.rng,
            )
        };
        let value = ls.radiance * (f / light_pdf);
        self.split_by_transmittance(out, s_light, path, value, w, tr, light.glow, light.part);
    }

    /// The density with which [`equiangular_light`](Self::equiangular_light) picks light
    /// `li` and the distance of `p` along `seg` (`None`: it never aims at that light).
    fn equiangular_pdf(&self, seg: &Ray, li: usize, p: Vec3A) -> Option<f32> {
        let e = self.aim(seg, li)?;
        let pmf = self.scene.light_select.pmf(li, seg.origin, Vec3A::ZERO);
        Some(pmf * e.pdf((p - seg.origin).dot(seg.dir)))
    }

    /// Single scattering towards a light along a flight's segment `seg`, the distance
    /// sampled equiangularly towards its centre (media/equiangular.rs), the light then
    /// sampled from there as a vertex samples it, weighed as the module doc says: the
    /// same `V` then `L` events as a medium vertex's light sample. The light is chosen
    /// from the segment's origin; lights the flight does not aim at are left to the
    /// vertices.
    fn equiangular_light(
        &self,
        out: &mut Sink,
        path: &mut PathState,
        m: MediumUse,
        object: u32,
        seg: &Ray,
    ) {
        let scene = self.scene;
        let a = &scene.automaton;
        let (u_light, u_t) = (path.rng.next_f32(), path.rng.next_f32());
        if path.depth + 1 >= scene.settings.max_depth {
            return;
        }
        let s_v = a.step(path.state, m.scatter_class);
        let Some((li, pmf)) = scene.light_select.sample(u_light, seg.origin, Vec3A::ZERO) else {
            return;
        };
        let light = &scene.lights[li];
        let s_light = a.step(s_v, light.classes.light);
        if a.accepting(s_light).is_empty() || !self.lit(object, li as u32) {
            return;
        }
        let volume = &scene.volumes[m.volume as usize];
        let Some(e) = self.aim(seg, li) else {
            return;
        };
        let (t, pdf_t) = e.sample(u_t);
        let p = seg.origin + seg.dir * t;
        // σs at the distance, the transmittance to it, and the free-flight density there
        // (`None` for a grid, whose tracking has none to give: it takes the light alone).
        let (sigma_s, tr, pdf_d) = match &volume.medium {
            Medium::Heterogeneous(h) if thin_grid(&volume.medium, seg) => {
                let to_t = Ray { tmax: t, ..*seg };
                let tr = h.transmittance(&to_t, &mut path.rng);
                (h.sigma_s_at(p), tr, None)
            }
            m => match m.collision_terms(t, path.throughput) {
                Some((sigma_s, tr, pdf_d)) => (sigma_s, tr, Some(pdf_d)),
                None => return,
            },
        };
        // An area light's point takes two numbers (a delta light's none, which keeps
        // their streams as they were).
        let u_point = match light.is_delta() {
            true => Vec2::ZERO,
            false => Vec2::new(path.rng.next_f32(), path.rng.next_f32()),
        };
        let Some(ls) = light.sample(p, Vec3A::ZERO, u_point, scene.accel.prims()) else {
            return;
        };
        let f = volume.phase.eval(seg.dir, ls.wi);
        let pdf_e = pmf * pdf_t;
        if f <= 0.0 || pdf_e.is_nan() || pdf_e <= 0.0 {
            return;
        }
        let pmf_p = scene.light_select.pmf(li, p, Vec3A::ZERO);
        // Against the direction density a free-flight vertex at p would sample with.
        let guide = self.guide_in_medium(p);
        let share = light_share(light, &ls, pmf_p * ls.pdf, self.medium_pdf(guide, f, ls.wi));
        let w = share * pdf_d.map_or(1.0, |pdf_d| power_heuristic(pdf_e, pdf_d * pmf_p));
        let shadow = Ray {
            origin: p,
            dir: ls.wi,
            tmax: ls.dist - 2.0 * scene.epsilon,
        };
        let t_shadow = if shadow.tmax <= 0.0 {
            Vec3A::ONE
        } else {
            self.transmittance(
                out,
                &shadow,
                &path.media,
                (light.shadow_exempt(), li as u32),
                &mut path.rng,
            )
        };
        let value = sigma_s * tr * ls.radiance * (f / (pdf_e * ls.pdf));
        self.split_by_transmittance(
            out, s_light, path, value, w, t_shadow, light.glow, light.part,
        );
    }

    /// Adds a light sample `value` (weight `w`) reached with transmittance `tr`: the
    /// transmitted part as visible, the rest as blocked (what `shadows` takes, so plain
    /// + shadows = unoccluded); a glow only its transmitted part.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn split_by_transmittance(
        &self,
        out: &mut Sink,
        state: StateId,
        path: &PathState,
        value: Vec3A,
        w: f32,
        tr: Vec3A,
        glow: bool,
        part: u32,
    ) {
        let origin = |via| Origin {
            via,
            scatters: path.depth + 1,
            part,
        };
        if tr != Vec3A::ZERO {
            let via = if glow {
                Via::Glow
            } else {
                Via::LightSample { visible: true }
            };
            self.contribute(out, state, path.throughput, value * tr, w, origin(via));
        }
        let blocked = Vec3A::ONE - tr;
        if !glow && blocked != Vec3A::ZERO {
            let via = Via::LightSample { visible: false };
            self.contribute(out, state, path.throughput, value * blocked, w, origin(via));
        }
    }

    /// The emission a medium adds along the segment `seg` (an `O` with its groups).
    pub(super) fn medium_emission(
        &self,
        out: &mut Sink,
        path: &mut PathState,
        m: MediumUse,
        seg: &Ray,
    ) {
        let scene = self.scene;
        let volume = &scene.volumes[m.volume as usize];
        if volume.emission == Vec3A::ZERO {
            return;
        }
        let s = scene.automaton.step(path.state, m.glow_class);
        if scene.automaton.accepting(s).is_empty() {
            return;
        }
        let origin = Origin {
            via: Via::Glow,
            scatters: path.depth,
            part: self.default_part,
        };
        let le = volume.emitted(seg, &mut path.rng);
        self.contribute(out, s, path.throughput, le, 1.0, origin);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aov;
    use crate::scene::Source;

    fn scene(render: &str) -> Scene {
        let text = format!(
            "[render]\n{render}\n[media.fog]\nsigma_s = [0.1, 0.1, 0.1]\n\
             [[objects]]\nname = \"box\"\nshape = \"cube\"\nscale = 3\nmaterial = \"null\"\n\
             interior = \"fog\"\n\
             [[lights]]\ntype = \"disk\"\nscale = [0.08, 0.08, 1]\nrotate = [180, 0, 0]\n\
             translate = [-0.2, 0, 1.9]\nradiance = [5, 5, 5]\n\
             [[lights]]\ntype = \"rect\"\nscale = [0.1, 0.2, 1]\nrotate = [30, 0, 0]\n\
             translate = [1, 1, 0]\nradiance = [5, 5, 5]\n\
             [[lights]]\ntype = \"sphere\"\ncenter = [0, 0.5, 0]\nradius = 0.1\n\
             radiance = [5, 5, 5]\n\
             [[lights]]\ntype = \"point\"\nposition = [0, 0, 1]\nintensity = [1, 1, 1]\n\
             [[lights]]\ntype = \"distant\"\ndirection = [0, 0, -1]\nirradiance = [1, 1, 1]\n"
        );
        let desc = Source {
            name: "aims.toml".into(),
            text,
            dir: Default::default(),
        }
        .parse()
        .unwrap();
        Scene::build(&desc, &aov::assemble(vec![])).unwrap()
    }

    /// With `mis-area`, disk, rect, sphere and point lights are aimed at by their
    /// bounding spheres (the disk's and rect's from their triangles), a distant light
    /// not; `mis` (the default) leaves the disk and rect out; `distance` aims at none.
    #[test]
    fn lights_are_aimed_at_by_their_bounding_spheres() {
        let s = scene("volume_sampling = \"mis-area\"");
        let aims = aims(&s);
        let want = [
            Some((Vec3A::new(-0.2, 0.0, 1.9), 0.08)),
            Some((Vec3A::new(1.0, 1.0, 0.0), (0.1f32 * 0.1 + 0.2 * 0.2).sqrt())),
            Some((Vec3A::new(0.0, 0.5, 0.0), 0.1)),
            Some((Vec3A::new(0.0, 0.0, 1.0), 0.0)),
            None,
        ];
        assert_eq!(aims.len(), want.len());
        for (k, (got, want)) in aims.iter().zip(want).enumerate() {
            match (got, want) {
                (Some(a), Some((c, r))) => assert!(
                    a.centre.distance(c) < 1e-5 && (a.radius - r).abs() < 1e-5,
                    "light {k}: {a:?}, want {c} {r}"
                ),
                (None, None) => {}
                _ => panic!("light {k}: {got:?}, want {want:?}"),
            }
        }
        let default: Vec<_> = super::aims(&scene(""))
            .iter()
            .map(Option::is_some)
            .collect();
        assert_eq!(default, [false, false, true, true, false]);
        assert!(super::aims(&scene("volume_sampling = \"distance\"")).is_empty());
    }
}
