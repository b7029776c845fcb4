//! Path guiding in the integrator (Müller, Gross and Novák 2017, "Practical Path
//! Guiding for Efficient Light-Transport Simulation"; the SD-tree is guiding/): the
//! training passes, the record of a path's vertices, and one-sample MIS between BSDF
//! and guide sampling with a probability each leaf learns (guiding/mod.rs, `FRACTIONS`).
//!
//! The LPE needs one lobe event per vertex, so guide sampling samples a pair: a
//! direction from the quadtree, then one of the eligible lobes (non-delta reflection or
//! diffuse lobes) in proportion to the luminance of its `f` there. The pdf of a
//! (lobe, direction) pair mixes BSDF sampling's (`eval_lobe`) and the guide's; every
//! lobe's estimate stays unbiased on its own, so partitions still sum to the beauty.
//! Light sampling weighs its samples against the same mixture.
//!
//! A scattering vertex in a medium mixes the phase function and the medium root's guide
//! the same way (its one lobe is the `V` event), and its light samples, free-flight and
//! equiangular alike, weigh against that mixture (volume.rs).

use super::path::{PathState, Vertex};
use super::{Sink, Tracer};
use crate::guiding::{GuidingMode, SdTree};
use crate::light::luminance;
use crate::material::{AtWo, Bsdf, BsdfSample, Shading, MAX_LOBES};
use crate::media::phase::HenyeyGreenstein;
use glam::{Vec2, Vec3A};
use lpe::ScatterClass;
use rayon::prelude::*;

/// Lobe events a Bsdf can have.
const MAX_EVENTS: usize = 2 * MAX_LOBES;
/// Vertices of one path that are recorded for training (later ones are not).
pub(super) const MAX_RECORDED: usize = 16;
/// The seed of training pass `k` is the render's mixed with this and `k`, so training
/// never reuses the render's own numbers.
const TRAINING_SEED: u64 = 0x6775_6964_696e_6721;

/// Guiding at one vertex: the spatial leaf there, whether its guide learnt anything
/// and the probability of guide sampling (the leaf's learnt fraction; 0 where it learnt
/// nothing yet, in the first training pass).
#[derive(Clone, Copy, Debug)]
pub(super) struct GuideAt {
    pub leaf: u32,
    pub trained: bool,
    pub alpha: f32,
}

/// The two densities of a guided vertex's (lobe, direction) pair: BSDF sampling's and
/// the guide's (times its lobe choice), which the leaf's fraction mixes.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct GuidedPdfs {
    pub bsdf: f32,
    pub guide: f32,
}

/// A recorded vertex of a path: where it left, along which direction with which pdf,
/// the throughput after it, and the radiance that came back along it so far.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct RecordedVertex {
    leaf: u32,
    dir: Vec3A,
    pdf: f32,
    /// |cos θ| between the direction and the shading normal (see `flush_record`).
    cos: f32,
    /// The sampled lobe's `f` (cosine included) and, when the guide's density there was
    /// evaluated, the mixture's parts (for learning the fraction).
    f: Vec3A,
    pdfs: Option<GuidedPdfs>,
    /// The luminance of the path's throughput before the vertex.
    before: f32,
    throughput: Vec3A,
    radiance: Vec3A,
}

/// The recorded vertices of the path being traced (a training pass's; empty otherwise).
#[derive(Clone, Debug)]
pub(super) struct PathRecord {
    verts: [RecordedVertex; MAX_RECORDED],
    n: usize,
}

impl Default for PathRecord {
    fn default() -> Self {
        PathRecord {
            verts: [RecordedVertex::default(); MAX_RECORDED],
            n: 0,
        }
    }
}

impl PathRecord {
    /// A contribution `c` (throughput included) reached the camera: each recorded vertex
    /// before it receives its share, the radiance arriving along its direction (light
    /// found by the vertex's own ray included, MIS-weighted as the paper does; leaving
    /// out what light sampling covers measured no better).
    #[inline]
    pub fn add(&mut self, c: Vec3A) {
        for v in &mut self.verts[..self.n] {
            // A channel the throughput lost is one `c` has not: 0, not 0/0.
            v.radiance += c / v.throughput.max(Vec3A::splat(1e-30));
        }
    }

    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    pub fn clear(&mut self) {
        self.n = 0;
    }
}

/// Whether lobe event `k` may be sampled by the guide: not a delta, and diffuse or a
/// reflection (a guided direction leaves the interface unrefracted).
#[inline]
fn eligible(bsdf: &Bsdf, k: usize) -> bool {
    let t = bsdf.lobes()[k];
    !t.delta && (!t.transmit || t.scatter.class == ScatterClass::Diffuse)
}

/// Whether a Bsdf is guided at all: it has a non-delta diffuse lobe, and no subsurface
/// lobe (whose samples start random walks, not rays). Glossy-only and delta materials
/// keep BSDF sampling.
pub(super) fn guidable(bsdf: &Bsdf) -> bool {
    let lobes = bsdf.lobes();
    lobes
        .iter()
        .any(|t| !t.delta && t.scatter.class == ScatterClass::Diffuse)
        && (0..lobes.len()).all(|k| bsdf.subsurface(k).is_none())
}

/// Every lobe event's `f` and BSDF-sampling pdf at local `wi`, and the luminance sum
/// of the eligible ones' `f` (how guide sampling chooses among them).
pub(super) struct LobeValues {
    pub f: [Vec3A; MAX_EVENTS],
    pub pdf: [f32; MAX_EVENTS],
    pub eligible_sum: f32,
}

impl LobeValues {
    pub fn at(bsdf: &Bsdf, sh: &Shading, at: Option<&AtWo>, wi: Vec3A) -> LobeValues {
        let mut lv = LobeValues {
            f: [Vec3A::ZERO; MAX_EVENTS],
            pdf: [0.0; MAX_EVENTS],
            eligible_sum: 0.0,
        };
        for (k, tag) in bsdf.lobes().iter().enumerate() {
            if tag.delta {
                continue;
            }
            let (f, pdf) = bsdf.eval_lobe_at(k, sh, at, wi);
            lv.f[k] = f;
            lv.pdf[k] = pdf;
            if eligible(bsdf, k) {
                lv.eligible_sum += luminance(f).max(0.0);
            }
        }
        lv
    }

    /// The mixture's pdf of lobe `k` and the direction, the guide's density there
    /// being `guide_pdf`.
    pub fn mixed_pdf(&self, bsdf: &Bsdf, k: usize, alpha: f32, guide_pdf: f32) -> f32 {
        let p = self.parts(bsdf, k, guide_pdf);
        (1.0 - alpha) * p.bsdf + alpha * p.guide
    }

    /// BSDF sampling's and guide sampling's densities of lobe `k` and the direction.
    pub fn parts(&self, bsdf: &Bsdf, k: usize, guide_pdf: f32) -> GuidedPdfs {
        let q = if eligible(bsdf, k) && self.eligible_sum > 0.0 {
            luminance(self.f[k]).max(0.0) / self.eligible_sum
        } else {
            0.0
        };
        GuidedPdfs {
            bsdf: self.pdf[k],
            guide: guide_pdf * q,
        }
    }
}

impl Tracer<'_> {
    /// Guiding at point `p` shaded by `sh` (its normal turned towards the incoming ray),
    /// if the render guides and its Bsdf is guided. Inlined, so that a render that does
    /// not guide pays one test per vertex, not a call.
    #[inline(always)]
    pub(super) fn guide_at(&self, bsdf: &Bsdf, p: Vec3A, sh: &Shading) -> Option<GuideAt> {
        let tree = self.guide?;
        self.guide_in(tree, bsdf, p, sh.frame.n)
    }

    /// `guide_at` in a render that guides with `tree`.
    fn guide_in(&self, tree: &SdTree, bsdf: &Bsdf, p: Vec3A, n: Vec3A) -> Option<GuideAt> {
        if !guidable(bsdf) {
            return None;
        }
        let leaf = tree.leaf_index(p, n);
        let alpha = tree.alpha(leaf);
        // Only training samples a leaf's guide where it does not guide (path.rs).
        let trained = alpha > 0.0 || (self.learn && tree.leaf(leaf).sampling.total() > 0.0);
        Some(GuideAt {
            leaf,
            trained,
            alpha,
        })
    }

    /// Guiding at a scattering vertex in a medium at `p` (the medium root's leaves), if
    /// the render guides.
    #[inline(always)]
    pub(super) fn guide_in_medium(&self, p: Vec3A) -> Option<GuideAt> {
        let tree = self.guide?;
        let leaf = tree.leaf_index(p, Vec3A::ZERO);
        let alpha = tree.alpha(leaf);
        let trained = alpha > 0.0 || (self.learn && tree.leaf(leaf).sampling.total() > 0.0);
        Some(GuideAt {
            leaf,
            trained,
            alpha,
        })
    }

    /// The density with which a medium vertex at guide `g` samples direction `wi`, the
    /// phase function's own density there being `phase`: the mixture's where the leaf
    /// guides. Light sampling weighs against this, so MIS stays exact.
    #[inline]
    pub(super) fn medium_pdf(&self, g: Option<GuideAt>, phase: f32, wi: Vec3A) -> f32 {
        match (g, self.guide) {
            (Some(g), Some(tree)) if g.alpha > 0.0 => {
                let guide = tree.leaf(g.leaf).sampling.pdf(wi);
                (1.0 - g.alpha) * phase + g.alpha * guide
            }
            _ => phase,
        }
    }

    /// One-sample MIS of phase and guide sampling at a medium vertex travelling along
    /// `dir` (`g.trained`; with `g.alpha` 0, a training pass's phase sample that also
    /// measures the guide): the direction, the mixture's pdf, the phase function's value
    /// and the two densities mixed.
    pub(super) fn sample_medium_guided(
        &self,
        g: GuideAt,
        phase: &HenyeyGreenstein,
        dir: Vec3A,
        u_choice: f32,
        u_dir: Vec2,
    ) -> Option<(Vec3A, f32, f32, GuidedPdfs)> {
        let tree = self.guide?;
        let quad = &tree.leaf(g.leaf).sampling;
        let wi = if u_choice < 1.0 - g.alpha {
            phase.sample(dir, u_dir).0
        } else {
            quad.sample(u_dir)?
        };
        let f = phase.eval(dir, wi);
        let pdfs = GuidedPdfs {
            bsdf: f,
            guide: quad.pdf(wi),
        };
        let pdf = (1.0 - g.alpha) * pdfs.bsdf + g.alpha * pdfs.guide;
        (pdf > 0.0 && f > 0.0).then_some((wi, pdf, f, pdfs))
    }

    /// One-sample MIS of BSDF and guide sampling at a guided vertex (`g.trained`; with
    /// `g.alpha` 0, a training pass's BSDF sample that also measures the guide), and
    /// the densities it mixed (none for a delta lobe's sample).
    pub(super) fn sample_guided(
        &self,
        v: &Vertex,
        g: GuideAt,
        u_lobe: f32,
        u_dir: Vec2,
    ) -> Option<(BsdfSample, Option<GuidedPdfs>)> {
        let tree = self.guide?;
        let quad = &tree.leaf(g.leaf).sampling;
        let bsdf = v.bsdf;
        let keep = 1.0 - g.alpha;
        let (lobe, wi_world, wi) = if u_lobe < keep {
            let u = (u_lobe / keep).min(1.0 - f32::EPSILON / 2.0);
            let bs = bsdf.sample_at(&v.sh, v.at_wo.as_ref(), u, u_dir)?;
            if bs.delta {
                // The guide never samples a delta lobe's direction.
                let bs = BsdfSample {
                    lobe: bs.lobe,
                    wi: bs.wi,
                    weight: bs.weight / keep,
                    pdf: bs.pdf * keep,
                    delta: true,
                    eta: bs.eta,
                };
                return Some((bs, None));
            }
            (Some(bs.lobe), bs.wi, v.sh.frame.to_local(bs.wi))
        } else {
            let d = quad.sample(u_dir)?;
            (None, d, v.sh.frame.to_local(d))
        };
        let lv = LobeValues::at(bsdf, &v.sh, v.at_wo.as_ref(), wi);
        let lobe = match lobe {
            Some(k) => k,
            None => {
                // The lobe in proportion to its luminance, from what is left of u_lobe.
                if lv.eligible_sum <= 0.0 {
                    return None;
                }
                let mut u = (u_lobe - keep) / g.alpha * lv.eligible_sum;
                let n = bsdf.lobes().len();
                let mut chosen = None;
                for k in (0..n).filter(|&k| eligible(bsdf, k)) {
                    let l = luminance(lv.f[k]).max(0.0);
                    if l <= 0.0 {
                        continue;
                    }
                    chosen = Some(k);
                    if u < l {
                        break;
                    }
                    u -= l;
                }
                chosen?
            }
        };
        let f = lv.f[lobe];
        let pdfs = lv.parts(bsdf, lobe, quad.pdf(wi_world));
        let pdf = (1.0 - g.alpha) * pdfs.bsdf + g.alpha * pdfs.guide;
        if pdf <= 0.0 || f == Vec3A::ZERO {
            return None;
        }
        let bs = BsdfSample {
            lobe,
            wi: wi_world,
            weight: f / pdf,
            pdf,
            delta: false,
            eta: 1.0,
        };
        Some((bs, Some(pdfs)))
    }

    /// Records vertex `g` left by sample `bs` (with the mixture's parts `pdfs`) into
    /// the training path record (after `path.throughput` took the vertex's weight and
    /// before `path.depth` counts it).
    pub(super) fn record_vertex(
        &self,
        out: &mut Sink,
        path: &PathState,
        g: GuideAt,
        bs: &BsdfSample,
        pdfs: Option<GuidedPdfs>,
        before: Vec3A,
    ) {
        let r = &mut out.record;
        let pdf = bs.pdf;
        if !self.learn || r.n >= MAX_RECORDED || pdf.is_nan() || pdf <= 0.0 {
            return;
        }
        r.verts[r.n] = RecordedVertex {
            leaf: g.leaf,
            dir: bs.wi,
            pdf,
            // A medium vertex (no normal) records the radiance itself.
            cos: if path.prev_n == Vec3A::ZERO {
                1.0
            } else {
                bs.wi.dot(path.prev_n).abs()
            },
            f: bs.weight * pdf,
            pdfs,
            before: luminance(before),
            throughput: path.throughput,
            radiance: Vec3A::ZERO,
        };
        r.n += 1;
    }

    /// The path ended: its recorded vertices go into their leaves' recording trees.
    /// A record is the incident radiance times the receiver's |cos θ|, not the paper's
    /// radiance alone: at a diffuse vertex that is the integrand itself, so the guide
    /// learns the product with the cosine that the paper leaves to the BSDF half of
    /// the mixture (leaves are split by orientation, so one leaf's normals agree to
    /// within 55°). Measured on the room at 64 spp (seeds 1, 2): 12–17 % less error than
    /// unguided, against 3–4 % with radiance records (docs/performance.md).
    pub(super) fn flush_record(&self, out: &mut Sink) {
        if out.record.is_empty() {
            return;
        }
        if let (Some(tree), true) = (self.guide, self.learn) {
            for v in &out.record.verts[..out.record.n] {
                let leaf = tree.leaf(v.leaf);
                leaf.record(v.dir, luminance(v.radiance) * v.cos / v.pdf);
                if let Some(p) = v.pdfs {
                    let f_li = luminance(v.f * v.radiance) * v.before;
                    leaf.record_moments(f_li, p.bsdf, p.guide, v.pdf);
                }
            }
        }
        out.record.clear();
    }
}

/// Training passes that sample a sixteenth of the pixels (x and y multiples of 4): the
/// pilot that decides `auto`, 0.19 samples a pixel at about twice a render sample's
/// cost, so ~2 % of a 16-spp render where guiding does not pay.
const PILOT_PASSES: u32 = 2;
/// Under `auto` the render guides only if the pilot measured that the leaves' chosen
/// fractions lower the second moment (guided vertices' cost included) to below this
/// share of BSDF sampling's: a gain smaller than that would not pay back the rest of
/// training and the lookups in the render.
const AUTO_MIN_GAIN: f64 = 1.25;
/// Nor unless the pilot's last pass recorded at least this many vertices: on a 20×20
/// frame (25 pilot pixels, ~200 vertices over six orientation roots) one leaf's few
/// samples measured a gain of 1.27 that three more passes did not confirm (1.01), and a
/// guide there is not worth training anyway.
const AUTO_MIN_VERTICES: u64 = 4096;

/// The guide a render samples from, if it guides: `guiding_passes` training passes over
/// the frame (1, 2 samples a pixel on a sixteenth of the pixels, then 4, 8, … on all;
/// seeds of their own), each sampling what the one before learnt, then a check pass
/// (`CHECK_SPP` on all pixels) that measures the fractions again with the trees the
/// render samples, each leaf keeping the smaller (`SdTree::check_fractions`). Under `auto`, after
/// the first two the render goes on unguided unless they measured a gain (`SdTree::gain`).
/// The same scene and settings give the same tree and the same decision whatever the
/// thread count, the window or the farm part.
pub(super) fn train(scene: &crate::scene::Scene) -> Option<SdTree> {
    let settings = &scene.settings;
    let passes = settings.guiding_passes;
    if settings.guiding == GuidingMode::Off || passes == 0 {
        return None;
    }
    let (lo, hi) = scene.accel.bounds();
    let mut tree = SdTree::new(lo, hi);
    for k in 0..passes {
        let pilot = k < PILOT_PASSES;
        training_pass(scene, &tree, k, if pilot { 4 } else { 1 }, 1 << k);
        tree.end_pass(k);
        if k + 1 == PILOT_PASSES
            && settings.guiding == GuidingMode::Auto
            && (tree.gain < AUTO_MIN_GAIN || tree.vertices < AUTO_MIN_VERTICES)
        {
            return None;
        }
    }
    // The fractions were measured with the guides the last pass sampled, but the render
    // samples the ones it recorded: a short pass over the frame samples those and each
    // leaf keeps the smaller of the two fractions.
    if tree.guides() {
        training_pass(scene, &tree, passes, 1, CHECK_SPP);
        tree.check_fractions();
    }
    // Where no leaf chose to guide, the render is the unguided one, without lookups.
    tree.guides().then_some(tree)
}

/// Samples a pixel of the pass that checks the fractions against the guides the render
/// samples (`SdTree::check_fractions`), on every pixel. On the caustic stand-in
/// (benches/guiding/caustic.toml) the last pass's fractions made `on` 1.5x worse than
/// unguided (the guides recorded from heavy-tailed caustic paths are worse than the ones
/// the fractions were measured with); 1 sample a pixel left +13 %, 2 +5 %, and the
/// room kept its gain (benches/guiding/CAUSTIC.md).
const CHECK_SPP: u32 = 2;

/// Training pass `k` (its seed) with `spp` samples on every `step`-th row and column:
/// its paths record into `tree`'s recording trees and candidate fractions.
fn training_pass(scene: &crate::scene::Scene, tree: &SdTree, k: u32, step: u32, spp: u32) {
    let settings = &scene.settings;
    let (w, h) = (scene.camera.width, scene.camera.height);
    let mut tracer = Tracer::new(scene);
    tracer.guide = Some(tree);
    tracer.learn = true;
    tracer.seed = settings.seed ^ TRAINING_SEED.wrapping_add(k as u64);
    let stride = crate::film::Film::stride_with(scene.aovs.len(), scene.variance_aovs.len());
    (0..h)
        .into_par_iter()
        .filter(|y| y % step == 0)
        .for_each_init(
            || {
                (
                    crate::film::SampleAccumulator::with_squares(
                        scene.aovs.len(),
                        scene.variance_aovs.clone(),
                    ),
                    vec![0.0f32; stride],
                )
            },
            |(acc, run), y| {
                let mut out = Sink::new(acc);
                let mut nothing = |_: &Sink| {};
                for x in (0..w).step_by(step as usize) {
                    run.fill(0.0);
                    let job = super::pixel::PixelJob {
                        x,
                        y,
                        run,
                        first_sample: 0,
                        taken: 0,
                        spp,
                        after_sample: &mut nothing,
                        moments: None,
                    };
                    tracer.render_pixel(job, &mut out);
                }
            },
        );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aov;
    use crate::media::phase::HenyeyGreenstein;
    use crate::sampling::Rng;
    use crate::scene::{Scene, Source};
    use std::f32::consts::PI;

    /// Fog in a room whose lamp a plate hides from below: the fog under the plate is lit
    /// only by light that bounced, which its guide learns.
    const FOG: &str = r#"
[camera]
position = [0, 0, 3.5]
look_at = [0, 0, 0]
fov = 40
[film]
resolution = [48, 48]
[render]
max_depth = 6
atmosphere = "fog"
guiding = "on"
guiding_passes = 5
[media.fog]
sigma_s = [0.8, 0.8, 0.8]
g = 0.3
[materials.white]
type = "diffuse"
albedo = [0.8, 0.8, 0.8]
[[objects]]
name = "floor"
shape = "quad"
material = "white"
corners = [[-1, -1, 1], [1, -1, 1], [1, -1, -1], [-1, -1, -1]]
[[objects]]
name = "ceiling"
shape = "quad"
material = "white"
corners = [[-1, 1, -1], [1, 1, -1], [1, 1, 1], [-1, 1, 1]]
[[objects]]
name = "back"
shape = "quad"
material = "white"
corners = [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1]]
[[objects]]
name = "plate"
shape = "quad"
material = "white"
corners = [[-0.4, 0.6, -0.4], [0.4, 0.6, -0.4], [0.4, 0.6, 0.4], [-0.4, 0.6, 0.4]]
[[lights]]
type = "quad"
name = "lamp"
radiance = [30, 30, 30]
corners = [[-0.2, 0.62, -0.2], [-0.2, 0.62, 0.2], [0.2, 0.62, 0.2], [0.2, 0.62, -0.2]]
"#;

    /// A medium vertex in a leaf that guides samples directions with exactly the density
    /// light sampling weighs against (`medium_pdf`): the pdf it returns is that density,
    /// the density integrates to one over the sphere, and a histogram of 400,000 samples
    /// over 16 × 32 cells of (cos θ, φ) matches its integral over each cell.
    #[test]
    fn guided_medium_vertices_sample_the_density_light_sampling_weighs_against() {
        let desc = Source {
            name: "fog.toml".into(),
            text: FOG.into(),
            dir: Default::default(),
        }
        .parse()
        .unwrap();
        let scene = Scene::build(&desc, &aov::assemble(vec![])).unwrap();
        let tree = train(&scene).expect("the fog under the plate guides");
        let mut tracer = Tracer::new(&scene);
        tracer.guide = Some(&tree);
        // A point in the fog whose leaf guides, the most strongly found on a grid.
        let mut best: Option<(GuideAt, Vec3A)> = None;
        for i in 0..9 {
            for j in 0..9 {
                for k in 0..9 {
                    let p = Vec3A::new(i as f32, j as f32, k as f32) * 0.2 - Vec3A::splat(0.8);
                    let g = tracer.guide_in_medium(p).unwrap();
                    if g.alpha > best.map_or(0.0, |b| b.0.alpha) {
                        best = Some((g, p));
                    }
                }
            }
        }
        let (g, _) = best.expect("some fog leaf guides");
        let phase = HenyeyGreenstein::new(0.3);
        let dir = Vec3A::new(0.3, -0.8, 0.2).normalize();
        let density = |wi: Vec3A| tracer.medium_pdf(Some(g), phase.eval(dir, wi), wi);
        let to_dir = |c: f32, phi: f32| {
            let s = (1.0 - c * c).max(0.0).sqrt();
            Vec3A::new(s * phi.cos(), s * phi.sin(), c)
        };
        let (nc, np) = (16usize, 32usize);
        // Each cell's probability: the density on a 12 × 12 grid inside it.
        let sub = 12;
        let mut expected = vec![0.0f64; nc * np];
        for (cell, e) in expected.iter_mut().enumerate() {
            let (ci, pi) = (cell / np, cell % np);
            for a in 0..sub {
                for b in 0..sub {
                    let c = -1.0 + 2.0 * (ci as f32 + (a as f32 + 0.5) / sub as f32) / nc as f32;
                    let phi = 2.0 * PI * (pi as f32 + (b as f32 + 0.5) / sub as f32) / np as f32;
                    *e += density(to_dir(c, phi)) as f64;
                }
            }
            *e *= (2.0 / nc as f64) * (2.0 * std::f64::consts::PI / np as f64) / (sub * sub) as f64;
        }
        let total: f64 = expected.iter().sum();
        assert!((total - 1.0).abs() < 0.01, "∫ pdf = {total}");
        let n = 400_000;
        let mut counts = vec![0u32; nc * np];
        let mut rng = Rng::for_sample(17, 0, 0);
        for _ in 0..n {
            let u = Vec2::new(rng.next_f32(), rng.next_f32());
            let Some((wi, pdf, f, _)) =
                tracer.sample_medium_guided(g, &phase, dir, rng.next_f32(), u)
            else {
                continue;
            };
            assert!(
                (pdf - density(wi)).abs() <= 1e-4 * pdf,
                "{pdf} {}",
                density(wi)
            );
            assert!((f - phase.eval(dir, wi)).abs() <= 1e-6 * f);
            let ci = (((wi.z + 1.0) * 0.5 * nc as f32) as usize).min(nc - 1);
            let phi = wi.y.atan2(wi.x).rem_euclid(2.0 * PI);
            let pi = ((phi / (2.0 * PI) * np as f32) as usize).min(np - 1);
            counts[ci * np + pi] += 1;
        }
        // Pearson's statistic over the cells expecting at least 5 samples.
        let (mut chi2, mut dof) = (0.0, 0);
        for (c, e) in counts.iter().zip(&expected) {
            let e = e * n as f64;
            if e >= 5.0 {
                chi2 += (*c as f64 - e).powi(2) / e;
                dof += 1;
            }
        }
        // The 1e-6 quantile of χ² with dof ≈ 500 lies near dof + 5.3·√(2·dof).
        let limit = dof as f64 + 5.3 * (2.0 * dof as f64).sqrt();
        assert!(chi2 < limit, "χ² {chi2} over {dof} cells (limit {limit})");
    }
}
