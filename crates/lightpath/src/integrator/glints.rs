//! Sun glints: a small distant light (the sun's half-degree disc) or sphere light (a
//! bulb) seen from the camera through smooth mirrors and glass alone, such as the sun
//! in a chrome ball, or the sun through a glass ball seen in a chrome one
//! (`C<RS><TS><TS>L`, the brightest pixel of the held-out glTF shot of
//! benches/peer/real_scenes.py). A glint covers a
//! speck of its pixel (there, one camera sample in ~1500), so pixel sampling alone
//! leaves it missing, or a firefly, for thousands of samples.
//!
//! A second strategy samples film positions inside the glint:
//! 1. It takes each of the pixel's chains: a sequence of delta events (reflect or
//!    transmit at each vertex) that a ray through the pixel centre (or near it) can
//!    follow and that shows a glint light's disc within the pixel filter's reach.
//! 2. It draws a direction in that light's disc, or a point on the sphere light (as its
//!    light samples from the chain's last vertex at the start draw it).
//! 3. It solves for the film position whose ray leaves the chain in that direction, or
//!    towards that point, by Newton's method in film space from the chain's start.
//!
//! This is specular manifold sampling (Zeltner, Georgiev and Jakob, "Specular Manifold
//! Sampling for Rendering High-Frequency Caustics and Glints", 2020) with the film
//! position as the unknown. The first step is a chord step with the Jacobian at the
//! start, worked out once a pixel; the next take a fresh Jacobian wherever the miss does
//! not shrink fourfold (through a glass ball the chord alone oscillated).
//!
//! - **Density.** A film position's density is the light's direction pdf times
//!   |∂ω/∂x|, the solid angle the chain's last ray sweeps per unit of film area (for a
//!   sphere light, the solid angle, seen from the start's last vertex, of where that ray
//!   meets it). It comes from finite differences of four more camera rays.
//! - **Weights.** Camera samples and glint samples are weighed by the power heuristic
//!   (the balance heuristic left a 3° sun's glint through a glass ball 4 % to camera
//!   samples, whose rare hits were most of its noise). A camera sample's density is the
//!   pixel filter's times its delta events' choices (a glass's Fresnel choice).
//! - **Unbiased.** A path counts for glint sampling only where Newton from its chain's
//!   start finds it, which a camera sample's weight checks by solving again. Where one
//!   pixel holds several solutions, the others are left to camera samples.
//!
//! **Where it applies.**
//! - Cameras and scenes: any camera (a thin lens's glints for each lens position, the
//!   chains looked for with its chief ray, so a glint blurred over more than the
//!   filter's reach is left to camera samples); no media; no partly present surfaces.
//! - Vertices: materials with one delta reflection or transmission (a smooth conductor
//!   or glass, a smooth coat over a rough base: lacquer, car paint, plastic), up to
//!   [`MAX_CHAIN`] vertices before Russian roulette starts.
//! - Lights: the first [`MAX_GLINT_LIGHTS`] distant lights with a disc and sphere lights,
//!   where they look at most [`MAX_GLINT_RADIUS`] in radius.
//!
//! Elsewhere, camera samples alone make glints, as before.
//!
//! ```toml
//! [render]
//! glint_sampling = "on"   # on (default) | off
//! ```

use super::path::PathState;
use super::{Sink, Tracer};
use crate::geometry::{sphere_intersect, Hit, Ray, Visibility};
use crate::light::LightShape;
use crate::material::Shading;
use crate::sampling::{Frame, Rng};
use crate::scene::Scene;
use glam::{Mat2, Vec2, Vec3A};
use lpe::StateId;

/// Whether renders sample film positions inside sun glints (`[render] glint_sampling`,
/// `--glint-sampling`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum GlintSampling {
    #[default]
    On,
    Off,
}

impl GlintSampling {
    pub const NAMES: [&'static str; 2] = ["on", "off"];

    pub fn parse(s: &str) -> Option<GlintSampling> {
        match s {
            "on" => Some(GlintSampling::On),
            "off" => Some(GlintSampling::Off),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            GlintSampling::On => "on",
            GlintSampling::Off => "off",
        }
    }
}

/// Lights glint sampling aims at, at most: the first ones declared. The others' glints
/// are left to camera samples.
pub const MAX_GLINT_LIGHTS: usize = 8;

/// The largest angular radius (radians, ~1.7°) of a light glint sampling aims at, as
/// seen from a chain's last vertex: camera samples find a larger light's reflection
/// often enough alone (the built-in `cornell`'s fill light, 7° from its glass ball,
/// cost 3 % more CPU for no less error).
const MAX_GLINT_RADIUS: f32 = 0.03;

/// Delta vertices in a chain, at most.
pub const MAX_CHAIN: u32 = 4;

/// (Chain, light) pairs a pixel samples, at most: the first found, shortest chains first.
const MAX_CANDIDATES: usize = 8;

/// Where a pixel's chains are looked for: its centre, then these offsets (pixels) off
/// it, for the chains and lights the centre's ray misses.
const STARTS: [[f32; 2]; 5] = [
    [0.0, 0.0],
    [0.75, 0.0],
    [-0.75, 0.0],
    [0.0, 0.75],
    [0.0, -0.75],
];

/// Newton steps before a solve gives up.
const MAX_STEPS: u32 = 10;

/// Film step (pixels) of the Jacobians' differences: a power of two, so that adding it
/// to a film position is exact.
const FILM_STEP: f32 = 1.0 / 1024.0;

/// How close (film pixels) a camera sample must be to what Newton finds from its
/// direction for the two to be one solution.
const SAME_SOLUTION: f32 = 1e-3;

/// The lights glint sampling aims at: distant lights with a disc and sphere lights, if
/// the render samples glints and the scene lets it (no media, no partly present
/// surfaces).
pub(super) fn glint_lights(scene: &Scene) -> Vec<u32> {
    let fits = scene.settings.glint_sampling == GlintSampling::On
        && !scene.has_media
        && !scene.has_presence;
    if !fits {
        return Vec::new();
    }
    scene
        .lights
        .iter()
        .enumerate()
        .filter(|(_, l)| match &l.shape {
            LightShape::Distant(d) => {
                d.one_minus_cos > 0.0 && (2.0 * d.one_minus_cos).sqrt() <= MAX_GLINT_RADIUS
            }
            LightShape::Sphere(s) => {
                // Small as seen from the farthest the scene reaches, at least.
                let far = s.center.distance(scene.scene_center) + scene.scene_radius;
                s.radius > 0.0 && s.radius <= MAX_GLINT_RADIUS * far
            }
            _ => false,
        })
        .map(|(i, _)| i as u32)
        .take(MAX_GLINT_LIGHTS)
        .collect()
}

/// A chain's delta events: `len` of them, bit k of `transmit` set where event k
/// transmits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Chain {
    len: u32,
    transmit: u32,
}

impl Chain {
    fn then(self, transmit: bool) -> Chain {
        Chain {
            len: self.len + 1,
            transmit: self.transmit | ((transmit as u32) << self.len),
        }
    }
}

/// A chain and a light one pixel samples, and where Newton starts for it: the start's
/// leaving direction, two directions across it in which directions near it are
/// measured, and the inverse of the Jacobian there (film pixels per radian).
#[derive(Clone, Copy, Debug, Default)]
struct Candidate {
    chain: Chain,
    light: u32,
    /// Where Newton starts: the pixel centre, or a point off it where the centre's ray
    /// does not follow the chain.
    start: Vec2,
    /// The start's last vertex: where a sphere light's points are drawn as seen from.
    from: Vec3A,
    leaving: Vec3A,
    across: (Vec3A, Vec3A),
    inverse: Mat2,
    /// Newton's tolerance (radians).
    tolerance: f32,
}

impl Candidate {
    /// The chord step towards `target` from a position leaving along `leaving`.
    fn step(&self, target: Vec3A, leaving: Vec3A) -> Vec2 {
        let miss = target - leaving;
        self.inverse * Vec2::new(miss.dot(self.across.0), miss.dot(self.across.1))
    }
}

/// One pixel's candidates.
#[derive(Clone, Copy, Debug)]
pub(super) struct GlintPixel {
    centre: Vec2,
    candidates: [Candidate; MAX_CANDIDATES],
    n: usize,
}

impl GlintPixel {
    fn candidates(&self) -> &[Candidate] {
        &self.candidates[..self.n]
    }
}

impl Default for GlintPixel {
    fn default() -> GlintPixel {
        GlintPixel {
            centre: Vec2::ZERO,
            candidates: [Candidate::default(); MAX_CANDIDATES],
            n: 0,
        }
    }
}

/// One camera sample's film and lens positions in a pixel where glints are sampled
/// (the pixel's candidates are the sink's `glint_pixel`, set once a pixel: a copy of
/// them each sample was ~2 % of the built-in `cornell`'s CPU): its glint samples go
/// through the same lens position (a thin lens's), so that both strategies sample film
/// positions for that lens position.
#[derive(Clone, Copy, Debug)]
pub(super) struct GlintSample {
    pub film: Vec2,
    pub lens: Vec2,
}

/// The lens position of a thin lens's chief ray (its centre), which a pixel's chains
/// are looked for with.
const CHIEF: Vec2 = Vec2::splat(0.5);

/// A camera ray through a chain: where it leaves the last vertex, and what the events
/// made of it.
struct Followed {
    last: Hit,
    /// The direction leaving the last vertex.
    leaving: Vec3A,
    /// The product of the events' weights (f·cos / pdf) and of their choices' pdfs.
    weight: Vec3A,
    choices: f32,
    /// The automaton state after the events, the last event's pdf and shading normal.
    state: StateId,
    last_pdf: f32,
    last_n: Vec3A,
}

impl Tracer<'_> {
    /// The camera ray through film position `film` along `chain`: every vertex a
    /// material with the chain's delta event there; `None` otherwise, or
    /// where the automaton dies or a depth limit would stop the path first.
    fn follow(&self, film: Vec2, lens: Vec2, chain: Chain) -> Option<Followed> {
        let scene = self.scene;
        let settings = &scene.settings;
        if chain.len + 1 > settings.max_depth
            || chain.len >= settings.rr_depth
            || settings.max_specular_depth.is_some_and(|m| chain.len > m)
        {
            return None;
        }
        let a = &scene.automaton;
        let mut ray = scene.camera.ray(film, lens);
        let mut mask = Visibility::CAMERA;
        let mut state = a.step(a.start(), scene.camera_class);
        let (mut weight, mut choices) = (Vec3A::ONE, 1.0);
        let mut travelled = 0.0;
        let mut last = None;
        for k in 0..chain.len {
            let hit = scene.accel.intersect(&ray, 0.0, mask)?;
            travelled += hit.t;
            let transmit = chain.transmit >> k & 1 == 1;
            let (event, wi) = self.delta_event(&ray, &hit, travelled, transmit)?;
            state = a.step(
                state,
                scene.objects[hit.object as usize].lobe_classes[event.lobe],
            );
            if a.is_dead(state) {
                return None;
            }
            weight *= event.weight;
            choices *= event.pdf;
            ray = self.spawn(&hit, wi, f32::INFINITY);
            mask = Visibility::INDIRECT;
            last = Some((hit, event.pdf, event.n));
        }
        let (last, last_pdf, last_n) = last?;
        Some(Followed {
            last,
            leaving: ray.dir,
            weight,
            choices,
            state,
            last_pdf,
            last_n,
        })
    }

    /// The delta event of the material at `hit` (`transmit`: its one delta
    /// transmission, else its one delta reflection), as a camera path samples it there
    /// (its lobe's choice included).
    fn delta_event(
        &self,
        ray: &Ray,
        hit: &Hit,
        travelled: f32,
        transmit: bool,
    ) -> Option<(DeltaEvent, Vec3A)> {
        let scene = self.scene;
        let obj = &scene.objects[hit.object as usize];
        if obj.holdout {
            return None;
        }
        let material = &scene.materials[obj.material? as usize];
        let textured;
        let (bsdf, ns) = match &material.textured {
            Some(t) => {
                let cone_width = scene.camera.pixel_spread() * travelled;
                textured = self.textured(t, hit, ray.dir, cone_width);
                (&textured.0, textured.1)
            }
            None => (&material.bsdf, hit.ns),
        };
        // The one delta event of the kind: with two (a smooth coat over a mirror) a
        // camera path's event would be ambiguous from its direction.
        let mut events = (0..bsdf.lobes().len())
            .filter(|&k| bsdf.lobes()[k].delta && bsdf.lobes()[k].transmit == transmit);
        let (Some(k), None) = (events.next(), events.next()) else {
            return None;
        };
        let sh = self.oriented(Shading::new(bsdf, ns, hit.ng, -ray.dir), material, hit);
        if sh.wo.z == 0.0 {
            return None;
        }
        // A smooth glass reflects where its share of `u_lobe` falls below the Fresnel
        // factor, and transmits above it.
        let u_rest = if transmit { 1.0 } else { 0.0 };
        let at = bsdf.at_wo(sh.wo);
        let bs = bsdf.sample_event_at(&sh, at.as_ref(), k, u_rest)?;
        if !bs.delta || bs.lobe != k || bs.pdf <= 0.0 {
            return None;
        }
        let event = DeltaEvent {
            lobe: bs.lobe,
            weight: bs.weight,
            pdf: bs.pdf,
            n: sh.frame.n,
        };
        Some((event, bs.wi))
    }

    /// Whether the camera ray through `film` finds a material with a delta event: most
    /// pixels' starts do not, and are done with in one ray.
    fn sees_delta(&self, film: Vec2) -> bool {
        let scene = self.scene;
        let ray = scene.camera.ray(film, CHIEF);
        scene
            .accel
            .intersect(&ray, 0.0, Visibility::CAMERA)
            .is_some_and(|hit| self.is_delta(&hit))
    }

    /// Whether the material at `hit` may have a delta event there.
    fn is_delta(&self, hit: &Hit) -> bool {
        let scene = self.scene;
        let obj = &scene.objects[hit.object as usize];
        obj.material.is_some_and(|m| {
            let m = &scene.materials[m as usize];
            // A textured material's Bsdf varies over it: it may be delta here.
            m.textured.is_some() || m.bsdf.lobes().iter().any(|t| t.delta)
        })
    }

    fn leaving(&self, film: Vec2, lens: Vec2, chain: Chain) -> Option<Vec3A> {
        self.follow(film, lens, chain).map(|f| f.leaving)
    }

    /// The candidates of pixel (`x`, `y`): the chains a ray through its centre, or
    /// through [`STARTS`] off it, can follow, each with the glint lights whose disc it
    /// may show within the pixel filter's reach; one start for each chain and light.
    pub(super) fn glint_pixel(&self, x: u32, y: u32) -> Option<GlintPixel> {
        // Guiding's training passes keep no image: their glints are nobody's.
        if self.glint_lights.is_empty() || self.learn {
            return None;
        }
        let centre = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
        let mut pixel = GlintPixel {
            centre,
            candidates: [Candidate::default(); MAX_CANDIDATES],
            n: 0,
        };
        for offset in STARTS {
            self.explore(&mut pixel, centre + Vec2::from(offset));
        }
        (pixel.n > 0).then_some(pixel)
    }

    /// Adds the candidates of the chains a ray through `start` follows, shortest first.
    fn explore(&self, pixel: &mut GlintPixel, start: Vec2) {
        if !self.sees_delta(start) {
            return;
        }
        let mut chains = [Chain::default(); 2 << MAX_CHAIN];
        let (mut head, mut tail) = (0, 0);
        for transmit in [false, true] {
            chains[tail] = Chain::default().then(transmit);
            tail += 1;
        }
        while head < tail && pixel.n < MAX_CANDIDATES {
            let chain = chains[head];
            head += 1;
            let Some(f) = self.follow(start, CHIEF, chain) else {
                continue;
            };
            // What the leaving ray finds decides what to look at next: a material with a
            // delta event, longer chains (inside a glass ball, the way out); anything
            // else or nothing, the chain's candidates (nearby, the ray may leave the
            // scene). A chain blocked by a mirror or glass here is left to camera samples
            // where it is not.
            let ray = self.spawn(&f.last, f.leaving, f32::INFINITY);
            match self.scene.accel.intersect(&ray, 0.0, Visibility::INDIRECT) {
                Some(h) if self.is_delta(&h) => {
                    if chain.len < MAX_CHAIN {
                        for transmit in [false, true] {
                            chains[tail] = chain.then(transmit);
                            tail += 1;
                        }
                    }
                }
                _ => self.add_candidates(pixel, chain, (start, f.last.p), f.leaving),
            }
        }
    }

    /// Adds `chain`'s candidates from `start` (its last vertex at `from`, leaving
    /// along `leaving`) to `pixel`: the glint lights not yet paired with the chain whose
    /// centre a chord step predicts within the filter's reach and a pixel more.
    fn add_candidates(
        &self,
        pixel: &mut GlintPixel,
        chain: Chain,
        (start, from): (Vec2, Vec3A),
        leaving: Vec3A,
    ) {
        let reach = self.scene.filter.radius() + 1.0;
        let mut jacobian = None;
        for &li in &self.glint_lights {
            let Some((aim, angular_radius)) = self
                .light_centre(li, from)
                .filter(|&(_, r)| r <= MAX_GLINT_RADIUS)
            else {
                continue;
            };
            let towards = self.leaving_towards(li, aim, from);
            let paired = pixel
                .candidates()
                .iter()
                .any(|c| c.chain == chain && c.light == li);
            if pixel.n == MAX_CANDIDATES || paired || towards.dot(leaving) < 0.5 {
                continue;
            }
            if jacobian.is_none() {
                jacobian = Some(self.chord(start, CHIEF, chain, leaving));
            }
            let Some(Some((across, inverse, scale))) = jacobian else {
                return;
            };
            let mut c = Candidate {
                chain,
                light: li,
                start,
                from,
                leaving,
                across,
                inverse,
                tolerance: 0.0,
            };
            if (start + c.step(towards, leaving) - pixel.centre)
                .abs()
                .max_element()
                > reach
            {
                continue;
            }
            // A thousandth of the light's angular radius, but no finer than film
            // positions resolve in f32.
            let resolved = 4.0 * scale * pixel.centre.max_element().max(1.0) * f32::EPSILON;
            c.tolerance = (1e-3 * angular_radius).max(resolved).max(1e-6);
            // Kept if Newton finds the light's centre: the chord's prediction is rough
            // where the chain bends rays strongly (through a glass ball).
            if self.solve(pixel.centre, &c, CHIEF, aim).is_some() {
                pixel.candidates[pixel.n] = c;
                pixel.n += 1;
            }
        }
    }

    /// Glint light `li`'s centre as seen from `from`: the direction of a distant light's
    /// disc or a sphere light's centre (the aim Newton takes towards it), and its
    /// angular radius.
    fn light_centre(&self, li: u32, from: Vec3A) -> Option<(Vec3A, f32)> {
        match &self.scene.lights[li as usize].shape {
            LightShape::Distant(d) => Some((-d.dir, (2.0 * d.one_minus_cos).sqrt())),
            LightShape::Sphere(s) => {
                let d = s.center.distance(from);
                (d > s.radius).then(|| (s.center, (s.radius / d).asin()))
            }
            _ => None,
        }
    }

    /// The direction a chain's last vertex at `from` must leave along to meet `aim`: a
    /// distant light's aim is a direction, a sphere light's a point on it.
    fn leaving_towards(&self, li: u32, aim: Vec3A, from: Vec3A) -> Vec3A {
        match &self.scene.lights[li as usize].shape {
            LightShape::Sphere(_) => (aim - from).normalize_or_zero(),
            _ => aim,
        }
    }

    /// The chord Jacobian of `chain` at film position `film` (leaving along `leaving`):
    /// the directions across `leaving`, the inverse, and the larger column's norm
    /// (radians per pixel).
    #[allow(clippy::type_complexity)]
    fn chord(
        &self,
        film: Vec2,
        lens: Vec2,
        chain: Chain,
        leaving: Vec3A,
    ) -> Option<((Vec3A, Vec3A), Mat2, f32)> {
        let dx = self.leaving(film + Vec2::new(FILM_STEP, 0.0), lens, chain)? - leaving;
        let dy = self.leaving(film + Vec2::new(0.0, FILM_STEP), lens, chain)? - leaving;
        let frame = Frame::new(leaving);
        let across = (frame.s, frame.t);
        let jacobian = Mat2::from_cols(
            Vec2::new(dx.dot(across.0), dx.dot(across.1)),
            Vec2::new(dy.dot(across.0), dy.dot(across.1)),
        ) / FILM_STEP;
        let det = jacobian.determinant();
        if !det.is_finite() || det.abs() < 1e-12 {
            return None;
        }
        let scale = jacobian.x_axis.length().max(jacobian.y_axis.length());
        Some((across, jacobian.inverse(), scale))
    }

    /// The film position near the pixel centre whose ray leaves candidate `c`'s chain
    /// towards `aim` (a distant light's direction, a point on a sphere light; within
    /// its tolerance), by Newton steps from the chord step off
    /// the candidate's start, each at most a pixel long;
    /// `None` if the steps leave the filter's reach, break the chain or do not converge.
    fn solve(
        &self,
        centre: Vec2,
        c: &Candidate,
        lens: Vec2,
        aim: Vec3A,
    ) -> Option<(Vec2, Followed)> {
        let reach = self.scene.filter.radius();
        let first =
            c.start + c.step(self.leaving_towards(c.light, aim, c.from), c.leaving) - centre;
        let mut film = centre + first.clamp(Vec2::splat(-reach), Vec2::splat(reach));
        let (mut across, mut inverse) = (c.across, c.inverse);
        let mut last_miss = f32::INFINITY;
        for _ in 0..MAX_STEPS {
            if (film - centre).abs().max_element() > reach {
                return None;
            }
            let f = self.follow(film, lens, c.chain)?;
            let miss = self.leaving_towards(c.light, aim, f.last.p) - f.leaving;
            let miss_len = miss.length();
            if miss_len <= c.tolerance {
                return Some((film, f));
            }
            // The Jacobian it has while the miss shrinks fourfold a step, a new one
            // where it does not (two more rays).
            if miss_len > 0.25 * last_miss {
                (across, inverse, _) = self.chord(film, lens, c.chain, f.leaving)?;
            }
            last_miss = miss_len;
            let step = inverse * Vec2::new(miss.dot(across.0), miss.dot(across.1));
            film += step / step.length().max(1.0);
        }
        None
    }

    /// How fast candidate `c`'s chain sweeps over its light at film position `film`,
    /// per pixel of film area, by finite differences: the solid angle (steradians) of
    /// its leaving ray for a distant light; for a sphere light, of the direction from the
    /// candidate's `from` to where its leaving ray meets the sphere. (In solid angle from
    /// `from`, the measure a sphere light's points are drawn in, their density is the
    /// same over the sphere: a point found within Newton's tolerance of the one drawn
    /// has the drawn one's density. Per unit area it falls to zero at the rim.)
    fn sweep(&self, film: Vec2, lens: Vec2, c: &Candidate) -> Option<f32> {
        let h = FILM_STEP;
        let at = |x: Vec2| -> Option<Vec3A> {
            let f = self.follow(x, lens, c.chain)?;
            match &self.scene.lights[c.light as usize].shape {
                LightShape::Sphere(s) => {
                    let t = sphere_intersect(
                        s.center,
                        s.radius,
                        f.last.p,
                        f.leaving,
                        0.0,
                        f32::INFINITY,
                    );
                    t.is_finite()
                        .then(|| (f.last.p + f.leaving * t - c.from).normalize())
                }
                _ => Some(f.leaving),
            }
        };
        // Central differences, or one-sided ones where a side leaves the light (at a
        // sphere's rim) or breaks the chain.
        let centre = at(film);
        let axis = |e: Vec2| -> Option<Vec3A> {
            match (at(film + e * h), at(film - e * h)) {
                (Some(a), Some(b)) => Some((a - b) / (2.0 * h)),
                (Some(a), None) => Some((a - centre?) / h),
                (None, Some(b)) => Some((centre? - b) / h),
                (None, None) => None,
            }
        };
        Some(axis(Vec2::X)?.cross(axis(Vec2::Y)?).length())
    }

    /// The density with which glint sampling draws `aim` for candidate `c`: a distant
    /// light's direction pdf, or a sphere light's solid-angle density of that point of
    /// its surface as its light samples from the candidate's `from` draw it (0 for a
    /// point on its far side).
    fn aim_pdf(&self, c: &Candidate, aim: Vec3A) -> f32 {
        let light = &self.scene.lights[c.light as usize];
        match &light.shape {
            LightShape::Sphere(s) => {
                let to = aim - c.from;
                let d = to.length();
                if d.is_nan() || d <= 0.0 {
                    return 0.0;
                }
                let dir = to / d;
                let near = sphere_intersect(s.center, s.radius, c.from, dir, 0.0, f32::INFINITY);
                // Drawn points are on the side facing `from`: the ray's first hit.
                if (near - d).abs() > 1e-3 * d {
                    return 0.0;
                }
                light.pdf_hit(c.from, Vec3A::ZERO, dir, d, (aim - s.center) / s.radius)
            }
            _ => light.pdf_hit(Vec3A::ZERO, Vec3A::ZERO, aim, f32::INFINITY, Vec3A::ZERO),
        }
    }

    /// The camera strategy's share (the power heuristic) of a path that reached light
    /// `li` along `dir` (at `point` on it, for a light with a surface) through delta
    /// events alone, its camera sample in a pixel where glints are sampled; 1 where
    /// glint sampling could not have made the path.
    #[inline(always)]
    pub(super) fn glint_share(
        &self,
        out: &Sink,
        path: &PathState,
        li: u32,
        (dir, point): (Vec3A, Option<Vec3A>),
    ) -> f32 {
        match out.glint.as_ref() {
            Some(g) if path.only_delta && path.depth > 0 => {
                self.camera_share(g, &out.glint_pixel, path, li, (dir, point))
            }
            _ => 1.0,
        }
    }

    #[inline(never)]
    fn camera_share(
        &self,
        g: &GlintSample,
        pixel: &GlintPixel,
        path: &PathState,
        li: u32,
        (dir, point): (Vec3A, Option<Vec3A>),
    ) -> f32 {
        let filter = self.scene.filter.pdf(g.film - pixel.centre);
        if filter <= 0.0 {
            return 1.0;
        }
        for c in pixel.candidates() {
            if c.light != li || c.chain.len != path.depth {
                continue;
            }
            // Which chain the path took: the one whose leaving ray is its own.
            let Some(f) = self.follow(g.film, g.lens, c.chain) else {
                continue;
            };
            if f.leaving.distance(dir) > 1e-4 {
                continue;
            }
            let camera = filter * f.choices;
            let aim = point.unwrap_or(dir);
            return self
                .glint_density(pixel, c, (g.film, g.lens), aim)
                .map_or(1.0, |glint| {
                    camera * camera / (camera * camera + glint * glint)
                });
        }
        1.0
    }

    /// Glint sampling's density of the path through film position `film` (and lens
    /// position `lens`) along candidate `c` to `aim` (a direction, or a point on a
    /// sphere light): the aim's density times the sweep. `None` (no density) where
    /// Newton from the candidate's start finds another solution, or none.
    fn glint_density(
        &self,
        pixel: &GlintPixel,
        c: &Candidate,
        (film, lens): (Vec2, Vec2),
        aim: Vec3A,
    ) -> Option<f32> {
        let aim_pdf = self.aim_pdf(c, aim);
        if aim_pdf <= 0.0 {
            return None;
        }
        let (x, _) = self.solve(pixel.centre, c, lens, aim)?;
        if (x - film).abs().max_element() > SAME_SOLUTION {
            return None;
        }
        let sweep = self.sweep(film, lens, c)?;
        Some(sweep * aim_pdf).filter(|d| d.is_finite())
    }

    /// Glint sampling for one camera sample (`index`: the frame pixel, `sample` its
    /// number): for each candidate of the pixel's, an aim at its light (a direction in a
    /// distant light's disc, a point on a sphere light), the film position whose chain
    /// leaves that way, and that path to the light. Every candidate each sample, not one
    /// chosen: a choice's noise was most of a glint's through a glass ball where a pixel
    /// had two.
    pub(super) fn sample_glint(&self, out: &mut Sink, g: GlintSample, index: u64, sample: u64) {
        let mut rng = Rng::for_sample(self.seed ^ GLINT_STREAM, index, sample);
        let pixel = out.glint_pixel;
        for c in pixel.candidates() {
            self.sample_candidate(out, (pixel.centre, g.lens), c, rng.next_2d());
        }
    }

    fn sample_candidate(
        &self,
        out: &mut Sink,
        (centre, lens): (Vec2, Vec2),
        c: &Candidate,
        u: Vec2,
    ) {
        let scene = self.scene;
        let light = &scene.lights[c.light as usize];
        let Some(ls) = light.sample(c.from, Vec3A::ZERO, u, scene.accel.prims()) else {
            return;
        };
        if ls.delta || ls.pdf <= 0.0 {
            return;
        }
        let sphere = matches!(light.shape, LightShape::Sphere(_));
        let aim = if sphere {
            c.from + ls.wi * ls.dist
        } else {
            ls.wi
        };
        out.rays += 1;
        let Some((film, f)) = self.solve(centre, c, lens, aim) else {
            return;
        };
        let filter = scene.filter.pdf(film - centre);
        if filter <= 0.0 || !self.lit(f.last.object, c.light) {
            return;
        }
        // What the leaving ray meets: the sky beyond a distant light's disc, or the
        // sphere light's own surface.
        let ray = self.spawn(&f.last, f.leaving, f32::INFINITY);
        let found = scene.accel.intersect(&ray, 0.0, Visibility::INDIRECT);
        let (blocked, aim, le) = match (sphere, found) {
            (false, found) => (found.is_some(), aim, ls.radiance),
            (true, Some(h)) if scene.objects[h.object as usize].light == Some(c.light) => {
                (false, h.p, light.emitted_at(h.ng, ray.dir))
            }
            (true, _) => (true, aim, ls.radiance),
        };
        let Some(sweep) = self.sweep(film, lens, c) else {
            return;
        };
        // The power heuristic's weight over glint sampling's density, as a share of the
        // camera strategy's estimate (the path's throughput over its filter density).
        let (camera, glint) = (filter * f.choices, sweep * self.aim_pdf(c, aim));
        let share = camera * glint / (camera * camera + glint * glint);
        if !share.is_finite() || glint <= 0.0 {
            return;
        }
        let mut path = PathState::start(scene, &scene.camera.ray(film, lens), false);
        path.state = f.state;
        path.throughput = f.weight;
        path.prev_p = f.last.p;
        path.prev_n = f.last_n;
        path.prev_pdf = f.last_pdf;
        path.prev_object = f.last.object;
        path.specular = c.chain.len;
        path.depth = c.chain.len;
        if scene.lights_only_live[scene.automaton.state_index(path.state)] {
            self.light_only_seen(out, &path, c.light, le, share, blocked);
        }
        if !blocked {
            // Through delta events no other strategy makes the path: `light_seen` weighs
            // it 1 whatever the light pdf.
            self.light_seen(out, &path, c.light, le * share, |_| 0.0);
        }
    }
}

/// A delta event at a chain's vertex.
struct DeltaEvent {
    lobe: usize,
    weight: Vec3A,
    pdf: f32,
    n: Vec3A,
}

/// Separates glint sampling's random numbers from every other stream of a sample.
const GLINT_STREAM: u64 = 0x6c69_6e74_676c_6e74;
