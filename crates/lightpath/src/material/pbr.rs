//! The metallic-roughness material of glTF 2.0 (its Appendix B) as a list of the
//! existing lobes, each keeping RenderMan's event and lobe number:
//!
//! | part | lobe | event |
//! |---|---|---|
//! | diffuse: base colour × (1 − metallic) × (1 − F0) | `Lambert` | `RD2` |
//! | specular: GGX, Schlick Fresnel from F0 = mix(((ior−1)/(ior+1))², base, metallic) | `Conductor` | `RS2` |
//! | transmission (glass) | `Dielectric` tinted by the base colour | `RS8`, `TS8` |
//! | clearcoat (KHR_materials_clearcoat) | `Coat`, ior 1.5, weighted | `RS4` |
//!
//! The diffuse part is scaled by 1 − F0 (the dielectric's normal-incidence reflectance)
//! rather than by the per-direction 1 − F of the reference shader, which keeps it one
//! Lambertian lobe. A material whose transmission is at least one half is glass (the
//! dielectric lobe alone); partial transmission is not blended.

use super::{Bsdf, Coat, Conductor, Dielectric, Lambert};
use glam::{Vec2, Vec3A};

/// Roughness below which a textured material's lobes stay rough (their events must not
/// change from hit to hit): GGX alpha never goes under this square.
pub const MIN_TEXTURED_ROUGHNESS: f32 = 0.02;

/// The parameters of a metallic-roughness material at one shading point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PbrParams {
    pub base: Vec3A,
    pub metallic: f32,
    /// GGX alpha of the specular (and glass) lobe; 0 is smooth.
    pub alpha: f32,
    pub ior: f32,
    /// Transmission ≥ ½: a dielectric lobe instead of diffuse + specular.
    pub glass: bool,
    /// KHR_materials_clearcoat: its factor (0: no coat) and GGX alpha.
    pub clearcoat: f32,
    pub clearcoat_alpha: f32,
}

/// Reflectance at normal incidence of a dielectric of index `ior` in air.
pub fn dielectric_f0(ior: f32) -> f32 {
    let r = (ior - 1.0) / (ior + 1.0);
    r * r
}

impl Bsdf {
    /// glTF's metallic-roughness material (see the module's table).
    pub fn pbr(p: &PbrParams) -> Bsdf {
        let metallic = p.metallic.clamp(0.0, 1.0);
        let base = p.base.clamp(Vec3A::ZERO, Vec3A::ONE);
        let coat = (p.clearcoat > 0.0).then_some(Coat {
            eta: 1.5,
            alpha: Vec2::splat(p.clearcoat_alpha),
            weight: p.clearcoat.min(1.0),
        });
        if p.glass {
            return Bsdf::layered(
                &[Dielectric {
                    compensate: true,
                    eta: p.ior,
                    alpha: glam::Vec2::splat(p.alpha),
                    tint: base,
                    reflect_tint: Vec3A::ONE,
                }
                .into()],
                None,
                base,
            );
        }
        let f0 = dielectric_f0(p.ior);
        Bsdf::layered(
            &[
                Lambert {
                    albedo: base * ((1.0 - metallic) * (1.0 - f0)),
                }
                .into(),
                Conductor::schlick(Vec3A::splat(f0).lerp(base, metallic), p.alpha).into(),
            ],
            coat,
            base,
        )
    }
}
