//! Layers: a lobe that lies over others (the specular over a dielectric base, a coat, a
//! fuzz) and takes from the light that reaches what is beneath it. A layer attenuates
//! every lobe below it by what it reflects itself ("albedo scaling", as Cycles and the
//! OpenPBR specification do), so a white, lossless stack reflects everything once.

use super::coat::Coat;
use super::fresnel::fresnel_dielectric;
use super::fuzz::Fuzz;
use super::specular::Specular;
use glam::Vec3A;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Layer {
    /// Dielectric specular reflection (OpenPBR's specular over the opaque base), at its
    /// full weight: the base gets 1 − E(μo) of the light, E its directional albedo
    /// towards the viewer (specular.rs says why not the reciprocal form).
    Specular(Specular),
    /// A clear coat: Fresnel transmission in and out, absorption by its colour over the
    /// path through it, and the darkening of light trapped beneath it.
    Coat {
        coat: Coat,
        color: Vec3A,
        /// Constant over directions: the coat's darkening, and 1 / (1 − w·F̄) so that a
        /// white diffuse base gets back what the coat does not reflect (the reciprocal
        /// Fresnel transmission in and out alone left 0.915 of the light in the furnace).
        darken: f32,
    },
    /// A fuzz (sheen) layer: what its fibres scatter towards `wo` (their directional
    /// albedo, Zeltner et al.'s table) does not reach beneath.
    Fuzz(Fuzz),
}

impl Layer {
    /// A coat of `color` over a base whose albedo has luminance `base_albedo`, darkened
    /// by `darkening` (OpenPBR's `coat_darkening`).
    pub fn coat(coat: Coat, color: Vec3A, darkening: f32, base_albedo: f32) -> Layer {
        Layer::Coat {
            coat,
            color,
            darken: darken(coat.eta, base_albedo, darkening * coat.weight)
                / (1.0 - coat.weight * super::albedo::dielectric_f_avg(coat.eta)).max(1e-3),
        }
    }
}

impl Layer {
    /// The factor on a lobe beneath this layer for light from `wi` leaving along `wo`
    /// (local frame, `wo.z > 0`).
    pub fn attenuation(&self, wo: Vec3A, wi: Vec3A) -> Vec3A {
        match *self {
            Layer::Specular(s) => Vec3A::splat(s.base_attenuation(wo)),
            Layer::Coat {
                coat,
                color,
                darken,
            } => {
                let w = coat.weight;
                let fresnel = coat.transmittance(wo, wi);
                // Absorption over the two refracted paths through a coat of unit
                // thickness, `color` being the transmittance at normal incidence.
                let tint = if color == Vec3A::ONE {
                    Vec3A::ONE
                } else {
                    let path = 0.5
                        * (1.0 / refracted_cos(wo.z, coat.eta)
                            + 1.0 / refracted_cos(wi.z, coat.eta));
                    let absorbed =
                        Vec3A::new(color.x.powf(path), color.y.powf(path), color.z.powf(path));
                    Vec3A::ONE + (absorbed - Vec3A::ONE) * w
                };
                fresnel * tint * darken
            }
            Layer::Fuzz(fuzz) => Vec3A::splat(1.0 - fuzz.albedo(wo.z.abs()).min(1.0)),
        }
    }

    /// [`attenuation`](Self::attenuation), given what [`transmission_towards`]
    /// (Self::transmission_towards) gave for `wo`: the specular and fuzz layers'
    /// attenuation is that number, the coat's depends on `wi` too.
    #[inline]
    pub fn attenuation_through(&self, through: f32, wo: Vec3A, wi: Vec3A) -> Vec3A {
        match *self {
            Layer::Specular(_) => Vec3A::splat(through.max(0.0)),
            Layer::Coat { .. } => self.attenuation(wo, wi),
            Layer::Fuzz(_) => Vec3A::splat(through),
        }
    }

    /// What the layer leaves for the lobes beneath towards `wo`, as one number (for
    /// choosing between lobes).
    pub fn transmission_towards(&self, wo: Vec3A) -> f32 {
        match *self {
            Layer::Specular(s) => 1.0 - s.albedo(wo),
            Layer::Coat { coat, .. } => {
                1.0 - coat.weight * fresnel_dielectric(wo.z.abs(), coat.eta)
            }
            Layer::Fuzz(fuzz) => 1.0 - fuzz.albedo(wo.z.abs()).min(1.0),
        }
    }
}

/// Cosine of the direction refracted into a layer of index `eta` from one at `cos`.
fn refracted_cos(cos: f32, eta: f32) -> f32 {
    let sin2 = (1.0 - cos * cos).max(0.0) / (eta * eta);
    (1.0 - sin2).max(1e-4).sqrt()
}

/// OpenPBR's coat darkening: light reflected back down by the coat's inside meets the
/// base again, so a base of albedo `e` under a coat whose inside reflects `k` of diffuse
/// light keeps (1 − k) / (1 − e·k) of its light. `amount` blends it in.
fn darken(eta: f32, e: f32, amount: f32) -> f32 {
    if amount <= 0.0 {
        return 1.0;
    }
    let k = internal_diffuse_reflectance(eta);
    let e = e.clamp(0.0, 1.0);
    1.0 + ((1.0 - k) / (1.0 - e * k) - 1.0) * amount
}

/// Hemispherical (cosine-weighted) reflectance of a smooth interface seen from the dense
/// side, 1 − (1 − F̄ₑₓₜ)/η² (energy reaching out equals what came in, Stokes).
fn internal_diffuse_reflectance(eta: f32) -> f32 {
    // F̄ outside by 32-point midpoint integration of 2 F(μ) μ dμ.
    let n = 32;
    let mut favg = 0.0;
    for i in 0..n {
        let mu = (i as f32 + 0.5) / n as f32;
        favg += 2.0 * fresnel_dielectric(mu, eta) * mu / n as f32;
    }
    1.0 - (1.0 - favg) / (eta * eta)
}
