//! Path guiding with the SD-tree of Müller, Gross and Novák 2017, "Practical Path
//! Guiding for Efficient Light-Transport Simulation": a binary kd-tree over the scene's
//! bounds whose leaves each hold a directional quadtree (quadtree.rs) of the incident
//! radiance there. Training makes passes of 1, 2, 4, … samples a pixel; each pass
//! samples from the trees the previous one froze and records into a refined copy:
//! a spatial leaf is split in two (cycling x, y, z) when it saw more than
//! c·√(2^k) path vertices in pass k (c = 12000, the paper's), a directional quadrant
//! while it holds more than ρ = 1 % of its tree's energy.
//!
//! What one pass records is a sum of integers (fixed point, quadtree.rs), so the trees
//! do not depend on the number of threads or the order rows finish in. The integrator
//! (integrator/guided.rs) mixes BSDF and guide sampling one sample at a time with a
//! fixed probability, the paper's baseline (docs/performance.md, "Path guiding").

pub mod quadtree;

use glam::Vec3A;
pub use quadtree::{Quadtree, Recording};
use std::sync::atomic::{AtomicU64, Ordering};

/// The paper's spatial threshold constant c.
const SPATIAL_C: f64 = 12000.0;
/// The paper's directional energy threshold ρ.
pub const RHO: f32 = 0.01;
/// Most leaves of the spatial tree: with [`quadtree::MAX_NODES`] this bounds the guide
/// at 4096 × 512 × 80 bytes ≈ 168 MB (typical trees are a few MB).
pub const MAX_LEAVES: usize = 4096;

/// A leaf of the spatial tree: the quadtree sampled in this pass, the one recorded
/// into, and how many vertices recorded here.
#[derive(Debug)]
pub struct Leaf {
    pub sampling: Quadtree,
    pub recording: Recording,
    count: AtomicU64,
}

impl Clone for Leaf {
    fn clone(&self) -> Self {
        Leaf {
            sampling: self.sampling.clone(),
            recording: self.recording.clone(),
            count: AtomicU64::new(self.count.load(Ordering::Relaxed)),
        }
    }
}

impl Leaf {
    fn new() -> Leaf {
        Leaf {
            sampling: Quadtree::default(),
            recording: Recording::default(),
            count: AtomicU64::new(0),
        }
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

/// The SD-tree.
#[derive(Clone, Debug)]
pub struct SdTree {
    lo: Vec3A,
    size: Vec3A,
    nodes: Vec<SNode>,
    /// Each node's depth (its split axis is depth mod 3).
    depth: Vec<u8>,
    leaves: Vec<Leaf>,
}

impl SdTree {
    /// One leaf over the cube around `(lo, hi)` (the scene's box; a unit cube if it is
    /// empty or not finite).
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
            nodes: vec![SNode::Leaf(0)],
            depth: vec![0],
            leaves: vec![Leaf::new()],
        }
    }

    /// The index of the leaf whose cell holds `p` (a point outside goes to the nearest
    /// cell across the split planes).
    #[inline]
    pub fn leaf_index(&self, p: Vec3A) -> u32 {
        let mut p = ((p - self.lo) / self.size).clamp(Vec3A::ZERO, Vec3A::ONE);
        let mut n = 0usize;
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

    /// Total quadtree nodes (sampling trees), for reporting and memory checks.
    pub fn node_count(&self) -> usize {
        self.leaves.iter().map(|l| l.sampling.node_count()).sum()
    }

    /// Ends training pass `k` (0-based): what it recorded becomes what the next pass
    /// samples, leaves that saw many vertices are split, and every leaf's recording
    /// tree is refined from its new sampling tree.
    pub fn end_pass(&mut self, k: u32) {
        for leaf in &mut self.leaves {
            leaf.sampling = leaf.recording.freeze();
        }
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
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    #[test]
    fn busy_leaves_split_and_lookups_land_in_their_cells() {
        let mut tree = SdTree::new(Vec3A::ZERO, Vec3A::splat(2.0));
        let mut rng = Rng::for_sample(5, 0, 0);
        // Records only in the corner x, y, z < 0.5: only the cells holding it split
        // further.
        for _ in 0..100_000 {
            let p = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 0.5;
            let l = tree.leaf_index(p);
            tree.leaf(l).record(Vec3A::Z, 1.0);
        }
        tree.end_pass(0);
        // Every leaf split from the root inherited what the root learnt.
        let far = tree.leaf_index(Vec3A::splat(1.9));
        assert!(tree.leaf(far).sampling.total() > 0.0);
        // A second pass, recorded into the split tree, splits it further.
        for _ in 0..100_000 {
            let p = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 0.5;
            tree.leaf(tree.leaf_index(p)).record(Vec3A::Z, 1.0);
        }
        let before = tree.leaf_count();
        tree.end_pass(1);
        assert!(tree.leaf_count() > before, "{before}");
        assert!(tree.leaf_count() > 4, "{}", tree.leaf_count());
        let far = tree.leaf_index(Vec3A::splat(1.9));
        let near = tree.leaf_index(Vec3A::splat(0.1));
        assert_ne!(far, near);
        // The corner's leaves learnt the +z records of the second pass.
        assert!(tree.leaf(near).sampling.pdf(Vec3A::Z) > 1.0);
    }

    #[test]
    fn bad_bounds_give_a_unit_cube() {
        let tree = SdTree::new(Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY));
        assert_eq!(tree.leaf_index(Vec3A::splat(f32::NAN)), 0);
    }
}
