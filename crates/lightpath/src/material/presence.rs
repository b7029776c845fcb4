//! Presence: OpenPBR's `geometry_opacity`, glTF's `alphaMode` (MASK with `alphaCutoff`,
//! BLEND with the base colour's alpha) and cut-out textures. A surface of opacity `a` is
//! there for a fraction `a` of the rays that reach it; the others go on straight through
//! it as if it were absent: no scattering, no LPE event, no emission, for camera,
//! indirect and shadow rays alike (docs/lpe.md#presence). Which rays pass is decided by
//! a hash of the ray and the primitive hit, so renders stay deterministic and the
//! decision costs no sampler dimension.

use super::texture::Texture;
use crate::geometry::{Hit, Ray};
use crate::sampling::splitmix64;
use glam::Vec2;

/// A material's presence where it is not simply opaque.
#[derive(Clone, Debug)]
pub struct Presence {
    /// The untextured opacity (OpenPBR `geometry_opacity`, glTF's base colour alpha).
    pub opacity: f32,
    /// A texture multiplying it, and the channel read (glTF: the base colour's alpha).
    pub texture: Option<(Texture, u8)>,
    /// With a cutoff (glTF MASK), the surface is there where the opacity reaches it and
    /// absent elsewhere.
    pub cutoff: Option<f32>,
}

impl Presence {
    /// `None` where every ray would find the surface (opacity 1, no texture).
    pub fn new(
        opacity: f32,
        texture: Option<(Texture, u8)>,
        cutoff: Option<f32>,
    ) -> Option<Presence> {
        let p = Presence {
            opacity: if opacity.is_finite() {
                opacity.clamp(0.0, 1.0)
            } else {
                1.0
            },
            texture,
            cutoff: cutoff.filter(|c| c.is_finite()),
        };
        (p.texture.is_some() || p.at(None) < 1.0).then_some(p)
    }

    /// The opacity at texture coordinate `uv` (`None`: a mesh without UVs, which reads
    /// the texture at its corner (0, 0) as the BSDF's textures do not, so a cut-out
    /// without UVs is the factor alone).
    pub fn at(&self, uv: Option<Vec2>) -> f32 {
        let mut a = self.opacity;
        if let (Some((tex, channel)), Some(uv)) = (&self.texture, uv) {
            // The finest level: a cut-out's edge stays sharp.
            let v = tex.eval(uv, 0.0)[(*channel).min(3) as usize];
            a *= if v.is_finite() {
                v.clamp(0.0, 1.0)
            } else {
                1.0
            };
        }
        match self.cutoff {
            Some(c) => {
                if a >= c {
                    1.0
                } else {
                    0.0
                }
            }
            None => a,
        }
    }
}

/// Whether `ray` goes on through a surface of opacity `a` at `hit`: with probability
/// 1 − `a`, from a hash of the ray and the primitive (uniform in [0, 1)).
pub fn passes_through(a: f32, ray: &Ray, hit: &Hit) -> bool {
    if a >= 1.0 {
        return false;
    }
    if a <= 0.0 {
        return true;
    }
    presence_u(ray, hit) >= a
}

/// A uniform number in [0, 1) from the ray's origin and direction and the primitive
/// hit: a new one at every crossing (the origin moves), the same for the same ray.
fn presence_u(ray: &Ray, hit: &Hit) -> f32 {
    let mut h = 0x5052_4553_454e_4345_u64 ^ ((hit.prim as u64) << 32 | hit.inner as u64);
    for x in [
        ray.origin.x,
        ray.origin.y,
        ray.origin.z,
        ray.dir.x,
        ray.dir.y,
        ray.dir.z,
    ] {
        h = splitmix64(h ^ x.to_bits() as u64);
    }
    (h >> 40) as f32 / (1u64 << 24) as f32
}
