//! Materials whose parameters vary over the surface: the material's constructor is run
//! again at each hit with the textured values. The lobes, and so the LPE events, are the
//! stored material's: a texture changes values, never the list of lobes (a textured
//! roughness stays at least [`MIN_TEXTURED_ROUGHNESS`] so rough lobes stay rough).

use super::openpbr::{InputMut, LobeSet, OpenPbr};
use super::pbr::MIN_TEXTURED_ROUGHNESS;
use super::texture::Texture;
use super::Bsdf;
use crate::geometry::SurfaceUv;
use glam::{Vec2, Vec3A, Vec4Swizzles};

/// Sets or borrows one OpenPBR parameter (an entry of `openpbr::INPUTS`).
pub type InputRef = fn(&mut OpenPbr) -> InputMut<'_>;

/// A material's untextured parameters and the lobes it has everywhere.
#[derive(Clone, Debug, PartialEq)]
pub struct ShadeModel {
    pub params: OpenPbr,
    pub lobes: LobeSet,
    /// The colour inputs the base-colour texture and vertex colours multiply.
    pub color_targets: Vec<InputRef>,
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
    /// OpenPBR inputs, each with its texture, for numbers the channel read, and the power
    /// the texel is raised to (`InputTexture::exponent`).
    pub inputs: Vec<(InputRef, Texture, u8, f32)>,
}

/// A textured material: evaluated at each hit.
#[derive(Clone, Debug)]
pub struct Textured {
    pub model: ShadeModel,
    pub textures: MaterialTextures,
}

impl Textured {
    /// The BSDF at texture coordinate `uv`, for a footprint `width` wide in UV units,
    /// with `vertex` (the interpolated vertex colour; white without one) on the base
    /// colour as the texture is.
    pub fn bsdf(&self, uv: Vec2, width: f32, vertex: Vec3A) -> Bsdf {
        let t = &self.textures;
        let mut p = self.model.params;
        let color = match &t.base_color {
            Some(tex) => vertex * Vec3A::from(tex.eval(uv, width).xyz()),
            None => vertex,
        };
        if color != Vec3A::ONE {
            for target in &self.model.color_targets {
                if let InputMut::Color(c) = target(&mut p) {
                    *c *= color;
                }
            }
        }
        if let Some(tex) = &t.metallic_roughness {
            let v = tex.eval(uv, width);
            p.specular_roughness *= v.y;
            p.base_metalness *= v.z;
        }
        for (input, tex, channel, exponent) in &t.inputs {
            let mut v = tex.eval(uv, width);
            if *exponent != 1.0 {
                v = v.max(glam::Vec4::ZERO).powf(*exponent);
            }
            match input(&mut p) {
                InputMut::Scalar(x) => *x *= v[usize::from(*channel).min(3)],
                InputMut::Color(c) => *c *= Vec3A::from(v.xyz()),
                InputMut::Bool(_) => {}
            }
        }
        // A lobe rough somewhere stays rough everywhere (its events are fixed).
        let floor = |r: f32, base: f32| {
            if base > 0.0 {
                r.max(MIN_TEXTURED_ROUGHNESS)
            } else {
                r
            }
        };
        p.specular_roughness = floor(p.specular_roughness, self.model.params.specular_roughness);
        p.coat_roughness = floor(p.coat_roughness, self.model.params.coat_roughness);
        Bsdf::openpbr(&p, &self.model.lobes)
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
