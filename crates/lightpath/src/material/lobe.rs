//! The lobe interface every lobe kind implements, and [`Lobe`], the closed set of kinds
//! a [`Bsdf`](super::Bsdf) stores inline (dispatch by `match`, no allocation).
//!
//! A lobe works in the shading frame (`z` = normal, two-sided lobes see `wo.z > 0`).
//! Most lobes emit one LPE event; a lobe that chooses between reflection and
//! transmission inside its own sampling (glass, per microfacet) emits two, and `sub`
//! numbers them.

use super::fuzz::Fuzz;
use super::iridescence::Iridescence;
use super::{
    coat::Coat, conductor::Conductor, dielectric::Dielectric, lambert::Lambert,
    rough_diffuse::RoughDiffuse, specular::Specular, subsurface::Subsurface,
    translucent::DiffuseTransmission,
};
use glam::{Vec2, Vec3A};
use lpe::Scatter;

/// How a lobe reads as an LPE event.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LobeTag {
    pub transmit: bool,
    pub scatter: Scatter,
    /// A Dirac lobe (smooth mirror or glass): never light-sampled.
    pub delta: bool,
}

pub const fn tag(transmit: bool, scatter: Scatter, delta: bool) -> LobeTag {
    LobeTag {
        transmit,
        scatter,
        delta,
    }
}

/// What the [`Bsdf`](super::Bsdf) tells a lobe it samples.
#[derive(Clone, Copy, Debug)]
pub struct SampleCtx {
    /// Probability with which the lobe was chosen.
    pub sel: f32,
    /// `u_lobe` rescaled to [0, 1) within the chosen lobe, for lobes that choose again.
    pub u_lobe: f32,
    /// Chosen with probability one and not attenuated by a layer: the lobe's own
    /// `f · |cos θi| / pdf` is the final weight.
    pub alone: bool,
}

pub struct LobeSample {
    /// Which of the lobe's events (index into `tags()`).
    pub sub: usize,
    pub wi: Vec3A,
    /// Relative index of refraction crossed (1 for reflection).
    pub eta: f32,
    /// `Some((weight, pdf, delta))` when the lobe computed the sample's value itself
    /// (delta lobes, or exact ratios); `None`: the Bsdf evaluates `wi` (weight f / pdf).
    pub value: Option<(Vec3A, f32, bool)>,
}

impl LobeSample {
    pub fn direction(sub: usize, wi: Vec3A) -> Option<LobeSample> {
        Some(LobeSample {
            sub,
            wi,
            eta: 1.0,
            value: None,
        })
    }
}

/// The one lobe interface.
pub trait LobeModel {
    /// The LPE events the lobe emits, in `sub` order.
    fn tags(&self) -> &'static [LobeTag];
    /// `f · |cos θi|` of event `sub` and its pdf, the selection probability `sel`
    /// folded in (where and how the lobe multiplies it keeps renders bit-stable).
    fn eval(&self, sub: usize, wo: Vec3A, wi: Vec3A, sel: f32) -> (Vec3A, f32);
    /// Samples a direction from `u`.
    fn sample(&self, wo: Vec3A, ctx: SampleCtx, u: Vec2) -> Option<LobeSample>;
    /// Unnormalised weight for choosing this lobe among its siblings.
    fn selection_weight(&self, wo: Vec3A) -> f32;
    /// False for lobes whose frame must keep the geometric orientation (inside/outside).
    fn two_sided(&self) -> bool {
        true
    }
}

macro_rules! lobes {
    ($($kind:ident),* $(,)?) => {
        /// Every lobe kind; adding one is a new file plus its name here.
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub enum Lobe {
            $($kind($kind),)*
        }

        impl LobeModel for Lobe {
            fn tags(&self) -> &'static [LobeTag] {
                match self { $(Lobe::$kind(l) => l.tags(),)* }
            }
            fn eval(&self, sub: usize, wo: Vec3A, wi: Vec3A, sel: f32) -> (Vec3A, f32) {
                match self { $(Lobe::$kind(l) => l.eval(sub, wo, wi, sel),)* }
            }
            fn sample(&self, wo: Vec3A, ctx: SampleCtx, u: Vec2) -> Option<LobeSample> {
                match self { $(Lobe::$kind(l) => l.sample(wo, ctx, u),)* }
            }
            fn selection_weight(&self, wo: Vec3A) -> f32 {
                match self { $(Lobe::$kind(l) => l.selection_weight(wo),)* }
            }
            fn two_sided(&self) -> bool {
                match self { $(Lobe::$kind(l) => l.two_sided(),)* }
            }
        }

        $(impl From<$kind> for Lobe {
            fn from(l: $kind) -> Lobe {
                Lobe::$kind(l)
            }
        })*
    };
}

lobes!(
    Lambert,
    RoughDiffuse,
    DiffuseTransmission,
    Conductor,
    Dielectric,
    Coat,
    Subsurface,
    Fuzz,
    Iridescence,
    Specular
);
