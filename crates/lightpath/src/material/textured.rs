//! Materials whose parameters vary over the surface: the material's constructor is run
//! again at each hit with the textured values. The lobes, and so the LPE events, are the
//! stored material's: a texture changes values, never the list of lobes (a textured
//! roughness stays at least [`MIN_TEXTURED_ROUGHNESS`] so rough lobes stay rough).

use super::pbr::{PbrParams, MIN_TEXTURED_ROUGHNESS};
use super::texture::Texture;
use super::{roughness_to_alpha, Bsdf};
use crate::geometry::SurfaceUv;
use glam::{Vec2, Vec3A, Vec4Swizzles};

/// A material's constructor and its untextured parameters.
#[derive(Clone, Debug, PartialEq)]
pub enum ShadeModel {
    Diffuse {
        albedo: Vec3A,
    },
    Translucent {
        reflect: Vec3A,
        transmit: Vec3A,
    },
    Conductor {
        f0: Vec3A,
        roughness: f32,
    },
    Dielectric {
        eta: f32,
        roughness: f32,
        tint: Vec3A,
    },
    Plastic {
        albedo: Vec3A,
        eta: f32,
        roughness: f32,
    },
    /// Roughness lives in `params.alpha`'s place as artists write it: see `roughness`.
    Pbr {
        params: PbrParams,
        roughness: f32,
        clearcoat_roughness: f32,
    },
}

/// The textures of a material; each multiplies the parameter it names.
#[derive(Clone, Debug, Default)]
pub struct MaterialTextures {
    /// Base colour, albedo, f0 or tint (RGB, sRGB-decoded).
    pub base_color: Option<Texture>,
    /// Roughness in green, metallic in blue (glTF's layout; linear).
    pub metallic_roughness: Option<Texture>,
    /// A tangent-space normal map (linear) and its scale.
    pub normal: Option<(Texture, f32)>,
    /// Emission colour (sRGB-decoded).
    pub emissive: Option<Texture>,
}

/// A textured material: evaluated at each hit.
#[derive(Clone, Debug)]
pub struct Textured {
    pub model: ShadeModel,
    pub textures: MaterialTextures,
}

fn alpha(roughness: f32, textured: bool) -> f32 {
    if textured {
        roughness_to_alpha(roughness.max(MIN_TEXTURED_ROUGHNESS))
    } else {
        roughness_to_alpha(roughness)
    }
}

impl Textured {
    /// The BSDF at texture coordinate `uv`, for a footprint `width` wide in UV units,
    /// with `vertex` (the interpolated vertex colour; white without one) on the base
    /// colour as the texture is.
    pub fn bsdf(&self, uv: Vec2, width: f32, vertex: Vec3A) -> Bsdf {
        let t = &self.textures;
        let color = |c: Vec3A| match &t.base_color {
            Some(tex) => c * vertex * Vec3A::from(tex.eval(uv, width).xyz()),
            None => c * vertex,
        };
        // (roughness, metallic) factors from the green and blue channels.
        let (r_scale, m_scale) = match &t.metallic_roughness {
            Some(tex) => {
                let v = tex.eval(uv, width);
                (v.y, v.z)
            }
            None => (1.0, 1.0),
        };
        let rough_tex = t.metallic_roughness.is_some();
        match &self.model {
            ShadeModel::Diffuse { albedo } => Bsdf::diffuse(color(*albedo)),
            ShadeModel::Translucent { reflect, transmit } => {
                Bsdf::translucent(color(*reflect), color(*transmit))
            }
            ShadeModel::Conductor { f0, roughness } => {
                Bsdf::conductor(color(*f0), alpha(roughness * r_scale, rough_tex))
            }
            ShadeModel::Dielectric {
                eta,
                roughness,
                tint,
            } => Bsdf::dielectric(*eta, alpha(roughness * r_scale, rough_tex), color(*tint)),
            ShadeModel::Plastic {
                albedo,
                eta,
                roughness,
            } => Bsdf::plastic(color(*albedo), *eta, alpha(roughness * r_scale, rough_tex)),
            ShadeModel::Pbr {
                params,
                roughness,
                clearcoat_roughness,
            } => Bsdf::pbr(&PbrParams {
                base: color(params.base),
                metallic: params.metallic * m_scale,
                alpha: alpha(roughness * r_scale, rough_tex),
                clearcoat_alpha: alpha(*clearcoat_roughness, false),
                ..*params
            }),
        }
    }

    /// The shading normal after the normal map (unit, world space), or `ns` without one.
    pub fn shading_normal(&self, ns: Vec3A, surface: &SurfaceUv, width: f32) -> Vec3A {
        let Some((tex, scale)) = &self.textures.normal else {
            return ns;
        };
        let v = tex.eval(surface.uv, width);
        let m = Vec3A::new(
            (2.0 * v.x - 1.0) * scale,
            (2.0 * v.y - 1.0) * scale,
            2.0 * v.z - 1.0,
        );
        let Some((t, b)) = surface.tangent_frame(ns) else {
            return ns;
        };
        (t * m.x + b * m.y + ns * m.z).normalize_or(ns)
    }

    /// The factor on the object's emission at `uv` (one without an emissive texture).
    pub fn emission(&self, uv: Vec2, width: f32) -> Vec3A {
        match &self.textures.emissive {
            Some(tex) => Vec3A::from(tex.eval(uv, width).xyz()),
            None => Vec3A::ONE,
        }
    }
}
