//! Direct light with multiple importance sampling: light samples at each scattering
//! vertex (every non-delta lobe through its own event, then `L`, or a glow's `O`), lights
//! and sampled glows found by BSDF rays with the complementary weight, and the lights-only test that `unoccluded` and
//! `shadows` AOVs see. The renderer's power heuristic lives here: over two strategies, and
//! from the sums of pdf ratios bidirectional path tracing carries (connect.rs) over all of
//! its strategies (`weight_over`; docs/architecture.md).

use super::guided::LobeValues;
use super::path::{PathState, Vertex};
use super::routing::{Origin, Via};
use super::{Sink, Tracer};
use crate::geometry::{Hit, Ray, Visibility};
use crate::light::{Light, LightModel, LightShape};
use crate::sampler::{dim, Sampler};
use crate::sampling::Rng;
use glam::{Vec2, Vec3A};
use std::f32::consts::FRAC_1_PI;

/// The largest f32 below 1.
const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;

/// A box around each declared triangle light (rect, quad, disk), padded far past float
/// rounding (1e-4 of the scene's size): the lights-only test tries a light's triangles
/// only when its ray crosses the box, and most rays miss a small light. The same
/// answers for less work (on cornell-classic the two triangles were ~6 % of a render).
pub(super) fn light_boxes(scene: &crate::scene::Scene) -> Vec<Option<(Vec3A, Vec3A)>> {
    let prims = scene.accel.prims();
    scene.lights[..scene.first_glow_light as usize]
        .iter()
        .map(|light| {
            let LightShape::Triangles(t) = &light.shape else {
                return None;
            };
            let (mut lo, mut hi) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
            for &i in &t.prims {
                let (a, b) = prims.get(i as usize)?.bounds();
                (lo, hi) = (lo.min(a), hi.max(b));
            }
            if !(lo.is_finite() && hi.is_finite()) {
                return None;
            }
            let size = scene.scene_radius + lo.abs().max(hi.abs()).max_element();
            let pad = Vec3A::splat(1e-4 * size);
            Some((lo - pad, hi + pad))
        })
        .collect()
}

/// Whether `ray` may cross the box `lo`–`hi` (slab test). Rounding and NaN (a ray in
/// a face's plane) answer yes, or no only for rays that stay outside the padding.
#[inline]
fn may_cross(ray: &Ray, lo: Vec3A, hi: Vec3A) -> bool {
    let inv = ray.dir.recip();
    let (t0, t1) = ((lo - ray.origin) * inv, (hi - ray.origin) * inv);
    let near = t0.min(t1).max_element();
    let far = t0.max(t1).min_element();
    !(far < 0.0 || near > far + 1e-4 * far.abs())
}

/// The power heuristic with β = 2 (Veach 1997), for the strategy with pdf `a` against `b`.
#[inline]
pub(super) fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 == 0.0 {
        0.0
    } else if a2.is_infinite() {
        1.0
    } else {
        a2 / (a2 + b2)
    }
}

/// The power heuristic's weight of a strategy whose pdf of a path is p, from the sum
/// over the others of (their pdf / p)², as bidirectional weights (connect.rs) carry it:
/// 0 for a sum that is not a number (a zero pdf against an infinite one).
#[inline]
pub(super) fn weight_over(others: f32) -> f32 {
    if others.is_nan() {
        0.0
    } else {
        1.0 / (1.0 + others)
    }
}

impl Tracer<'_> {
    /// Whether light `light` lights surfaces of `object` (`u32::MAX`: the camera).
    /// Always inlined: left to itself the compiler kept it a call at every light sample
    /// (~15 instructions, for a test that is nearly always an empty list's).
    #[inline(always)]
    pub(super) fn lit(&self, object: u32, light: u32) -> bool {
        // Most objects are lit by every light: the empty list is tested first, as
        // `contains`' vectorised search took ~30 instructions to find nothing in it
        // (twice per scattering vertex).
        object == u32::MAX || {
            let unlit = &self.scene.objects[object as usize].unlit_by;
            unlit.is_empty() || !unlit.contains(&light)
        }
    }

    /// Whether `object` casts no shadow from light `light` (shadow linking).
    #[inline]
    pub(super) fn unshadowing(&self, object: u32, light: u32) -> bool {
        self.scene
            .objects
            .get(object as usize)
            .is_some_and(|o| o.unshadowing.contains(&light))
    }

    /// The MIS weight of a BSDF-sampled ray of `path` that found light `li`
    /// (`light_pdf`: the solid-angle pdf light sampling would have had for it).
    #[inline]
    pub(super) fn bsdf_weight(
        &self,
        path: &PathState,
        li: u32,
        light_pdf: impl FnOnce(&Light) -> f32,
    ) -> f32 {
        self.bsdf_weight_reached(path, li, light_pdf, true)
    }

    /// [`bsdf_weight`](Self::bsdf_weight), for a ray that `reached` the light or (the
    /// lights-only test) was blocked before it: only a reached light weighs against the
    /// light subpaths of bidirectional path tracing (connect.rs), which never make a
    /// blocked segment.
    #[inline]
    pub(super) fn bsdf_weight_reached(
        &self,
        path: &PathState,
        li: u32,
        light_pdf: impl FnOnce(&Light) -> f32,
        reached: bool,
    ) -> f32 {
        if path.prev_delta {
            // Light sampling cannot make a path through a delta lobe; a light subpath
            // through it can (connect.rs).
            let light = &self.scene.lights[li as usize];
            self.found_light_weight(path, li, 0.0, || light_pdf(light))
                .filter(|_| reached)
                .unwrap_or(1.0)
        } else if self.scene.lights[li as usize].shadow_linked {
            // Its light samples see past the objects that cast no shadow from it; a BSDF
            // ray stops at them: light sampling alone estimates it.
            0.0
        } else {
            let scene = self.scene;
            let direction_pdf = light_pdf(&scene.lights[li as usize]);
            let light_pdf = scene
                .light_select
                .pmf(li as usize, path.prev_p, path.prev_n)
                * path.prev_light_samples
                * direction_pdf;
            // With light subpaths that make the same path (connect.rs): never a blocked one.
            match self
                .found_light_weight(path, li, light_pdf, || direction_pdf)
                .filter(|_| reached)
            {
                Some(w) => w,
                None => power_heuristic(path.prev_pdf, light_pdf),
            }
        }
    }

    /// Light `li` found by a ray with radiance `le`: an `O` event seen from the camera,
    /// else an `L` event weighted against light sampling.
    pub(super) fn light_seen(
        &self,
        out: &mut Sink,
        path: &PathState,
        li: u32,
        le: Vec3A,
        light_pdf: impl FnOnce(&Light) -> f32,
    ) {
        let scene = self.scene;
        let light = &scene.lights[li as usize];
        let part = light.part;
        let (class, weight, origin) = if path.depth == 0 {
            if !light.camera_visible {
                return;
            }
            let via = Via::Hit {
                light_sampled: false,
                light_after_scatter: false,
            };
            let origin = Origin {
                via,
                scatters: 0,
                part,
            };
            (light.classes.seen, 1.0, origin)
        } else {
            let weight = self.bsdf_weight(path, li, light_pdf);
            // Weighted where another strategy makes the path too: light sampling, or
            // (through a delta lobe) a light subpath joined to the camera (connect.rs).
            let via = Via::Hit {
                light_sampled: !path.prev_delta || weight < 1.0,
                light_after_scatter: true,
            };
            let origin = Origin {
                via,
                scatters: path.depth,
                part,
            };
            (light.classes.light, weight, origin)
        };
        let s = scene.automaton.step(path.state, class);
        self.contribute(out, s, path.throughput, le, weight, origin);
    }

    /// How many light samples direct light takes at the vertex `path` has reached:
    /// `light_samples` at the first rough vertex, seen directly or through mirrors and
    /// smooth glass, where its noise is seen undimmed; one deeper.
    #[inline(always)]
    pub(super) fn light_samples(&self, path: &PathState) -> f32 {
        if path.only_delta {
            self.scene.settings.light_samples.max(1) as f32
        } else {
            1.0
        }
    }

    /// Light sampling at a scattering vertex: `light_samples` lights, their choices
    /// stratified (the i-th of n from (i + u)/n), each with one point on it and every
    /// non-delta lobe through its own event, then `L`, weighted against BSDF sampling.
    /// n samples are Veach's multi-sample model: light sampling's density is n times
    /// one sample's, in these weights and in the weight of a BSDF ray that finds a light
    /// (`PathState::prev_light_samples`). `RICH` as in `trace_path` (path.rs): without
    /// it, no medium or guide is tested.
    #[inline(always)]
    pub(super) fn direct_light<S: Sampler, const RICH: bool>(
        &self,
        out: &mut Sink,
        path: &mut PathState,
        v: &Vertex,
        sampler: &mut S,
    ) {
        let scene = self.scene;
        let u_light = sampler.vertex_1d(path.depth, dim::LIGHT_CHOICE);
        let u_point = sampler.vertex_2d(path.depth, dim::LIGHT_POINT);
        if scene.lights.is_empty() || v.bsdf.lobes().iter().all(|l| l.delta) {
            return;
        }
        let n = self.light_samples(path);
        if n == 1.0 {
            return self.light_sample::<RICH>(out, path, v, (u_light, u_point), 1.0);
        }
        for i in 0..n as u32 {
            // Each point shifted by the R2 sequence's step (Roberts 2018), so that two
            // samples of one light do not take one point.
            let shift = Vec2::new(0.754_877_7, 0.569_840_3) * i as f32;
            let u_i = ((i as f32 + u_light) / n).min(ONE_BELOW);
            let p_i = (u_point + shift).fract();
            self.light_sample::<RICH>(out, path, v, (u_i, p_i), n);
        }
    }

    /// One light sample of `n` at `v` (`direct_light`), from the numbers `u`.
    #[inline(always)]
    fn light_sample<const RICH: bool>(
        &self,
        out: &mut Sink,
        path: &mut PathState,
        v: &Vertex,
        (u_light, u_point): (f32, Vec2),
        n: f32,
    ) {
        let scene = self.scene;
        let a = &scene.automaton;
        let bsdf = v.bsdf;
        let lobes = bsdf.lobes();
        // One candidate, or several resampled (light_choice.rs).
        let Some(chosen) = self.choose_light(path, v, u_light, u_point) else {
            return;
        };
        let (li, ls, wi) = (chosen.li, chosen.ls, chosen.wi);
        let light = &scene.lights[li];
        let l_class = light.classes.light;
        let (part, glow) = (light.part, light.glow);
        let (light_pdf, estimate_pdf) = (chosen.mis_pdf * n, chosen.estimate_pdf * n);
        // The camera side of light subpaths that make the same paths (connect.rs); none
        // at the camera's first vertex, where only light tracing would, and it leaves
        // direct light alone (connect/light_tracing.rs).
        let direct = RICH || self.connect.is_none() || light.shadow_linked || path.depth == 0;
        let camera_side = (!direct).then(|| self.camera_side(v, ls.wi)).flatten();
        // The shadow ray is traced once, and only if some lobe's contribution counts.
        let mut visible: Option<bool> = None;
        // With media, its transmittance instead (volume.rs).
        let mut transmitted: Option<Vec3A> = None;
        // At a guided vertex BSDF sampling is a mixture with the guide (guided.rs).
        let mixture = match (v.guide, self.guide) {
            (Some(g), Some(tree)) if RICH && g.alpha > 0.0 => Some((
                g.alpha,
                LobeValues::at(bsdf, &v.sh, v.at_wo.as_ref(), wi),
                tree.leaf(g.leaf).sampling.pdf(ls.wi),
            )),
            _ => None,
        };
        for (k, tag) in lobes.iter().enumerate() {
            if tag.delta {
                continue;
            }
            let s_lobe = a.step(path.state, v.obj.lobe_classes[k]);
            if a.is_dead(s_lobe) {
                continue;
            }
            let s_light = a.step(s_lobe, l_class);
            if a.accepting(s_light).is_empty() {
                continue;
            }
            let (f, lobe_pdf) = match &mixture {
                Some((alpha, lv, guide_pdf)) => {
                    (lv.f[k], lv.mixed_pdf(bsdf, k, *alpha, *guide_pdf))
                }
                None => bsdf.eval_lobe_at(k, &v.sh, v.at_wo.as_ref(), wi),
            };
            if f == Vec3A::ZERO {
                continue;
            }
            let mut w = if ls.delta || light.shadow_linked {
                1.0
            } else {
                power_heuristic(light_pdf, lobe_pdf)
            };
            if RICH && scene.has_media {
                let tr = *transmitted.get_or_insert_with(|| {
                    let tmax = if ls.dist.is_finite() {
                        ls.dist - 2.0 * scene.epsilon
                    } else {
                        f32::INFINITY
                    };
                    if tmax <= 0.0 {
                        return Vec3A::ONE;
                    }
                    let stack = self.stack_after(&path.media, v.hit, v.dir, ls.wi);
                    let ray = self.spawn(v.hit, ls.wi, tmax);
                    self.transmittance(
                        out,
                        &ray,
                        &stack,
                        (light.shadow_exempt(), li as u32),
                        &mut path.rng,
                    )
                });
                let value = f * ls.radiance / estimate_pdf;
                self.split_by_transmittance(out, s_light, path, value, w, tr, glow, part);
                continue;
            }
            // A `match`, not `get_or_insert_with`, which the compiler kept as a call.
            let vis = match visible {
                Some(vis) => vis,
                None => {
                    out.rays += 1;
                    let tmax = if ls.dist.is_finite() {
                        ls.dist - 2.0 * scene.epsilon
                    } else {
                        f32::INFINITY
                    };
                    let vis = tmax <= 0.0
                        || !self.occluded(out, &self.spawn(v.hit, ls.wi, tmax), light, li as u32);
                    visible = Some(vis);
                    vis
                }
            };
            if let Some(camera) = camera_side.as_ref().filter(|_| vis) {
                let sample = (li as u32, ls.wi, light_pdf, ls.delta.then_some(ls.dist));
                w = self
                    .light_sample_weight(v, camera, sample, (k, lobe_pdf))
                    .unwrap_or(w);
            }
            let via = match (glow, vis) {
                // A glow is no light: what cannot reach it is no shadow.
                (true, false) => continue,
                (true, true) => Via::Glow,
                (false, visible) => Via::LightSample { visible },
            };
            let origin = Origin {
                via,
                scatters: path.depth + 1,
                part,
            };
            let value = f * ls.radiance / estimate_pdf;
            self.contribute(out, s_light, path.throughput, value, w, origin);
        }
    }

    /// Light sampling where a subsurface walk left its object (subsurface.rs): a
    /// Lambertian exit lobe around `n` (outwards; `ng` the outward geometric normal) with
    /// the path's state already past its `TD3` event, so the next event is the light's
    /// `L`, weighted against the exit lobe's cosine sampling. The numbers come from the
    /// walk's `rng`.
    pub(super) fn exit_light(
        &self,
        out: &mut Sink,
        path: &PathState,
        hit: &Hit,
        n: Vec3A,
        ng: Vec3A,
        rng: &mut Rng,
    ) {
        let scene = self.scene;
        let a = &scene.automaton;
        let u_light = rng.next_f32();
        let u_point = rng.next_2d();
        if scene.lights.is_empty() {
            return;
        }
        let Some((li, select_pmf)) = scene.light_select.sample(u_light, hit.p, n) else {
            return;
        };
        let light = &scene.lights[li];
        if !self.lit(hit.object, li as u32) {
            return;
        }
        let s_light = a.step(path.state, light.classes.light);
        if a.accepting(s_light).is_empty() {
            return;
        }
        let Some(ls) = light.sample(hit.p, n, u_point, scene.accel.prims()) else {
            return;
        };
        let cos = ls.wi.dot(n);
        if cos <= 0.0 || ls.wi.dot(ng) <= 0.0 {
            return;
        }
        let f = cos * FRAC_1_PI;
        let light_pdf = select_pmf * ls.pdf;
        let w = if ls.delta || light.shadow_linked {
            1.0
        } else {
            power_heuristic(light_pdf, f)
        };
        out.rays += 1;
        let tmax = if ls.dist.is_finite() {
            ls.dist - 2.0 * scene.epsilon
        } else {
            f32::INFINITY
        };
        let visible =
            tmax <= 0.0 || !self.occluded(out, &self.spawn(hit, ls.wi, tmax), light, li as u32);
        let via = match (light.glow, visible) {
            (true, false) => return,
            (true, true) => Via::Glow,
            (false, visible) => Via::LightSample { visible },
        };
        let origin = Origin {
            via,
            scatters: path.depth + 1,
            part: light.part,
        };
        let value = ls.radiance * (f / light_pdf);
        self.contribute(out, s_light, path.throughput, value, w, origin);
    }

    /// The nearest light surface along `ray`, ignoring everything else: (light, t,
    /// normal). Mesh lights are found in their own BVH (their triangles are many); the
    /// other declared lights each try their own surface (glows are not lights here).
    fn nearest_light(&self, ray: &Ray) -> Option<(usize, f32, Vec3A)> {
        let scene = self.scene;
        let mut best: Option<(usize, f32, Vec3A)> = scene
            .mesh_lights
            .intersect(ray, 0.0, Visibility::ALL)
            .map(|h| (h.object as usize, h.t, h.ng));
        let declared = &scene.lights[..scene.first_glow_light as usize];
        for (li, light) in declared.iter().enumerate() {
            if let Some(&Some((lo, hi))) = self.light_boxes.get(li) {
                if !may_cross(ray, lo, hi) {
                    continue;
                }
            }
            let tmax = best.map_or(f32::INFINITY, |b| b.1);
            if let Some((t, n)) = light.shape.intersect(ray, tmax, scene.accel.prims()) {
                best = Some((li, t, n));
            }
        }
        best
    }

    /// The BSDF-sampled `ray` of `path` tested against the lights alone, for
    /// `unoccluded` and `shadows` AOVs (docs/lpe.md#prefixes): the nearest light surface along it,
    /// or the escape lights if there is none, with the same MIS weight as the light the
    /// real ray would find. `hit` is what the real ray found: the light counts as
    /// occluded unless it is that, so `plain + shadows = unoccluded` sample by sample.
    /// Inlined down to whether such an AOV can still take a light's event from the
    /// path's state (most renders have none: `Scene::lights_only_live`).
    #[inline(always)]
    pub(super) fn lights_only(
        &self,
        out: &mut Sink,
        path: &PathState,
        ray: &Ray,
        hit: Option<&Hit>,
    ) {
        let scene = self.scene;
        if scene.lights_only_live[scene.automaton.state_index(path.state)] {
            self.lights_only_test(out, path, ray, hit);
        }
    }

    fn lights_only_test(&self, out: &mut Sink, path: &PathState, ray: &Ray, hit: Option<&Hit>) {
        let scene = self.scene;
        match self.nearest_light(ray) {
            Some((li, t, n)) => {
                let light = &scene.lights[li];
                let le = light.emitted_at(n, ray.dir);
                if le == Vec3A::ZERO || !self.lit(path.prev_object, li as u32) {
                    return;
                }
                if scene.has_media {
                    let w = self
                        .bsdf_weight(path, li as u32, |light| path.pdf_of(light, ray.dir, t, n));
                    let seg = Ray {
                        tmax: t - 2.0 * scene.epsilon,
                        ..*ray
                    };
                    let tr = self.lights_only_transmittance(out, path, &seg, light.shadow_exempt());
                    self.light_only_split(out, path, li as u32, le, w, tr);
                    return;
                }
                let reached = self
                    .present_hit(ray, hit)
                    .is_some_and(|h| scene.objects[h.object as usize].light == Some(li as u32));
                let w = self.bsdf_weight_reached(
                    path,
                    li as u32,
                    |light| path.pdf_of(light, ray.dir, t, n),
                    reached,
                ) * self.glint_share(
                    out,
                    path,
                    li as u32,
                    (ray.dir, Some(ray.origin + ray.dir * t)),
                );
                self.light_only_seen(out, path, li as u32, le, w, !reached);
            }
            None => {
                for &li in &scene.escape_lights {
                    let le = scene.lights[li as usize].emitted_escaped(ray.dir);
                    if le == Vec3A::ZERO || !self.lit(path.prev_object, li) {
                        continue;
                    }
                    let w = self.bsdf_weight(path, li, |light| {
                        path.pdf_of(light, ray.dir, f32::INFINITY, Vec3A::ZERO)
                    }) * self.glint_share(out, path, li, (ray.dir, None));
                    if scene.has_media {
                        let tr = self.lights_only_transmittance(out, path, ray, u32::MAX);
                        self.light_only_split(out, path, li, le, w, tr);
                        continue;
                    }
                    let blocked = self.present_hit(ray, hit).is_some();
                    self.light_only_seen(out, path, li, le, w, blocked);
                }
            }
        }
    }

    /// The transmittance of a BSDF-sampled ray (from the vertex `path` scattered at) to a
    /// light, for the lights-only test with media: from the stack the ray started in.
    fn lights_only_transmittance(
        &self,
        out: &mut Sink,
        path: &PathState,
        ray: &Ray,
        ignore: u32,
    ) -> Vec3A {
        let mut rng = path.rng.clone();
        self.transmittance(out, ray, &path.media, (ignore, u32::MAX), &mut rng)
    }

    /// A lights-only contribution reached with transmittance `tr`: the transmitted part
    /// as unblocked, the rest as blocked (so `shadows` takes what media and occluders
    /// remove, `unoccluded` the whole).
    fn light_only_split(
        &self,
        out: &mut Sink,
        path: &PathState,
        li: u32,
        le: Vec3A,
        weight: f32,
        tr: Vec3A,
    ) {
        if tr != Vec3A::ZERO {
            self.light_only_seen(out, path, li, le * tr, weight, false);
        }
        if tr != Vec3A::ONE {
            self.light_only_seen(out, path, li, le * (Vec3A::ONE - tr), weight, true);
        }
    }

    pub(super) fn light_only_seen(
        &self,
        out: &mut Sink,
        path: &PathState,
        li: u32,
        le: Vec3A,
        weight: f32,
        occluded: bool,
    ) {
        let scene = self.scene;
        let light = &scene.lights[li as usize];
        let s = scene.automaton.step(path.state, light.classes.light);
        let origin = Origin {
            via: Via::LightsOnly { occluded },
            scatters: path.depth,
            part: light.part,
        };
        self.contribute(out, s, path.throughput, le, weight, origin);
    }
}
