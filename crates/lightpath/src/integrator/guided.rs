//! Path guiding in the integrator (Müller, Gross and Novák 2017, "Practical Path
//! Guiding for Efficient Light-Transport Simulation"; the SD-tree is guiding/): the
//! training passes, the record of a path's vertices, and one-sample MIS between BSDF
//! and guide sampling with the paper's fixed selection probability ½.
//!
//! The LPE needs one lobe event per vertex, so guide sampling samples a pair: a
//! direction from the quadtree, then one of the eligible lobes (non-delta reflection or
//! diffuse lobes) in proportion to the luminance of its `f` there. The pdf of a
//! (lobe, direction) pair mixes BSDF sampling's (`eval_lobe`) and the guide's; every
//! lobe's estimate stays unbiased on its own, so partitions still sum to the beauty.
//! Light sampling weighs its samples against the same mixture.

use super::path::{PathState, Vertex};
use super::{Sink, Tracer};
use crate::guiding::SdTree;
use crate::light::luminance;
use crate::material::{Bsdf, BsdfSample, Shading, MAX_LOBES};
use glam::{Vec2, Vec3A};
use lpe::ScatterClass;
use rayon::prelude::*;

/// The probability of guide sampling at a guided vertex (the paper's baseline).
const GUIDE_FRACTION: f32 = 0.5;
/// Lobe events a Bsdf can have.
const MAX_EVENTS: usize = 2 * MAX_LOBES;
/// Vertices of one path that are recorded for training (later ones are not).
pub(super) const MAX_RECORDED: usize = 16;
/// The seed of training pass `k` is the render's mixed with this and `k`, so training
/// never reuses the render's own numbers.
const TRAINING_SEED: u64 = 0x6775_6964_696e_6721;

/// Guiding at one vertex: the spatial leaf there and the probability of guide sampling
/// (0 where the leaf has learnt nothing yet, in the first training pass).
#[derive(Clone, Copy, Debug)]
pub(super) struct GuideAt {
    pub leaf: u32,
    pub alpha: f32,
}

/// A recorded vertex of a path: where it left, along which direction with which pdf,
/// the throughput after it, and the radiance that came back along it so far.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct RecordedVertex {
    leaf: u32,
    dir: Vec3A,
    pdf: f32,
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
    /// before it receives its share, the radiance arriving along its direction.
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
    pub fn at(bsdf: &Bsdf, sh: &Shading, wi: Vec3A) -> LobeValues {
        let mut lv = LobeValues {
            f: [Vec3A::ZERO; MAX_EVENTS],
            pdf: [0.0; MAX_EVENTS],
            eligible_sum: 0.0,
        };
        for (k, tag) in bsdf.lobes().iter().enumerate() {
            if tag.delta {
                continue;
            }
            let (f, pdf) = bsdf.eval_lobe(k, sh, wi);
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
        let q = if eligible(bsdf, k) && self.eligible_sum > 0.0 {
            luminance(self.f[k]).max(0.0) / self.eligible_sum
        } else {
            0.0
        };
        (1.0 - alpha) * self.pdf[k] + alpha * guide_pdf * q
    }
}

impl Tracer<'_> {
    /// Guiding at vertex `v`, if the render guides and its Bsdf is guided.
    #[inline]
    pub(super) fn guide_at(&self, bsdf: &Bsdf, p: Vec3A) -> Option<GuideAt> {
        let tree = self.guide?;
        if !guidable(bsdf) {
            return None;
        }
        let leaf = tree.leaf_index(p);
        let alpha = if tree.leaf(leaf).sampling.total() > 0.0 {
            GUIDE_FRACTION
        } else {
            0.0
        };
        Some(GuideAt { leaf, alpha })
    }

    /// One-sample MIS of BSDF and guide sampling at a guided vertex (`g.alpha > 0`).
    pub(super) fn sample_guided(
        &self,
        v: &Vertex,
        g: GuideAt,
        u_lobe: f32,
        u_dir: Vec2,
    ) -> Option<BsdfSample> {
        let tree = self.guide?;
        let quad = &tree.leaf(g.leaf).sampling;
        let bsdf = v.bsdf;
        let keep = 1.0 - g.alpha;
        let (lobe, wi_world, wi) = if u_lobe < keep {
            let u = (u_lobe / keep).min(1.0 - f32::EPSILON / 2.0);
            let bs = bsdf.sample(&v.sh, u, u_dir)?;
            if bs.delta {
                // The guide never samples a delta lobe's direction.
                return Some(BsdfSample {
                    lobe: bs.lobe,
                    wi: bs.wi,
                    weight: bs.weight / keep,
                    pdf: bs.pdf * keep,
                    delta: true,
                    eta: bs.eta,
                });
            }
            (Some(bs.lobe), bs.wi, v.sh.frame.to_local(bs.wi))
        } else {
            let d = quad.sample(u_dir)?;
            (None, d, v.sh.frame.to_local(d))
        };
        let lv = LobeValues::at(bsdf, &v.sh, wi);
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
        let pdf = lv.mixed_pdf(bsdf, lobe, g.alpha, quad.pdf(wi_world));
        if pdf <= 0.0 || f == Vec3A::ZERO {
            return None;
        }
        Some(BsdfSample {
            lobe,
            wi: wi_world,
            weight: f / pdf,
            pdf,
            delta: false,
            eta: 1.0,
        })
    }

    /// Records vertex `g` left along `dir` with `pdf` into the training path record
    /// (after `path.throughput` took the vertex's weight).
    pub(super) fn record_vertex(
        &self,
        out: &mut Sink,
        path: &PathState,
        g: GuideAt,
        dir: Vec3A,
        pdf: f32,
    ) {
        let r = &mut out.record;
        if !self.learn || r.n >= MAX_RECORDED || pdf.is_nan() || pdf <= 0.0 {
            return;
        }
        r.verts[r.n] = RecordedVertex {
            leaf: g.leaf,
            dir,
            pdf,
            throughput: path.throughput,
            radiance: Vec3A::ZERO,
        };
        r.n += 1;
    }

    /// The path ended: its recorded vertices go into their leaves' recording trees.
    pub(super) fn flush_record(&self, out: &mut Sink) {
        if out.record.is_empty() {
            return;
        }
        if let (Some(tree), true) = (self.guide, self.learn) {
            for v in &out.record.verts[..out.record.n] {
                let l = luminance(v.radiance);
                tree.leaf(v.leaf).record(v.dir, l / v.pdf);
            }
        }
        out.record.clear();
    }
}

/// The guide a render samples from: `passes` training passes over the whole frame
/// (1, 2, 4, … samples a pixel, seeds of their own), each sampling what the one before
/// learnt. The same scene and settings give the same tree whatever the thread count,
/// the window or the farm part.
pub(super) fn train(scene: &crate::scene::Scene, passes: u32) -> SdTree {
    let (lo, hi) = scene.accel.bounds();
    let mut tree = SdTree::new(lo, hi);
    let (w, h) = (scene.camera.width, scene.camera.height);
    for k in 0..passes {
        let mut tracer = Tracer::new(scene);
        tracer.guide = Some(&tree);
        tracer.learn = true;
        tracer.seed = scene.settings.seed ^ TRAINING_SEED.wrapping_add(k as u64);
        let stride = crate::film::Film::stride_with(scene.aovs.len(), scene.variance_aovs.len());
        (0..h).into_par_iter().for_each_init(
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
                for x in 0..w {
                    run.fill(0.0);
                    let job = super::pixel::PixelJob {
                        x,
                        y,
                        run,
                        first_sample: 0,
                        taken: 0,
                        spp: 1 << k,
                        after_sample: &mut nothing,
                        moments: None,
                    };
                    tracer.render_pixel(job, &mut out);
                }
            },
        );
        tree.end_pass(k);
    }
    tree
}
