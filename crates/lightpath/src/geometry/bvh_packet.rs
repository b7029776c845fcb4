//! Camera rays traced as a packet: up to [`PACKET`] rays from one point (a pinhole
//! camera's rays through one pixel) walk the tree together. A node is tested once for the
//! whole packet, with bounds on every ray's slab distances; a leaf's triangles are tested
//! ray by ray with the single-ray test (`RayLanes::hit_triangles`), so each ray finds the
//! distance `Accel::intersect` finds. Rays from different points, or whose directions
//! differ in sign on an axis, are traced one at a time.

#[cfg(target_arch = "x86_64")]
use super::F8;
use super::{Accel, Lanes, Mask, Node, RayLanes, Stack, TraversalStack, Tree, Trees};
use super::{LEAF, STACK};
use crate::geometry::{Hit, Prim, Ray};

/// Most rays traced as one packet.
pub const PACKET: usize = 8;

/// A ray's nearest hit so far: (slot or `u32::MAX`, distance, instanced mesh's slot).
type Nearest = (u32, f32, u32);

/// Widening of the packet's slab bounds, relative: they are computed as (plane − origin)
/// × inverse direction, the single ray's as plane × inverse − origin × inverse; this
/// covers both roundings (~80 ulps) so the packet never skips a box one of its rays enters.
const WIDEN: f32 = 1e-5;

/// What the packet's box test needs: the common origin and, per axis, the range of the
/// rays' inverse directions (all of one sign).
struct PacketLanes<L: Lanes> {
    origin: [L; 3],
    inv_lo: [L; 3],
    inv_hi: [L; 3],
    near: [usize; 3],
    tmin: f32,
}

impl<L: Lanes> PacketLanes<L> {
    /// `None` when the rays do not share an origin or a direction sign per axis.
    #[inline(always)]
    fn new(rays: &[Ray], lanes: &[RayLanes<L>], tmin: f32) -> Option<PacketLanes<L>> {
        let origin = rays[0].origin;
        let near = lanes[0].near;
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        for (ray, r) in rays.iter().zip(lanes) {
            if ray.origin != origin || r.near != near {
                return None;
            }
            for axis in 0..3 {
                let inv = r.inv[axis].store().as_ref()[0];
                lo[axis] = lo[axis].min(inv);
                hi[axis] = hi[axis].max(inv);
            }
        }
        Some(PacketLanes {
            origin: [L::splat(origin.x), L::splat(origin.y), L::splat(origin.z)],
            inv_lo: lo.map(L::splat),
            inv_hi: hi.map(L::splat),
            near,
            tmin,
        })
    }

    /// Which children's boxes some ray of the packet may enter before `tmax`, and a lower
    /// bound of where. A slab distance (plane − origin) × inverse is linear in the
    /// inverse, so over the packet it lies between its values at the range's two ends.
    #[inline(always)]
    fn hit_children(&self, node: &Node<L>, tmax: f32) -> (u32, L) {
        let b = &node.bounds;
        let [nx, ny, nz] = self.near;
        let ends = |plane: L, axis: usize| {
            let n = plane - self.origin[axis];
            (n * self.inv_lo[axis], n * self.inv_hi[axis])
        };
        let lowest = |plane: L, axis: usize| {
            let (a, b) = ends(plane, axis);
            a.min(b)
        };
        let highest = |plane: L, axis: usize| {
            let (a, b) = ends(plane, axis);
            a.max(b)
        };
        let tn = lowest(b[nx], 0)
            .max(lowest(b[ny], 1))
            .max(lowest(b[nz], 2).max(L::splat(self.tmin)));
        let tf = highest(b[3 - nx], 0)
            .min(highest(b[5 - ny], 1))
            .min(highest(b[7 - nz], 2).min(L::splat(tmax)));
        let tnear = tn * L::splat(1.0 - WIDEN);
        let tfar = tf * L::splat(1.0 + WIDEN);
        (tnear.le(tfar).bits() & node.lanes, tnear)
    }
}

impl Accel {
    /// The nearest hits of `rays` (at most [`PACKET`]) among primitives visible to rays
    /// of kind `mask`: the hits `intersect` finds ray by ray, traced as one packet where
    /// the rays share an origin (a pinhole camera's rays through one pixel).
    pub fn intersect_packet(&self, rays: &[Ray], tmin: f32, mask: u8, hits: &mut [Option<Hit>]) {
        debug_assert!(rays.len() <= PACKET && hits.len() == rays.len());
        let found = if rays.len() < 2 || self.prims.is_empty() || self.uses_embree() {
            None
        } else {
            match &self.tree {
                Trees::Four(tree) => self.nearest_packet(tree, rays, tmin, mask),
                // SAFETY: `Eight` trees are only built where AVX2 was detected.
                #[cfg(target_arch = "x86_64")]
                Trees::Eight(tree) => unsafe { self.nearest_packet_avx2(tree, rays, tmin, mask) },
            }
        };
        match found {
            Some(found) => {
                for ((hit, ray), &(prim, t, inner)) in hits.iter_mut().zip(rays).zip(&found) {
                    *hit = (prim != u32::MAX).then(|| self.surface(ray, prim, t, inner));
                }
            }
            None => {
                for (hit, ray) in hits.iter_mut().zip(rays) {
                    *hit = self.intersect(ray, tmin, mask);
                }
            }
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn nearest_packet_avx2(
        &self,
        tree: &Tree<F8>,
        rays: &[Ray],
        tmin: f32,
        mask: u8,
    ) -> Option<[Nearest; PACKET]> {
        self.nearest_packet(tree, rays, tmin, mask)
    }

    /// Packet traversal, nearest child (by the packet's bound) first; `None` where the
    /// rays cannot form a packet or the tree is deeper than the fixed stack.
    #[inline(always)]
    fn nearest_packet<L: Lanes>(
        &self,
        tree: &Tree<L>,
        rays: &[Ray],
        tmin: f32,
        mask: u8,
    ) -> Option<[Nearest; PACKET]> {
        if tree.stack_need > STACK {
            return None;
        }
        let n = rays.len();
        let lanes: [RayLanes<L>; PACKET] =
            std::array::from_fn(|k| RayLanes::new(&rays[k.min(n - 1)], tmin));
        let packet = PacketLanes::new(rays, &lanes[..n], tmin)?;
        let mask = (mask & 7) as usize;
        let mut found = [(u32::MAX, f32::INFINITY, u32::MAX); PACKET];
        for (f, ray) in found.iter_mut().zip(rays) {
            f.1 = ray.tmax;
        }
        // The farthest any ray still looks: a box beyond it helps none of them.
        let mut reach = rays.iter().fold(0.0f32, |m, r| m.max(r.tmax));
        let mut stack = Stack::<(u32, f32), STACK>::new();
        let mut sp = 0;
        let mut current = 0u32;
        loop {
            if current & LEAF == 0 {
                let node = &tree.nodes[current as usize];
                let (hits, tnear) = packet.hit_children(node, reach);
                if hits != 0 {
                    current = visit_nearest(node, hits, tnear, &mut stack, &mut sp);
                    continue;
                }
            } else {
                let first = (current & !LEAF) as usize;
                for (k, ray) in rays.iter().enumerate() {
                    self.leaf_nearest(tree, first, ray, &lanes[k], mask, &mut found[k]);
                }
                reach = found[..n].iter().fold(0.0f32, |m, f| m.max(f.1));
            }
            // Next stacked child that some ray may still find a nearer hit in.
            loop {
                if sp == 0 {
                    return Some(found);
                }
                sp -= 1;
                let (child, t) = stack.take(sp);
                if t <= reach {
                    current = child;
                    break;
                }
            }
        }
    }

    /// One ray against the leaf that starts at packet `first` (`closest`'s leaf step).
    #[inline(always)]
    fn leaf_nearest<L: Lanes>(
        &self,
        tree: &Tree<L>,
        first: usize,
        ray: &Ray,
        r: &RayLanes<L>,
        mask: usize,
        nearest: &mut Nearest,
    ) {
        let (best, tmax, inner) = nearest;
        let mut index = first;
        loop {
            let leaf = &tree.leaves[index];
            let lanes = leaf.triangles[mask] as u32;
            if lanes != 0 {
                let (mut hits, t) = r.hit_triangles(leaf, *tmax);
                hits &= lanes;
                if hits != 0 {
                    let t = t.store();
                    let t = t.as_ref();
                    while hits != 0 {
                        let lane = hits.trailing_zeros() as usize;
                        hits &= hits - 1;
                        if t[lane] < *tmax {
                            *tmax = t[lane];
                            *best = leaf.first + lane as u32;
                        }
                    }
                }
            }
            let mut spheres = leaf.spheres[mask] as u32;
            while spheres != 0 {
                let slot = leaf.first + spheres.trailing_zeros();
                spheres &= spheres - 1;
                let prim = &self.prims[slot as usize];
                let t = if let Prim::Instance { index, .. } = *prim {
                    let (hit, t) = self.instance_nearest(index, ray, r.tmin, *tmax);
                    if t < *tmax {
                        *inner = hit;
                    }
                    t
                } else {
                    prim.intersect(ray.origin, ray.dir, r.tmin, *tmax)
                };
                if t < *tmax {
                    *tmax = t;
                    *best = slot;
                }
            }
            if leaf.last {
                break;
            }
            index += 1;
        }
    }
}

/// Of the children `hits` of `node`, stacks all but the nearest (far ones first) and
/// returns the nearest, by their distances `tnear`.
#[inline(always)]
fn visit_nearest<L: Lanes>(
    node: &Node<L>,
    hits: u32,
    tnear: L,
    stack: &mut Stack<(u32, f32), STACK>,
    sp: &mut usize,
) -> u32 {
    let child = node.child.as_ref();
    let first = hits.trailing_zeros() as usize;
    let rest = hits & (hits - 1);
    if rest == 0 {
        return child[first];
    }
    let tnear = tnear.store();
    let tnear = tnear.as_ref();
    if rest & (rest - 1) == 0 {
        // Two children, the commonest case: the nearer first, ties as `closest` breaks them.
        let second = rest.trailing_zeros() as usize;
        let (near, far) = if tnear[second] < tnear[first] {
            (second, first)
        } else {
            (first, second)
        };
        stack.put(*sp, (child[far], tnear[far]));
        *sp += 1;
        return child[near];
    }
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
        stack.put(*sp, (child, t));
        *sp += 1;
    }
    order[n - 1].1
}

#[cfg(test)]
mod tests {
    use super::super::Width;
    use super::*;
    use crate::geometry::Visibility;
    use crate::sampling::{uniform_sphere, Rng};
    use glam::Vec3A;

    /// Packets of rays from one point through a small cone (a pixel's camera rays), from
    /// inside and outside a soup of triangles and spheres: every ray's hit is the one
    /// `intersect` finds, bit for bit; mixed-sign packets fall back and agree too.
    #[test]
    fn packets_find_what_single_rays_find() {
        let mut rng = Rng::for_sample(11, 12, 13);
        let (prims, objects, visibility) = super::super::tests::soup(4000, &mut rng);
        for width in [Width::Four, Width::Eight] {
            let accel = Accel::build_with(
                prims.clone(),
                objects.clone(),
                Vec::new(),
                visibility.clone(),
                width,
            );
            let mut packets = 0;
            for case in 0..400 {
                let origin = if case % 2 == 0 {
                    Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 0.5
                } else {
                    uniform_sphere(rng.next_2d()) * 3.0
                };
                let axis = uniform_sphere(rng.next_2d());
                // Cones from a pixel's width to a wide one.
                let spread = [1e-3, 1e-2, 0.3][case % 3];
                let n = 2 + case % (PACKET - 1);
                let rays: Vec<Ray> = (0..n)
                    .map(|_| Ray {
                        origin,
                        dir: (axis + uniform_sphere(rng.next_2d()) * spread).normalize(),
                        tmax: if case % 5 == 0 { 1.5 } else { f32::INFINITY },
                    })
                    .collect();
                let mut hits = vec![None; n];
                let mask = [Visibility::CAMERA, Visibility::ALL][case % 2];
                accel.intersect_packet(&rays, 0.0, mask, &mut hits);
                for (ray, hit) in rays.iter().zip(&hits) {
                    let single = accel.intersect(ray, 0.0, mask);
                    // The same distance on the same primitive, or on an exact copy of it
                    // (a tie, which visiting boxes in another order may break otherwise).
                    let seen = |h: &Option<Hit>| {
                        h.map(|h| (h.t.to_bits(), accel.prims()[h.prim as usize].bounds()))
                    };
                    assert_eq!(seen(hit), seen(&single), "{width:?}, case {case}");
                }
                packets += usize::from(hits.iter().any(Option::is_some));
            }
            assert!(packets > 100, "too few packets hit anything: {packets}");
        }
    }
}
