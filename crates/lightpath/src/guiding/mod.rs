//! Path guiding with the SD-tree of Müller, Gross and Novák 2017, "Practical Path
//! Guiding for Efficient Light-Transport Simulation": a binary kd-tree over the scene's
//! bounds whose leaves each hold a directional quadtree (quadtree.rs) of the incident
//! radiance there. Training makes passes of 1, 2, 4, … samples a pixel; each pass
//! samples from the trees the previous one froze and records into a refined copy:
//! a spatial leaf is split in two (cycling x, y, z) when it saw more than
//! c·√(2^k) path vertices in pass k (c = 3000, a quarter of the paper's), a directional
//! quadrant while it holds more than ρ = 1 % of its tree's energy. Unlike the paper,
//! the spatial tree has one root per orientation of the shading normal and one for
//! scattering vertices in media ([`ORIENTATIONS`]): the quadtrees cover the whole
//! sphere, so a medium vertex samples them as a surface does (Cycles guides volume
//! scattering through Open PGL likewise, `use_volume_guiding`).
//!
//! What one pass records is a sum of integers (fixed point, quadtree.rs), so the trees
//! do not depend on the number of threads or the order rows finish in. The integrator
//! (integrator/guided.rs) mixes BSDF and guide sampling one sample at a time with a
//! probability each leaf learns (docs/performance.md, "Path guiding").

pub mod quadtree;

use glam::Vec3A;
pub use quadtree::{Quadtree, Recording};
use std::sync::atomic::{AtomicU64, Ordering};

/// Whether a render guides its paths: always, never, or where training measured that
/// it pays (integrator/guided.rs, `train`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum GuidingMode {
    #[default]
    Auto,
    On,
    Off,
}

impl GuidingMode {
    pub const NAMES: [&'static str; 3] = ["auto", "on", "off"];

    pub fn parse(s: &str) -> Option<GuidingMode> {
        match s {
            "auto" => Some(GuidingMode::Auto),
            "on" => Some(GuidingMode::On),
            "off" => Some(GuidingMode::Off),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            GuidingMode::Auto => "auto",
            GuidingMode::On => "on",
            GuidingMode::Off => "off",
        }
    }
}

/// The spatial threshold constant c: the paper's 12000 is for passes over megapixel
/// frames; on the 128² to 256² frames measured here it left a few dozen cells, each
/// mixing surfaces that face apart, and no leaf chose to guide (docs/performance.md,
/// "Path guiding"). A quarter of it gave 7–8 % less error on the indirect box and room.
const SPATIAL_C: f64 = 3000.0;
/// The paper's directional energy threshold ρ.
pub const RHO: f32 = 0.01;
/// Most leaves of the spatial tree: with [`quadtree::MAX_NODES`] this bounds the guide
/// at 4096 × 512 × 80 bytes ≈ 168 MB (typical trees are a few MB).
pub const MAX_LEAVES: usize = 4096;

/// The guide-sampling probabilities a leaf chooses among (Müller et al. 2019,
/// "Practical Path Guiding in Production", learn this fraction per leaf by stochastic
/// gradient descent on the estimator's second moment; here the same objective is
/// estimated for each candidate from one pass's sums, which keeps training independent
/// of the order threads record in). At most 0.9: some BSDF sampling always remains.
pub const FRACTIONS: [f32; 7] = [0.0, 0.15, 0.3, 0.45, 0.6, 0.75, 0.9];
/// The fraction of a leaf that has not measured its candidates yet (the paper's ½).
pub const DEFAULT_FRACTION: f32 = 0.5;
/// A guided vertex costs this much more than a BSDF-sampled one (the guide's lookups
/// and every lobe evaluated; about 1.4x a sample measured on the indirect box where
/// most vertices are guided): a fraction above 0 must lower the second moment below
/// 1 / this of BSDF sampling's to be chosen.
const GUIDED_COST: f64 = 1.15;
/// A leaf the check pass (`SdTree::check_fractions`) reached fewer times than this
/// keeps its fraction: the check has a quarter of the last pass's samples or fewer,
/// and on a 32² frame of fog its 281 vertices in the one leaf that guided made that
/// leaf stop (tests/it/guiding.rs); the caustic's floor leaves see thousands.
const CHECK_MIN_VERTICES: u64 = 1024;
/// Fixed-point scale of the candidates' second-moment sums.
const MOMENT_FIXED: f64 = (1u64 << 24) as f64;
/// The largest single second-moment term (fixed point), so that sums cannot overflow.
const MOMENT_MAX: f64 = (1u64 << 40) as f64;

/// A leaf of the spatial tree: the quadtree sampled in this pass, the one recorded
/// into, how many vertices recorded here, the probability of guide sampling here and
/// the second moments of each candidate probability (fixed point).
#[derive(Debug)]
pub struct Leaf {
    pub sampling: Quadtree,
    pub recording: Recording,
    count: AtomicU64,
    pub fraction: f32,
    moments: [AtomicU64; FRACTIONS.len()],
}

impl Clone for Leaf {
    fn clone(&self) -> Self {
        Leaf {
            sampling: self.sampling.clone(),
            recording: self.recording.clone(),
            count: AtomicU64::new(self.count.load(Ordering::Relaxed)),
            fraction: self.fraction,
            moments: std::array::from_fn(|i| {
                AtomicU64::new(self.moments[i].load(Ordering::Relaxed))
            }),
        }
    }
}

impl Leaf {
    fn new() -> Leaf {
        Leaf {
            sampling: Quadtree::default(),
            recording: Recording::default(),
            count: AtomicU64::new(0),
            fraction: DEFAULT_FRACTION,
            moments: Default::default(),
        }
    }

    /// Records what a vertex sampled with this leaf's guide tells about the candidate
    /// fractions: the estimate's integrand `f_li` (luminance of f·Li) times the path's
    /// throughput before the vertex, the BSDF's and the guide's densities of the (lobe,
    /// direction) pair and the pdf it was actually sampled with. Each candidate α adds
    /// f_li² / (q_α · pdf), an unbiased estimate of the second moment ∫ f_li² / q_α
    /// had the vertex sampled with q_α: its share of the pixel's second moment.
    pub fn record_moments(&self, f_li: f32, bsdf_pdf: f32, guide_pdf: f32, pdf: f32) {
        if !(f_li.is_finite() && f_li > 0.0 && pdf > 0.0 && pdf.is_finite()) {
            return;
        }
        let f2 = f_li as f64 * f_li as f64 / pdf as f64;
        for (m, &a) in self.moments.iter().zip(&FRACTIONS) {
            let q = (1.0 - a as f64) * bsdf_pdf as f64 + a as f64 * guide_pdf as f64;
            let term = if q > 0.0 {
                (f2 / q * MOMENT_FIXED).min(MOMENT_MAX)
            } else {
                MOMENT_MAX
            };
            m.fetch_add(term as u64, Ordering::Relaxed);
        }
    }

    /// The candidate fraction of least second moment times cost (the current one if
    /// nothing was measured), that cost-weighted moment and BSDF sampling's.
    fn best_fraction(&self) -> (f32, f64, f64) {
        let m: [f64; FRACTIONS.len()] =
            std::array::from_fn(|i| self.moments[i].load(Ordering::Relaxed) as f64);
        if m[0] <= 0.0 {
            return (self.fraction, 0.0, 0.0);
        }
        let mut best = (m[0], 0.0);
        for (i, &a) in FRACTIONS.iter().enumerate().skip(1) {
            if m[i] * GUIDED_COST < best.0 {
                best = (m[i] * GUIDED_COST, a);
            }
        }
        (best.1, best.0, m[0])
    }

    /// Records a vertex whose path arrived along unit `dir` with `value` = incident
    /// radiance (luminance) over the pdf the direction was sampled with.
    pub fn record(&self, dir: Vec3A, value: f32) {
        self.count.fetch_add(1, Ordering::Relaxed);
        if value.is_finite() && value > 0.0 {
            self.recording.record(dir, value);
        }
    }
}

#[derive(Clone, Copy, Debug)]
enum SNode {
    /// Split at the middle of the node's box along `axis`; children at `first` and
    /// `first + 1`.
    Inner {
        axis: u8,
        first: u32,
    },
    Leaf(u32),
}

/// The spatial tree's roots: one per orientation class of the shading normal (its
/// dominant axis and that axis's sign, [`orientation`]), so that surfaces a few
/// millimetres apart but facing apart (a ceiling and the baffle below it, a baffle's
/// top and bottom) never share a leaf, and one for scattering vertices in media
/// ([`MEDIUM`]), whose incident light comes from the whole sphere and whose records
/// carry no cosine. The paper keys leaves by position alone; in cells that mixed facing
/// surfaces half of the guide's samples went below the surface and no leaf there chose
/// to guide (docs/performance.md, "Path guiding").
pub const ORIENTATIONS: usize = 7;

/// The root of medium vertices: what [`orientation`] gives the zero normal.
pub const MEDIUM: usize = 6;

/// The orientation class of unit normal `n`: 2 × its dominant axis, + 1 if that
/// component is negative; [`MEDIUM`] for the zero normal (a vertex in a medium).
#[inline]
pub fn orientation(n: Vec3A) -> usize {
    if n == Vec3A::ZERO {
        return MEDIUM;
    }
    let a = n.abs();
    let axis = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    2 * axis + (n[axis] < 0.0) as usize
}

/// The SD-tree.
#[derive(Clone, Debug)]
pub struct SdTree {
    lo: Vec3A,
    size: Vec3A,
    nodes: Vec<SNode>,
    /// Each node's depth (its split axis is depth mod 3).
    depth: Vec<u8>,
    leaves: Vec<Leaf>,
    /// Each leaf's probability of guide sampling, 0 where its guide learnt nothing: a
    /// dense copy, so that a vertex whose leaf does not guide never touches its trees.
    alphas: Vec<f32>,
    /// What the last pass measured over all leaves: the second moment with each leaf's
    /// chosen fraction (guided vertices' cost included) over BSDF sampling's alone;
    /// 1 before anything was measured.
    pub gain: f64,
    /// How many path vertices the last pass recorded.
    pub vertices: u64,
}

impl SdTree {
    /// One leaf per orientation over the cube around `(lo, hi)` (the scene's box; a unit
    /// cube if it is empty or not finite).
    pub fn new(lo: Vec3A, hi: Vec3A) -> SdTree {
        let (lo, hi) = if lo.is_finite() && hi.is_finite() && lo.cmple(hi).all() {
            (lo, hi)
        } else {
            (Vec3A::ZERO, Vec3A::ONE)
        };
        // A cube, so that cycling the split axes keeps cells from getting thin; a
        // margin so that points on the box's faces fall inside.
        let extent = (hi - lo).max_element().max(1e-3) * 1.01;
        let centre = (lo + hi) * 0.5;
        SdTree {
            lo: centre - Vec3A::splat(extent * 0.5),
            size: Vec3A::splat(extent),
            nodes: (0..ORIENTATIONS as u32).map(SNode::Leaf).collect(),
            depth: vec![0; ORIENTATIONS],
            leaves: (0..ORIENTATIONS).map(|_| Leaf::new()).collect(),
            alphas: vec![0.0; ORIENTATIONS],
            gain: 1.0,
            vertices: 0,
        }
    }

    /// The index of the leaf whose cell holds `p` among those of normal `normal`'s
    /// orientation (a point outside goes to the nearest cell across the split planes).
    #[inline]
    pub fn leaf_index(&self, p: Vec3A, normal: Vec3A) -> u32 {
        let mut p = ((p - self.lo) / self.size).clamp(Vec3A::ZERO, Vec3A::ONE);
        let mut n = orientation(normal);
        loop {
            match self.nodes[n] {
                SNode::Leaf(l) => return l,
                SNode::Inner { axis, first } => {
                    let a = axis as usize;
                    let upper = p[a] >= 0.5;
                    p[a] = p[a] * 2.0 - upper as u32 as f32;
                    n = first as usize + upper as usize;
                }
            }
        }
    }

    #[inline]
    pub fn leaf(&self, index: u32) -> &Leaf {
        &self.leaves[index as usize]
    }

    pub fn leaf_count(&self) -> usize {
        self.leaves.len()
    }

    /// The probability of guide sampling in leaf `index` (0: BSDF sampling alone).
    #[inline]
    pub fn alpha(&self, index: u32) -> f32 {
        self.alphas[index as usize]
    }

    /// Whether any leaf samples its guide.
    pub fn guides(&self) -> bool {
        self.alphas.iter().any(|&a| a > 0.0)
    }

    /// Total quadtree nodes (sampling trees), for reporting and memory checks.
    pub fn node_count(&self) -> usize {
        self.leaves.iter().map(|l| l.sampling.node_count()).sum()
    }

    /// After a pass that sampled the trees the render will sample (and recorded
    /// nothing that is used but its candidate moments): each leaf keeps the smaller of
    /// the fraction the last training pass chose, measured with the guide that pass
    /// sampled, and the one this pass measured with the guide itself. A guide learnt
    /// from few, heavy-tailed records can be worse than the one before it
    /// (docs/performance.md, "Path guiding").
    pub fn check_fractions(&mut self) {
        for leaf in &mut self.leaves {
            if leaf.count.load(Ordering::Relaxed) >= CHECK_MIN_VERTICES {
                let (fraction, _, _) = leaf.best_fraction();
                leaf.fraction = leaf.fraction.min(fraction);
            }
        }
        self.update_alphas();
    }

    /// The dense copy of the fractions, 0 where a leaf's guide learnt nothing.
    fn update_alphas(&mut self) {
        self.alphas = self
            .leaves
            .iter()
            .map(|l| {
                if l.sampling.total() > 0.0 {
                    l.fraction
                } else {
                    0.0
                }
            })
            .collect();
    }

    /// Ends training pass `k` (0-based): what it recorded becomes what the next pass
    /// samples, leaves that saw many vertices are split, and every leaf's recording
    /// tree is refined from its new sampling tree.
    pub fn end_pass(&mut self, k: u32) {
        let (mut chosen, mut bsdf) = (0.0, 0.0);
        for leaf in &mut self.leaves {
            leaf.sampling = leaf.recording.freeze();
            let (fraction, m, m0) = leaf.best_fraction();
            leaf.fraction = fraction;
            (chosen, bsdf) = (chosen + m, bsdf + m0);
        }
        self.gain = if bsdf > 0.0 { bsdf / chosen } else { 1.0 };
        self.vertices = self
            .leaves
            .iter()
            .map(|l| l.count.load(Ordering::Relaxed))
            .sum();
        let threshold = SPATIAL_C * 2f64.powi(k as i32).sqrt();
        // Breadth over the node list: the children a split appends are visited too.
        let mut n = 0;
        while n < self.nodes.len() {
            if let SNode::Leaf(l) = self.nodes[n] {
                let count = self.leaves[l as usize].count.load(Ordering::Relaxed);
                if count as f64 > threshold && self.leaves.len() < MAX_LEAVES {
                    let first = self.nodes.len() as u32;
                    let half = count / 2;
                    let mut upper = self.leaves[l as usize].clone();
                    upper.count = AtomicU64::new(half);
                    self.leaves[l as usize].count = AtomicU64::new(half);
                    let upper_index = self.leaves.len() as u32;
                    self.leaves.push(upper);
                    self.nodes.push(SNode::Leaf(l));
                    self.nodes.push(SNode::Leaf(upper_index));
                    let d = self.depth[n];
                    self.depth.extend([d + 1, d + 1]);
                    self.nodes[n] = SNode::Inner { axis: d % 3, first };
                }
            }
            n += 1;
        }
        for leaf in &mut self.leaves {
            leaf.recording = leaf.sampling.refined(RHO);
            leaf.count = AtomicU64::new(0);
            leaf.moments = Default::default();
        }
        self.update_alphas();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    /// A normal of each surface orientation class, in class order.
    const AXES: [Vec3A; 6] = [
        Vec3A::X,
        Vec3A::NEG_X,
        Vec3A::Y,
        Vec3A::NEG_Y,
        Vec3A::Z,
        Vec3A::NEG_Z,
    ];

    #[test]
    fn busy_leaves_split_and_lookups_land_in_their_cells() {
        let mut tree = SdTree::new(Vec3A::ZERO, Vec3A::splat(2.0));
        let mut rng = Rng::for_sample(5, 0, 0);
        // Records only in the corner x, y, z < 0.5: only the cells holding it split
        // further.
        for _ in 0..100_000 {
            let p = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 0.5;
            let l = tree.leaf_index(p, Vec3A::Z);
            tree.leaf(l).record(Vec3A::Z, 1.0);
        }
        tree.end_pass(0);
        // Every leaf split from the root inherited what the root learnt.
        let far = tree.leaf_index(Vec3A::splat(1.9), Vec3A::Z);
        assert!(tree.leaf(far).sampling.total() > 0.0);
        // A second pass, recorded into the split tree, splits it further.
        for _ in 0..100_000 {
            let p = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 0.5;
            tree.leaf(tree.leaf_index(p, Vec3A::Z))
                .record(Vec3A::Z, 1.0);
        }
        let before = tree.leaf_count();
        tree.end_pass(1);
        assert!(tree.leaf_count() > before, "{before}");
        assert!(tree.leaf_count() > 4, "{}", tree.leaf_count());
        let far = tree.leaf_index(Vec3A::splat(1.9), Vec3A::Z);
        let near = tree.leaf_index(Vec3A::splat(0.1), Vec3A::Z);
        assert_ne!(far, near);
        // The corner's leaves learnt the +z records of the second pass.
        assert!(tree.leaf(near).sampling.pdf(Vec3A::Z) > 1.0);
    }

    /// Samples drawn by BSDF sampling (uniform on [0, 1) here) of an integrand bright on
    /// a tenth of the domain: a guide proportional to it earns the largest fraction, a
    /// guide that avoids it earns none.
    #[test]
    fn leaves_choose_the_fraction_that_lowers_the_second_moment() {
        let integrand = |x: f32| if x < 0.1 { 1.0 } else { 0.01 };
        let total = 0.1 + 0.9 * 0.01;
        let mut rng = Rng::for_sample(11, 0, 0);
        let (good, bad) = (Leaf::new(), Leaf::new());
        for _ in 0..20_000 {
            let x = rng.next_f32();
            let f = integrand(x);
            good.record_moments(f, 1.0, f / total, 1.0);
            let avoid = if x < 0.1 { 0.0 } else { 1.0 / 0.9 };
            bad.record_moments(f, 1.0, avoid, 1.0);
        }
        assert_eq!(good.best_fraction().0, *FRACTIONS.last().unwrap());
        assert_eq!(bad.best_fraction().0, 0.0);
        // Nothing recorded: the leaf keeps its fraction.
        assert_eq!(Leaf::new().best_fraction().0, DEFAULT_FRACTION);
    }

    /// The check pass (`check_fractions`) keeps each leaf's smaller fraction: a leaf
    /// whose last pass chose to guide stops where the guide it will sample measured
    /// worse than BSDF sampling, and a leaf that chose not to guide does not start.
    #[test]
    fn the_check_pass_keeps_the_smaller_fraction() {
        let integrand = |x: f32| if x < 0.1 { 1.0 } else { 0.01 };
        let total = 0.1 + 0.9 * 0.01;
        let good = |x: f32| integrand(x) / total;
        let bad = |x: f32| if x < 0.1 { 0.0 } else { 1.0 / 0.9 };
        let mut tree = SdTree::new(Vec3A::ZERO, Vec3A::ONE);
        let p = Vec3A::splat(0.5);
        // Fewer records than split a leaf: the indices stay valid.
        let record =
            |tree: &SdTree, seed: u64, up: &dyn Fn(f32) -> f32, down: &dyn Fn(f32) -> f32| {
                let mut rng = Rng::for_sample(seed, 0, 0);
                for _ in 0..2000 {
                    let x = rng.next_f32();
                    let f = integrand(x);
                    let (u, d) = (tree.leaf_index(p, Vec3A::Z), tree.leaf_index(p, -Vec3A::Z));
                    tree.leaf(u).record(Vec3A::Z, f);
                    tree.leaf(d).record(-Vec3A::Z, f);
                    tree.leaf(u).record_moments(f, 1.0, up(x), 1.0);
                    tree.leaf(d).record_moments(f, 1.0, down(x), 1.0);
                }
            };
        record(&tree, 3, &good, &bad);
        tree.end_pass(0);
        let (u, d) = (tree.leaf_index(p, Vec3A::Z), tree.leaf_index(p, -Vec3A::Z));
        assert_eq!(tree.alpha(u), *FRACTIONS.last().unwrap());
        assert_eq!(tree.alpha(d), 0.0);
        // The guides the render would sample measure the other way round.
        record(&tree, 4, &bad, &good);
        tree.check_fractions();
        assert_eq!(tree.alpha(u), 0.0);
        assert_eq!(tree.alpha(d), 0.0);
        assert!(!tree.guides());
    }

    /// Points a millimetre apart on surfaces facing apart (a ceiling and a plate under
    /// it) land in different leaves however coarse the tree, and learn apart.
    #[test]
    fn opposite_orientations_never_share_a_leaf() {
        let mut tree = SdTree::new(Vec3A::splat(-1.0), Vec3A::ONE);
        let (p, q) = (Vec3A::new(0.1, 0.8, 0.1), Vec3A::new(0.1, 0.801, 0.1));
        let (up, down) = (tree.leaf_index(p, Vec3A::Y), tree.leaf_index(q, -Vec3A::Y));
        assert_ne!(up, down);
        tree.leaf(up).record(Vec3A::Y, 1.0);
        tree.leaf(down).record(-Vec3A::Y, 1.0);
        tree.end_pass(0);
        let up = tree.leaf(tree.leaf_index(p, Vec3A::Y));
        assert!(up.sampling.pdf(Vec3A::Y) > 0.3);
        assert_eq!(up.sampling.pdf(-Vec3A::Y), 0.0);
        // Each of the six classes is the dominant axis and its sign.
        let classes: Vec<usize> = AXES.iter().map(|&n| orientation(n)).collect();
        assert_eq!(classes, [0, 1, 2, 3, 4, 5]);
        assert_eq!(orientation(Vec3A::new(0.3, -0.9, 0.3).normalize()), 3);
    }

    /// A point in a medium (zero normal) has leaves of its own: fog right above a floor
    /// never shares the floor's guide, whose records are cosine-weighted and hemispherical.
    #[test]
    fn medium_vertices_have_a_root_of_their_own() {
        let mut tree = SdTree::new(Vec3A::splat(-1.0), Vec3A::ONE);
        let p = Vec3A::new(0.2, -0.99, 0.1);
        let fog = tree.leaf_index(p, Vec3A::ZERO);
        let surfaces: Vec<u32> = AXES.iter().map(|&n| tree.leaf_index(p, n)).collect();
        assert!(!surfaces.contains(&fog), "{fog} {surfaces:?}");
        assert_eq!(orientation(Vec3A::ZERO), MEDIUM);
        // Records from below the floor's plane stay the fog's.
        for _ in 0..10 {
            tree.leaf(fog).record(-Vec3A::Y, 1.0);
        }
        tree.end_pass(0);
        let fog = tree.leaf(tree.leaf_index(p, Vec3A::ZERO));
        assert!(fog.sampling.pdf(-Vec3A::Y) > 0.3);
        let floor = tree.leaf(tree.leaf_index(p, Vec3A::Y));
        assert_eq!(floor.sampling.total(), 0.0);
    }

    #[test]
    fn bad_bounds_give_a_unit_cube() {
        let tree = SdTree::new(Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY));
        assert_eq!(tree.leaf_index(Vec3A::splat(f32::NAN), Vec3A::Z), 4);
    }
}
