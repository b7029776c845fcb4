//! Heterogeneous media: a voxel density in world space, a coarse grid of per-cell
//! density bounds walked along rays, and the two null-collision trackers built on them.
//!
//! - [`DensityGrid`]: voxels in sparse 8³ bricks (OpenVDB's leaf size; constant tiles
//!   share one brick), an index-to-world transform and a scale; [`DensityGrid::density`]
//!   interpolates trilinearly between voxel centres, which sit at integer index
//!   coordinates as in OpenVDB. Only active voxels carry density; everything else is 0.
//! - [`MajorantGrid`]: per cell of `cell`³ voxels, the minimum and maximum density any
//!   point of the cell can take, counting the trilinear footprint (one voxel past the
//!   cell on each side) plus one voxel of slack against rounding. [`MajorantGrid::segments`]
//!   walks a ray through the cells with Amanatides & Woo's DDA ("A fast voxel traversal
//!   algorithm for ray tracing", 1987), yielding [`Segment`]s.
//! - [`delta_tracking`]: free-flight distance sampling by null collisions (Woodcock et
//!   al. 1965, "Techniques used in the GEM code for Monte Carlo neutronics
//!   calculations"), with each segment's minimum as a homogeneous control sampled in
//!   closed form: Kutz et al. 2017, "Spectral and decomposition tracking for rendering
//!   heterogeneous volumes", §4 (decomposition tracking). With a zero minimum it is plain
//!   delta tracking.
//! - [`ratio_tracking`]: shadow-ray transmittance by residual ratio tracking (Novák,
//!   Selle and Jarosz 2014, "Residual ratio tracking for estimating attenuation in
//!   participating media"): the minimum is the control, attenuated in closed form, and
//!   ratio tracking estimates the residual; with Russian roulette on small estimates.
//!
//! Chromatic σt: a medium's σt is `density(p) · sigma_t` with an RGB `sigma_t`. Ratio
//! tracking uses one majorant for all channels, the max over channels, which keeps
//! every channel's factor `1 − σr,c/μ̄` in [0, 1] and every channel unbiased. Delta
//! tracking samples the free flight of one channel (the caller's hero channel, or the
//! max channel for an achromatic bound); the caller weights the others.
//!
//! Ray parameters: `t` is distance along a unit world-space direction; σ is per world
//! unit. Hot paths (lookups, the DDA, both trackers) allocate nothing; random numbers
//! come from a caller's `FnMut() -> f32` returning uniform values in [0, 1).

use crate::limits::Limits;
use crate::scene::load::vdb::{VdbGrid, LEAF_VOXELS};
use glam::{Affine3A, IVec3, Vec3};
use std::collections::HashMap;

/// Voxels along a brick's edge (as in an OpenVDB leaf).
const BRICK: i32 = 8;

/// A density field on voxels, in world space.
#[derive(Clone, Debug)]
pub struct DensityGrid {
    index_to_world: Affine3A,
    world_to_index: Affine3A,
    /// Brick `b`'s voxel `n` at `voxels[b * 512 + n]`, `n = (x << 6) | (y << 3) | z`.
    /// Brick 0 is all zeros.
    voxels: Vec<f32>,
    /// For each brick of the box, x slowest, its index in `voxels`.
    brick_of: Vec<u32>,
    /// Index coordinates of the box's first voxel (a multiple of 8).
    origin: IVec3,
    /// Bricks along each axis of the box.
    dims: IVec3,
    scale: f32,
    max: f32,
}

impl DensityGrid {
    /// A grid's active voxels times `scale` (inactive voxels are 0, negative values are
    /// clamped to 0). Errors: a scale that is negative or not finite, a grid whose box
    /// needs more than `limits` allows.
    pub fn from_vdb(grid: &VdbGrid, scale: f32) -> Result<DensityGrid, String> {
        check_scale(scale)?;
        let to_world = grid.index_to_world;
        let index_to_world = Affine3A::from_mat3_translation(
            to_world.matrix3.as_mat3(),
            to_world.translation.as_vec3(),
        );
        let mut lo = IVec3::MAX;
        let mut hi = IVec3::MIN;
        for leaf in &grid.leaves {
            lo = lo.min(leaf.origin);
            hi = hi.max(leaf.origin + BRICK);
        }
        for tile in &grid.tiles {
            lo = lo.min(tile.origin);
            hi = hi.max(tile.origin.saturating_add(IVec3::splat(tile.edge)));
        }
        let mut g = DensityGrid::empty(index_to_world, scale, lo, hi)?;
        // One shared brick per distinct tile value.
        let mut tile_bricks: HashMap<u32, u32> = HashMap::new();
        for tile in &grid.tiles {
            let v = (tile.value * scale).max(0.0);
            if v == 0.0 {
                continue;
            }
            let b = match tile_bricks.get(&v.to_bits()) {
                Some(&b) => b,
                None => {
                    let b = g.push_brick(&[v; LEAF_VOXELS])?;
                    tile_bricks.insert(v.to_bits(), b);
                    b
                }
            };
            let n = tile.edge / BRICK;
            for x in 0..n {
                for y in 0..n {
                    for z in 0..n {
                        let at = tile.origin + IVec3::new(x, y, z) * BRICK;
                        if let Some(cell) = g.brick_cell(at) {
                            g.brick_of[cell] = b;
                        }
                    }
                }
            }
        }
        let mut values = [0.0f32; LEAF_VOXELS];
        for leaf in &grid.leaves {
            for (n, v) in values.iter_mut().enumerate() {
                *v = if leaf.is_active(n) {
                    (leaf.values[n] * scale).max(0.0)
                } else {
                    0.0
                };
            }
            if values.iter().all(|&v| v == 0.0) {
                continue;
            }
            let b = g.push_brick(&values)?;
            if let Some(cell) = g.brick_cell(leaf.origin) {
                g.brick_of[cell] = b;
            }
        }
        Ok(g)
    }

    /// A dense block of `size` voxels from index (0, 0, 0), `values[(k * ny + j) * nx + i]`
    /// for voxel (i, j, k) (x fastest), times `scale`.
    pub fn from_dense(
        size: IVec3,
        values: &[f32],
        index_to_world: Affine3A,
        scale: f32,
    ) -> Result<DensityGrid, String> {
        check_scale(scale)?;
        if size.min_element() <= 0 {
            return Err(format!("a dense grid of {size} voxels"));
        }
        let count = size.as_i64vec3().element_product();
        if values.len() as i64 != count {
            return Err(format!(
                "a dense grid of {size} voxels needs {count} values, not {}",
                values.len()
            ));
        }
        let mut g = DensityGrid::empty(index_to_world, scale, IVec3::ZERO, size)?;
        let bricks = (size + BRICK - 1) / BRICK;
        let mut brick = [0.0f32; LEAF_VOXELS];
        for bx in 0..bricks.x {
            for by in 0..bricks.y {
                for bz in 0..bricks.z {
                    let base = IVec3::new(bx, by, bz) * BRICK;
                    for (n, v) in brick.iter_mut().enumerate() {
                        let p = base + crate::scene::load::vdb::leaf_offset(n);
                        *v = if p.cmplt(size).all() {
                            let i = ((p.z * size.y + p.y) * size.x + p.x) as usize;
                            (values[i] * scale).max(0.0)
                        } else {
                            0.0
                        };
                    }
                    if brick.iter().any(|&v| v != 0.0) {
                        let b = g.push_brick(&brick)?;
                        if let Some(cell) = g.brick_cell(base) {
                            g.brick_of[cell] = b;
                        }
                    }
                }
            }
        }
        Ok(g)
    }

    /// An empty grid whose box covers voxels `lo..hi` (rounded out to bricks).
    fn empty(
        index_to_world: Affine3A,
        scale: f32,
        lo: IVec3,
        hi: IVec3,
    ) -> Result<DensityGrid, String> {
        let det = index_to_world.matrix3.determinant();
        if !index_to_world.is_finite() || det.abs() < 1e-30 || !det.is_finite() {
            return Err(format!(
                "a degenerate index-to-world transform (determinant {det:e})"
            ));
        }
        let (origin, dims) = if lo.cmplt(hi).all() {
            let origin = lo.div_euclid(IVec3::splat(BRICK)) * BRICK;
            let end = hi.as_i64vec3();
            let dims = (end - origin.as_i64vec3() + (BRICK as i64 - 1)) / BRICK as i64;
            let bricks = dims.x.saturating_mul(dims.y).saturating_mul(dims.z);
            // Lookups index bricks with i32 arithmetic.
            if bricks > i32::MAX as i64 {
                return Err(format!(
                    "a density grid spanning {} voxels: more than 2^31 bricks of 8³",
                    (end - origin.as_i64vec3())
                ));
            }
            Limits::current().check_memory(
                (bricks as u64).saturating_mul(4),
                "the brick index of a density grid",
            )?;
            (origin, dims.as_ivec3())
        } else {
            (IVec3::ZERO, IVec3::ZERO)
        };
        let bricks = dims.as_i64vec3().element_product() as usize;
        Ok(DensityGrid {
            index_to_world,
            world_to_index: index_to_world.inverse(),
            voxels: vec![0.0; LEAF_VOXELS],
            brick_of: vec![0; bricks],
            origin,
            dims,
            scale,
            max: 0.0,
        })
    }

    fn push_brick(&mut self, values: &[f32; LEAF_VOXELS]) -> Result<u32, String> {
        let b = self.voxels.len() / LEAF_VOXELS;
        Limits::current().check_memory(
            ((b + 1) * LEAF_VOXELS * 4) as u64,
            "the voxels of a density grid",
        )?;
        let b = u32::try_from(b).map_err(|_| "more than 2^32 bricks of voxels".to_string())?;
        self.voxels.extend_from_slice(values);
        self.max = values.iter().fold(self.max, |m, &v| m.max(v));
        Ok(b)
    }

    /// The `brick_of` slot of the brick holding voxel `at`.
    fn brick_cell(&self, at: IVec3) -> Option<usize> {
        let rel = at.as_i64vec3() - self.origin.as_i64vec3();
        let b = rel.div_euclid(glam::I64Vec3::splat(BRICK as i64));
        let dims = self.dims.as_i64vec3();
        if rel.min_element() < 0 || b.cmpge(dims).any() {
            return None;
        }
        Some(((b.x * dims.y + b.y) * dims.z + b.z) as usize)
    }

    /// The (scaled) value of voxel `ijk`; 0 outside the stored voxels.
    #[inline]
    pub fn voxel(&self, ijk: IVec3) -> f32 {
        let rel = ijk.wrapping_sub(self.origin);
        let b: IVec3 = rel >> 3i32;
        if rel.min_element() < 0 || b.cmpge(self.dims).any() {
            return 0.0;
        }
        let brick = self.brick_of[((b.x * self.dims.y + b.y) * self.dims.z + b.z) as usize];
        let n = ((rel.x & 7) << 6) | ((rel.y & 7) << 3) | (rel.z & 7);
        self.voxels[brick as usize * LEAF_VOXELS + n as usize]
    }

    /// Density at a point of index space (trilinear between voxel centres).
    #[inline]
    pub fn density_index(&self, q: Vec3) -> f32 {
        let f = q.floor();
        if !f.is_finite() || f.abs().max_element() > (i32::MAX / 2) as f32 {
            return 0.0;
        }
        let i = f.as_ivec3();
        let t = q - f;
        let v = |dx: i32, dy: i32, dz: i32| self.voxel(i + IVec3::new(dx, dy, dz));
        let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
        let x00 = lerp(v(0, 0, 0), v(1, 0, 0), t.x);
        let x10 = lerp(v(0, 1, 0), v(1, 1, 0), t.x);
        let x01 = lerp(v(0, 0, 1), v(1, 0, 1), t.x);
        let x11 = lerp(v(0, 1, 1), v(1, 1, 1), t.x);
        lerp(lerp(x00, x10, t.y), lerp(x01, x11, t.y), t.z).max(0.0)
    }

    /// Density at a world-space point.
    #[inline]
    pub fn density(&self, p: Vec3) -> f32 {
        self.density_index(self.world_to_index.transform_point3(p))
    }

    pub fn index_to_world(&self) -> Affine3A {
        self.index_to_world
    }
    pub fn world_to_index(&self) -> Affine3A {
        self.world_to_index
    }
    pub fn scale(&self) -> f32 {
        self.scale
    }
    /// The largest (scaled) voxel value.
    pub fn max_density(&self) -> f32 {
        self.max
    }
    /// Index-space box outside which the density is 0: the stored voxels widened by the
    /// one voxel the trilinear footprint reaches.
    pub fn index_bounds(&self) -> (Vec3, Vec3) {
        let lo = self.origin.as_vec3() - 1.0;
        let hi = (self.origin + self.dims * BRICK).as_vec3();
        (lo, hi)
    }
    /// World-space axis-aligned box holding every point of non-zero density.
    pub fn world_bounds(&self) -> (Vec3, Vec3) {
        let (lo, hi) = self.index_bounds();
        let mut a = Vec3::splat(f32::INFINITY);
        let mut b = Vec3::splat(f32::NEG_INFINITY);
        for c in 0..8 {
            let corner = Vec3::new(
                if c & 1 == 0 { lo.x } else { hi.x },
                if c & 2 == 0 { lo.y } else { hi.y },
                if c & 4 == 0 { lo.z } else { hi.z },
            );
            let w = self.index_to_world.transform_point3(corner);
            a = a.min(w);
            b = b.max(w);
        }
        (a, b)
    }
    /// Bytes the voxels and their index take.
    pub fn memory_bytes(&self) -> usize {
        self.voxels.len() * 4 + self.brick_of.len() * 4
    }
}

fn check_scale(scale: f32) -> Result<(), String> {
    if scale.is_finite() && scale >= 0.0 {
        Ok(())
    } else {
        Err(format!(
            "a density scale of {scale}: expected a finite number ≥ 0"
        ))
    }
}

/// A stretch `[t0, t1)` of a ray in one majorant cell: every density on it lies in
/// `[min, max]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    pub t0: f32,
    pub t1: f32,
    pub min: f32,
    pub max: f32,
}

/// Per-cell density bounds over a [`DensityGrid`], in its index space.
#[derive(Clone, Debug)]
pub struct MajorantGrid {
    world_to_index: Affine3A,
    /// Index-space corner of cell (0, 0, 0).
    lo: Vec3,
    /// Voxels along a cell's edge.
    cell: f32,
    res: IVec3,
    /// `[min, max]` per cell, x slowest.
    bounds: Vec<[f32; 2]>,
}

impl MajorantGrid {
    /// Cells of `cell`³ voxels (16 is a good default: OpenVDB's leaf is 8).
    pub fn new(grid: &DensityGrid, cell: u32) -> Result<MajorantGrid, String> {
        if !(1..=4096).contains(&cell) {
            return Err(format!(
                "majorant cells of {cell} voxels: expected 1 to 4096"
            ));
        }
        let c = cell as i32;
        let (lo, hi) = grid.index_bounds();
        let extent = (hi - lo).as_ivec3();
        let res = if extent.min_element() > 0 {
            (extent + c - 1) / c
        } else {
            IVec3::ZERO
        };
        let cells = res.as_i64vec3().element_product().max(0) as u64;
        Limits::current()
            .check_memory(cells.saturating_mul(8), "the majorant grid of a density")?;
        let lo_i = lo.as_ivec3();
        // Brick-level maxima first: cells over empty bricks are skipped without a scan.
        let brick_max: Vec<f32> = grid
            .voxels
            .chunks_exact(LEAF_VOXELS)
            .map(|b| b.iter().fold(0.0f32, |m, &v| m.max(v)))
            .collect();
        let mut bounds = Vec::with_capacity(cells as usize);
        for x in 0..res.x {
            for y in 0..res.y {
                for z in 0..res.z {
                    let a = lo_i + IVec3::new(x, y, z) * c;
                    // The trilinear footprint of [a, a + c) is voxels a..=a + c; one more
                    // on each side covers points the DDA's rounding puts just outside.
                    let (v0, v1) = (a - 1, a + c + 1);
                    bounds.push(cell_bounds(grid, &brick_max, v0, v1));
                }
            }
        }
        Ok(MajorantGrid {
            world_to_index: grid.world_to_index,
            lo,
            cell: cell as f32,
            res,
            bounds,
        })
    }

    /// Cells along each axis.
    pub fn resolution(&self) -> IVec3 {
        self.res
    }

    /// The cells a ray `origin + t·dir`, `t` in `[t_min, t_max)`, crosses, in order.
    pub fn segments(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Segments<'_> {
        // Cell coordinates: g = (q - lo) / cell, q the index-space point.
        let go = (self.world_to_index.transform_point3(origin) - self.lo) / self.cell;
        let gd = self.world_to_index.transform_vector3(dir) / self.cell;
        let res = self.res.as_vec3();
        let (mut t0, mut t1) = (t_min.max(0.0), t_max);
        for a in 0..3 {
            if gd[a] == 0.0 {
                if !(go[a] >= 0.0 && go[a] < res[a]) {
                    t1 = f32::NEG_INFINITY;
                }
                continue;
            }
            let (mut near, mut far) = ((0.0 - go[a]) / gd[a], (res[a] - go[a]) / gd[a]);
            if near > far {
                std::mem::swap(&mut near, &mut far);
            }
            t0 = t0.max(near);
            t1 = t1.min(far);
        }
        let mut s = Segments {
            grid: self,
            cell: IVec3::ZERO,
            step: IVec3::ZERO,
            t_next: Vec3::INFINITY,
            t_delta: Vec3::INFINITY,
            t: t0,
            t_end: t1,
        };
        if t0.partial_cmp(&t1) != Some(std::cmp::Ordering::Less) || self.bounds.is_empty() {
            s.t_end = f32::NEG_INFINITY;
            return s;
        }
        let start = go + gd * t0;
        s.cell = start.floor().as_ivec3().clamp(IVec3::ZERO, self.res - 1);
        for a in 0..3 {
            if gd[a] > 0.0 {
                s.step[a] = 1;
                s.t_next[a] = (s.cell[a] as f32 + 1.0 - go[a]) / gd[a];
                s.t_delta[a] = 1.0 / gd[a];
            } else if gd[a] < 0.0 {
                s.step[a] = -1;
                s.t_next[a] = (s.cell[a] as f32 - go[a]) / gd[a];
                s.t_delta[a] = -1.0 / gd[a];
            }
        }
        s
    }
}

/// The `[min, max]` density of voxels `v0..=v1`.
fn cell_bounds(grid: &DensityGrid, brick_max: &[f32], v0: IVec3, v1: IVec3) -> [f32; 2] {
    // Bricks the voxel range touches (clipped to the box): all empty means [0, 0].
    let org = grid.origin;
    let b0: IVec3 = ((v0 - org).max(IVec3::ZERO) >> 3i32).min(grid.dims);
    let b1: IVec3 = (((v1 - org) >> 3i32) + 1).clamp(IVec3::ZERO, grid.dims);
    let mut any = false;
    for x in b0.x..b1.x {
        for y in b0.y..b1.y {
            for z in b0.z..b1.z {
                let b = grid.brick_of[((x * grid.dims.y + y) * grid.dims.z + z) as usize];
                any |= brick_max[b as usize] > 0.0;
            }
        }
    }
    if !any {
        return [0.0, 0.0];
    }
    let (mut lo, mut hi) = (f32::INFINITY, 0.0f32);
    for x in v0.x..=v1.x {
        for y in v0.y..=v1.y {
            for z in v0.z..=v1.z {
                let v = grid.voxel(IVec3::new(x, y, z));
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
    }
    [lo, hi]
}

/// The DDA over a [`MajorantGrid`]: one [`Segment`] per cell crossed.
pub struct Segments<'a> {
    grid: &'a MajorantGrid,
    cell: IVec3,
    step: IVec3,
    t_next: Vec3,
    t_delta: Vec3,
    t: f32,
    t_end: f32,
}

impl Iterator for Segments<'_> {
    type Item = Segment;

    #[inline]
    fn next(&mut self) -> Option<Segment> {
        if self.t.partial_cmp(&self.t_end) != Some(std::cmp::Ordering::Less) {
            return None;
        }
        let res = self.grid.res;
        if self.cell.cmplt(IVec3::ZERO).any() || self.cell.cmpge(res).any() {
            return None;
        }
        let a = if self.t_next.x <= self.t_next.y && self.t_next.x <= self.t_next.z {
            0
        } else if self.t_next.y <= self.t_next.z {
            1
        } else {
            2
        };
        let t1 = self.t_next[a].min(self.t_end);
        let i = ((self.cell.x * res.y + self.cell.y) * res.z + self.cell.z) as usize;
        let [min, max] = self.grid.bounds[i];
        let seg = Segment {
            t0: self.t,
            t1,
            min,
            max,
        };
        self.t = t1;
        self.cell[a] += self.step[a];
        self.t_next[a] += self.t_delta[a];
        Some(seg)
    }
}

/// An exponential distance of rate `mu` from a uniform `u` in [0, 1).
#[inline]
fn exponential(u: f32, mu: f32) -> f32 {
    -(1.0 - u).ln() / mu
}

/// Free-flight distance sampling by decomposition tracking (Kutz et al. 2017, §4; delta
/// tracking, Woodcock et al. 1965, on the residual). `sigma_t` is the tracked channel's
/// extinction per unit density, `density(t)` the density at ray parameter `t`. Returns
/// the first real collision, distributed as `σt(t) T(t)`, or None if the ray leaves the
/// segments first (probability `T` over them).
#[inline]
pub fn delta_tracking(
    segments: impl Iterator<Item = Segment>,
    sigma_t: f32,
    mut density: impl FnMut(f32) -> f32,
    rng: &mut impl FnMut() -> f32,
) -> Option<f32> {
    // Also refuses NaN.
    if sigma_t.is_nan() || sigma_t <= 0.0 {
        return None;
    }
    for seg in segments {
        // The control: a homogeneous medium of the segment's minimum, sampled exactly.
        let mu_c = seg.min * sigma_t;
        let t_c = if mu_c > 0.0 {
            seg.t0 + exponential(rng(), mu_c)
        } else {
            f32::INFINITY
        };
        let end = t_c.min(seg.t1);
        // The residual: null collisions against its majorant.
        let mu_r = (seg.max - seg.min) * sigma_t;
        if mu_r > 0.0 {
            let mut t = seg.t0;
            loop {
                t += exponential(rng(), mu_r);
                if t >= end {
                    break;
                }
                let sigma_r = density(t) * sigma_t - mu_c;
                if rng() * mu_r < sigma_r {
                    return Some(t);
                }
            }
        }
        if t_c < seg.t1 {
            return Some(t_c);
        }
    }
    None
}

/// Below this estimate, ratio tracking plays Russian roulette.
const ROULETTE_BELOW: f32 = 0.05;
/// Probability of ending the estimate at 0 in that roulette.
const ROULETTE_KILL: f32 = 0.75;

/// Transmittance along the segments by residual ratio tracking (Novák et al. 2014):
/// each segment's minimum attenuates in closed form, the rest by ratio tracking
/// against `(max − min) · max_c sigma_t[c]`. An unbiased estimate of
/// `exp(−∫ density · sigma_t[c])` for each channel.
#[inline]
pub fn ratio_tracking(
    segments: impl Iterator<Item = Segment>,
    sigma_t: [f32; 3],
    mut density: impl FnMut(f32) -> f32,
    rng: &mut impl FnMut() -> f32,
) -> [f32; 3] {
    let s_max = sigma_t[0].max(sigma_t[1]).max(sigma_t[2]);
    let mut tr = [1.0f32; 3];
    if s_max.is_nan() || s_max <= 0.0 {
        return tr;
    }
    for seg in segments {
        let len = seg.t1 - seg.t0;
        if seg.min > 0.0 {
            for c in 0..3 {
                tr[c] *= (-seg.min * sigma_t[c] * len).exp();
            }
        }
        let mu_r = (seg.max - seg.min) * s_max;
        if mu_r.is_nan() || mu_r <= 0.0 {
            continue;
        }
        let mut t = seg.t0;
        loop {
            t += exponential(rng(), mu_r);
            if t >= seg.t1 {
                break;
            }
            let excess = (density(t) - seg.min).max(0.0);
            for c in 0..3 {
                tr[c] *= (1.0 - excess * sigma_t[c] / mu_r).max(0.0);
            }
            let m = tr[0].max(tr[1]).max(tr[2]);
            if m < ROULETTE_BELOW {
                if m <= 0.0 || rng() < ROULETTE_KILL {
                    return [0.0; 3];
                }
                for v in &mut tr {
                    *v /= 1.0 - ROULETTE_KILL;
                }
            }
        }
    }
    tr
}

/// A density grid with its majorants: what a heterogeneous medium holds.
#[derive(Clone, Debug)]
pub struct GridDensity {
    pub grid: DensityGrid,
    pub majorants: MajorantGrid,
}

impl GridDensity {
    pub fn new(grid: DensityGrid, cell: u32) -> Result<GridDensity, String> {
        let majorants = MajorantGrid::new(&grid, cell)?;
        Ok(GridDensity { grid, majorants })
    }

    /// Delta tracking along `origin + t·dir` (unit `dir`), `t` in `[0, t_max)`.
    #[inline]
    pub fn sample_distance(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_max: f32,
        sigma_t: f32,
        rng: &mut impl FnMut() -> f32,
    ) -> Option<f32> {
        let (qo, qd) = self.index_ray(origin, dir);
        let segs = self.majorants.segments(origin, dir, 0.0, t_max);
        delta_tracking(segs, sigma_t, |t| self.grid.density_index(qo + qd * t), rng)
    }

    /// Ratio-tracking transmittance along `origin + t·dir` (unit `dir`), `t` in `[0, t_max)`.
    #[inline]
    pub fn transmittance(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_max: f32,
        sigma_t: [f32; 3],
        rng: &mut impl FnMut() -> f32,
    ) -> [f32; 3] {
        let (qo, qd) = self.index_ray(origin, dir);
        let segs = self.majorants.segments(origin, dir, 0.0, t_max);
        ratio_tracking(segs, sigma_t, |t| self.grid.density_index(qo + qd * t), rng)
    }

    #[inline]
    fn index_ray(&self, origin: Vec3, dir: Vec3) -> (Vec3, Vec3) {
        let w2i = self.grid.world_to_index;
        (w2i.transform_point3(origin), w2i.transform_vector3(dir))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::load::vdb::{self, tests::ramp};
    use glam::Quat;

    /// SplitMix64 as uniform f32s in [0, 1).
    struct Rng(u64);
    impl Rng {
        fn u(&mut self) -> f32 {
            self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
        }
    }

    fn file_grid(name: &str, scale: f32) -> DensityGrid {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/vdb")
            .join(name);
        let g = vdb::parse(&std::fs::read(path).unwrap(), "density").unwrap();
        DensityGrid::from_vdb(&g, scale).unwrap()
    }

    /// A lumpy 24×20×16 grid (zeros, smooth bumps, spikes; `floor` added everywhere)
    /// under a rotation and scale.
    fn lumpy(floor: f32) -> DensityGrid {
        let size = IVec3::new(24, 20, 16);
        let mut rng = Rng(3);
        let mut values = Vec::new();
        for k in 0..size.z {
            for j in 0..size.y {
                for i in 0..size.x {
                    let p = Vec3::new(i as f32, j as f32, k as f32);
                    let bump = (-(p - Vec3::new(12.0, 9.0, 8.0)).length_squared() / 30.0).exp();
                    let spike = if rng.u() < 0.05 { 3.0 } else { 0.0 };
                    let hole = if i < 5 { 0.0 } else { 1.0 };
                    values.push(floor + hole * (2.0 * bump + 0.3 * rng.u() + spike));
                }
            }
        }
        let to_world = Affine3A::from_scale_rotation_translation(
            Vec3::splat(0.1),
            Quat::from_euler(glam::EulerRot::XYZ, 0.3, -0.5, 0.9),
            Vec3::new(0.5, -1.0, 2.0),
        );
        DensityGrid::from_dense(size, &values, to_world, 1.0).unwrap()
    }

    /// A ray from outside the grid's world box through a random point of it.
    fn random_ray(g: &DensityGrid, rng: &mut Rng) -> (Vec3, Vec3, f32) {
        let (lo, hi) = g.world_bounds();
        // Through a point of the voxels' box (the world box of a rotated grid is larger).
        let (qlo, qhi) = g.index_bounds();
        let q = qlo + (qhi - qlo) * Vec3::new(rng.u(), rng.u(), rng.u());
        let target = g.index_to_world().transform_point3(q);
        let z = 2.0 * rng.u() - 1.0;
        let phi = std::f32::consts::TAU * rng.u();
        let r = (1.0 - z * z).max(0.0).sqrt();
        let dir = Vec3::new(r * phi.cos(), r * phi.sin(), z);
        let reach = (hi - lo).length();
        (target - dir * reach, dir, 2.0 * reach)
    }

    /// ∫ density over [0, t] on `n` midpoint steps.
    fn march(g: &DensityGrid, o: Vec3, d: Vec3, t: f32, n: usize) -> f64 {
        let h = t as f64 / n as f64;
        (0..n)
            .map(|i| g.density(o + d * ((i as f64 + 0.5) * h) as f32) as f64 * h)
            .sum()
    }

    #[test]
    fn the_ramp_file_gives_its_voxels_and_trilinear_lookups_reproduce_it() {
        for (file, scale) in [
            ("ramp.vdb", 1.0),
            ("ramp_zip.vdb", 0.5),
            ("ramp_half.vdb", 2.0),
        ] {
            let g = file_grid(file, scale);
            for x in -6..14 {
                for y in -2..12 {
                    for z in 0..12 {
                        let p = IVec3::new(x, y, z);
                        let want = if vdb::tests::in_ramp_box(p) {
                            ramp(p) * scale
                        } else {
                            0.0
                        };
                        assert_eq!(g.voxel(p), want, "{file} voxel {p}");
                        // At the voxel's centre in world space.
                        let w = g.index_to_world().transform_point3(p.as_vec3());
                        assert!((g.density(w) - want).abs() < 1e-4, "{file} at {p}");
                    }
                }
            }
            // Trilinear interpolation reproduces a linear function inside the box.
            let mut rng = Rng(11);
            for _ in 0..2000 {
                let q = Vec3::new(-4.0, 0.0, 2.0)
                    + Vec3::new(15.0, 9.0, 7.0) * Vec3::new(rng.u(), rng.u(), rng.u());
                let want = scale * (2.0 + q.x / 4.0 + q.y / 8.0 + q.z / 16.0);
                assert!(
                    (g.density_index(q) - want).abs() < 1e-4 * want,
                    "{file} at {q}"
                );
            }
        }
    }

    #[test]
    fn trilinear_weights_match_the_formula_on_a_cube() {
        let c = [1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0, 128.0]; // (i, j, k) at c[i + 2j + 4k]
        let g = DensityGrid::from_dense(IVec3::splat(2), &c, Affine3A::IDENTITY, 1.0).unwrap();
        let (tx, ty, tz) = (0.25f32, 0.5f32, 0.875f32);
        let mut want = 0.0;
        for (n, cn) in c.iter().enumerate() {
            let w = |bit: usize, t: f32| if n & bit != 0 { t } else { 1.0 - t };
            want += w(1, tx) * w(2, ty) * w(4, tz) * cn;
        }
        assert!((g.density_index(Vec3::new(tx, ty, tz)) - want).abs() < 1e-5);
        // Half a voxel outside, half the corner's value (the rest is outside, 0).
        assert!((g.density_index(Vec3::new(-0.5, 0.0, 0.0)) - 0.5).abs() < 1e-6);
        assert_eq!(g.density_index(Vec3::new(-1.0, 0.0, 0.0)), 0.0);
    }

    #[test]
    fn tiles_share_one_brick_and_read_their_value() {
        let g = file_grid("tiles.vdb", 1.0);
        assert_eq!(g.density_index(Vec3::new(60.3, 17.5, 99.0)), 1.5);
        assert_eq!(g.density_index(Vec3::new(130.0, 3.5, 4.0)), 3.0);
        assert_eq!(g.voxel(IVec3::new(137, 1, 2)), 4.0);
        // The zero brick, one per tile value and one leaf.
        assert_eq!(g.voxels.len(), 4 * LEAF_VOXELS);
    }

    #[test]
    fn majorant_cells_bound_the_density_along_random_rays() {
        let g = lumpy(0.0);
        for cell in [1, 4, 16] {
            let m = MajorantGrid::new(&g, cell).unwrap();
            let mut rng = Rng(cell as u64);
            for _ in 0..500 {
                let (o, d, t_max) = random_ray(&g, &mut rng);
                let segs: Vec<Segment> = m.segments(o, d, 0.0, t_max).collect();
                for w in segs.windows(2) {
                    assert_eq!(w[0].t1, w[1].t0, "cell {cell}: a gap between segments");
                }
                // Every point of the ray: inside a segment whose bounds hold, or of zero density.
                for i in 0..400 {
                    let t = t_max * (i as f32 + rng.u()) / 400.0;
                    let rho = g.density(o + d * t);
                    match segs.iter().find(|s| s.t0 <= t && t < s.t1) {
                        Some(s) => assert!(
                            s.min * (1.0 - 1e-5) - 1e-6 <= rho
                                && rho <= s.max * (1.0 + 1e-5) + 1e-6,
                            "cell {cell}: density {rho} outside [{}, {}]",
                            s.min,
                            s.max
                        ),
                        None => assert!(
                            rho == 0.0,
                            "cell {cell}: density {rho} outside every segment"
                        ),
                    }
                }
            }
        }
    }

    /// Per channel, the sum over rays of (mean − reference) in units of its standard error.
    fn ratio_tracking_z(
        g: &GridDensity,
        plain: bool,
        rays: usize,
        per_ray: usize,
        seed: u64,
    ) -> [f64; 3] {
        let sigma = [0.8f32, 2.0, 5.0];
        let mut rng = Rng(seed);
        let (mut diff, mut var) = ([0.0f64; 3], [0.0f64; 3]);
        for _ in 0..rays {
            let (o, d, t_max) = random_ray(&g.grid, &mut rng);
            let tau = march(&g.grid, o, d, t_max, 20_000);
            // The march has converged far below the noise: halving its step changes little.
            let tau2 = march(&g.grid, o, d, t_max, 40_000);
            assert!((tau - tau2).abs() < 1e-4 * tau.max(1.0), "{tau} vs {tau2}");
            let (qo, qd) = g.index_ray(o, d);
            let (mut s, mut s2) = ([0.0f64; 3], [0.0f64; 3]);
            let mut u = || rng.u();
            for _ in 0..per_ray {
                let segs = g.majorants.segments(o, d, 0.0, t_max).map(|s| Segment {
                    min: if plain { 0.0 } else { s.min },
                    ..s
                });
                let tr = ratio_tracking(segs, sigma, |t| g.grid.density_index(qo + qd * t), &mut u);
                for c in 0..3 {
                    s[c] += tr[c] as f64;
                    s2[c] += (tr[c] as f64).powi(2);
                }
            }
            for c in 0..3 {
                let n = per_ray as f64;
                let mean = s[c] / n;
                let reference = (-(sigma[c] as f64) * tau).exp();
                diff[c] += mean - reference;
                var[c] += (s2[c] / n - mean * mean).max(0.0) / (n - 1.0);
            }
        }
        std::array::from_fn(|c| {
            if var[c] > 0.0 {
                diff[c] / var[c].sqrt()
            } else {
                diff[c] * 1e9
            }
        })
    }

    #[test]
    fn ratio_tracking_is_unbiased_against_ray_marching() {
        // 64 rays × 2000 estimates; |z| < 5 has probability ≈ 6e-7 of failing by chance.
        for floor in [0.0, 0.5] {
            let g = GridDensity::new(lumpy(floor), 4).unwrap();
            for plain in [false, true] {
                let z = ratio_tracking_z(&g, plain, 64, 2000, 41 + plain as u64);
                assert!(
                    z.iter().all(|z| z.abs() < 5.0),
                    "floor {floor}, residual control {}: z = {z:?}",
                    !plain
                );
            }
        }
        let file = GridDensity::new(file_grid("ramp_half.vdb", 1.0), 16).unwrap();
        let z = ratio_tracking_z(&file, false, 32, 2000, 7);
        assert!(z.iter().all(|z| z.abs() < 5.0), "ramp_half.vdb: z = {z:?}");
    }

    /// Kolmogorov–Smirnov distance of sampled distances (None: escaped) from `cdf`.
    fn ks(mut samples: Vec<Option<f32>>, cdf: impl Fn(f32) -> f64, escape_cdf: f64) -> f64 {
        let n = samples.len() as f64;
        samples.sort_by(|a, b| {
            a.unwrap_or(f32::INFINITY)
                .total_cmp(&b.unwrap_or(f32::INFINITY))
        });
        let mut d = 0.0f64;
        let mut hits = 0;
        for (i, s) in samples.iter().enumerate() {
            let Some(t) = s else { break };
            let f = cdf(*t);
            d = d
                .max((f - i as f64 / n).abs())
                .max((f - (i + 1) as f64 / n).abs());
            hits += 1;
        }
        d.max((escape_cdf - hits as f64 / n).abs())
    }

    /// The KS critical distance at level `alpha` for `n` samples (asymptotic).
    fn ks_critical(n: usize, alpha: f64) -> f64 {
        (-(alpha / 2.0).ln() / 2.0).sqrt() / (n as f64).sqrt()
    }

    #[test]
    fn delta_tracking_distances_follow_one_minus_transmittance() {
        // With a floor, the decomposition's control carries most collisions.
        let grids = [
            GridDensity::new(lumpy(0.0), 4).unwrap(),
            GridDensity::new(lumpy(0.5), 4).unwrap(),
        ];
        let sigma = 1.5f32;
        let n = 20_000;
        let mut rng = Rng(99);
        let rays = 8;
        for r in 0..rays {
            let g = &grids[r % 2];
            let (o, d, t_max) = random_ray(&g.grid, &mut rng);
            // Optical depth table on fine steps, for the analytic CDF 1 − T(t).
            let steps = 8192;
            let h = t_max as f64 / steps as f64;
            let mut tau = vec![0.0f64; steps + 1];
            for i in 0..steps {
                let rho = g.grid.density(o + d * ((i as f64 + 0.5) * h) as f32) as f64;
                tau[i + 1] = tau[i] + sigma as f64 * rho * h;
            }
            let cdf = |t: f32| {
                let x = (t as f64 / h).clamp(0.0, steps as f64);
                let i = (x as usize).min(steps - 1);
                let tt = tau[i] + (tau[i + 1] - tau[i]) * (x - i as f64);
                1.0 - (-tt).exp()
            };
            let mut u = || rng.u();
            let samples: Vec<Option<f32>> = (0..n)
                .map(|_| g.sample_distance(o, d, t_max, sigma, &mut u))
                .collect();
            let dist = ks(samples, cdf, 1.0 - (-tau[steps]).exp());
            let crit = ks_critical(n, 0.001 / rays as f64);
            assert!(dist < crit, "ray {r}: KS distance {dist} ≥ {crit}");
        }
    }

    #[test]
    fn in_a_constant_grid_delta_tracking_is_beer_lambert() {
        let size = IVec3::new(40, 40, 40);
        let g = DensityGrid::from_dense(
            size,
            &vec![1.0; 64_000],
            Affine3A::from_scale(Vec3::splat(0.05)),
            2.0,
        )
        .unwrap();
        let g = GridDensity::new(g, 8).unwrap();
        let sigma = 1.5f32; // σt = 2 · 1.5 = 3 per unit
        let (o, d, t_max) = (
            Vec3::new(0.1, 0.3, 0.2),
            Vec3::new(1.0, 1.0, 1.0).normalize(),
            2.0f32,
        );
        // The ray stays a voxel inside the block: density exactly 2 along it.
        assert!((o + d * t_max).max_element() < 39.0 * 0.05);
        let n = 20_000;
        let mut rng = Rng(5);
        let mut u = || rng.u();
        let samples: Vec<Option<f32>> = (0..n)
            .map(|_| g.sample_distance(o, d, t_max, sigma, &mut u))
            .collect();
        let dist = ks(
            samples,
            |t| 1.0 - (-3.0 * t as f64).exp(),
            1.0 - (-3.0 * t_max as f64).exp(),
        );
        assert!(dist < ks_critical(n, 0.001), "KS distance {dist}");
        // Ratio tracking there: Beer–Lambert per channel within 5 standard errors (cells
        // of one value attenuate in closed form; the first ones reach outside the block).
        let sig = [sigma, 0.5, 0.0];
        let (mut s, mut s2) = ([0.0f64; 3], [0.0f64; 3]);
        let m = 4000;
        for _ in 0..m {
            let tr = g.transmittance(o, d, t_max, sig, &mut u);
            for c in 0..3 {
                s[c] += tr[c] as f64;
                s2[c] += (tr[c] as f64).powi(2);
            }
        }
        for c in 0..3 {
            let mean = s[c] / m as f64;
            let se = ((s2[c] / m as f64 - mean * mean).max(0.0) / (m - 1) as f64).sqrt();
            let want = (-2.0 * sig[c] as f64 * t_max as f64).exp();
            assert!(
                (mean - want).abs() <= 5.0 * se + 1e-6,
                "channel {c}: {mean} ± {se} vs {want}"
            );
        }
    }
}
