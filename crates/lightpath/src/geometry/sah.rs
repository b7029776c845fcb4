//! A top-down binned-SAH builder for large or overlapping inputs, on every core.
//!
//! obvhs's PLOC builder makes the best trees for ordinary scenes, but it merges mutual
//! nearest neighbours a round at a time, and when every box overlaps every other (a disk's
//! fan of triangles all touching the centre) a round merges only a few pairs: a fan of
//! 100k segments took 30 s. Binning splits each range in time linear in its size whatever
//! the boxes, so the whole build is O(n log n); the two halves of large ranges are built
//! in parallel (`rayon::join`) and so is the binning of the largest ranges.
//!
//! The output is obvhs's binary layout (node 0 the root, an inner node's children at
//! `first_index` and `first_index + 1`, a leaf's primitives at `indices[first_index ..
//! first_index + prim_count]`), which `bvh` flattens 4 wide like obvhs's own trees.

use glam::Vec3A;
use obvhs::aabb::Aabb;
use obvhs::bvh2::node::Bvh2Node;
use rayon::prelude::*;

/// Bins per axis.
const BINS: usize = 16;
/// A range this small becomes a leaf (a leaf packet tests four triangles at once).
const LEAF: usize = 4;
/// Ranges larger than this build their two halves in parallel …
const PARALLEL_SPLIT: usize = 16 * 1024;
/// … and larger than this also bin in parallel.
const PARALLEL_BINNING: usize = 256 * 1024;

#[derive(Clone, Copy)]
struct Bin {
    bounds: Aabb,
    count: u32,
}

const EMPTY_BIN: Bin = Bin {
    bounds: Aabb::INVALID,
    count: 0,
};

/// Bins of the three axes.
type Bins = [[Bin; BINS]; 3];

fn half_area(b: &Aabb) -> f32 {
    if b.min.x > b.max.x {
        0.0
    } else {
        b.half_area()
    }
}

fn union(a: &Aabb, b: &Aabb) -> Aabb {
    Aabb::new(a.min.min(b.min), a.max.max(b.max))
}

/// A box with its primitive's index: the builder partitions these in place, so every
/// pass reads memory in order (indexing a million boxes at random was cache misses).
#[derive(Clone, Copy)]
struct Item {
    bounds: Aabb,
    index: u32,
}

impl Item {
    #[inline]
    fn centroid(&self) -> Vec3A {
        (self.bounds.min + self.bounds.max) * 0.5
    }
}

struct Builder;

/// Builds a binary BVH over `boxes`: (nodes, primitive indices).
pub fn build(boxes: &[Aabb]) -> (Vec<Bvh2Node>, Vec<u32>) {
    let mut items: Vec<Item> = boxes
        .par_iter()
        .enumerate()
        .map(|(i, b)| Item {
            bounds: *b,
            index: i as u32,
        })
        .collect();
    let mut nodes = Vec::with_capacity(2 * boxes.len().div_ceil(2));
    nodes.push(Bvh2Node::new(Aabb::INVALID, 0, 0));
    Builder.subtree(&mut items, 0, &mut nodes, 0);
    (nodes, items.par_iter().map(|item| item.index).collect())
}

impl Builder {
    /// Bounds of the boxes and of their centroids.
    fn bounds(&self, indices: &[Item]) -> (Aabb, Aabb) {
        let one = |(b, c): (Aabb, Aabb), item: &Item| {
            let bx = &item.bounds;
            let p = item.centroid();
            (
                Aabb::new(b.min.min(bx.min), b.max.max(bx.max)),
                Aabb::new(c.min.min(p), c.max.max(p)),
            )
        };
        let none = (Aabb::INVALID, Aabb::INVALID);
        if indices.len() > PARALLEL_BINNING {
            indices
                .par_chunks(16 * 1024)
                .map(|chunk| chunk.iter().fold(none, one))
                .reduce(|| none, |(a, b), (c, d)| (union(&a, &c), union(&b, &d)))
        } else {
            indices.iter().fold(none, one)
        }
    }

    /// Each box's bin along each axis, accumulated.
    fn bin(&self, indices: &[Item], lo: Vec3A, scale: Vec3A) -> Bins {
        let fill = |bins: &mut Bins, part: &[Item]| {
            let top = Vec3A::splat(BINS as f32 - 1.0);
            for item in part {
                let b = &item.bounds;
                let at = ((item.centroid() - lo) * scale).min(top).max(Vec3A::ZERO);
                for (axis, bins) in bins.iter_mut().enumerate() {
                    let bin = &mut bins[at[axis] as usize];
                    bin.count += 1;
                    bin.bounds = union(&bin.bounds, b);
                }
            }
        };
        let mut bins = [[EMPTY_BIN; BINS]; 3];
        if indices.len() > PARALLEL_BINNING {
            let parts: Vec<Bins> = indices
                .par_chunks(64 * 1024)
                .map(|chunk| {
                    let mut bins = [[EMPTY_BIN; BINS]; 3];
                    fill(&mut bins, chunk);
                    bins
                })
                .collect();
            for part in &parts {
                for axis in 0..3 {
                    for k in 0..BINS {
                        bins[axis][k].count += part[axis][k].count;
                        bins[axis][k].bounds = union(&bins[axis][k].bounds, &part[axis][k].bounds);
                    }
                }
            }
        } else {
            fill(&mut bins, indices);
        }
        bins
    }

    /// Fills `nodes[at]` with the subtree over `indices` (which sit at `offset` in the
    /// whole index list), appending its descendants to `nodes`.
    fn subtree(&self, indices: &mut [Item], offset: u32, nodes: &mut Vec<Bvh2Node>, at: usize) {
        let (bounds, centroids) = self.bounds(indices);
        let n = indices.len();
        if n <= LEAF {
            nodes[at] = Bvh2Node::new(bounds, n as u32, offset);
            return;
        }
        let mid = self.split(indices, &centroids);
        let (left, right) = indices.split_at_mut(mid);
        let first = nodes.len();
        nodes[at] = Bvh2Node::new(bounds, 0, first as u32);
        let empty = Bvh2Node::new(Aabb::INVALID, 0, 0);
        if n > PARALLEL_SPLIT && rayon::current_num_threads() > 1 {
            // Each half into its own list (its root at 0), then appended here.
            let half = |part: &mut [Item], offset: u32| {
                let mut sub = vec![empty];
                self.subtree(part, offset, &mut sub, 0);
                sub
            };
            let (a, b) = rayon::join(|| half(left, offset), || half(right, offset + mid as u32));
            nodes.push(a[0]);
            nodes.push(b[0]);
            let base_a = nodes.len();
            let base_b = base_a + a.len() - 1;
            // By position, not by comparing bases: they are equal when the first half is
            // a lone leaf (a.len() == 1), and the second root then overwrote the first
            // and stayed unrelocated (a cycle back to the top of the tree).
            for (k, (sub, base)) in [(&a, base_a), (&b, base_b)].into_iter().enumerate() {
                nodes[first + k] = relocated(&sub[0], base);
                nodes.extend(sub[1..].iter().map(|node| relocated(node, base)));
            }
        } else {
            nodes.push(empty);
            nodes.push(empty);
            self.subtree(left, offset, nodes, first);
            self.subtree(right, offset + mid as u32, nodes, first + 1);
        }
    }

    /// Partitions `indices` by the cheapest binned SAH plane; returns the size of the
    /// first part (never 0 or all: equal centroids split in the middle).
    fn split(&self, indices: &mut [Item], centroids: &Aabb) -> usize {
        let n = indices.len();
        let extent = centroids.max - centroids.min;
        if extent.max_element() <= 0.0 || !extent.is_finite() {
            return n / 2;
        }
        let scale = Vec3A::select(
            extent.cmpgt(Vec3A::ZERO),
            Vec3A::splat(BINS as f32) / extent,
            Vec3A::ZERO,
        );
        let bins = self.bin(indices, centroids.min, scale);
        // Cost of each plane k (bins < k left): area × count on both sides.
        let mut best = (f32::INFINITY, 0usize, 0usize);
        for axis in 0..3 {
            if scale[axis] == 0.0 {
                continue;
            }
            let b = &bins[axis];
            let mut right_cost = [0.0f32; BINS];
            let (mut acc, mut count) = (Aabb::INVALID, 0u32);
            for k in (1..BINS).rev() {
                acc = union(&acc, &b[k].bounds);
                count += b[k].count;
                right_cost[k] = half_area(&acc) * count as f32;
            }
            let (mut acc, mut count) = (Aabb::INVALID, 0u32);
            for k in 1..BINS {
                acc = union(&acc, &b[k - 1].bounds);
                count += b[k - 1].count;
                if count == 0 || count as usize == n {
                    continue;
                }
                let cost = half_area(&acc) * count as f32 + right_cost[k];
                if cost < best.0 {
                    best = (cost, axis, k);
                }
            }
        }
        if !best.0.is_finite() {
            return n / 2;
        }
        let (_, axis, k) = best;
        let (lo, s) = (centroids.min[axis], scale[axis]);
        let bin_of = |item: &Item| {
            (((item.centroid()[axis] - lo) * s).min(BINS as f32 - 1.0)).max(0.0) as usize
        };
        // In-place partition: bins below k first.
        let mut left = 0;
        let mut right = n;
        while left < right {
            if bin_of(&indices[left]) < k {
                left += 1;
            } else {
                right -= 1;
                indices.swap(left, right);
            }
        }
        if left == 0 || left == n {
            n / 2
        } else {
            left
        }
    }
}

/// A node of a subtree built on its own (root at 0) whose positions p ≥ 1 land at
/// `base + p − 1` of the whole list.
fn relocated(node: &Bvh2Node, base: usize) -> Bvh2Node {
    let mut node = *node;
    if node.prim_count == 0 {
        node.first_index = (base + node.first_index as usize - 1) as u32;
    }
    node
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    /// Every primitive sits in exactly one leaf, every node bounds what is under it.
    fn check(boxes: &[Aabb]) {
        let (nodes, indices) = build(boxes);
        let mut seen = vec![0u32; boxes.len()];
        let mut work = vec![0usize];
        while let Some(k) = work.pop() {
            let node = &nodes[k];
            let inside =
                |b: &Aabb| node.aabb.min.cmple(b.min).all() && b.max.cmple(node.aabb.max).all();
            if node.prim_count == 0 {
                let c = node.first_index as usize;
                assert!(c > k && c + 1 < nodes.len());
                assert!(inside(&nodes[c].aabb) && inside(&nodes[c + 1].aabb));
                work.extend([c, c + 1]);
            } else {
                assert!(node.prim_count as usize <= LEAF);
                for &i in &indices[node.first_index as usize..][..node.prim_count as usize] {
                    assert!(inside(&boxes[i as usize]));
                    seen[i as usize] += 1;
                }
            }
        }
        assert!(seen.iter().all(|&s| s == 1));
    }

    #[test]
    fn every_primitive_is_in_one_leaf_under_bounding_nodes() {
        let mut rng = Rng::for_sample(5, 6, 7);
        for n in [1, 2, 5, 17, 1000, 40_000] {
            let boxes: Vec<Aabb> = (0..n)
                .map(|i| {
                    let p = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
                    // Some exact repeats, which no plane separates.
                    let p = if i % 3 == 0 { Vec3A::splat(0.5) } else { p };
                    Aabb::new(p, p + Vec3A::splat(0.01 * rng.next_f32()))
                })
                .collect();
            check(&boxes);
        }
    }

    /// A split of a range large enough to build its halves in parallel whose first half
    /// is a single leaf: a few boxes far from many (a big mesh in a room of large walls).
    #[test]
    fn a_lone_leaf_beside_a_parallel_half() {
        let mut rng = Rng::for_sample(8, 9, 10);
        let mut boxes: Vec<Aabb> = (0..3)
            .map(|i| {
                let p = Vec3A::new(-100.0, i as f32, 0.0);
                Aabb::new(p, p + Vec3A::ONE)
            })
            .collect();
        boxes.extend((0..2 * PARALLEL_SPLIT).map(|_| {
            let p = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            Aabb::new(p, p + Vec3A::splat(0.01))
        }));
        // Two workers even on a one-core machine, so the halves are built in parallel.
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        pool.install(|| check(&boxes));
    }
}
