//! Which light a shading point samples, with what probability (docs/architecture.md's owner of that
//! decision). Three strategies, `[render] light_selection` / `--light-selection`:
//!
//! - `tree` (default): a bounding volume hierarchy over the lights with a surface, points
//!   and spots, each node bounding its lights' power, extent and emission directions
//!   (pbrt-v4's `BVHLightSampler`, the idea of Cycles' light tree). At a shading point
//!   the traversal picks a child in proportion to an importance that bounds what the
//!   child's lights can send there: power × bounded cosines / distance². Domes and
//!   distant lights are weighed against the tree by the irradiance they can deliver
//!   (π × average radiance for a dome, the irradiance for a distant light).
//! - `power`: one distribution over all lights by emitted power, the same everywhere
//!   (pbrt-v4's `PowerLightSampler`).
//! - `uniform`: every light equally likely. Nothing in the selection depends on a light's
//!   colour, so a render relit from its light-group AOVs (`lightpath comp --gain`)
//!   equals a re-render with the new colours bit for bit; with `tree` and `power` the two
//!   agree within their noise.
//!
//! A light's probability depends on the shading point (and its normal) under `tree`; the
//! integrator asks [`LightSelector::pmf`] with the point it scattered from when a BSDF
//! ray finds a light, so MIS weighs both strategies with the probabilities they had.
//!
//! ```toml
//! [render]
//! light_selection = "tree"   # tree | power | uniform
//! ```

use super::Light;
use crate::geometry::Prim;
use crate::sampling::Distribution1D;
use glam::Vec3A;
use std::f32::consts::PI;

/// How lights are chosen for light sampling.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LightSelection {
    #[default]
    Tree,
    Power,
    Uniform,
}

impl LightSelection {
    pub const NAMES: [&'static str; 3] = ["tree", "power", "uniform"];

    pub fn parse(s: &str) -> Option<LightSelection> {
        match s {
            "tree" => Some(LightSelection::Tree),
            "power" => Some(LightSelection::Power),
            "uniform" => Some(LightSelection::Uniform),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            LightSelection::Tree => "tree",
            LightSelection::Power => "power",
            LightSelection::Uniform => "uniform",
        }
    }
}

/// The light sampler of a scene.
#[derive(Clone, Debug)]
pub enum LightSelector {
    /// Every light with probability `pmf = 1 / count`; `scale` is `count as f32`
    /// (both kept: the conversions and the division were most of a single-light
    /// scene's light choice).
    Uniform {
        count: usize,
        scale: f32,
        pmf: f32,
    },
    /// One distribution over all lights.
    Power(Distribution1D),
    Tree(LightTree),
}

impl LightSelector {
    /// Uniform selection among `count` lights.
    fn uniform(count: usize) -> LightSelector {
        LightSelector::Uniform {
            count,
            scale: count as f32,
            pmf: 1.0 / count as f32,
        }
    }

    /// The selector `selection` asks for over `lights` (`scene_radius`: the radius of the
    /// scene's bounding sphere, for the power of lights at infinity).
    pub fn build(
        selection: LightSelection,
        lights: &[Light],
        prims: &[Prim],
        scene_radius: f32,
    ) -> LightSelector {
        match selection {
            LightSelection::Uniform => LightSelector::uniform(lights.len()),
            LightSelection::Power => {
                let w: Vec<f32> = lights.iter().map(|l| l.power(scene_radius)).collect();
                if w.iter().sum::<f32>() > 0.0 {
                    LightSelector::Power(Distribution1D::new(&w))
                } else {
                    LightSelector::uniform(lights.len())
                }
            }
            // One light needs no tree: its probability is 1 wherever it can reach, and
            // where the tree would find that it cannot (behind a one-sided emitter,
            // outside a spot's cone), its light sample finds no light anyway. The tree
            // walk was 5 % of a `cornell-classic` render's instructions.
            LightSelection::Tree if lights.len() == 1 => LightSelector::uniform(1),
            LightSelection::Tree => LightSelector::Tree(LightTree::build(lights, prims)),
        }
    }

    /// Picks a light for shading point `p` with normal `n` (zero: no normal): the light
    /// and its probability, or `None` when no light can reach `p`.
    #[inline]
    pub fn sample(&self, u: f32, p: Vec3A, n: Vec3A) -> Option<(usize, f32)> {
        match self {
            &LightSelector::Uniform { count, scale, pmf } => {
                // One light (most scenes, and every `Tree` over one light): no
                // float-to-index cast, whose saturating conversion was ~17 instructions a
                // vertex on the indirect box. The same index as below for any `u`.
                if count == 1 {
                    return Some((0, pmf));
                }
                if count == 0 {
                    return None;
                }
                let i = ((u * scale) as usize).min(count - 1);
                Some((i, pmf))
            }
            LightSelector::Power(d) => {
                if d.is_empty() {
                    return None;
                }
                let (i, pmf, _) = d.sample(u);
                Some((i, pmf))
            }
            LightSelector::Tree(t) => t.sample(u, p, n),
        }
    }

    /// The probability that [`sample`](Self::sample) at (`p`, `n`) picks `light`.
    #[inline]
    pub fn pmf(&self, light: usize, p: Vec3A, n: Vec3A) -> f32 {
        match self {
            LightSelector::Uniform { pmf, .. } => *pmf,
            LightSelector::Power(d) => d.pmf(light),
            LightSelector::Tree(t) => t.pmf(light, p, n),
        }
    }
}

/// What the light tree knows of a light ([`LightModel::reach`](super::LightModel::reach)).
#[derive(Clone, Copy, Debug)]
pub enum Reach {
    /// A light with a place: its bounds in the tree.
    Bounded(LightBounds),
    /// A light at infinity beside the tree: the irradiance it can deliver (dome: π ×
    /// average radiance; distant: its irradiance) and a distant light's direction, whose
    /// cosine with the receiver's normal scales it (zero: none).
    Infinite { irradiance: f32, dir: Vec3A },
    /// A light that sends nothing (black, or without area).
    Nowhere,
}

/// A cone of directions: axis `w` and the cosine of its half angle.
#[derive(Clone, Copy, Debug)]
pub struct Cone {
    pub w: Vec3A,
    pub cos_theta: f32,
}

impl Cone {
    pub const SPHERE: Cone = Cone {
        w: Vec3A::Z,
        cos_theta: -1.0,
    };

    /// The smallest cone holding both (pbrt-v4 `Union(DirectionCone, DirectionCone)`).
    pub fn union(a: Cone, b: Cone) -> Cone {
        let theta_a = a.cos_theta.clamp(-1.0, 1.0).acos();
        let theta_b = b.cos_theta.clamp(-1.0, 1.0).acos();
        let theta_d = a.w.dot(b.w).clamp(-1.0, 1.0).acos();
        if (theta_d + theta_b).min(PI) <= theta_a {
            return a;
        }
        if (theta_d + theta_a).min(PI) <= theta_b {
            return b;
        }
        let theta_o = (theta_a + theta_d + theta_b) / 2.0;
        if theta_o >= PI {
            return Cone::SPHERE;
        }
        let theta_r = theta_o - theta_a;
        let wr = a.w.cross(b.w);
        if wr.length_squared() < 1e-12 {
            return Cone::SPHERE;
        }
        let q = glam::Quat::from_axis_angle(wr.normalize().into(), theta_r);
        Cone {
            w: Vec3A::from(q * glam::Vec3::from(a.w)).normalize(),
            cos_theta: theta_o.cos(),
        }
    }
}

/// What a node knows of its lights (pbrt-v4 `LightBounds`): their extent, total power,
/// the cone of their surface normals (`cos_o`) and how far around a normal they emit
/// (`cos_e`: cos 90° for diffuse emitters).
///
/// `phi` is the lights' largest radiant intensity (radiance × projected area for a
/// surface, the intensity of a point or spot), so that `phi × cos / d²` estimates the
/// irradiance they deliver: the same unit as the domes' and distant lights' weights
/// beside the tree (pbrt-v4 uses the flux, which overweights points by 4 against
/// surfaces).
#[derive(Clone, Copy, Debug)]
pub struct LightBounds {
    pub min: Vec3A,
    pub max: Vec3A,
    pub phi: f32,
    pub normals: Cone,
    pub cos_e: f32,
    pub two_sided: bool,
}

/// cos(a − b), or 1 when b ≥ a's angle is not smaller (pbrt-v4's clamped differences).
#[inline]
fn cos_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b {
        1.0
    } else {
        cos_a * cos_b + sin_a * sin_b
    }
}

#[inline]
fn sin_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b {
        0.0
    } else {
        sin_a * cos_b - cos_a * sin_b
    }
}

#[inline]
fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

impl LightBounds {
    fn union(a: &LightBounds, b: &LightBounds) -> LightBounds {
        if a.phi == 0.0 {
            return *b;
        }
        if b.phi == 0.0 {
            return *a;
        }
        LightBounds {
            min: a.min.min(b.min),
            max: a.max.max(b.max),
            phi: a.phi + b.phi,
            normals: Cone::union(a.normals, b.normals),
            cos_e: a.cos_e.min(b.cos_e),
            two_sided: a.two_sided || b.two_sided,
        }
    }

    fn centroid(&self) -> Vec3A {
        0.5 * (self.min + self.max)
    }
}

/// A node's bounds as the traversal reads them, precomputed from its [`LightBounds`].
#[derive(Clone, Copy, Debug)]
struct NodeBounds {
    centroid: Vec3A,
    /// Squared radius of the box's bounding sphere.
    radius2: f32,
    /// The smallest squared distance the importance divides by (pbrt-v4's clamp).
    d2_min: f32,
    phi: f32,
    w: Vec3A,
    cos_o: f32,
    sin_o: f32,
    cos_e: f32,
    two_sided: bool,
}

impl NodeBounds {
    fn new(b: &LightBounds) -> NodeBounds {
        let diag = (b.max - b.min).length();
        let cos_o = b.normals.cos_theta;
        NodeBounds {
            centroid: b.centroid(),
            radius2: 0.25 * diag * diag,
            d2_min: 0.5 * diag,
            phi: b.phi,
            w: b.normals.w,
            cos_o,
            sin_o: safe_sqrt(1.0 - cos_o * cos_o),
            cos_e: b.cos_e,
            two_sided: b.two_sided,
        }
    }

    /// An upper bound of what the node's lights send to `p` with normal `n` (zero: no
    /// normal), in irradiance (pbrt-v4 `LightBounds::Importance`): power × the cosine
    /// of the smallest angle between the emission cone and `p`, widened by the angle the
    /// bounds subtend, over the squared distance, × the receiver's bounded cosine. Zero
    /// when `p` is outside every direction the lights emit into.
    #[inline]
    fn importance(&self, p: Vec3A, n: Vec3A) -> f32 {
        let to_p = p - self.centroid;
        let dist2 = to_p.length_squared();
        let d2 = dist2.max(self.d2_min);
        let wi = if dist2 > 0.0 {
            to_p * dist2.sqrt().recip()
        } else {
            Vec3A::Z
        };
        // The angle the bounding sphere subtends from `p` (`cos_b = -1`: all of it).
        let (cos_b, sin_b) = if dist2 <= self.radius2 {
            (-1.0, 0.0)
        } else {
            let s2 = self.radius2 / dist2;
            (safe_sqrt(1.0 - s2), s2.sqrt())
        };
        let cos_p = if self.cos_o <= -1.0 {
            1.0
        } else {
            let mut cos_w = self.w.dot(wi);
            if self.two_sided {
                cos_w = cos_w.abs();
            }
            let sin_w = safe_sqrt(1.0 - cos_w * cos_w);
            let cos_x = cos_sub_clamped(sin_w, cos_w, self.sin_o, self.cos_o);
            let sin_x = sin_sub_clamped(sin_w, cos_w, self.sin_o, self.cos_o);
            cos_sub_clamped(sin_x, cos_x, sin_b, cos_b)
        };
        if cos_p <= self.cos_e {
            return 0.0;
        }
        let mut importance = self.phi * cos_p / d2;
        if n != Vec3A::ZERO && cos_b > -1.0 {
            let cos_i = wi.dot(n).abs();
            let sin_i = safe_sqrt(1.0 - cos_i * cos_i);
            importance *= cos_sub_clamped(sin_i, cos_i, sin_b, cos_b);
        }
        importance.max(0.0)
    }
}

#[derive(Clone, Debug)]
struct Node {
    bounds: NodeBounds,
    /// A leaf: the light; an interior node: its second child (the first follows it).
    index: u32,
    leaf: bool,
}

/// A light at infinity beside the tree: what it can deliver, as in
/// [`NodeBounds::importance`]'s unit.
#[derive(Clone, Copy, Debug)]
struct Infinite {
    light: u32,
    /// Irradiance it can deliver (dome: π × average radiance; distant: its irradiance).
    irradiance: f32,
    /// A distant light's direction (the receiver's cosine scales it), or zero.
    dir: Vec3A,
}

impl Infinite {
    #[inline]
    fn importance(&self, n: Vec3A) -> f32 {
        if self.dir == Vec3A::ZERO || n == Vec3A::ZERO {
            self.irradiance
        } else {
            // Never zero: a grazing normal still receives light on a two-sided surface
            // or a rough BSDF's far lobe.
            self.irradiance * self.dir.dot(n).abs().max(1e-3)
        }
    }
}

/// The light tree and the lights at infinity beside it.
#[derive(Clone, Debug)]
pub struct LightTree {
    nodes: Vec<Node>,
    infinite: Vec<Infinite>,
    /// Per light: the turns from the root to its leaf (bit k: the turn at depth k, 1 =
    /// second child) and the leaf's depth; `u32::MAX` for lights not in the tree.
    trails: Vec<(u64, u32)>,
}

/// Deepest tree the bit trails describe; a median split reaches it only past 2^63 lights.
const MAX_DEPTH: u32 = 63;

/// Largest f32 below 1.
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

impl LightTree {
    /// `prims`: the scene's primitives, which area lights index.
    pub fn build(lights: &[Light], prims: &[Prim]) -> LightTree {
        let mut items = Vec::new();
        let mut infinite = Vec::new();
        for (i, l) in lights.iter().enumerate() {
            match l.reach(prims) {
                Reach::Bounded(b) if b.phi > 0.0 => items.push((i as u32, b)),
                Reach::Infinite { irradiance, dir } => infinite.push(Infinite {
                    light: i as u32,
                    irradiance,
                    dir,
                }),
                _ => {}
            }
        }
        let mut tree = LightTree {
            nodes: Vec::with_capacity(2 * items.len()),
            infinite,
            trails: vec![(0, u32::MAX); lights.len()],
        };
        if !items.is_empty() {
            tree.build_node(&mut items, 0, 0);
        }
        tree
    }

    /// Builds the subtree of `items`, reached from the root by `trail` at `depth`, and
    /// returns its node: the lights are split at the median of their centres along the
    /// axis the centres spread most.
    fn build_node(&mut self, items: &mut [(u32, LightBounds)], trail: u64, depth: u32) -> usize {
        let at = self.nodes.len();
        let mut all = items[0].1;
        for (_, b) in &items[1..] {
            all = LightBounds::union(&all, b);
        }
        if items.len() == 1 || depth >= MAX_DEPTH {
            let (light, bounds) = items[0];
            self.nodes.push(Node {
                bounds: NodeBounds::new(&bounds),
                index: light,
                leaf: true,
            });
            self.trails[light as usize] = (trail, depth);
            return at;
        }
        let mut cmin = Vec3A::splat(f32::INFINITY);
        let mut cmax = Vec3A::splat(f32::NEG_INFINITY);
        for (_, b) in items.iter() {
            cmin = cmin.min(b.centroid());
            cmax = cmax.max(b.centroid());
        }
        let extent = cmax - cmin;
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        let mid = items.len() / 2;
        items.select_nth_unstable_by(mid, |a, b| {
            a.1.centroid()[axis]
                .total_cmp(&b.1.centroid()[axis])
                .then(a.0.cmp(&b.0))
        });
        self.nodes.push(Node {
            bounds: NodeBounds::new(&all),
            index: 0,
            leaf: false,
        });
        let (first, second) = items.split_at_mut(mid);
        self.build_node(first, trail, depth + 1);
        let second = self.build_node(second, trail | 1 << depth, depth + 1);
        self.nodes[at].index = second as u32;
        at
    }

    /// The tree's weight at (`p`, `n`) and the sum of it and the lights at infinity's.
    #[inline]
    fn top(&self, p: Vec3A, n: Vec3A) -> (f32, f32) {
        let tree = self
            .nodes
            .first()
            .map_or(0.0, |r| r.bounds.importance(p, n));
        let total = tree + self.infinite.iter().map(|l| l.importance(n)).sum::<f32>();
        (tree, total)
    }

    /// The probability of the first child of interior node `node` at (`p`, `n`), or
    /// `None` when neither child can light `p`.
    #[inline]
    fn first_child_probability(&self, node: usize, p: Vec3A, n: Vec3A) -> Option<f32> {
        let c0 = self.nodes[node + 1].bounds.importance(p, n);
        let c1 = self.nodes[self.nodes[node].index as usize]
            .bounds
            .importance(p, n);
        let sum = c0 + c1;
        (sum > 0.0 && sum.is_finite()).then(|| c0 / sum)
    }

    fn sample(&self, u: f32, p: Vec3A, n: Vec3A) -> Option<(usize, f32)> {
        let (tree, total) = self.top(p, n);
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let target = u * total;
        if target >= tree || self.nodes.is_empty() {
            let mut rest = target - tree;
            let mut chosen = None;
            for l in &self.infinite {
                let w = l.importance(n);
                if w > 0.0 {
                    chosen = Some((l.light as usize, w / total));
                    if rest < w {
                        break;
                    }
                    rest -= w;
                }
            }
            // Rounding may leave `rest` past the last weight: that light is chosen.
            if chosen.is_some() || self.nodes.is_empty() {
                return chosen;
            }
        }
        let mut pmf = tree / total;
        let mut u = (target / tree).min(ONE_MINUS_EPSILON);
        let mut node = 0;
        loop {
            let nd = &self.nodes[node];
            if nd.leaf {
                return Some((nd.index as usize, pmf));
            }
            let p0 = self.first_child_probability(node, p, n)?;
            if u < p0 {
                node += 1;
                u = (u / p0).min(ONE_MINUS_EPSILON);
                pmf *= p0;
            } else {
                node = nd.index as usize;
                u = ((u - p0) / (1.0 - p0)).min(ONE_MINUS_EPSILON);
                pmf *= 1.0 - p0;
            }
        }
    }

    fn pmf(&self, light: usize, p: Vec3A, n: Vec3A) -> f32 {
        let (tree, total) = self.top(p, n);
        if !(total > 0.0 && total.is_finite()) {
            return 0.0;
        }
        let (trail, depth) = self.trails[light];
        if depth == u32::MAX {
            return self
                .infinite
                .iter()
                .find(|l| l.light as usize == light)
                .map_or(0.0, |l| l.importance(n) / total);
        }
        let mut pmf = tree / total;
        let mut node = 0;
        for k in 0..depth {
            let Some(p0) = self.first_child_probability(node, p, n) else {
                return 0.0;
            };
            if trail >> k & 1 == 0 {
                node += 1;
                pmf *= p0;
            } else {
                node = self.nodes[node].index as usize;
                pmf *= 1.0 - p0;
            }
        }
        pmf
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::{Distant, Dome, LightShape, Point, Sphere, Spot, Triangles};
    use crate::sampling::{uniform_sphere, Rng};

    fn light(shape: impl Into<LightShape>, color: f32) -> Light {
        Light::new(shape, Vec3A::splat(color))
    }

    /// A mixed scene: 40 points and spheres of different powers spread over a box, a
    /// one-sided triangle facing down, a spot, a dome and a distant light.
    fn scene() -> (Vec<Light>, Vec<Prim>) {
        let mut rng = Rng::for_sample(11, 0, 0);
        let mut lights = Vec::new();
        for i in 0..40 {
            let p = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 8.0 - 4.0;
            let power = 0.1 + 10.0 * rng.next_f32();
            let shape: LightShape = if i % 2 == 0 {
                Point { position: p }.into()
            } else {
                Sphere {
                    center: p,
                    radius: 0.1,
                }
                .into()
            };
            lights.push(light(shape, power));
        }
        let prims = vec![Prim::Triangle {
            p0: Vec3A::new(0.0, 5.0, 0.0),
            e1: Vec3A::new(1.0, 0.0, 0.0),
            e2: Vec3A::new(0.0, 0.0, 1.0),
            normals: u32::MAX,
        }];
        lights.push(light(
            Triangles {
                prims: vec![0],
                normals: vec![prims[0].face_normal()],
                parallelogram: None,
                rect: None,
                by_area: Distribution1D::new(&[1.0]),
                area: 0.5,
                two_sided: false,
                shaping: None,
            },
            20.0,
        ));
        lights.push(light(
            Spot {
                position: Vec3A::new(0.0, 4.0, 0.0),
                axis: -Vec3A::Y,
                cos_inner: 0.9,
                cos_outer: 0.8,
            },
            30.0,
        ));
        lights.push(light(
            Dome {
                map: None,
                portals: Vec::new(),
            },
            0.05,
        ));
        lights.push(light(
            Distant::new(Vec3A::new(0.3, -1.0, 0.1).normalize(), 0.0),
            1.0,
        ));
        (lights, prims)
    }

    fn selectors() -> Vec<(LightSelector, usize)> {
        let (lights, prims) = scene();
        [
            LightSelection::Tree,
            LightSelection::Power,
            LightSelection::Uniform,
        ]
        .map(|s| (LightSelector::build(s, &lights, &prims, 8.0), lights.len()))
        .into()
    }

    /// At any point the probabilities of all lights sum to one, and the probability
    /// `sample` reports is the one `pmf` gives for that light (MIS relies on both).
    #[test]
    fn probabilities_sum_to_one_and_agree_with_sampling() {
        let mut rng = Rng::for_sample(3, 1, 4);
        for (sel, n) in selectors() {
            for _ in 0..200 {
                let p = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 10.0 - 5.0;
                let normal = uniform_sphere(rng.next_2d());
                let total: f32 = (0..n).map(|i| sel.pmf(i, p, normal)).sum();
                assert!((total - 1.0).abs() < 1e-4, "{total}");
                let (i, pmf) = sel.sample(rng.next_f32(), p, normal).unwrap();
                let again = sel.pmf(i, p, normal);
                assert!(
                    (pmf - again).abs() <= 1e-5 * pmf.max(1e-3),
                    "{pmf} vs {again}"
                );
            }
        }
    }

    /// Sampling picks each light as often as its probability says: counts over 200 000
    /// draws at one point within 5 standard errors of n × pmf.
    #[test]
    fn sampling_frequencies_match_the_probabilities() {
        let p = Vec3A::new(0.5, 1.0, -0.5);
        let normal = Vec3A::new(0.0, 1.0, 0.0);
        let draws = 200_000;
        for (sel, n) in selectors() {
            let mut counts = vec![0u32; n];
            let mut rng = Rng::for_sample(5, 0, 0);
            for _ in 0..draws {
                if let Some((i, _)) = sel.sample(rng.next_f32(), p, normal) {
                    counts[i] += 1;
                }
            }
            for (i, &c) in counts.iter().enumerate() {
                let q = sel.pmf(i, p, normal) as f64;
                let expected = draws as f64 * q;
                let se = (draws as f64 * q * (1.0 - q)).sqrt().max(1.0);
                assert!(
                    (c as f64 - expected).abs() <= 5.0 * se,
                    "light {i}: {c} draws, expected {expected:.0} ± {se:.0}"
                );
            }
        }
    }

    /// Power decides without a tree: a light ten times brighter is ten times as likely.
    #[test]
    fn power_selection_follows_power() {
        let lights = [
            light(
                Point {
                    position: Vec3A::ZERO,
                },
                1.0,
            ),
            light(Point { position: Vec3A::X }, 10.0),
        ];
        let sel = LightSelector::build(LightSelection::Power, &lights, &[], 1.0);
        let ratio = sel.pmf(1, Vec3A::Y, Vec3A::ZERO) / sel.pmf(0, Vec3A::Y, Vec3A::ZERO);
        assert!((ratio - 10.0).abs() < 1e-4, "{ratio}");
    }

    /// The tree favours what matters where: next to one of 64 equal lights in a row,
    /// that light is far more likely than 1/64; behind a one-sided emitter, it is never
    /// chosen; a light that can reach a point always has a chance there.
    #[test]
    fn the_tree_weighs_distance_and_orientation() {
        let mut lights: Vec<Light> = (0..64)
            .map(|i| {
                light(
                    Point {
                        position: Vec3A::new(i as f32, 0.0, 0.0),
                    },
                    1.0,
                )
            })
            .collect();
        let sel = LightSelector::build(LightSelection::Tree, &lights, &[], 50.0);
        let near = sel.pmf(10, Vec3A::new(10.0, 0.2, 0.0), Vec3A::ZERO);
        assert!(near > 0.3, "{near}");
        for i in 0..64 {
            assert!(sel.pmf(i, Vec3A::new(10.0, 0.2, 0.0), Vec3A::ZERO) > 0.0);
        }
        // A one-sided triangle facing -y at y = 5 and a point light below it.
        let (_, prims) = scene();
        lights.truncate(1);
        lights.push(light(
            Triangles {
                prims: vec![0],
                normals: vec![prims[0].face_normal()],
                parallelogram: None,
                rect: None,
                by_area: Distribution1D::new(&[1.0]),
                area: 0.5,
                two_sided: false,
                shaping: None,
            },
            5.0,
        ));
        assert!(prims[0].face_normal().y < -0.99);
        let sel = LightSelector::build(LightSelection::Tree, &lights, &prims, 10.0);
        assert_eq!(sel.pmf(1, Vec3A::new(0.3, 8.0, 0.3), Vec3A::Y), 0.0);
        // One unit below the triangle (intensity 2.5) and four above the point (1).
        assert!(sel.pmf(1, Vec3A::new(0.3, 4.0, 0.3), Vec3A::Y) > 0.9);
    }
}
