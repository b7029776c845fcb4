//! Iridescence (`RS5`): the primary specular seen through a thin film, Belcour & Barla
//! 2017 ("A Practical Extension to Microfacet Theory for the Modeling of Varying
//! Iridescence", `thin_film.rs`), as a GGX reflection lobe whose Fresnel is the film's
//! over the base beneath it: a dielectric (OpenPBR's specular over the dielectric base)
//! or a metal given by its F0 and its reflectance at 82° (as Blender Cycles has it: see
//! [`Iridescence::on_metal`] and `FilmBase::F82`). OpenPBR mixes the filmed and the bare
//! specular by `thin_film_weight`; the filmed one is this lobe, numbered 5 so that
//! `C<RS5>` (the `iridescence` AOV) picks it out.

use super::fresnel::{f82_tint, f82_tint_avg, MU_BAR};
use super::lobe::{LobeModel, LobeSample, LobeTag, SampleCtx};
use super::microfacet::{
    clamp_weight, is_smooth, reflection_eval, reflection_sample, reflection_tags,
};
use super::thin_film::{thin_film_fresnel, FilmBase};
use crate::light::luminance;
use glam::{Vec2, Vec3A};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Iridescence {
    /// What lies beneath the film.
    pub base: FilmBase,
    pub film_ior: f32,
    pub thickness_nm: f32,
    /// Colour of the reflection (OpenPBR's specular colour for a dielectric).
    pub tint: Vec3A,
    /// Mixing weight in [0, 1].
    pub weight: f32,
    /// GGX alphas (tangent, bitangent); both 0 is smooth.
    pub alpha: Vec2,
    /// Mean Fresnel of the bare base, for the multiple scattering.
    pub f_avg: Vec3A,
}

impl Iridescence {
    /// A film on a dielectric of index `eta`.
    pub fn on_dielectric(
        eta: f32,
        film_ior: f32,
        thickness_nm: f32,
        tint: Vec3A,
        weight: f32,
        alpha: Vec2,
    ) -> Iridescence {
        Iridescence {
            base: FilmBase::Dielectric { eta },
            film_ior,
            thickness_nm,
            tint,
            weight,
            alpha,
            f_avg: Vec3A::splat(super::albedo::dielectric_f_avg(eta.max(1.0))),
        }
    }

    /// A film on a metal of normal-incidence colour `f0` and F82 edge tint `edge`: the
    /// metal the bare lobe shows, by the F82 model's reflectance at μ̄ = 1/7 (not the tint
    /// itself, a ratio to Schlick's value there), which is what Blender Cycles passes
    /// for a Principled metal under a thin film ([`FilmBase::F82`]).
    pub fn on_metal(
        f0: Vec3A,
        edge: Vec3A,
        film_ior: f32,
        thickness_nm: f32,
        weight: f32,
        alpha: Vec2,
    ) -> Iridescence {
        Iridescence {
            base: FilmBase::F82 {
                f0,
                f82: f82_tint(f0, edge, MU_BAR),
            },
            film_ior,
            thickness_nm,
            tint: Vec3A::ONE,
            weight,
            alpha,
            f_avg: f82_tint_avg(f0, edge),
        }
    }

    fn fresnel(&self, cos: f32) -> Vec3A {
        self.tint * thin_film_fresnel(cos, 1.0, self.film_ior, self.thickness_nm, self.base)
    }
}

impl LobeModel for Iridescence {
    fn tags(&self) -> &'static [LobeTag] {
        reflection_tags(5, is_smooth(self.alpha))
    }
    fn eval(&self, _: usize, wo: Vec3A, wi: Vec3A, sel: f32) -> (Vec3A, f32) {
        reflection_eval(
            self.alpha,
            self.weight,
            self.f_avg * self.tint,
            wo,
            wi,
            sel,
            |c| self.fresnel(c),
        )
    }
    fn sample(&self, wo: Vec3A, ctx: SampleCtx, u: Vec2) -> Option<LobeSample> {
        reflection_sample(
            self.alpha,
            self.weight,
            self.f_avg * self.tint,
            wo,
            ctx,
            u,
            |c| self.fresnel(c),
        )
    }
    fn selection_weight(&self, wo: Vec3A) -> f32 {
        clamp_weight(self.weight) * luminance(self.fresnel(wo.z.abs()))
    }
}
