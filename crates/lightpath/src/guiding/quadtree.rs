//! The directional quadtree of Müller, Gross and Novák 2017, "Practical Path Guiding
//! for Efficient Light-Transport Simulation" (§3.2): a distribution over the square
//! [0,1)² of the cylindrical parameterisation (cos θ = 2u − 1, φ = 2πv), which is
//! area-preserving, so a density on the square is one on the sphere times 4π.
//!
//! Two forms: [`Recording`], whose leaves add records with integer atomics (fixed
//! point, so the sums do not depend on the order threads add them in), and the frozen
//! [`Quadtree`] that sampling reads. Each node holds its four quadrants' sums and, per
//! quadrant, the index of the node that subdivides it (0: the quadrant is a leaf; the
//! root is node 0 and nobody's child).

use glam::{Vec2, Vec3A};
use std::f32::consts::PI;
use std::sync::atomic::{AtomicU64, Ordering};

/// Deepest level a quadrant may be subdivided to (the paper's 20).
pub const MAX_DEPTH: u32 = 20;
/// Most nodes one quadtree may have: bounds the memory of a leaf of the spatial tree
/// (a node is 32 bytes frozen plus 48 recording).
pub const MAX_NODES: usize = 512;
/// Fixed-point scale of recorded values (2⁻²⁴ resolution; a node sums up to 2⁴⁰).
const FIXED: f64 = (1u64 << 24) as f64;
/// The largest single record, so that no sum can overflow.
const MAX_RECORD: f64 = (1u64 << 40) as f64;

/// The square's point for a unit direction.
#[inline]
pub fn dir_to_square(d: Vec3A) -> Vec2 {
    let u = (d.z.clamp(-1.0, 1.0) + 1.0) * 0.5;
    let mut phi = d.y.atan2(d.x);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let v = phi * (0.5 / PI);
    Vec2::new(u.min(1.0 - f32::EPSILON), v.min(1.0 - f32::EPSILON))
}

/// The unit direction of a point of the square.
#[inline]
pub fn square_to_dir(p: Vec2) -> Vec3A {
    let cos_theta = 2.0 * p.x - 1.0;
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let (s, c) = (2.0 * PI * p.y).sin_cos();
    Vec3A::new(sin_theta * c, sin_theta * s, cos_theta)
}

/// The quadrant of `p` in a node and `p` in that quadrant's own unit square.
#[inline]
fn quadrant(p: Vec2) -> (usize, Vec2) {
    let (qx, qy) = ((p.x >= 0.5) as usize, (p.y >= 0.5) as usize);
    let local = Vec2::new(
        (p.x * 2.0 - qx as f32).clamp(0.0, 1.0 - f32::EPSILON),
        (p.y * 2.0 - qy as f32).clamp(0.0, 1.0 - f32::EPSILON),
    );
    (qx | qy << 1, local)
}

#[derive(Clone, Debug, PartialEq)]
struct Node {
    child: [u32; 4],
    sum: [f32; 4],
}

/// A frozen quadtree: what a pass samples directions from.
#[derive(Clone, Debug, PartialEq)]
pub struct Quadtree {
    nodes: Vec<Node>,
}

impl Default for Quadtree {
    fn default() -> Self {
        Quadtree {
            nodes: vec![Node {
                child: [0; 4],
                sum: [0.0; 4],
            }],
        }
    }
}

impl Quadtree {
    /// Sum of every record: zero when nothing was learnt (then it is not sampled).
    pub fn total(&self) -> f32 {
        self.nodes[0].sum.iter().sum()
    }

    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Density on the sphere (per steradian) of unit direction `d`.
    pub fn pdf(&self, d: Vec3A) -> f32 {
        let total = self.total();
        if total <= 0.0 {
            return 0.0;
        }
        let mut p = dir_to_square(d);
        let mut density = 1.0;
        let mut n = &self.nodes[0];
        loop {
            let node_total: f32 = n.sum.iter().sum();
            let (q, local) = quadrant(p);
            if node_total <= 0.0 || n.sum[q] <= 0.0 {
                return 0.0;
            }
            density *= 4.0 * n.sum[q] / node_total;
            if n.child[q] == 0 {
                return density / (4.0 * PI);
            }
            n = &self.nodes[n.child[q] as usize];
            p = local;
        }
    }

    /// A direction drawn in proportion to the recorded sums from `u` ∈ [0,1)², or
    /// `None` if nothing was recorded.
    pub fn sample(&self, mut u: Vec2) -> Option<Vec3A> {
        if self.total() <= 0.0 {
            return None;
        }
        let mut origin = Vec2::ZERO;
        let mut size = 1.0f32;
        let mut n = &self.nodes[0];
        loop {
            let s = n.sum;
            let total: f32 = s.iter().sum();
            if total <= 0.0 {
                return None;
            }
            // First the column (u.x), then the row within it (u.y); each rescaled.
            let left = s[0] + s[2];
            let px = left / total;
            let qx = if u.x < px && left > 0.0 {
                u.x /= px;
                0
            } else {
                u.x = (u.x - px) / (1.0 - px);
                1
            };
            let (lo, hi) = (s[qx], s[qx | 2]);
            let py = lo / (lo + hi);
            let qy = if u.y < py && lo > 0.0 {
                u.y /= py;
                0
            } else {
                u.y = (u.y - py) / (1.0 - py);
                1
            };
            u = u.clamp(Vec2::ZERO, Vec2::splat(1.0 - f32::EPSILON));
            size *= 0.5;
            origin += Vec2::new(qx as f32, qy as f32) * size;
            let q = qx | qy << 1;
            if n.child[q] == 0 {
                return Some(square_to_dir(origin + u * size));
            }
            n = &self.nodes[n.child[q] as usize];
        }
    }

    /// The structure the next pass records into (§3.3): a quadrant is subdivided while
    /// it holds more than `rho` of the total energy (and merged back otherwise), down to
    /// [`MAX_DEPTH`] and within [`MAX_NODES`]. An empty tree gives the root split once.
    pub fn refined(&self, rho: f32) -> Recording {
        let total = self.total();
        let mut nodes = vec![[0u32; 4]];
        if total > 0.0 {
            // Depth-first from the root: (new node, old node or none, energy of each of
            // the node's quadrants when the old tree had no node there, depth).
            let mut stack = vec![(0usize, Some(0usize), 0.0f32, 1u32)];
            while let Some((new, old, even, depth)) = stack.pop() {
                for q in 0..4 {
                    let (energy, old_child) = match old {
                        Some(o) => {
                            let n = &self.nodes[o];
                            let c = n.child[q];
                            (n.sum[q], (c != 0).then_some(c as usize))
                        }
                        None => (even, None),
                    };
                    if depth < MAX_DEPTH && energy > rho * total && nodes.len() < MAX_NODES {
                        let c = nodes.len();
                        nodes.push([0; 4]);
                        nodes[new][q] = c as u32;
                        stack.push((c, old_child, energy / 4.0, depth + 1));
                    }
                }
            }
        }
        Recording {
            nodes: nodes
                .into_iter()
                .map(|child| RecNode {
                    child,
                    sum: Default::default(),
                })
                .collect(),
        }
    }
}

#[derive(Debug)]
struct RecNode {
    child: [u32; 4],
    sum: [AtomicU64; 4],
}

/// A quadtree's structure whose leaves add records (integer atomics: exact and
/// order-independent).
#[derive(Debug)]
pub struct Recording {
    nodes: Vec<RecNode>,
}

impl Clone for Recording {
    fn clone(&self) -> Self {
        Recording {
            nodes: self
                .nodes
                .iter()
                .map(|n| RecNode {
                    child: n.child,
                    sum: std::array::from_fn(|q| AtomicU64::new(n.sum[q].load(Ordering::Relaxed))),
                })
                .collect(),
        }
    }
}

impl Default for Recording {
    /// The paper's starting tree: the root split once.
    fn default() -> Self {
        Quadtree::default().refined(0.0)
    }
}

impl Recording {
    /// Adds `value` (a radiance over a pdf, ≥ 0) at unit direction `d`.
    pub fn record(&self, d: Vec3A, value: f32) {
        let fixed = (value as f64 * FIXED).min(MAX_RECORD);
        if fixed.is_nan() || fixed < 1.0 {
            return;
        }
        let mut p = dir_to_square(d);
        let mut n = &self.nodes[0];
        loop {
            let (q, local) = quadrant(p);
            if n.child[q] == 0 {
                n.sum[q].fetch_add(fixed as u64, Ordering::Relaxed);
                return;
            }
            n = &self.nodes[n.child[q] as usize];
            p = local;
        }
    }

    /// The frozen tree of what was recorded: inner quadrants' sums are their subtrees'.
    pub fn freeze(&self) -> Quadtree {
        let mut nodes: Vec<Node> = self
            .nodes
            .iter()
            .map(|n| Node {
                child: n.child,
                sum: std::array::from_fn(|q| {
                    (n.sum[q].load(Ordering::Relaxed) as f64 / FIXED) as f32
                }),
            })
            .collect();
        // Children come after their parents: summing from the back sees every subtree
        // complete.
        for i in (0..nodes.len()).rev() {
            for q in 0..4 {
                let c = nodes[i].child[q] as usize;
                if c != 0 {
                    nodes[i].sum[q] = nodes[c].sum.iter().sum();
                }
            }
        }
        Quadtree { nodes }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    /// A tree learnt from directions around +z and a second lobe near −x, refined twice.
    fn lobed_tree() -> Quadtree {
        let mut rng = Rng::for_sample(7, 0, 0);
        let mut tree = Quadtree::default();
        for _ in 0..3 {
            let rec = tree.refined(0.01);
            for _ in 0..20_000 {
                let u = rng.next_2d();
                let d = if rng.next_f32() < 0.7 {
                    Vec3A::new(u.x - 0.5, u.y - 0.5, 2.0).normalize()
                } else {
                    Vec3A::new(-3.0, u.x - 0.5, u.y - 0.5).normalize()
                };
                rec.record(d, 1.0 + u.x);
                rec.record(square_to_dir(rng.next_2d()), 0.05);
            }
            tree = rec.freeze();
        }
        tree
    }

    #[test]
    fn square_mapping_round_trips() {
        let mut rng = Rng::for_sample(1, 0, 0);
        for _ in 0..1000 {
            let p = rng.next_2d();
            let q = dir_to_square(square_to_dir(p));
            assert!((p - q).abs().max_element() < 1e-4, "{p} {q}");
        }
    }

    #[test]
    fn refined_tree_is_deeper_where_energy_is() {
        let tree = lobed_tree();
        assert!(tree.node_count() > 20, "{}", tree.node_count());
        assert!(tree.node_count() <= MAX_NODES);
    }

    /// The pdf integrates to one over the sphere (midpoint rule on a fine grid of the
    /// square, where the density is piecewise constant on cells far coarser than the
    /// grid except at the deepest levels).
    #[test]
    fn pdf_integrates_to_one() {
        let tree = lobed_tree();
        let n = 1024;
        let mut sum = 0.0f64;
        for i in 0..n {
            for j in 0..n {
                let p = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                sum += tree.pdf(square_to_dir(p)) as f64;
            }
        }
        let integral = sum * 4.0 * std::f64::consts::PI / (n * n) as f64;
        assert!((integral - 1.0).abs() < 1e-3, "{integral}");
    }

    /// χ² test of sampling against the tree's own pdf on a 16×16 grid of the square
    /// (a chi-square with 255 degrees of freedom: mean 255, sd √510 ≈ 22.6; the bound
    /// is five sd above the mean). Expected counts come from the pdf integrated per cell.
    #[test]
    fn sampling_matches_pdf_chi_square() {
        let tree = lobed_tree();
        let (g, sub, n) = (16usize, 32usize, 400_000usize);
        let mut expected = vec![0.0f64; g * g];
        for (c, e) in expected.iter_mut().enumerate() {
            let (ci, cj) = (c % g, c / g);
            for a in 0..sub {
                for b in 0..sub {
                    let p = Vec2::new((ci * sub + a) as f32 + 0.5, (cj * sub + b) as f32 + 0.5)
                        / (g * sub) as f32;
                    *e += tree.pdf(square_to_dir(p)) as f64;
                }
            }
            *e *= 4.0 * std::f64::consts::PI / ((g * sub) * (g * sub)) as f64 * n as f64;
        }
        let mut counts = vec![0u64; g * g];
        let mut rng = Rng::for_sample(3, 0, 0);
        for _ in 0..n {
            let d = tree.sample(rng.next_2d()).expect("a learnt tree samples");
            assert!((d.length() - 1.0).abs() < 1e-4);
            assert!(tree.pdf(d) > 0.0, "sampled where the pdf is zero");
            let p = dir_to_square(d);
            let c = (p.x * g as f32) as usize + (p.y * g as f32) as usize * g;
            counts[c] += 1;
        }
        let mut chi2 = 0.0;
        let mut dof = 0;
        for (&o, &e) in counts.iter().zip(&expected) {
            if e > 5.0 {
                chi2 += (o as f64 - e).powi(2) / e;
                dof += 1;
            } else {
                assert!(
                    o as f64 <= e + 5.0 * e.sqrt() + 5.0,
                    "{o} in a cell expecting {e}"
                );
            }
        }
        let bound = dof as f64 + 5.0 * (2.0 * dof as f64).sqrt();
        assert!(chi2 < bound, "chi2 {chi2} over {dof} cells, bound {bound}");
    }

    #[test]
    fn empty_tree_neither_samples_nor_has_density() {
        let tree = Recording::default().freeze();
        assert_eq!(tree.total(), 0.0);
        assert!(tree.sample(Vec2::splat(0.3)).is_none());
        assert_eq!(tree.pdf(Vec3A::Z), 0.0);
    }

    #[test]
    fn recording_is_order_independent() {
        let rec_a = Recording::default();
        let rec_b = Recording::default();
        let mut rng = Rng::for_sample(9, 0, 0);
        let recs: Vec<(Vec3A, f32)> = (0..1000)
            .map(|_| (square_to_dir(rng.next_2d()), rng.next_f32() * 1e3))
            .collect();
        recs.iter().for_each(|&(d, v)| rec_a.record(d, v));
        recs.iter().rev().for_each(|&(d, v)| rec_b.record(d, v));
        assert_eq!(rec_a.freeze(), rec_b.freeze());
    }
}
