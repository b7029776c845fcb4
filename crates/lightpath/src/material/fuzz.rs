//! Fuzz (RS6): OpenPBR's fuzz layer, glTF's sheen. Zeltner, Burley & Chiang 2022,
//! "Practical Multiple-Scattering Sheen Using Linearly Transformed Cosines": the
//! reflection of a layer of normally oriented fibres, multiple scattering included, as a
//! linearly transformed cosine (LTC, Heitz et al. 2016) whose transform and albedo R come
//! from the paper's fit table ([`super::fuzz_table`]).
//!
//! `f · cos θi = colour · weight · R(μo, α) · D(wi)` with D the LTC, a normalised density
//! over the upper hemisphere: sampling D is exact, so every sample weighs
//! `colour · weight · R`, and the lobe reflects exactly `weight · R(μo)` ([`Fuzz::albedo`]),
//! the share the layers beneath give up (`1 − weight · R(μo)`). Like the paper's lobe, it
//! is not reciprocal (the table is indexed by `wo`).

use super::fuzz_table::{LTC, N};
use super::lobe::{tag, LobeModel, LobeSample, LobeTag, SampleCtx};
use crate::light::luminance;
use crate::sampling::cosine_hemisphere;
use glam::{Vec2, Vec3A};
use lpe::Scatter;
use std::f32::consts::FRAC_1_PI;

pub const RS6: LobeTag = tag(false, Scatter::specular(6), false);

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fuzz {
    pub color: Vec3A,
    /// Coverage of the fuzz layer, in [0, 1] (clamped).
    pub weight: f32,
    /// OpenPBR's `fuzz_roughness` in [0, 1], the table's α.
    pub roughness: f32,
}

/// The fit at one (μo, α): M⁻¹ = [[a, 0, b], [0, a, 0], [0, 0, 1]] and the albedo `r`.
#[derive(Clone, Copy, Debug)]
struct Fit {
    a: f32,
    b: f32,
    r: f32,
}

/// `x` in [0, 1] (NaN and below as 0) to a cell index and the fraction within it.
fn cell(x: f32) -> (usize, f32) {
    let x = if x > 0.0 { x.min(1.0) } else { 0.0 };
    let t = x * (N - 1) as f32;
    let i = (t as usize).min(N - 2);
    (i, t - i as f32)
}

/// Bilinear lookup of the table at (cos θo, α), as the paper's code reads it.
fn fit(cos_o: f32, alpha: f32) -> Fit {
    let (c, fc) = cell(cos_o);
    let (r, fr) = cell(alpha);
    let at = |ri: usize, ci: usize| LTC[ri * N + ci];
    let mut v = [0.0f32; 3];
    for (k, vk) in v.iter_mut().enumerate() {
        let lo = at(r, c)[k] * (1.0 - fc) + at(r, c + 1)[k] * fc;
        let hi = at(r + 1, c)[k] * (1.0 - fc) + at(r + 1, c + 1)[k] * fc;
        *vk = lo * (1.0 - fr) + hi * fr;
    }
    Fit {
        a: v[0],
        b: v[1],
        r: v[2],
    }
}

impl Fit {
    /// The LTC density of the unit direction `w` (in the frame whose x axis points
    /// towards `wo`): D_o(M⁻¹w/|M⁻¹w|) · |M⁻¹| / |M⁻¹w|³ with D_o = cos/π, which is
    /// `w.z · (a / |M⁻¹w|²)² / π`.
    fn density(&self, w: Vec3A) -> f32 {
        if w.z <= 0.0 {
            return 0.0;
        }
        let x = self.a * w.x + self.b * w.z;
        let y = self.a * w.y;
        let len2 = x * x + y * y + w.z * w.z;
        let q = self.a / len2;
        FRAC_1_PI * w.z * q * q
    }

    /// Maps a cosine-distributed direction through M = (M⁻¹)⁻¹.
    fn transform(&self, c: Vec3A) -> Vec3A {
        Vec3A::new((c.x - self.b * c.z) / self.a, c.y / self.a, c.z).normalize_or_zero()
    }
}

/// cos and sin of `wo`'s azimuth: the LTC's frame has its x axis towards `wo`.
fn azimuth(wo: Vec3A) -> (f32, f32) {
    let len = (wo.x * wo.x + wo.y * wo.y).sqrt();
    if len > 0.0 {
        (wo.x / len, wo.y / len)
    } else {
        (1.0, 0.0)
    }
}

impl Fuzz {
    /// The table's fit towards `wo`; `None` where the lobe reflects nothing (below the
    /// horizon, no coverage, or an albedo that rounds to zero).
    fn fit(&self, wo_z: f32) -> Option<Fit> {
        if wo_z <= 0.0 || self.coverage() <= 0.0 {
            return None;
        }
        let f = fit(wo_z, self.roughness);
        (f.r > 0.0 && f.a > 0.0).then_some(f)
    }

    /// `weight` within [0, 1] (NaN as 0).
    fn coverage(&self) -> f32 {
        if self.weight > 0.0 {
            self.weight.min(1.0)
        } else {
            0.0
        }
    }

    /// Directional albedo towards `wo` (`wo_z` = cos θo), weight included: the fraction
    /// of white light the fuzz reflects, so the layers beneath are scaled by
    /// `1 − albedo(wo_z)`. Zero below the horizon, where the lobe reflects nothing.
    pub fn albedo(&self, wo_z: f32) -> f32 {
        self.fit(wo_z).map_or(0.0, |f| self.coverage() * f.r)
    }
}

impl LobeModel for Fuzz {
    fn tags(&self) -> &'static [LobeTag] {
        &[RS6]
    }
    fn eval(&self, _: usize, wo: Vec3A, wi: Vec3A, sel: f32) -> (Vec3A, f32) {
        let Some(f) = self.fit(wo.z) else {
            return (Vec3A::ZERO, 0.0);
        };
        if wi.z <= 0.0 {
            return (Vec3A::ZERO, 0.0);
        }
        let (c, s) = azimuth(wo);
        let w = Vec3A::new(c * wi.x + s * wi.y, c * wi.y - s * wi.x, wi.z);
        let d = f.density(w);
        (self.color * (self.coverage() * f.r * d), sel * d)
    }
    fn sample(&self, wo: Vec3A, _: SampleCtx, u: Vec2) -> Option<LobeSample> {
        let f = self.fit(wo.z)?;
        let w = f.transform(cosine_hemisphere(u));
        if w.z <= 0.0 {
            return None;
        }
        let (c, s) = azimuth(wo);
        LobeSample::direction(0, Vec3A::new(c * w.x - s * w.y, s * w.x + c * w.y, w.z))
    }
    /// What it reflects towards `wo`.
    fn selection_weight(&self, wo: Vec3A) -> f32 {
        (luminance(self.color) * self.albedo(wo.z)).max(0.0)
    }
}
