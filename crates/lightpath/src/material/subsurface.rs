//! Subsurface scattering (TD3): the entry of a random walk under the surface (Chiang,
//! Kutz & Burley 2016, "Practical and Controllable Subsurface Scattering for Production
//! Path Tracing"; the walk itself is integrator/subsurface.rs). Parameters are
//! OpenPBR's. Light does not reach subsurface at the entry point but where the walk
//! leaves the object, so `eval` is zero; `sample` refracts the view direction through
//! the rough specular interface above the medium (a GGX visible normal, OpenPBR's
//! layering; Cycles' random-walk entry does the same), and the integrator, seeing
//! [`Bsdf::subsurface`](super::Bsdf::subsurface), walks from there (docs/lpe.md:
//! entering emits one `TD3` event, the walk none).

use super::fresnel::refract;
use super::lobe::{tag, LobeModel, LobeSample, LobeTag, SampleCtx};
use super::microfacet::Ggx;
use crate::light::luminance;
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
    /// GGX α of the boundary the entry refracts through (`specular_roughness`²).
    pub alpha: f32,
}

/// Below this α the entry refracts about the normal itself.
const SMOOTH_ALPHA: f32 = 1e-4;

impl LobeModel for Subsurface {
    fn tags(&self) -> &'static [LobeTag] {
        &[TD3]
    }
    fn eval(&self, _: usize, _: Vec3A, _: Vec3A, _: f32) -> (Vec3A, f32) {
        (Vec3A::ZERO, 0.0)
    }
    /// `wo` refracted into the surface about a visible GGX normal of the boundary; its
    /// weight is `weight / sel`: the colour comes from the walk, which leaves with about
    /// `color` of what enters, and what the interface reflects is the specular layer's
    /// (so no Fresnel or shadowing factor here: the entry fixes only where the walk
    /// starts heading). A smooth boundary refracts `wo` exactly. The
    /// direction matters: a cosine-distributed entry starts walks shallower, which left
    /// low-albedo channels with short mean free paths 10–13 % brighter than Cycles
    /// (benches/materials/RESULTS.md). The pdf only ranks the sample (nothing is
    /// evaluated towards it: `eval` is zero), so a smooth boundary reports the selection
    /// probability alone.
    fn sample(&self, wo: Vec3A, ctx: SampleCtx, u: Vec2) -> Option<LobeSample> {
        if wo.z <= 0.0 || self.weight <= 0.0 || ctx.sel <= 0.0 {
            return None;
        }
        let eta = if self.ior.is_finite() {
            self.ior.max(1.0)
        } else {
            1.0
        };
        let smooth = self.alpha.is_nan() || self.alpha < SMOOTH_ALPHA;
        let (m, pdf) = if smooth {
            (Vec3A::Z, 1.0)
        } else {
            let ggx = Ggx::isotropic(self.alpha.min(1.0));
            let m = ggx.sample_visible(wo, u);
            (m, ggx.pdf_visible(wo, m))
        };
        let wi = refract(wo, m, eta)?;
        if wi.z >= 0.0 {
            return None;
        }
        // Half-vector density to refracted-direction density (Walter et al. 2007).
        let pdf = if smooth {
            ctx.sel
        } else {
            let denom = wi.dot(m) + wo.dot(m) / eta;
            ctx.sel * pdf * wi.dot(m).abs() / (denom * denom).max(1e-12)
        };
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{Bsdf, Lambert, Shading};

    /// Light sampling never reaches subsurface at the entry; a sample goes into the
    /// surface with weight `weight / selection`, and the Bsdf names the lobe as
    /// subsurface so the integrator walks.
    #[test]
    fn samples_go_inside_and_the_bsdf_says_walk() {
        let lobe = Subsurface {
            weight: 0.7,
            color: Vec3A::new(0.9, 0.5, 0.2),
            radius: Vec3A::ONE,
            anisotropy: 0.0,
            ior: 1.4,
            alpha: 0.09,
        };
        let bsdf = Bsdf::layered(
            &[
                Lambert {
                    albedo: Vec3A::splat(0.3),
                }
                .into(),
                lobe.into(),
            ],
            None,
            Vec3A::ONE,
        );
        assert_eq!(bsdf.lobes(), &[crate::material::lambert::RD2, TD3]);
        assert!(bsdf.subsurface(0).is_none());
        assert_eq!(bsdf.subsurface(1), Some(&lobe));
        assert!(bsdf.subsurface(2).is_none());
        let n = Vec3A::new(0.2, 0.3, 0.9).normalize();
        let sh = Shading::new(&bsdf, n, n, Vec3A::new(0.0, 0.6, 0.8));
        let mut walks = 0;
        for i in 0..64 {
            let u = (i as f32 + 0.5) / 64.0;
            let s = bsdf
                .sample(&sh, u, Vec2::new(u, 1.0 - u))
                .expect("a sample");
            let wi = sh.frame.to_local(s.wi);
            assert_eq!(bsdf.eval_lobe(1, &sh, wi).0, Vec3A::ZERO);
            if s.lobe == 1 {
                walks += 1;
                assert!(wi.z < 0.0, "into the surface: {wi}");
                // Refracted through a slightly rough interface: towards −n, bent
                // from the view direction by Snell's law (sin θt ≤ sin θo / 1.4).
                let wo = sh.frame.to_local(sh.wo);
                let sin_o = (1.0 - wo.z * wo.z).sqrt();
                let sin_t = (1.0 - wi.z * wi.z).sqrt();
                assert!(sin_t < sin_o / 1.4 + 0.35, "{wi} from {wo}");
                assert!(s.pdf > 0.0 && s.weight.min_element() >= 0.7);
            }
        }
        assert!(walks > 0);
    }
}
