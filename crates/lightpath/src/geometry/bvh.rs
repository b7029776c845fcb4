//! The acceleration structure. `obvhs` builds a binary BVH (PLOC, reinsertion, SAH leaf
//! collapse to a few primitives per leaf); we flatten it into a wide BVH whose nodes store
//! their children's boxes as SIMD lanes and whose leaves store triangles laid out for an
//! all-lanes-at-once ray test. The width is chosen at run time ([`Width`]): eight lanes
//! (AVX) on CPUs with AVX2, four (SSE2, or glam's portable code) elsewhere; the traversal
//! is one generic function compiled for each (`lanes.rs`).
//!
//! Why not obvhs's own CWBVH traversal: its nodes are quantised and decoded byte by byte,
//! about 250 instructions a node, and its leaves are tested one primitive at a time. On
//! `cornell-classic` a shadow ray took ~560 instructions; here ~350, with a box test of
//! ~45 (docs/performance.md).

use super::accel::{Accel, Visibility};
#[cfg(target_arch = "x86_64")]
use super::lanes::F8;
use super::lanes::{Lanes, Mask};
use super::{Prim, Ray};
use glam::{Vec3A, Vec4};
use obvhs::aabb::Aabb;
use obvhs::bvh2::builder::build_bvh2;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::{Boundable, BvhBuildParams};
use rayon::prelude::*;

struct Bounded(Aabb);

impl Boundable for Bounded {
    fn aabb(&self) -> Aabb {
        self.0
    }
}

/// A child reference with this bit set names a leaf, otherwise a node.
const LEAF: u32 = 1 << 31;
/// Traversal stack entries kept on the machine stack (scenes of a million random triangles
/// need ~40); deeper trees, from degenerate inputs, use a per-thread heap stack.
const STACK: usize = 64;

thread_local! {
    // Grown once per thread, so rays through a very deep tree still allocate nothing.
    static DEEP_CLOSEST: std::cell::RefCell<Vec<(u32, f32)>> = const { std::cell::RefCell::new(Vec::new()) };
    static DEEP_ANY: std::cell::RefCell<Vec<u32>> = const { std::cell::RefCell::new(Vec::new()) };
    // The same for the meshes of instances, traced while the scene's tree holds its own.
    static DEEP_CLOSEST_MESH: std::cell::RefCell<Vec<(u32, f32)>> = const { std::cell::RefCell::new(Vec::new()) };
    static DEEP_ANY_MESH: std::cell::RefCell<Vec<u32>> = const { std::cell::RefCell::new(Vec::new()) };
}

type DeepStack<T> = std::thread::LocalKey<std::cell::RefCell<Vec<T>>>;

/// Below this many boxes obvhs's PLOC builder (with spatial splits and reinsertion: the
/// best trees) is fast whatever the input.
const PLOC_ALWAYS_BELOW: usize = 4096;
/// Above this many, or when boxes overlap like a fan's (the mean box more than this
/// fraction of the root's area), the binned-SAH builder on every core (`sah`): PLOC's
/// rounds can merge only a few pairs each when everything overlaps (quadratic time).
const SAH_ABOVE: usize = 50_000;
const SAH_OVERLAP: f32 = 0.02;

/// The lane width of a tree: its nodes' children and its leaves' triangles tested at once.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Width {
    /// SSE2 on x86-64, glam's portable code elsewhere.
    Four,
    /// AVX, on x86-64 CPUs with AVX2 only.
    Eight,
}

impl Width {
    /// The widest this CPU runs: eight lanes where AVX2 is detected, else four.
    /// `LIGHTPATH_BVH_WIDTH=4` forces four (to compare the two; renders are the same).
    pub fn detect() -> Width {
        static WIDTH: std::sync::OnceLock<Width> = std::sync::OnceLock::new();
        *WIDTH.get_or_init(|| {
            let forced_four = std::env::var("LIGHTPATH_BVH_WIDTH").is_ok_and(|v| v.trim() == "4");
            if !forced_four && Width::eight_available() {
                Width::Eight
            } else {
                Width::Four
            }
        })
    }

    /// Whether this CPU can run eight-lane trees.
    pub fn eight_available() -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            is_x86_feature_detected!("avx2")
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            false
        }
    }

    /// Most primitives obvhs's SAH collapse puts in a leaf: one leaf packet's lanes.
    fn leaf_prims(self) -> u32 {
        match self {
            Width::Four => 4,
            Width::Eight => 8,
        }
    }
}

/// The boxes obvhs builds over: each primitive's, except that many exact duplicates of
/// one box become one. Returns the boxes, and the primitives listed box by box
/// (`by_group[group_start[g]..group_start[g + 1]]` are box `g`'s).
fn group_duplicate_boxes(prims: &[Prim]) -> (Vec<Bounded>, Vec<u32>, Vec<u32>) {
    // Many exact duplicates of one box (doubled faces, copies stacked in place) go to
    // obvhs once: its PLOC build pairs identical boxes into a chain as deep as their
    // number, in quadratic time. They share a leaf as consecutive packets (a ray that
    // enters one box enters them all). A few (the two halves of an axis-aligned quad)
    // stay apart, where the tree can separate them best.
    const MERGE_ABOVE: u32 = 4;
    let bounds: Vec<Aabb> = prims
        .iter()
        .map(|p| {
            let (lo, hi) = p.bounds();
            Aabb::new(lo, hi)
        })
        .collect();
    let key = |b: &Aabb| [b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z].map(f32::to_bits);
    // Copies found by sorting (key, index) pairs, in parallel and in memory order (a
    // hash map's random probes were a third of a million-triangle build): for each
    // primitive with more than MERGE_ABOVE copies, the first of them.
    let mut keyed: Vec<([u32; 6], u32)> = bounds
        .par_iter()
        .enumerate()
        .map(|(i, b)| (key(b), i as u32))
        .collect();
    keyed.par_sort_unstable();
    let mut first_copy = vec![u32::MAX; bounds.len()];
    for run in keyed.chunk_by(|a, b| a.0 == b.0) {
        if run.len() > MERGE_ABOVE as usize {
            for &(_, i) in run {
                first_copy[i as usize] = run[0].1;
            }
        }
    }
    drop(keyed);
    // Boxes numbered in the order of their first primitive.
    let mut boxes: Vec<Bounded> = Vec::new();
    let mut group = vec![0u32; bounds.len()];
    for (i, b) in bounds.iter().enumerate() {
        let first = first_copy[i];
        group[i] = if first == u32::MAX || first == i as u32 {
            boxes.push(Bounded(*b));
            boxes.len() as u32 - 1
        } else {
            group[first as usize]
        };
    }
    drop(first_copy);
    // Primitives listed group by group (a counting sort).
    let mut group_start = vec![0u32; boxes.len() + 1];
    for &g in &group {
        group_start[g as usize + 1] += 1;
    }
    for g in 0..boxes.len() {
        group_start[g + 1] += group_start[g];
    }
    let mut by_group = vec![0u32; prims.len()];
    let mut fill = group_start.clone();
    for (i, &g) in group.iter().enumerate() {
        by_group[fill[g as usize] as usize] = i as u32;
        fill[g as usize] += 1;
    }
    (boxes, group_start, by_group)
}

/// A binary tree over `boxes` (obvhs's layout): nodes and primitive order.
fn build_tree(boxes: &[Bounded], leaf_prims: u32) -> (Vec<Bvh2Node>, Vec<u32>) {
    let n = boxes.len();
    let use_sah = n > SAH_ABOVE
        || (n >= PLOC_ALWAYS_BELOW && {
            let root = boxes.iter().fold(Aabb::INVALID, |a, b| a.union(&b.0));
            let mean = boxes.iter().map(|b| b.0.half_area() as f64).sum::<f64>() / n as f64;
            mean > (SAH_OVERLAP * root.half_area()) as f64
        });
    if use_sah {
        let aabbs: Vec<Aabb> = boxes.iter().map(|b| b.0).collect();
        return super::sah::build(&aabbs);
    }
    let params = BvhBuildParams {
        max_prims_per_leaf: leaf_prims,
        ..BvhBuildParams::slow_build()
    };
    let bvh = build_bvh2(boxes, params, &mut Default::default());
    (bvh.nodes, bvh.primitive_indices)
}

/// An inner node: up to `L::WIDTH` children, their boxes one lane each.
#[derive(Clone, Copy)]
struct Node<L: Lanes> {
    /// min x, min y, min z, max x, max y, max z of each child, lane per child.
    bounds: [L; 6],
    child: L::Refs,
    /// Bit per lane that holds a child.
    lanes: u32,
}

impl<L: Lanes> Node<L> {
    const EMPTY: Self = Node {
        bounds: [L::ZERO; 6],
        child: L::ZERO_REFS,
        lanes: 0,
    };
}

/// Up to `L::WIDTH` primitives: triangles as SIMD lanes (vertex and edges), spheres tested
/// one at a time. A leaf may run over several consecutive packets (`last` ends it).
#[derive(Clone, Copy)]
struct Leaf<L: Lanes> {
    p0: [L; 3],
    e1: [L; 3],
    e2: [L; 3],
    /// e1 × e2, unnormalised (`super::edge_normal`).
    n: [L; 3],
    /// Slot of lane 0 in the primitive arrays; lane `l` is slot `first + l`.
    first: u32,
    /// For each ray-kind mask (0..8), the lanes holding a triangle that kind of ray sees.
    triangles: [u8; 8],
    /// The same for primitives tested one at a time: spheres and instances.
    spheres: [u8; 8],
    last: bool,
}

/// The wide tree of one lane width.
pub(super) struct Tree<L: Lanes> {
    nodes: Vec<Node<L>>,
    leaves: Vec<Leaf<L>>,
    /// Stack entries the deepest path can need.
    stack_need: usize,
}

/// An accelerator's tree, at the width chosen when it was built.
pub(super) enum Trees {
    Four(Tree<Vec4>),
    /// Only made where AVX2 was detected: its traversal runs AVX instructions.
    #[cfg(target_arch = "x86_64")]
    Eight(Tree<F8>),
}

/// Per-ray constants of the box and triangle tests.
struct RayLanes<L: Lanes> {
    o: [L; 3],
    d: [L; 3],
    inv: [L; 3],
    /// origin × inverse direction, so a slab distance is `bound * inv - oinv`.
    oinv: [L; 3],
    /// Index into `Node::bounds` of the near plane per axis (the far one is 3 away).
    near: [usize; 3],
    tmin: f32,
}

impl<L: Lanes> RayLanes<L> {
    #[inline(always)]
    fn new(ray: &Ray, tmin: f32) -> RayLanes<L> {
        // A zero direction component would make 0 × ∞ = NaN in the slab test.
        let tiny = Vec3A::splat(1e-30);
        let safe = Vec3A::select(ray.dir.abs().cmplt(tiny), tiny.copysign(ray.dir), ray.dir);
        let inv = Vec3A::ONE / safe;
        let oinv = ray.origin * inv;
        let splat = |v: Vec3A| [L::splat(v.x), L::splat(v.y), L::splat(v.z)];
        let negative = inv.cmplt(Vec3A::ZERO).bitmask() as usize;
        RayLanes {
            o: splat(ray.origin),
            d: splat(ray.dir),
            inv: splat(inv),
            oinv: splat(oinv),
            near: [
                3 * (negative & 1),
                1 + 3 * ((negative >> 1) & 1),
                2 + 3 * ((negative >> 2) & 1),
            ],
            tmin,
        }
    }

    /// Which children's boxes the ray enters before `tmax`, and where.
    #[inline(always)]
    fn hit_children(&self, node: &Node<L>, tmax: f32) -> (u32, L) {
        let b = &node.bounds;
        let [nx, ny, nz] = self.near;
        let tn_x = b[nx] * self.inv[0] - self.oinv[0];
        let tn_y = b[ny] * self.inv[1] - self.oinv[1];
        let tn_z = b[nz] * self.inv[2] - self.oinv[2];
        let tf_x = b[3 - nx] * self.inv[0] - self.oinv[0];
        let tf_y = b[5 - ny] * self.inv[1] - self.oinv[1];
        let tf_z = b[7 - nz] * self.inv[2] - self.oinv[2];
        let tnear = tn_x.max(tn_y).max(tn_z.max(L::splat(self.tmin)));
        // Widened by a few ulps so rounding never loses a box the ray grazes.
        let tfar = tf_x.min(tf_y).min(tf_z.min(L::splat(tmax))) * L::splat(1.000_000_4);
        (tnear.le(tfar).bits() & node.lanes, tnear)
    }

    /// The triangle test on a packet of triangles (`Prim::intersect`'s, lane by lane):
    /// distances and the lanes hit in (tmin, tmax).
    #[inline(always)]
    fn hit_triangles(&self, leaf: &Leaf<L>, tmax: f32) -> (u32, L) {
        let [dx, dy, dz] = self.d;
        let [e1x, e1y, e1z] = leaf.e1;
        let [e2x, e2y, e2z] = leaf.e2;
        let [nx, ny, nz] = leaf.n;
        let zero = L::splat(0.0);
        let tvx = self.o[0] - leaf.p0[0];
        let tvy = self.o[1] - leaf.p0[1];
        let tvz = self.o[2] - leaf.p0[2];
        let rx = dy * tvz - dz * tvy;
        let ry = dz * tvx - dx * tvz;
        let rz = dx * tvy - dy * tvx;
        let den = dx * nx + dy * ny + dz * nz;
        let absden = den.abs();
        let neg = zero - den;
        let u = (e2x * rx + e2y * ry + e2z * rz).xor_sign(den);
        let v = (e1x * rx + e1y * ry + e1z * rz).xor_sign(neg);
        let tn = (tvx * nx + tvy * ny + tvz * nz).xor_sign(neg);
        let ok = absden.ge(L::splat(1e-12))
            & u.ge(zero)
            & v.ge(zero)
            & (u + v).le(absden)
            & tn.gt(L::splat(self.tmin) * absden)
            & tn.lt(L::splat(tmax) * absden);
        let bits = ok.bits();
        // The division only for a packet with a hit (shadow rays never need it).
        (bits, if bits != 0 { tn / absden } else { tn })
    }
}

/// A BVH over some primitives, and the order it lays them out in.
pub(super) struct LaidOut {
    pub tree: Trees,
    /// Per slot (leaf order), the index of the primitive given to [`lay_out`].
    pub order: Vec<u32>,
    /// The primitives in slot order.
    pub prims: Vec<Prim>,
    /// Which ray kinds see each slot's primitive.
    #[cfg_attr(not(feature = "embree"), allow(dead_code))]
    pub visibility: Vec<u8>,
}

/// Builds the wide BVH over `prims` (`visibility[i]`: which ray kinds see `prims[i]`) at
/// `width` (eight falls back to four on CPUs without AVX2), with the primitives laid out in
/// leaf order so leaves address them by range.
pub(super) fn lay_out(prims: &[Prim], visibility: &[u8], width: Width) -> LaidOut {
    let width = if Width::eight_available() {
        width
    } else {
        Width::Four
    };
    if prims.is_empty() {
        return LaidOut {
            tree: Trees::Four(Tree {
                nodes: Vec::new(),
                leaves: Vec::new(),
                stack_need: 0,
            }),
            order: Vec::new(),
            prims: Vec::new(),
            visibility: Vec::new(),
        };
    }
    let (boxes, group_start, by_group) = group_duplicate_boxes(prims);
    let (tree, tree_indices) = build_tree(&boxes, width.leaf_prims());
    // `slot_start[k]` is the first slot of the k-th box in obvhs's order.
    let mut order = Vec::with_capacity(prims.len());
    let mut slot_start = Vec::with_capacity(tree_indices.len() + 1);
    for &g in &tree_indices {
        slot_start.push(order.len() as u32);
        let g = g as usize;
        order.extend_from_slice(&by_group[group_start[g] as usize..group_start[g + 1] as usize]);
    }
    slot_start.push(order.len() as u32);
    let laid: Vec<Prim> = order.iter().map(|&i| prims[i as usize]).collect();
    let visibility: Vec<u8> = order.iter().map(|&i| visibility[i as usize]).collect();
    let tree = match width {
        #[cfg(target_arch = "x86_64")]
        Width::Eight => Trees::Eight(Tree::build(&tree, &slot_start, &laid, &visibility)),
        _ => Trees::Four(Tree::build(&tree, &slot_start, &laid, &visibility)),
    };
    LaidOut {
        tree,
        order,
        prims: laid,
        visibility,
    }
}

impl Trees {
    pub(super) fn width(&self) -> Width {
        match self {
            Trees::Four(_) => Width::Four,
            #[cfg(target_arch = "x86_64")]
            Trees::Eight(_) => Width::Eight,
        }
    }
}

/// The BVH's traversal of an accelerator's tree (the tree, primitives and instances
/// `accel` holds).
impl Accel {
    /// The nearest hit (slot, t, instanced slot) on anything but object `ignore`
    /// (`u32::MAX`: none ignored), or `u32::MAX` for none.
    #[inline]
    pub(super) fn bvh_nearest(
        &self,
        ray: &Ray,
        tmin: f32,
        mask: u8,
        ignore: u32,
    ) -> (u32, f32, u32) {
        // The test for an ignored object compiled in only where one is given: the
        // traversal of every other ray is the one without it (~18 instructions a ray on
        // cornell-classic).
        if ignore == u32::MAX {
            self.nearest::<false>(ray, tmin, mask, ignore, &DEEP_CLOSEST)
        } else {
            self.nearest::<true>(ray, tmin, mask, ignore, &DEEP_CLOSEST)
        }
    }

    /// Whether anything but object `ignore` blocks the shadow ray.
    #[inline]
    pub(super) fn bvh_occluded(&self, ray: &Ray, tmin: f32, ignore: u32) -> bool {
        self.occluded_with(ray, tmin, ignore, &DEEP_ANY)
    }

    /// `closest` in the tree of whatever width, on the machine stack or on `deep` for very
    /// deep trees.
    #[inline]
    fn nearest<const EXCEPT: bool>(
        &self,
        ray: &Ray,
        tmin: f32,
        mask: u8,
        ignore: u32,
        deep: &'static DeepStack<(u32, f32)>,
    ) -> (u32, f32, u32) {
        match &self.tree {
            Trees::Four(tree) => self.nearest_in::<_, EXCEPT>(tree, ray, tmin, mask, ignore, deep),
            // SAFETY: `Eight` trees are only built where AVX2 was detected.
            #[cfg(target_arch = "x86_64")]
            Trees::Eight(tree) => unsafe {
                self.nearest_avx2::<EXCEPT>(tree, ray, tmin, mask, ignore, deep)
            },
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn nearest_avx2<const EXCEPT: bool>(
        &self,
        tree: &Tree<F8>,
        ray: &Ray,
        tmin: f32,
        mask: u8,
        ignore: u32,
        deep: &'static DeepStack<(u32, f32)>,
    ) -> (u32, f32, u32) {
        self.nearest_in::<_, EXCEPT>(tree, ray, tmin, mask, ignore, deep)
    }

    #[inline(always)]
    fn nearest_in<L: Lanes, const EXCEPT: bool>(
        &self,
        tree: &Tree<L>,
        ray: &Ray,
        tmin: f32,
        mask: u8,
        ignore: u32,
        deep: &'static DeepStack<(u32, f32)>,
    ) -> (u32, f32, u32) {
        if tree.stack_need <= STACK {
            self.closest::<L, EXCEPT>(
                tree,
                ray,
                tmin,
                mask,
                ignore,
                &mut Stack::<(u32, f32), STACK>::new(),
            )
        } else {
            // Taken out and put back rather than borrowed in a closure: the closure would
            // be compiled without the AVX2 of the caller.
            let mut stack = deep.take();
            if stack.len() < tree.stack_need {
                stack.resize(tree.stack_need, (0, 0.0));
            }
            let found = self.closest::<L, EXCEPT>(tree, ray, tmin, mask, ignore, &mut stack);
            deep.set(stack);
            found
        }
    }

    /// The nearest hit on instance `index` before `tmax`: (the mesh's slot, t), t
    /// infinite for none.
    #[inline(never)]
    fn instance_nearest(&self, index: u32, ray: &Ray, tmin: f32, tmax: f32) -> (u32, f32) {
        let (inst, local) = self.local_ray(index, ray, tmax);
        let mesh = &self.meshes[inst.mesh as usize];
        if mesh.prims.is_empty() {
            return (u32::MAX, f32::INFINITY);
        }
        let (slot, t, _) =
            mesh.nearest::<false>(&local, tmin, Visibility::ALL, u32::MAX, &DEEP_CLOSEST_MESH);
        if slot == u32::MAX {
            (slot, f32::INFINITY)
        } else {
            (slot, t)
        }
    }

    /// Does instance `index` block the ray before its `tmax`?
    #[inline(never)]
    fn instance_occluded(&self, index: u32, ray: &Ray, tmin: f32) -> bool {
        let (inst, local) = self.local_ray(index, ray, ray.tmax);
        let mesh = &self.meshes[inst.mesh as usize];
        !mesh.prims.is_empty() && mesh.occluded_with(&local, tmin, u32::MAX, &DEEP_ANY_MESH)
    }

    /// Closest-hit traversal, nearest child first; returns (slot, t, the instanced mesh's
    /// slot when the slot is an instance) or (`u32::MAX`, _, _). With `EXCEPT`, hits on
    /// object `ignore` are skipped.
    ///
    /// The hot loop, one ~125-line body on purpose (the exception to the 120-line rule):
    /// it is inlined into each lane width's `#[target_feature]` entry point, and the node
    /// loop, leaf test and stack share their locals; an early traversal split into
    /// functions was slower until it was inlined back (docs/performance.md).
    #[inline(always)]
    fn closest<L: Lanes, const EXCEPT: bool>(
        &self,
        tree: &Tree<L>,
        ray: &Ray,
        tmin: f32,
        mask: u8,
        ignore: u32,
        stack: &mut impl TraversalStack<(u32, f32)>,
    ) -> (u32, f32, u32) {
        let r = RayLanes::<L>::new(ray, tmin);
        let mask = (mask & 7) as usize;
        let mut tmax = ray.tmax;
        let mut best = u32::MAX;
        let mut inner = u32::MAX;
        let mut sp = 0;
        let mut current = 0u32;
        loop {
            if current & LEAF == 0 {
                let node = &tree.nodes[current as usize];
                let child = node.child.as_ref();
                let (hits, tnear) = r.hit_children(node, tmax);
                if hits != 0 {
                    let first = hits.trailing_zeros() as usize;
                    let rest = hits & (hits - 1);
                    if rest == 0 {
                        current = child[first];
                        continue;
                    }
                    let tnear = tnear.store();
                    let tnear = tnear.as_ref();
                    if rest & (rest - 1) == 0 {
                        // Two children, the commonest case: visit the nearer first.
                        let second = rest.trailing_zeros() as usize;
                        let (near, far) = if tnear[second] < tnear[first] {
                            (second, first)
                        } else {
                            (first, second)
                        };
                        stack.put(sp, (child[far], tnear[far]));
                        sp += 1;
                        current = child[near];
                        continue;
                    }
                    // Three or more: visit the nearest, stack the rest far to near.
                    let mut order = [(0.0f32, 0u32); 8];
                    let mut n = 0;
                    let mut bits = hits;
                    while bits != 0 {
                        let lane = bits.trailing_zeros() as usize;
                        bits &= bits - 1;
                        let entry = (tnear[lane], child[lane]);
                        // Insertion into descending order.
                        let mut j = n;
                        while j > 0 && order[j - 1].0 < entry.0 {
                            order[j] = order[j - 1];
                            j -= 1;
                        }
                        order[j] = entry;
                        n += 1;
                    }
                    for &(t, child) in &order[..n - 1] {
                        stack.put(sp, (child, t));
                        sp += 1;
                    }
                    current = order[n - 1].1;
                    continue;
                }
            } else {
                let mut index = (current & !LEAF) as usize;
                loop {
                    let leaf = &tree.leaves[index];
                    let lanes = leaf.triangles[mask] as u32;
                    if lanes != 0 {
                        let (mut hits, t) = r.hit_triangles(leaf, tmax);
                        hits &= lanes;
                        if hits != 0 {
                            let t = t.store();
                            let t = t.as_ref();
                            while hits != 0 {
                                let lane = hits.trailing_zeros() as usize;
                                hits &= hits - 1;
                                let slot = leaf.first + lane as u32;
                                if t[lane] < tmax
                                    && !(EXCEPT && self.objects[slot as usize] == ignore)
                                {
                                    tmax = t[lane];
                                    best = slot;
                                }
                            }
                        }
                    }
                    let mut spheres = leaf.spheres[mask] as u32;
                    while spheres != 0 {
                        let slot = leaf.first + spheres.trailing_zeros();
                        spheres &= spheres - 1;
                        if EXCEPT && self.objects[slot as usize] == ignore {
                            continue;
                        }
                        let prim = &self.prims[slot as usize];
                        let t = if let Prim::Instance { index, .. } = *prim {
                            let (hit, t) = self.instance_nearest(index, ray, tmin, tmax);
                            if t < tmax {
                                inner = hit;
                            }
                            t
                        } else {
                            prim.intersect(ray.origin, ray.dir, tmin, tmax)
                        };
                        if t < tmax {
                            tmax = t;
                            best = slot;
                        }
                    }
                    if leaf.last {
                        break;
                    }
                    index += 1;
                }
            }
            // Next stacked child that is still nearer than the nearest hit.
            loop {
                if sp == 0 {
                    return (best, tmax, inner);
                }
                sp -= 1;
                let (child, t) = stack.take(sp);
                if t <= tmax {
                    current = child;
                    break;
                }
            }
        }
    }

    /// `any_hit` in the tree of whatever width, on the machine stack or on `deep` for very
    /// deep trees.
    #[inline]
    fn occluded_with(
        &self,
        ray: &Ray,
        tmin: f32,
        ignore: u32,
        deep: &'static DeepStack<u32>,
    ) -> bool {
        match &self.tree {
            Trees::Four(tree) => self.occluded_in(tree, ray, tmin, ignore, deep),
            // SAFETY: `Eight` trees are only built where AVX2 was detected.
            #[cfg(target_arch = "x86_64")]
            Trees::Eight(tree) => unsafe { self.occluded_avx2(tree, ray, tmin, ignore, deep) },
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn occluded_avx2(
        &self,
        tree: &Tree<F8>,
        ray: &Ray,
        tmin: f32,
        ignore: u32,
        deep: &'static DeepStack<u32>,
    ) -> bool {
        self.occluded_in(tree, ray, tmin, ignore, deep)
    }

    #[inline(always)]
    fn occluded_in<L: Lanes>(
        &self,
        tree: &Tree<L>,
        ray: &Ray,
        tmin: f32,
        ignore: u32,
        deep: &'static DeepStack<u32>,
    ) -> bool {
        if tree.stack_need <= STACK {
            self.any_hit(tree, ray, tmin, ignore, &mut Stack::<u32, STACK>::new())
        } else {
            // As in `nearest_in`.
            let mut stack = deep.take();
            if stack.len() < tree.stack_need {
                stack.resize(tree.stack_need, 0);
            }
            let blocked = self.any_hit(tree, ray, tmin, ignore, &mut stack);
            deep.set(stack);
            blocked
        }
    }

    /// Any-hit traversal in whatever order is cheapest.
    #[inline(always)]
    fn any_hit<L: Lanes>(
        &self,
        tree: &Tree<L>,
        ray: &Ray,
        tmin: f32,
        ignore: u32,
        stack: &mut impl TraversalStack<u32>,
    ) -> bool {
        const SHADOW: usize = super::Visibility::SHADOW as usize;
        let r = RayLanes::<L>::new(ray, tmin);
        let tmax = ray.tmax;
        let mut sp = 0;
        let mut current = 0u32;
        loop {
            if current & LEAF == 0 {
                let node = &tree.nodes[current as usize];
                let child = node.child.as_ref();
                let (mut hits, _) = r.hit_children(node, tmax);
                if hits != 0 {
                    current = child[hits.trailing_zeros() as usize];
                    hits &= hits - 1;
                    while hits != 0 {
                        stack.put(sp, child[hits.trailing_zeros() as usize]);
                        sp += 1;
                        hits &= hits - 1;
                    }
                    continue;
                }
            } else {
                let mut index = (current & !LEAF) as usize;
                loop {
                    let leaf = &tree.leaves[index];
                    let lanes = leaf.triangles[SHADOW] as u32;
                    if lanes != 0 {
                        let (mut hits, _) = r.hit_triangles(leaf, tmax);
                        hits &= lanes;
                        while hits != 0 {
                            let slot = leaf.first + hits.trailing_zeros();
                            hits &= hits - 1;
                            if self.objects[slot as usize] != ignore {
                                return true;
                            }
                        }
                    }
                    let mut spheres = leaf.spheres[SHADOW] as u32;
                    while spheres != 0 {
                        let slot = leaf.first + spheres.trailing_zeros();
                        spheres &= spheres - 1;
                        if self.objects[slot as usize] != ignore
                            && match self.prims[slot as usize] {
                                Prim::Instance { index, .. } => {
                                    self.instance_occluded(index, ray, tmin)
                                }
                                ref prim => {
                                    prim.intersect(ray.origin, ray.dir, tmin, tmax).is_finite()
                                }
                            }
                        {
                            return true;
                        }
                    }
                    if leaf.last {
                        break;
                    }
                    index += 1;
                }
            }
            if sp == 0 {
                return false;
            }
            sp -= 1;
            current = stack.take(sp);
        }
    }
}

impl<L: Lanes> Tree<L> {
    /// The wide tree over obvhs's binary `tree`, whose boxes' primitives (already laid out
    /// in leaf order in `prims`) start at `slot_start`.
    fn build(tree: &[Bvh2Node], slot_start: &[u32], prims: &[Prim], visibility: &[u8]) -> Self {
        let mut wide = Tree {
            nodes: Vec::new(),
            leaves: Vec::new(),
            stack_need: 0,
        };
        let root = &tree[0];
        let depth = if root.is_leaf() {
            // A lone leaf still goes under a node, so traversal always starts at node 0.
            wide.nodes.push(Node::EMPTY);
            let leaf = wide.add_leaf(
                slot_start,
                root.first_index,
                root.prim_count,
                prims,
                visibility,
            );
            wide.nodes[0] = node_of(&[(root.aabb, leaf)]);
            1
        } else {
            wide.add_nodes(tree, slot_start, prims, visibility)
        };
        // Each node visited stacks all but one of its children.
        wide.stack_need = (L::WIDTH - 1) * depth + 1;
        wide
    }

    /// Flattens the binary tree (its root an inner node) into wide nodes, node 0 its
    /// root; returns its depth in wide nodes. Iterative: a degenerate input (many
    /// identical primitives) can make a binary tree thousands of levels deep.
    fn add_nodes(
        &mut self,
        tree: &[Bvh2Node],
        slot_start: &[u32],
        prims: &[Prim],
        visibility: &[u8],
    ) -> usize {
        self.nodes.push(Node::EMPTY);
        // (binary node, its wide slot, depth of that slot)
        let mut work = vec![(0usize, 0usize, 1usize)];
        let mut deepest = 1;
        while let Some((index, slot, depth)) = work.pop() {
            deepest = deepest.max(depth);
            // Open the largest inner grandchildren until there are `WIDTH` children.
            let first = tree[index].first_index as usize;
            let mut kids = vec![first, first + 1];
            while kids.len() < L::WIDTH {
                let widest = kids
                    .iter()
                    .enumerate()
                    .filter(|(_, &k)| !tree[k].is_leaf())
                    .max_by(|a, b| {
                        let area = |k: usize| tree[k].aabb.half_area();
                        area(*a.1).total_cmp(&area(*b.1))
                    })
                    .map(|(at, _)| at);
                let Some(at) = widest else { break };
                let k = tree[kids[at]].first_index as usize;
                kids[at] = k;
                kids.push(k + 1);
            }
            let mut children = Vec::with_capacity(L::WIDTH);
            for &k in &kids {
                let n = &tree[k];
                let reference = if n.is_leaf() {
                    self.add_leaf(slot_start, n.first_index, n.prim_count, prims, visibility)
                } else {
                    let at = self.nodes.len();
                    self.nodes.push(Node::EMPTY);
                    work.push((k, at, depth + 1));
                    at as u32
                };
                children.push((n.aabb, reference));
            }
            self.nodes[slot] = node_of(&children);
        }
        deepest
    }

    /// Packs the primitives of obvhs's boxes `first .. first + count` (with their
    /// duplicates: slots `slot_start[first] .. slot_start[first + count]`) into leaf
    /// packets; returns the child reference of the first.
    fn add_leaf(
        &mut self,
        slot_start: &[u32],
        first: u32,
        count: u32,
        prims: &[Prim],
        visibility: &[u8],
    ) -> u32 {
        let width = L::WIDTH as u32;
        let reference = LEAF | self.leaves.len() as u32;
        let end = slot_start[(first + count) as usize];
        let mut start = slot_start[first as usize];
        while start < end {
            let mut p0 = [L::ZERO_FLOATS; 3];
            let mut e1 = [L::ZERO_FLOATS; 3];
            let mut e2 = [L::ZERO_FLOATS; 3];
            let mut n = [L::ZERO_FLOATS; 3];
            let mut triangles = [0u8; 8];
            let mut spheres = [0u8; 8];
            for lane in 0..(end - start).min(width) as usize {
                let slot = start as usize + lane;
                let seen_by = |mask: usize| visibility[slot] as usize & mask != 0;
                match prims[slot] {
                    Prim::Triangle {
                        p0: q0,
                        e1: f1,
                        e2: f2,
                        ..
                    } => {
                        let m = super::edge_normal(f1, f2);
                        for axis in 0..3 {
                            p0[axis].as_mut()[lane] = q0[axis];
                            e1[axis].as_mut()[lane] = f1[axis];
                            e2[axis].as_mut()[lane] = f2[axis];
                            n[axis].as_mut()[lane] = m[axis];
                        }
                        for (mask, lanes) in triangles.iter_mut().enumerate() {
                            if seen_by(mask) {
                                *lanes |= 1 << lane;
                            }
                        }
                    }
                    Prim::Sphere { .. } | Prim::Cylinder { .. } | Prim::Instance { .. } => {
                        for (mask, lanes) in spheres.iter_mut().enumerate() {
                            if seen_by(mask) {
                                *lanes |= 1 << lane;
                            }
                        }
                    }
                }
            }
            self.leaves.push(Leaf {
                p0: p0.map(|a| L::load(&a)),
                e1: e1.map(|a| L::load(&a)),
                e2: e2.map(|a| L::load(&a)),
                n: n.map(|a| L::load(&a)),
                first: start,
                triangles,
                spheres,
                last: start + width >= end,
            });
            start += width;
        }
        reference
    }
}

/// Storage for a traversal stack: entries are written with `put` before `take` reads them.
trait TraversalStack<T: Copy> {
    fn put(&mut self, at: usize, value: T);
    fn take(&self, at: usize) -> T;
}

/// The per-thread heap stack of very deep trees.
impl<T: Copy> TraversalStack<T> for Vec<T> {
    #[inline(always)]
    fn put(&mut self, at: usize, value: T) {
        self[at] = value;
    }
    #[inline(always)]
    fn take(&self, at: usize) -> T {
        self[at]
    }
}

/// A fixed stack on the machine stack, left uninitialised: zeroing it cost more than the
/// traversal of a short shadow ray. Each slot remembers nothing but what `put` wrote.
struct Stack<T, const N: usize> {
    items: [std::mem::MaybeUninit<T>; N],
    written: usize,
}

impl<T: Copy, const N: usize> Stack<T, N> {
    #[inline(always)]
    fn new() -> Self {
        Stack {
            items: [const { std::mem::MaybeUninit::uninit() }; N],
            written: 0,
        }
    }
}

impl<T: Copy, const N: usize> TraversalStack<T> for Stack<T, N> {
    #[inline(always)]
    fn put(&mut self, at: usize, value: T) {
        self.items[at].write(value);
        self.written = self.written.max(at + 1);
    }
    #[inline(always)]
    fn take(&self, at: usize) -> T {
        assert!(at < self.written);
        // SAFETY: every slot below `written` was written by `put` (slots are filled in
        // order from 0, as a stack does), and `T: Copy` has no drop.
        unsafe { self.items[at].assume_init() }
    }
}

/// A wide node over `children` (one to `L::WIDTH` boxes with their references).
fn node_of<L: Lanes>(children: &[(Aabb, u32)]) -> Node<L> {
    let mut bounds = [L::ZERO_FLOATS; 6];
    let mut child = L::ZERO_REFS;
    let mut lanes = 0;
    for (lane, (aabb, reference)) in children.iter().enumerate() {
        for axis in 0..3 {
            bounds[axis].as_mut()[lane] = aabb.min[axis];
            bounds[axis + 3].as_mut()[lane] = aabb.max[axis];
        }
        child.as_mut()[lane] = *reference;
        lanes |= 1 << lane;
    }
    Node {
        bounds: bounds.map(|a| L::load(&a)),
        child,
        lanes,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Instance;
    use crate::sampling::{uniform_sphere, Rng};

    /// Both widths: where AVX2 is missing `Eight` builds the four-lane tree, so the
    /// portable code is what both runs test there.
    const WIDTHS: [Width; 2] = [Width::Four, Width::Eight];

    impl Accel {
        /// Wide nodes and leaf packets.
        fn counts(&self) -> (usize, usize) {
            match &self.tree {
                Trees::Four(t) => (t.nodes.len(), t.leaves.len()),
                #[cfg(target_arch = "x86_64")]
                Trees::Eight(t) => (t.nodes.len(), t.leaves.len()),
            }
        }
    }

    #[test]
    fn eight_lanes_where_the_cpu_has_avx2() {
        let tri = Prim::Triangle {
            p0: Vec3A::ZERO,
            e1: Vec3A::X,
            e2: Vec3A::Y,
            normals: u32::MAX,
        };
        let build = |w| Accel::build_with(vec![tri], vec![0], Vec::new(), vec![7], w).width();
        assert_eq!(build(Width::Four), Width::Four);
        let eight = if Width::eight_available() {
            Width::Eight
        } else {
            Width::Four
        };
        assert_eq!(build(Width::Eight), eight);
    }

    /// A ray from a random point of the cube of side `side` around the origin, in a
    /// uniform direction, half of them infinite and half `finite` long.
    fn random_ray(rng: &mut Rng, side: f32, finite: f32) -> Ray {
        let origin = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * side
            - Vec3A::splat(side / 2.0);
        Ray {
            origin,
            dir: uniform_sphere(rng.next_2d()),
            tmax: if rng.next_f32() < 0.5 {
                f32::INFINITY
            } else {
                finite
            },
        }
    }

    /// A soup of triangles and spheres of mixed visibility, some duplicated, in and around a
    /// unit box.
    fn soup(n: usize, rng: &mut Rng) -> (Vec<Prim>, Vec<u32>, Vec<u8>) {
        let mut point =
            || Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - Vec3A::ONE;
        let mut prims = Vec::new();
        for i in 0..n {
            if i >= 50 && (1..=6).contains(&(i % 50)) {
                // Seven copies in a row, enough to be merged into one box.
                prims.push(prims[i - i % 50]);
            } else if i % 11 == 5 {
                // An exact duplicate of the previous one (of another object and visibility).
                prims.push(prims[i - 1]);
            } else if i % 7 == 3 {
                prims.push(Prim::Sphere {
                    center: point(),
                    radius: 0.05,
                });
            } else {
                let p0 = point();
                let e1 = (point() - p0) * 0.3;
                let e2 = (point() - p0) * 0.3;
                prims.push(Prim::Triangle {
                    p0,
                    e1,
                    e2,
                    normals: u32::MAX,
                });
            }
        }
        let objects = (0..n as u32).map(|i| i % 5).collect();
        let visibility = (0..n).map(|i| [7, 7, 7, 1, 2, 4, 6][i % 7]).collect();
        (prims, objects, visibility)
    }

    /// The BVH answers exactly what testing every primitive answers.
    #[test]
    fn traversal_matches_brute_force() {
        let mut rng = Rng::for_sample(7, 8, 9);
        for (n, width) in [1, 3, 4, 5, 9, 17, 300, 2000]
            .into_iter()
            .flat_map(|n| WIDTHS.map(|w| (n, w)))
        {
            let (prims, objects, visibility) = soup(n, &mut rng);
            let accel = Accel::build_with(
                prims.clone(),
                objects.clone(),
                Vec::new(),
                visibility.clone(),
                width,
            );
            for _ in 0..400 {
                let ray = random_ray(&mut rng, 3.0, 1.0);
                for mask in [Visibility::CAMERA, Visibility::INDIRECT, Visibility::SHADOW] {
                    let brute = (0..n)
                        .filter(|&i| visibility[i] & mask != 0)
                        .map(|i| prims[i].intersect(ray.origin, ray.dir, 0.0, ray.tmax))
                        .fold(f32::INFINITY, f32::min);
                    let got = accel
                        .intersect(&ray, 0.0, mask)
                        .map_or(f32::INFINITY, |h| h.t);
                    assert!(
                        got == brute || (got - brute).abs() <= 1e-5 * brute.abs(),
                        "n {n} mask {mask}: bvh {got} brute {brute}"
                    );
                }
                let ignore = (rng.next_f32() * 5.0) as u32;
                let brute_blocked = (0..n).any(|i| {
                    visibility[i] & Visibility::SHADOW != 0
                        && objects[i] != ignore
                        && prims[i]
                            .intersect(ray.origin, ray.dir, 0.0, ray.tmax)
                            .is_finite()
                });
                assert_eq!(accel.occluded(&ray, 0.0, ignore), brute_blocked, "n {n}");
            }
        }
    }

    /// Identical primitives (obvhs would pair them in a chain as deep as their number, in
    /// quadratic time) share one box of the tree.
    #[test]
    fn identical_primitives_share_a_leaf() {
        let n = 20_000;
        let tri = Prim::Triangle {
            p0: Vec3A::ZERO,
            e1: Vec3A::X,
            e2: Vec3A::Y,
            normals: u32::MAX,
        };
        let mut prims = vec![tri; n];
        prims.push(Prim::Sphere {
            center: Vec3A::new(5.0, 0.0, 0.0),
            radius: 1.0,
        });
        let objects: Vec<u32> = (0..=n as u32).collect();
        for width in WIDTHS {
            let accel = Accel::build_with(
                prims.clone(),
                objects.clone(),
                Vec::new(),
                vec![7; n + 1],
                width,
            );
            let lanes = if accel.width() == Width::Eight { 8 } else { 4 };
            assert_eq!(accel.counts(), (1, n / lanes + 1));
            identical_primitives_answer(&accel, n);
        }
    }

    fn identical_primitives_answer(accel: &Accel, n: usize) {
        let ray = Ray {
            origin: Vec3A::new(0.2, 0.2, 1.0),
            dir: -Vec3A::Z,
            tmax: f32::INFINITY,
        };
        let hit = accel.intersect(&ray, 0.0, Visibility::ALL).expect("a hit");
        assert!((hit.t - 1.0).abs() < 1e-6);
        assert!(hit.object < n as u32);
        assert!(accel.occluded(&ray, 0.0, u32::MAX));
        // Every copy but one ignored: still occluded by the others.
        assert!(accel.occluded(&ray, 0.0, hit.object));
    }

    /// Trees deeper than the fixed stack (none of the inputs above makes one any more)
    /// traverse on the per-thread heap stack: the same answers.
    #[test]
    fn heap_stack_traverses_like_the_fixed_one() {
        let mut rng = Rng::for_sample(4, 5, 6);
        let (prims, objects, visibility) = soup(3000, &mut rng);
        for width in WIDTHS {
            let accel = Accel::build_with(
                prims.clone(),
                objects.clone(),
                Vec::new(),
                visibility.clone(),
                width,
            );
            match &accel.tree {
                Trees::Four(tree) => heap_stack_answers(&accel, tree, &mut rng),
                // SAFETY: built only where AVX2 was detected.
                #[cfg(target_arch = "x86_64")]
                Trees::Eight(tree) => unsafe { heap_stack_answers_avx2(&accel, tree, &mut rng) },
            }
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn heap_stack_answers_avx2(accel: &Accel, tree: &Tree<F8>, rng: &mut Rng) {
        heap_stack_answers(accel, tree, rng)
    }

    #[inline(always)]
    fn heap_stack_answers<L: Lanes>(accel: &Accel, tree: &Tree<L>, rng: &mut Rng) {
        for _ in 0..500 {
            let ray = Ray {
                origin: Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32())
                    - Vec3A::splat(0.5),
                dir: uniform_sphere(rng.next_2d()),
                tmax: f32::INFINITY,
            };
            let need = tree.stack_need;
            let fixed = accel.closest::<L, false>(
                tree,
                &ray,
                0.0,
                7,
                u32::MAX,
                &mut Stack::<(u32, f32), STACK>::new(),
            );
            let heap =
                accel.closest::<L, false>(tree, &ray, 0.0, 7, u32::MAX, &mut vec![(0, 0.0); need]);
            assert_eq!(fixed, heap);
            let fixed = accel.any_hit(tree, &ray, 0.0, 2, &mut Stack::<u32, STACK>::new());
            let heap = accel.any_hit(tree, &ray, 0.0, 2, &mut vec![0; need]);
            assert_eq!(fixed, heap);
        }
    }

    /// Inputs the binned-SAH builder takes (a fan, whose boxes all overlap, and a soup
    /// above its size threshold) answer as testing every primitive does.
    #[test]
    fn sah_built_trees_match_brute_force() {
        let mut rng = Rng::for_sample(9, 8, 7);
        let fan = crate::geometry::shapes::disk(&glam::Affine3A::IDENTITY, 6000).prims;
        let (soup, _, _) = soup(SAH_ABOVE + 1, &mut rng);
        for (prims, width) in [fan, soup]
            .into_iter()
            .flat_map(|p| WIDTHS.map(|w| (p.clone(), w)))
        {
            let n = prims.len();
            let objects: Vec<u32> = (0..n as u32).map(|i| i % 3).collect();
            let accel = Accel::build_with(
                prims.clone(),
                objects.clone(),
                Vec::new(),
                vec![7; n],
                width,
            );
            for _ in 0..300 {
                let origin = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 3.0
                    - Vec3A::splat(1.5);
                let ray = Ray {
                    origin,
                    dir: uniform_sphere(rng.next_2d()),
                    tmax: f32::INFINITY,
                };
                let brute = prims
                    .iter()
                    .map(|p| p.intersect(ray.origin, ray.dir, 0.0, ray.tmax))
                    .fold(f32::INFINITY, f32::min);
                let got = accel
                    .intersect(&ray, 0.0, Visibility::ALL)
                    .map_or(f32::INFINITY, |h| h.t);
                assert!(got == brute, "n {n}: bvh {got} brute {brute}");
                let blocked = prims.iter().zip(&objects).any(|(p, &o)| {
                    o != 1 && p.intersect(ray.origin, ray.dir, 0.0, ray.tmax).is_finite()
                });
                assert_eq!(accel.occluded(&ray, 0.0, 1), blocked, "n {n}");
            }
        }
    }

    /// A mesh placed several times (turned, scaled unevenly, one mirrored) answers as the
    /// same triangles placed and built flat: the same distances, normals and objects.
    #[test]
    fn instances_trace_like_their_flattened_copies() {
        use glam::{Affine3A, Quat, Vec3};
        let mut rng = Rng::for_sample(2, 4, 6);
        let (mesh, _, _) = soup(300, &mut rng);
        let mesh: Vec<Prim> = mesh
            .into_iter()
            .filter(|p| matches!(p, Prim::Triangle { .. }))
            .collect();
        let placements = [
            Affine3A::from_scale_rotation_translation(
                Vec3::new(0.5, 0.8, 0.3),
                Quat::from_rotation_y(0.6),
                Vec3::new(1.5, 0.0, 0.0),
            ),
            Affine3A::from_rotation_translation(
                Quat::from_rotation_x(-1.1),
                Vec3::new(-1.2, 0.3, 0.4),
            ),
            Affine3A::from_scale_rotation_translation(
                Vec3::new(-0.6, 0.6, 0.6),
                Quat::from_rotation_z(0.3),
                Vec3::new(0.0, -1.4, 0.2),
            ),
        ];
        let meshes = vec![Accel::build(
            mesh.clone(),
            vec![0; mesh.len()],
            Vec::new(),
            vec![7; mesh.len()],
        )];
        let mut top = Vec::new();
        let mut flat = Vec::new();
        let mut flat_objects = Vec::new();
        let mut instances = Vec::new();
        for (k, xf) in placements.iter().enumerate() {
            let inst = Instance::new(0, *xf).unwrap();
            let (lo, hi) = meshes[0].bounds();
            let (lo, hi) = inst.world_bounds(lo, hi);
            top.push(Prim::Instance {
                lo,
                hi,
                index: k as u32,
            });
            instances.push(inst);
            for p in &mesh {
                let Prim::Triangle { p0, e1, e2, .. } = *p else {
                    unreachable!()
                };
                let q0 = xf.transform_point3a(p0);
                flat.push(Prim::Triangle {
                    p0: q0,
                    e1: xf.transform_point3a(p0 + e1) - q0,
                    e2: xf.transform_point3a(p0 + e2) - q0,
                    normals: u32::MAX,
                });
                flat_objects.push(k as u32);
            }
        }
        // The first placement is hidden from camera rays.
        let top_visibility = vec![6, 7, 7];
        let flat_visibility: Vec<u8> = flat_objects
            .iter()
            .map(|&k| top_visibility[k as usize])
            .collect();
        let n = top.len();
        let instanced = Accel::build(top, (0..n as u32).collect(), Vec::new(), top_visibility)
            .with_instances(meshes, instances);
        let flat = Accel::build(flat, flat_objects, Vec::new(), flat_visibility);
        let mut hits = 0;
        for _ in 0..4000 {
            let ray = random_ray(&mut rng, 5.0, 2.0);
            for mask in [Visibility::CAMERA, Visibility::INDIRECT] {
                let a = instanced.intersect(&ray, 0.0, mask);
                let b = flat.intersect(&ray, 0.0, mask);
                match (a, b) {
                    (None, None) => {}
                    (Some(a), Some(b)) => {
                        hits += 1;
                        assert!((a.t - b.t).abs() <= 1e-4 * b.t, "{} vs {}", a.t, b.t);
                        assert_eq!(a.object, b.object);
                        assert!((a.ng - b.ng).length() < 1e-3, "{} vs {}", a.ng, b.ng);
                        assert!((a.p - b.p).length() < 1e-4);
                    }
                    // A ray grazing an edge may pass between two triangles in one copy only.
                    (a, b) => panic!(
                        "instanced {:?} vs flat {:?}",
                        a.map(|h| h.t),
                        b.map(|h| h.t)
                    ),
                }
            }
            for ignore in [0, 1, u32::MAX] {
                assert_eq!(
                    instanced.occluded(&ray, 0.0, ignore),
                    flat.occluded(&ray, 0.0, ignore)
                );
            }
        }
        assert!(hits > 500, "{hits}");
    }

    #[test]
    fn empty_scene_hits_nothing() {
        let accel = Accel::build(Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let ray = Ray {
            origin: Vec3A::ZERO,
            dir: Vec3A::X,
            tmax: f32::INFINITY,
        };
        assert!(accel.intersect(&ray, 0.0, Visibility::ALL).is_none());
        assert!(!accel.occluded(&ray, 0.0, u32::MAX));
    }
}
