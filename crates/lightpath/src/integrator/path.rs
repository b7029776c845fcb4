//! One camera path as named steps over a [`PathState`]: emission where the ray lands,
//! data lobes, direct light (direct.rs), BSDF sampling and continuation, and Russian
//! roulette. Each step reads the path state; only `scatter` and `roulette` change it.

use super::guided::GuideAt;
use super::routing::{Origin, Via};
use super::volume::{media_seed, Coincident, Flight, MAX_CROSSINGS};
use super::{Sink, Tracer};
use crate::geometry::{Hit, Ray, Visibility};
use crate::light::Light;
use crate::material::{AtWo, Bsdf, Shading};
use crate::media::MediumStack;
use crate::sampler::{dim, Sampler};
use crate::sampling::Rng;
use crate::scene::{DataLobe, Material, Object};
use glam::Vec3A;
use lpe::{ScatterClass, StateId};

/// Where a path is between two vertices.
pub(super) struct PathState {
    /// The automaton state after the last event.
    pub state: StateId,
    pub throughput: Vec3A,
    /// Product of the relative indices of refraction crossed (for Russian roulette).
    pub eta_scale: f32,
    /// The last scattering point, the pdf of the direction sampled there and whether it
    /// came from a delta lobe (for MIS when the ray finds a light).
    pub prev_p: Vec3A,
    /// The normal light selection used there (the light tree's probabilities depend on
    /// the shading point and its normal).
    pub prev_n: Vec3A,
    pub prev_pdf: f32,
    pub prev_delta: bool,
    /// Light samples taken there (`light_samples` where it split, else 1): light
    /// sampling's density there is that many times one sample's.
    pub prev_light_samples: f32,
    /// Whether every scatter so far went through a delta lobe: the vertex the ray finds
    /// is seen directly, or through mirrors and smooth glass (where light sampling takes
    /// `light_samples`).
    pub only_delta: bool,
    /// The object scattered from last (`u32::MAX`: the camera), for light linking.
    pub prev_object: u32,
    pub diffuse: u32,
    pub specular: u32,
    /// Scattering vertices so far.
    pub depth: u32,
    /// The ray cone that picks texture mip levels: its width at the last vertex and its
    /// spread angle (shading.rs).
    pub cone_width: f32,
    pub cone_spread: f32,
    /// The interiors the path is in (volume.rs).
    pub media: MediumStack,
    /// Distance from `prev_p` to the current ray's origin: the boundaries passed since
    /// the last scatter (for the light pdf of what the ray finds).
    pub travelled: f32,
    /// Free-flight and channel choices, and shadow-ray transmittance estimates.
    pub rng: Rng,
    /// Bidirectional weights (connect.rs): the camera subpath's sums of pdf ratios for
    /// the ray now traced, before the distance and cosine where it lands count.
    pub dvcm: f32,
    pub dvc: f32,
}

/// A scattering vertex: the hit and what is there.
pub(super) struct Vertex<'a> {
    pub hit: &'a Hit,
    pub obj: &'a Object,
    pub material: &'a Material,
    /// The BSDF shading uses here: the material's, its textured one (textures evaluated),
    /// or its regularised one after a diffuse bounce.
    pub bsdf: &'a Bsdf,
    pub sh: Shading,
    /// The Bsdf's terms of `sh.wo` alone, worked out once here for every evaluation
    /// and sample at this vertex.
    pub at_wo: Option<AtWo>,
    /// The direction the path arrived along (world space).
    pub dir: Vec3A,
    /// Path guiding here, if the render guides and the Bsdf is guided (guided.rs).
    pub guide: Option<GuideAt>,
    /// The shading normal `bsdf` uses (before `sh` orients it).
    pub ns: Vec3A,
    /// The camera subpath's sums here (connect.rs; 0 without light subpaths).
    pub dvcm: f32,
    pub dvc: f32,
}

impl PathState {
    /// The solid-angle pdf with which light sampling at the last scattering point would
    /// have picked what a ray along `dir` finds on `light` at `t` with normal `ng`.
    #[inline]
    pub(super) fn pdf_of(&self, light: &Light, dir: Vec3A, t: f32, ng: Vec3A) -> f32 {
        light.pdf_hit(self.prev_p, self.prev_n, dir, t, ng)
    }

    /// A path at the camera, about to trace `ray`.
    /// `seeded`: whether the path draws from its own stream (`Tracer::path_rng`).
    /// Inlined: built in place, not returned through a copy.
    #[inline(always)]
    pub(super) fn start(scene: &crate::scene::Scene, ray: &Ray, seeded: bool) -> PathState {
        let a = &scene.automaton;
        PathState {
            state: a.step(a.start(), scene.camera_class),
            throughput: Vec3A::ONE,
            eta_scale: 1.0,
            prev_p: ray.origin,
            prev_n: Vec3A::ZERO,
            prev_pdf: 0.0,
            prev_delta: true,
            prev_light_samples: 1.0,
            only_delta: true,
            prev_object: u32::MAX,
            diffuse: 0,
            specular: 0,
            depth: 0,
            cone_width: 0.0,
            cone_spread: scene.camera.pixel_spread(),
            media: scene.camera_media,
            travelled: 0.0,
            // Seeding hashes the ray: only for the scenes that draw from it.
            rng: if seeded {
                Rng::for_sample(media_seed(ray), 0, 0)
            } else {
                Rng::UNUSED
            },
            dvcm: 0.0,
            dvc: 0.0,
        }
    }
}

impl Tracer<'_> {
    /// Traces one camera path (`film_pdf`: the pixel filter's density of the ray's
    /// offset in its pixel); returns its alpha. A training pass's path then records its
    /// vertices into the guide (guided.rs). Where the render traces light to the camera,
    /// the sample's light subpath is joined to it after (connect/light_tracing.rs).
    pub(super) fn trace<S: Sampler>(
        &self,
        ray: Ray,
        film_pdf: f32,
        sampler: &mut S,
        out: &mut Sink,
    ) -> f32 {
        let scene = self.scene;
        let alpha = if scene.has_media || scene.has_presence || self.guide.is_some() {
            self.trace_path::<S, true>(ray, film_pdf, sampler, out)
        } else {
            self.trace_path::<S, false>(ray, film_pdf, sampler, out)
        };
        self.flush_record(out);
        if self.splats.is_some() {
            self.splat(out, sampler);
        }
        alpha
    }

    /// `RICH`: whether the scene may have media, null boundaries, surfaces only partly
    /// there (presence) or a guide. Without them a ray always stops at what it finds,
    /// so the loop compiled with `RICH = false` carries none of their state and tests:
    /// the plain scenes (cornell-classic) render as fast as before those features.
    fn trace_path<S: Sampler, const RICH: bool>(
        &self,
        mut ray: Ray,
        film_pdf: f32,
        sampler: &mut S,
        out: &mut Sink,
    ) -> f32 {
        let scene = self.scene;
        let mut path = PathState::start(scene, &ray, self.path_rng);
        let mut alpha = 0.0;
        out.holdout = false;
        out.first_object = None;
        let mut crossings = 0;
        // Past a boundary without an event the ray starts on it and skips this much of
        // itself instead of being moved off it, so media see their whole thickness.
        let mut tmin = 0.0;
        // The sample's light subpath (connect.rs), traced at its first vertex that joins.
        let joins = !RICH && self.connect.is_some();
        if joins {
            out.light_path.reset();
            path.dvcm = self.camera_dvcm(film_pdf, ray.dir);
        }
        loop {
            out.rays += 1;
            let mask = [Visibility::INDIRECT, Visibility::CAMERA][(path.depth == 0) as usize];
            let (found, passes, null, also) = self.find::<RICH>(&path.media, &ray, tmin, mask);
            tmin = 0.0;
            if let Some(hit) = found.as_ref().filter(|_| !passes) {
                self.first_hit(out, path.depth, hit, &mut alpha);
            }
            // Here, after the roulette and with the real ray's result, so that the lights-only
            // estimate is the beauty's own, sample by sample; once per scatter, not past a null.
            if path.depth > 0 && path.travelled == 0.0 {
                self.lights_only(out, &path, &ray, found.as_ref());
            }
            if RICH && scene.has_media {
                let camera_ray = path.depth == 0;
                let flight = self.fly(out, &mut path, &ray, found.as_ref(), sampler);
                if camera_ray && !matches!(flight, Flight::Reached) {
                    alpha = 1.0;
                }
                match flight {
                    Flight::Reached => {}
                    Flight::Scattered(next) => (ray, crossings) = (next, 0),
                    Flight::Ended => break,
                }
                if !matches!(flight, Flight::Reached) {
                    continue;
                }
            }
            let Some(hit) = found else {
                self.escaped(out, &path, &ray);
                break;
            };
            path.cone_width += path.cone_spread * hit.t;
            if RICH && passes {
                // A null surface or a false boundary: no event, the ray goes on.
                crossings += 1;
                if crossings > MAX_CROSSINGS {
                    break;
                }
                if null {
                    self.cross(&mut path.media, &hit, ray.dir);
                }
                if let Some(c) = also {
                    self.cross(&mut path.media, &c, ray.dir);
                }
                path.travelled += hit.t;
                ray.origin = hit.p;
                tmin = scene.epsilon;
                continue;
            }
            crossings = 0;
            let obj = &scene.objects[hit.object as usize];
            self.emission_at_hit(out, &path, &ray, &hit, obj);

            // Mitsuba's convention: `max_depth` counts segments; scattering here adds one.
            if path.depth + 1 >= scene.settings.max_depth {
                break;
            }
            let Some(material) = obj.material.map(|m| &scene.materials[m as usize]) else {
                break;
            };
            let textured;
            let (bsdf, ns) = match (&material.textured, &material.regularized) {
                (Some(t), _) => {
                    textured = self.textured(t, &hit, ray.dir, path.cone_width);
                    (&textured.0, textured.1)
                }
                (None, Some(rough)) if path.diffuse > 0 => (rough, hit.ns),
                (None, _) => (&material.bsdf, hit.ns),
            };
            let sh = self.oriented(Shading::new(bsdf, ns, hit.ng, -ray.dir), material, &hit);
            if sh.wo.z == 0.0 {
                break;
            }
            let sums = path.sums_at(joins, &hit, ray.dir, material);
            let v = Vertex {
                hit: &hit,
                obj,
                material,
                bsdf,
                sh,
                at_wo: bsdf.at_wo(sh.wo),
                dir: ray.dir,
                guide: RICH.then(|| self.guide_at(bsdf, hit.p, &sh)).flatten(),
                ns,
                dvcm: sums.0,
                dvc: sums.1,
            };
            self.data_lobes(out, &path, &v);
            self.direct_light::<S, RICH>(out, &mut path, &v, sampler);
            self.join::<S, RICH>(out, &path, &v, sampler);
            let Some(mut next) = self.scatter(out, &mut path, &v, sampler) else {
                break;
            };
            if RICH && obj.interior.is_some() {
                tmin = self.enter_interior(&mut path, &hit, ray.dir, &mut next);
            }
            ray = next;
            if !self.roulette(&mut path, sampler) {
                break;
            }
        }
        alpha
    }

    /// Through the boundary of an interior at `hit` (not a subsurface walk's exit,
    /// elsewhere): the medium changes, and the flight of `next` starts on the surface;
    /// returns the length of itself it skips there (`tmin` in `trace_path`).
    fn enter_interior(&self, path: &mut PathState, hit: &Hit, dir: Vec3A, next: &mut Ray) -> f32 {
        let eps = self.scene.epsilon;
        let through = dir.dot(hit.ng) * next.dir.dot(hit.ng) > 0.0;
        if !through || next.origin.distance(hit.p) > 2.0 * eps {
            return 0.0;
        }
        path.media = self.stack_after(&path.media, hit, dir, next.dir);
        next.origin = hit.p;
        eps
    }

    /// What `ray` finds: the hit, whether it passes it without an event (a null surface,
    /// or one only partly there that this ray misses: presence), whether that is a null
    /// boundary, and another boundary lying on that one (crossed with it). A surface a
    /// passed null boundary lies on (a fog box resting on a floor) is found instead, and
    /// the boundary is not crossed (volume.rs, `coincident`). Without `RICH`, the hit.
    #[inline(always)]
    fn find<const RICH: bool>(
        &self,
        media: &MediumStack,
        ray: &Ray,
        tmin: f32,
        mask: u8,
    ) -> (Option<Hit>, bool, bool, Option<Hit>) {
        let mut found = self.scene.accel.intersect(ray, tmin, mask);
        if !RICH {
            return (found, false, false, None);
        }
        let (mut passes, null) = self.passing(media, found.as_ref(), ray);
        let mut also = None;
        if null {
            match found
                .as_ref()
                .and_then(|h| self.coincident(media, ray, h, mask))
            {
                Some(Coincident::Surface(c)) => (found, passes) = (Some(c), false),
                Some(Coincident::Boundary(c)) => also = Some(c),
                None => {}
            }
        }
        (found, passes, null, also)
    }

    /// Whether the ray goes on through `found` without an event, and whether that is a
    /// null surface (a medium boundary, crossed) rather than an absent one (presence:
    /// the medium does not change).
    #[inline(always)]
    fn passing(&self, media: &MediumStack, found: Option<&Hit>, ray: &Ray) -> (bool, bool) {
        let Some(h) = found else {
            return (false, false);
        };
        let null = self.scene.has_media && self.passes(media, h);
        (null || self.see_through(h, ray), null)
    }

    /// The path's first real surface: alpha, the object for the ID AOVs, holdouts.
    fn first_hit(&self, out: &mut Sink, depth: u32, hit: &Hit, alpha: &mut f32) {
        let holdout = self.scene.objects[hit.object as usize].holdout;
        if depth == 0 {
            *alpha = if holdout { 0.0 } else { 1.0 };
            out.first_object = (!holdout).then_some(hit.object);
        }
        out.holdout |= holdout;
    }

    /// The ray left the scene: the escape lights (domes, distant lights' sky) it sees.
    fn escaped(&self, out: &mut Sink, path: &PathState, ray: &Ray) {
        let scene = self.scene;
        for &li in &scene.escape_lights {
            let le = scene.lights[li as usize].emitted_escaped(ray.dir);
            if le != Vec3A::ZERO && self.lit(path.prev_object, li) {
                let le = le * self.glint_share(out, path, li, (ray.dir, None));
                self.light_seen(out, path, li, le, |light| {
                    path.pdf_of(light, ray.dir, f32::INFINITY, Vec3A::ZERO)
                });
            }
        }
    }

    /// Emission arriving along the ray at `hit`: a light's surface, or a glowing object
    /// that is not a light (`O`, weighted against light sampling when that samples it).
    /// Inlined down to the test of whether `obj` emits (most surfaces do not): the call
    /// was ~26 instructions a hit on the indirect box, nearly all of them for nothing.
    #[inline(always)]
    fn emission_at_hit(
        &self,
        out: &mut Sink,
        path: &PathState,
        ray: &Ray,
        hit: &Hit,
        obj: &Object,
    ) {
        if obj.light.is_some() || obj.glow_class.is_some() {
            self.emission_of(out, path, ray, hit, obj);
        }
    }

    fn emission_of(&self, out: &mut Sink, path: &PathState, ray: &Ray, hit: &Hit, obj: &Object) {
        let scene = self.scene;
        if let Some(li) = obj.light {
            let light = &scene.lights[li as usize];
            let le = light.emitted_at(hit.ng, ray.dir);
            if le != Vec3A::ZERO && self.lit(path.prev_object, li) {
                let le = le * self.glint_share(out, path, li, (ray.dir, Some(hit.p)));
                self.light_seen(out, path, li, le, |light| {
                    path.pdf_of(light, ray.dir, hit.t + path.travelled, hit.ng)
                });
            }
        } else if let Some(glow) = obj.glow_class {
            let s = scene.automaton.step(path.state, glow);
            let emission = obj.emission * self.glow_texture(obj, hit, ray.dir, path.cone_width);
            let weight = obj.glow_light.map_or(1.0, |li| {
                self.bsdf_weight(path, li, |light| {
                    path.pdf_of(light, ray.dir, hit.t + path.travelled, hit.ng)
                })
            });
            let origin = Origin {
                via: Via::Glow,
                scatters: path.depth,
                part: self.default_part,
            };
            self.contribute(out, s, path.throughput, emission, weight, origin);
        }
    }

    /// Data lobes, each as if lit by a unit light (docs/lpe.md#paths-and-events).
    /// Inlined down to the test of whether any data AOV is still live (past the first
    /// vertex, usually none): a call per vertex otherwise.
    #[inline(always)]
    fn data_lobes(&self, out: &mut Sink, path: &PathState, v: &Vertex) {
        let scene = self.scene;
        if scene.data_live[scene.automaton.state_index(path.state)] {
            self.live_data_lobes(out, path, v);
        }
    }

    fn live_data_lobes(&self, out: &mut Sink, path: &PathState, v: &Vertex) {
        let scene = self.scene;
        let a = &scene.automaton;
        for &(kind, class) in &v.obj.data_lobes {
            let s1 = a.step(path.state, class);
            if a.is_dead(s1) {
                continue;
            }
            let s2 = a.step(s1, scene.data_light_class);
            if a.accepting(s2).is_empty() {
                continue;
            }
            let value = match kind {
                // A denoiser's albedo is a reflectance: never above 1.
                DataLobe::Albedo => v.bsdf.albedo().min(Vec3A::ONE),
                DataLobe::Position => v.hit.p,
                DataLobe::Normal => v.sh.frame.n,
                DataLobe::UserColor => v.material.user_color.unwrap_or(Vec3A::ZERO),
                DataLobe::Depth => Vec3A::splat(scene.camera.depth(v.hit.p)),
            };
            let origin = Origin {
                via: Via::Data,
                scatters: path.depth + 1,
                part: self.default_part,
            };
            self.contribute_inlined(out, s2, path.throughput, value, 1.0, origin);
        }
    }

    /// Samples one lobe and a direction and steps the path through them (through a
    /// random walk for a subsurface lobe, subsurface.rs); the ray to trace next, or `None` where the path ends (no sample, depth limits, dead state).
    #[inline(always)]
    fn scatter<S: Sampler>(
        &self,
        out: &mut Sink,
        path: &mut PathState,
        v: &Vertex,
        sampler: &mut S,
    ) -> Option<Ray> {
        let scene = self.scene;
        let settings = &scene.settings;
        let u_lobe = sampler.vertex_1d(path.depth, dim::LOBE_CHOICE);
        let u_dir = sampler.vertex_2d(path.depth, dim::DIRECTION);
        // A training pass measures the guide even where its leaf samples the BSDF alone,
        // so that the leaf can learn to guide again (guiding/mod.rs, `FRACTIONS`).
        let (bs, pdfs) = match v.guide {
            Some(g) if g.alpha > 0.0 || (self.learn && g.trained) => {
                self.sample_guided(v, g, u_lobe, u_dir)?
            }
            _ => (
                v.bsdf.sample_at(&v.sh, v.at_wo.as_ref(), u_lobe, u_dir)?,
                None,
            ),
        };
        match v.bsdf.lobes()[bs.lobe].scatter.class {
            ScatterClass::Diffuse => {
                path.diffuse += 1;
                if settings
                    .max_diffuse_depth
                    .is_some_and(|max| path.diffuse > max)
                {
                    return None;
                }
            }
            _ => {
                path.specular += 1;
                if settings
                    .max_specular_depth
                    .is_some_and(|max| path.specular > max)
                {
                    return None;
                }
            }
        }
        path.state = scene
            .automaton
            .step(path.state, v.obj.lobe_classes[bs.lobe]);
        if scene.automaton.is_dead(path.state) {
            return None;
        }
        let before = path.throughput;
        path.throughput *= bs.weight;
        path.eta_scale *= bs.eta;
        // The camera subpath's sums (connect.rs): no light subpath scatters through a
        // subsurface walk or a delta lobe of several, nor is joined to one; through a
        // lone delta lobe they scatter, but none is joined there (`dvcm` 0, and the pdfs
        // both ways cancel in `dvc`).
        if self.connect.is_some() {
            let walks = v.bsdf.subsurface(bs.lobe).is_some();
            (path.dvcm, path.dvc) = if walks || (bs.delta && !v.bsdf.lone_lobe()) {
                (0.0, 0.0)
            } else if bs.delta {
                (0.0, v.dvc * v.hit.ng.dot(bs.wi).powi(2))
            } else {
                self.sums_after(v, bs.lobe, bs.wi, bs.pdf)
            };
        }
        if let Some(lobe) = v.bsdf.subsurface(bs.lobe) {
            let u = [u_lobe, u_dir.x, u_dir.y];
            return self.subsurface_scatter(out, path, v, lobe, bs.wi, u);
        }
        path.prev_p = v.hit.p;
        path.prev_n = v.sh.frame.n;
        path.prev_pdf = bs.pdf;
        path.prev_delta = bs.delta;
        path.prev_light_samples = self.light_samples(path);
        path.only_delta &= bs.delta;
        path.prev_object = v.hit.object;
        if let (Some(g), false) = (v.guide, bs.delta) {
            self.record_vertex(out, path, g, &bs, pdfs, before);
        }
        path.travelled = 0.0;
        if !bs.delta {
            path.cone_spread = path.cone_spread.max(super::shading::SCATTERED_SPREAD);
        }
        path.depth += 1;
        Some(self.spawn(v.hit, bs.wi, f32::INFINITY))
    }

    /// Russian roulette as Mitsuba does it: from `rr_depth` on, continue with
    /// probability max(throughput)·η², at most 0.95. `false`: the path ends.
    #[inline(always)]
    pub(super) fn roulette<S: Sampler>(&self, path: &mut PathState, sampler: &mut S) -> bool {
        let t_max = path.throughput.max_element();
        if t_max <= 0.0 || !t_max.is_finite() {
            return false;
        }
        if path.depth >= self.scene.settings.rr_depth {
            let q = (t_max * path.eta_scale * path.eta_scale).min(0.95);
            // The roulette of the vertex just scattered from (`depth` already counts it).
            if sampler.vertex_1d(path.depth - 1, dim::ROULETTE) >= q {
                return false;
            }
            path.throughput /= q;
        }
        true
    }
}
