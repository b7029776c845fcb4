//! Subsurface scattering (TD3): the entry of a random walk under the surface (Chiang,
//! Kutz & Burley 2016, "Practical and Controllable Subsurface Scattering for Production
//! Path Tracing"; the walk itself is integrator/subsurface.rs). Parameters are
//! OpenPBR's. Light does not reach subsurface at the entry point but where the walk
//! leaves the object, so `eval` is zero; `sample` gives a cosine-distributed direction
//! into the surface, and the integrator, seeing [`Bsdf::subsurface`](super::Bsdf::subsurface),
//! walks from there (docs/lpe.md: entering emits one `TD3` event, the walk none).

use super::lobe::{tag, LobeModel, LobeSample, LobeTag, SampleCtx};
use crate::light::luminance;
use crate::sampling::{cosine_hemisphere, cosine_hemisphere_pdf};
use glam::{Vec2, Vec3A};
use lpe::Scatter;

pub const TD3: LobeTag = tag(true, Scatter::diffuse(3), false);

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Subsurface {
    /// The share of the surface that is subsurface (`subsurface_weight`, in [0, 1]).
    pub weight: f32,
    /// The multiple-scattering albedo wanted (`subsurface_color`): what a thick slab of
    /// the medium reflects.
    pub color: Vec3A,
    /// Mean free path per channel, in scene units (`subsurface_radius` ×
    /// `subsurface_radius_scale`).
    pub radius: Vec3A,
    /// Henyey–Greenstein g of the medium (`subsurface_scatter_anisotropy`), in (−1, 1).
    pub anisotropy: f32,
    /// Index of refraction of the boundary (`specular_ior`).
    pub ior: f32,
}

impl LobeModel for Subsurface {
    fn tags(&self) -> &'static [LobeTag] {
        &[TD3]
    }
    fn eval(&self, _: usize, _: Vec3A, _: Vec3A, _: f32) -> (Vec3A, f32) {
        (Vec3A::ZERO, 0.0)
    }
    /// A cosine-distributed direction into the surface (Cycles' "random walk" entry);
    /// its weight is `weight / sel`: the colour comes from the walk, which leaves with
    /// about `color` of what enters.
    fn sample(&self, wo: Vec3A, ctx: SampleCtx, u: Vec2) -> Option<LobeSample> {
        if wo.z <= 0.0 || self.weight <= 0.0 || ctx.sel <= 0.0 {
            return None;
        }
        let mut wi = cosine_hemisphere(u);
        if wi.z <= 0.0 {
            return None;
        }
        let pdf = ctx.sel * cosine_hemisphere_pdf(wi.z);
        wi.z = -wi.z;
        Some(LobeSample {
            sub: 0,
            wi,
            eta: 1.0,
            value: Some((Vec3A::splat(self.weight / ctx.sel), pdf, false)),
        })
    }
    fn selection_weight(&self, _: Vec3A) -> f32 {
        self.weight * luminance(self.color)
    }
}
