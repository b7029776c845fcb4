//! Participating media (docs/lpe.md#volumes): what fills the inside of an object with an
//! `interior`, or the scene's `atmosphere`. A [`Volume`] is a medium (its coefficients)
//! with a phase function and an emission; the integrator sees a medium only through
//! [`Medium::sample`] (a free-flight distance along a ray segment) and
//! [`Medium::transmittance`] (along a shadow-ray segment), so a medium of another kind
//! (a density grid tracked against majorants) is one more variant and one file.
//!
//! Which medium a ray is in follows a [`MediumStack`] of the interiors it has entered,
//! resolved by priority (Schmidt & Budge 2002, "Simple Nested Dielectrics in Ray Traced
//! Images", as Cycles and OSL's testrender resolve overlaps).

pub mod equiangular;
pub mod grid;
pub mod heterogeneous;
pub mod homogeneous;
pub mod phase;

use crate::geometry::Ray;
use crate::sampling::Rng;
use glam::Vec3A;
pub use heterogeneous::Heterogeneous;
pub use homogeneous::Homogeneous;
pub use phase::HenyeyGreenstein;

/// What happened along a ray segment in a medium.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Collision {
    /// A real scattering collision at distance `t`; the throughput is multiplied by
    /// `weight` (σs times transmittance over the sampling density).
    Scatter { t: f32, weight: Vec3A },
    /// No real collision before the segment's end; the throughput is multiplied by
    /// `weight` (transmittance over the probability of passing).
    Pass { weight: Vec3A },
}

/// A medium's coefficients. Every variant samples and attenuates along a ray segment
/// (origin, direction, length), which is what a heterogeneous medium needs.
#[derive(Clone, Debug, PartialEq)]
pub enum Medium {
    Homogeneous(Homogeneous),
    Heterogeneous(Heterogeneous),
}

impl Medium {
    /// A free flight along `ray` up to `ray.tmax` (∞ allowed), with channel choice
    /// steered by the path's `throughput`.
    #[inline]
    pub fn sample(&self, ray: &Ray, throughput: Vec3A, rng: &mut Rng) -> Collision {
        match self {
            Medium::Homogeneous(m) => m.sample(ray.tmax, throughput, rng),
            Medium::Heterogeneous(m) => m.sample(ray, throughput, rng),
        }
    }

    /// The transmittance along `ray` up to `ray.tmax` (an unbiased estimate where it
    /// cannot be computed exactly: ratio tracking in a grid).
    #[inline]
    pub fn transmittance(&self, ray: &Ray, rng: &mut Rng) -> Vec3A {
        match self {
            Medium::Homogeneous(m) => m.transmittance(ray.tmax),
            Medium::Heterogeneous(m) => m.transmittance(ray, rng),
        }
    }

    /// What a real collision at distance `t` of `ray` would carry, exactly, for other
    /// sampling techniques to weigh against this one (equiangular sampling, MIS):
    /// σs there, the transmittance from the ray's origin, and the density with which
    /// [`sample`](Self::sample) (steered by `throughput`) picks it. `None`: this kind
    /// cannot say (it tracks collisions instead).
    #[inline]
    pub fn collision_terms(&self, t: f32, throughput: Vec3A) -> Option<(Vec3A, Vec3A, f32)> {
        match self {
            Medium::Homogeneous(m) => m.collision_terms(t, throughput),
            Medium::Heterogeneous(_) => None,
        }
    }

    /// ∫ ρ(s) T(s) ds along `ray` up to `ray.tmax` (ρ = 1 in a homogeneous medium, the
    /// density in a grid): what an emission per unit length at density 1 adds up to.
    /// Exact for a homogeneous medium, an unbiased estimate for a grid.
    #[inline]
    pub fn emission_integral(&self, ray: &Ray, rng: &mut Rng) -> Vec3A {
        match self {
            Medium::Homogeneous(m) => m.optical_integral(ray.tmax),
            Medium::Heterogeneous(m) => m.emission_integral(ray, rng),
        }
    }

    /// The single-scattering albedo σs/σt (for reports and the furnace test).
    pub fn albedo(&self) -> Vec3A {
        let (s, t) = match self {
            Medium::Homogeneous(m) => (m.sigma_s, m.sigma_t),
            Medium::Heterogeneous(m) => (m.sigma_s, m.sigma_t),
        };
        Vec3A::select(t.cmpgt(Vec3A::ZERO), s / t, Vec3A::ZERO)
    }
}

/// How flights through media pick the distances of single scattering towards lights
/// (`[render] volume_sampling`): `mis`, free-flight distances and, towards point, spot
/// and small sphere lights, equiangular ones weighed together (integrator/volume.rs);
/// `mis-area`, the same also towards small one-sided rect, quad and disk lights (it
/// lost at equal time in the scenes of benches/media/README.md, so it is not the
/// default); `distance`, free-flight distances alone (the plain estimator).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum VolumeSampling {
    #[default]
    Mis,
    MisArea,
    Distance,
}

impl VolumeSampling {
    pub const NAMES: [&'static str; 3] = ["mis", "mis-area", "distance"];

    pub fn parse(s: &str) -> Option<VolumeSampling> {
        match s {
            "mis" => Some(VolumeSampling::Mis),
            "mis-area" => Some(VolumeSampling::MisArea),
            "distance" => Some(VolumeSampling::Distance),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            VolumeSampling::Mis => "mis",
            VolumeSampling::MisArea => "mis-area",
            VolumeSampling::Distance => "distance",
        }
    }
}

/// A medium as a scene uses it: coefficients, phase function and emission.
#[derive(Clone, Debug, PartialEq)]
pub struct Volume {
    pub name: String,
    pub medium: Medium,
    pub phase: HenyeyGreenstein,
    /// Radiance emitted per unit length (zero: none), at density 1 in a grid.
    pub emission: Vec3A,
}

impl Volume {
    /// The emission the segment `ray` collects, attenuated along it (exact for a
    /// homogeneous medium, an unbiased estimate in a grid).
    #[inline]
    pub fn emitted(&self, ray: &Ray, rng: &mut Rng) -> Vec3A {
        if self.emission == Vec3A::ZERO {
            return Vec3A::ZERO;
        }
        self.emission * self.medium.emission_integral(ray, rng)
    }
}

/// Channel probabilities proportional to `w` (uniform when they sum to zero or are not
/// finite).
#[inline]
pub(crate) fn channel_pmf(w: Vec3A) -> Vec3A {
    let w = w.abs();
    let sum = w.element_sum();
    if sum > 0.0 && sum.is_finite() {
        w / sum
    } else {
        Vec3A::splat(1.0 / 3.0)
    }
}

/// The channel `u` picks with probabilities `p`.
#[inline]
pub(crate) fn pick_channel(p: Vec3A, u: f32) -> usize {
    if u < p.x || (p.y == 0.0 && p.z == 0.0) {
        0
    } else if u < p.x + p.y || p.z == 0.0 {
        1
    } else {
        2
    }
}

/// Interiors a stack holds at most; entering a further one is ignored (its medium is
/// not seen), which only very deep nesting reaches.
pub const MAX_NESTING: usize = 8;

/// The interiors a ray is inside, in the order it entered them: each the object that
/// bounds it and its priority.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MediumStack {
    entries: [(u32, i32); MAX_NESTING],
    len: u8,
}

impl MediumStack {
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    pub fn entries(&self) -> &[(u32, i32)] {
        &self.entries[..self.len as usize]
    }

    /// The interior that decides the medium: the highest priority, the latest entered
    /// among equals.
    #[inline]
    pub fn current(&self) -> Option<u32> {
        let mut best: Option<(u32, i32)> = None;
        for &(o, p) in self.entries() {
            if best.is_none_or(|b| p >= b.1) {
                best = Some((o, p));
            }
        }
        best.map(|b| b.0)
    }

    /// The highest priority inside, other than `object`'s own entry.
    pub fn top_priority_without(&self, object: u32) -> Option<i32> {
        self.entries()
            .iter()
            .filter(|e| e.0 != object)
            .map(|e| e.1)
            .max()
    }

    pub fn contains(&self, object: u32) -> bool {
        self.entries().iter().any(|e| e.0 == object)
    }

    /// Enters `object`'s interior.
    pub fn enter(&mut self, object: u32, priority: i32) {
        if (self.len as usize) < MAX_NESTING {
            self.entries[self.len as usize] = (object, priority);
            self.len += 1;
        }
    }

    /// Leaves `object`'s interior (its latest entry); nothing if it is not inside.
    pub fn leave(&mut self, object: u32) {
        let n = self.len as usize;
        if let Some(i) = self.entries[..n].iter().rposition(|e| e.0 == object) {
            self.entries.copy_within(i + 1..n, i);
            self.len -= 1;
        }
    }

    /// Enters `object` when `entering`, else leaves it.
    pub fn cross(&mut self, object: u32, priority: i32, entering: bool) {
        if entering {
            if !self.contains(object) {
                self.enter(object, priority);
            }
        } else {
            self.leave(object);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stack_resolves_overlaps_by_priority_then_order() {
        let mut s = MediumStack::default();
        assert_eq!(s.current(), None);
        s.cross(3, 0, true);
        s.cross(5, 2, true);
        s.cross(7, 0, true);
        assert_eq!(s.current(), Some(5));
        s.cross(5, 2, false);
        assert_eq!(s.current(), Some(7));
        s.cross(7, 0, false);
        assert_eq!(s.current(), Some(3));
        // Leaving what it is not in changes nothing; entering twice counts once.
        s.cross(9, 0, false);
        s.cross(3, 0, true);
        assert_eq!(s.entries(), &[(3, 0)]);
        assert_eq!(s.top_priority_without(3), None);
    }

    #[test]
    fn channel_choice_follows_its_probabilities() {
        let p = channel_pmf(Vec3A::new(2.0, 0.0, 1.0));
        assert_eq!(p, Vec3A::new(2.0 / 3.0, 0.0, 1.0 / 3.0));
        assert_eq!(pick_channel(p, 0.5), 0);
        assert_eq!(pick_channel(p, 0.7), 2);
        assert_eq!(channel_pmf(Vec3A::ZERO), Vec3A::splat(1.0 / 3.0));
    }
}
