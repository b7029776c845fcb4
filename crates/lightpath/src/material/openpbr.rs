//! OpenPBR Surface 1.1 (the Academy Software Foundation's surface shading model), with
//! its parameter names and defaults, as one list of lobes: every Lightpath material is
//! this model, the older types (`diffuse`, `conductor`, …) being presets of it.
//!
//! | layer, top to bottom | lobe | event |
//! |---|---|---|
//! | fuzz (`fuzz_*`) | `Fuzz` (Zeltner et al. 2022) | `RS6` |
//! | coat (`coat_*`) | `Coat` | `RS4` |
//! | specular over the dielectric base, thin film off / on | `Specular` | `RS2` / `RS5` |
//! | metal (`base_metalness`), thin film off / on | `Conductor` | `RS2` / `RS5` |
//! | transmission (glass) | `Dielectric` | `RS8`, `TS8` |
//! | subsurface (`subsurface_*`) | `Subsurface` (random walk) | `TD3` |
//! | translucency (thin-walled subsurface) | `DiffuseTransmission` | `TD2` |
//! | diffuse, `base_diffuse_roughness` 0 / above 0 or textured | `Lambert` / `RoughDiffuse` (EON) | `RD2` |
//!
//! Which lobes a material has is fixed when the scene is built ([`LobeSet`]): a lobe whose
//! weight is zero and untextured is left out, so a plain diffuse material is one Lambert
//! lobe (the fast path), and a textured weight keeps its lobe everywhere, so an object's
//! events never change from hit to hit. Mixing weights (metalness, transmission,
//! subsurface, thin film) scale the lobes they choose between; layers (specular over the
//! dielectric base, coat, fuzz) attenuate everything beneath them by what they reflect
//! (albedo scaling, as Cycles does), so a white, lossless material stays white.

use super::iridescence::Iridescence;
use super::layer::Layer;
use super::lobe::Lobe;
use super::microfacet::roughness_anisotropy_to_alpha;
use super::{
    Bsdf, Coat, Conductor, Dielectric, DiffuseTransmission, Fuzz, Lambert, RoughDiffuse, Specular,
    SpecularParams, Subsurface,
};
use glam::Vec3A;

/// What a parameter holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum InputKind {
    /// A number within `min..=max`.
    Scalar {
        default: f32,
        min: f32,
        max: f32,
    },
    /// A linear RGB colour, each channel ≥ 0.
    Color {
        default: [f32; 3],
    },
    Bool {
        default: bool,
    },
}

/// A parameter's value, borrowed from [`OpenPbr`] to be set by a loader or a texture.
pub enum InputMut<'a> {
    Scalar(&'a mut f32),
    Color(&'a mut Vec3A),
    Bool(&'a mut bool),
}

/// One OpenPBR parameter: its name (as the specification writes it), kind and default.
pub struct Input {
    pub name: &'static str,
    pub kind: InputKind,
    pub get: fn(&mut OpenPbr) -> InputMut<'_>,
}

macro_rules! openpbr_inputs {
    ($($name:ident: $kind:ident($($arg:expr),*) $doc:literal;)*) => {
        /// The parameters of an OpenPBR surface at one shading point.
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct OpenPbr {
            $(#[doc = $doc] pub $name: openpbr_inputs!(@ty $kind),)*
        }

        impl Default for OpenPbr {
            /// The specification's defaults.
            fn default() -> OpenPbr {
                OpenPbr { $($name: openpbr_inputs!(@default $kind($($arg),*)),)* }
            }
        }

        /// Every parameter, in the specification's order, then Lightpath's own.
        pub const INPUTS: &[Input] = &[
            $(Input {
                name: stringify!($name),
                kind: openpbr_inputs!(@kind $kind($($arg),*)),
                get: |p| openpbr_inputs!(@mut $kind, p.$name),
            },)*
        ];
    };
    (@ty Scalar) => { f32 };
    (@ty Color) => { Vec3A };
    (@ty Bool) => { bool };
    (@default Scalar($d:expr, $lo:expr, $hi:expr)) => { $d };
    (@default Color($r:expr, $g:expr, $b:expr)) => { Vec3A::new($r, $g, $b) };
    (@default Bool($d:expr)) => { $d };
    (@kind Scalar($d:expr, $lo:expr, $hi:expr)) => { InputKind::Scalar { default: $d, min: $lo, max: $hi } };
    (@kind Color($r:expr, $g:expr, $b:expr)) => { InputKind::Color { default: [$r, $g, $b] } };
    (@kind Bool($d:expr)) => { InputKind::Bool { default: $d } };
    (@mut Scalar, $e:expr) => { InputMut::Scalar(&mut $e) };
    (@mut Color, $e:expr) => { InputMut::Color(&mut $e) };
    (@mut Bool, $e:expr) => { InputMut::Bool(&mut $e) };
}

const BIG: f32 = f32::MAX;

openpbr_inputs! {
    base_weight: Scalar(1.0, 0.0, 1.0) "Multiplier on the base (diffuse, subsurface and metal).";
    base_color: Color(0.8, 0.8, 0.8) "Diffuse albedo, and the metal's reflectance at normal incidence.";
    base_metalness: Scalar(0.0, 0.0, 1.0) "Mix from dielectric (0) to metal (1).";
    base_diffuse_roughness: Scalar(0.0, 0.0, 1.0) "Roughness of the diffuse lobe: σ of the energy-preserving Oren–Nayar model (EON); 0 is Lambertian.";
    specular_weight: Scalar(1.0, 0.0, BIG) "Multiplier on the dielectric's reflectance at normal incidence, through its IOR (above 1 raises it); the metal's whole reflection, up to 1.";
    specular_color: Color(1.0, 1.0, 1.0) "Tint of the dielectric's reflection; the metal's edge tint (F82).";
    specular_roughness: Scalar(0.3, 0.0, 1.0) "Roughness of the specular reflection and of transmission.";
    specular_roughness_anisotropy: Scalar(0.0, 0.0, 1.0) "Stretch of the roughness along the tangent.";
    specular_ior: Scalar(1.5, 1.0, BIG) "Index of refraction of the dielectric base.";
    transmission_weight: Scalar(0.0, 0.0, 1.0) "Mix from opaque to transparent dielectric base.";
    transmission_color: Color(1.0, 1.0, 1.0) "Tint of transmitted light (with depth 0 a tint of the interface).";
    transmission_depth: Scalar(0.0, 0.0, BIG) "Distance at which the interior's absorption reaches transmission_color (0: a tint of the interface).";
    transmission_scatter: Color(0.0, 0.0, 0.0) "Colour of light scattered in the interior.";
    transmission_scatter_anisotropy: Scalar(0.0, -1.0, 1.0) "Phase function anisotropy of the interior.";
    transmission_dispersion_scale: Scalar(0.0, 0.0, 1.0) "Dispersion (read, not rendered: Lightpath is RGB).";
    transmission_dispersion_abbe_number: Scalar(20.0, 0.0, BIG) "Abbe number of the dispersion (read, not rendered).";
    subsurface_weight: Scalar(0.0, 0.0, 1.0) "Mix from diffuse reflection to subsurface scattering.";
    subsurface_color: Color(0.8, 0.8, 0.8) "The subsurface's multiple-scattering albedo.";
    subsurface_radius: Scalar(1.0, 0.0, BIG) "Mean free path, in scene units.";
    subsurface_radius_scale: Color(1.0, 0.5, 0.25) "Per-channel multiplier on subsurface_radius.";
    subsurface_scatter_anisotropy: Scalar(0.0, -1.0, 1.0) "Henyey–Greenstein g of the subsurface's phase function.";
    coat_weight: Scalar(0.0, 0.0, 1.0) "Coverage of the clear coat.";
    coat_color: Color(1.0, 1.0, 1.0) "Transmittance of the coat (absorption tints what lies beneath).";
    coat_roughness: Scalar(0.0, 0.0, 1.0) "Roughness of the coat.";
    coat_roughness_anisotropy: Scalar(0.0, 0.0, 1.0) "Stretch of the coat's roughness along the tangent.";
    coat_ior: Scalar(1.6, 1.0, BIG) "Index of refraction of the coat.";
    coat_darkening: Scalar(1.0, 0.0, 1.0) "How much light trapped under the coat darkens and saturates the base.";
    fuzz_weight: Scalar(0.0, 0.0, 1.0) "Coverage of the fuzz (sheen) layer.";
    fuzz_color: Color(1.0, 1.0, 1.0) "Colour of the fuzz.";
    fuzz_roughness: Scalar(0.5, 0.0, 1.0) "Roughness of the fuzz fibres.";
    thin_film_weight: Scalar(0.0, 0.0, 1.0) "Coverage of the iridescent thin film on the specular and metal.";
    thin_film_thickness: Scalar(0.5, 0.0, BIG) "Thickness of the film in micrometres.";
    thin_film_ior: Scalar(1.4, 1.0, BIG) "Index of refraction of the film.";
    emission_luminance: Scalar(0.0, 0.0, BIG) "Emitted luminance (1 is radiance 1, as Cycles' emission strength).";
    emission_color: Color(1.0, 1.0, 1.0) "Colour of the emission.";
    geometry_opacity: Scalar(1.0, 0.0, 1.0) "Presence: the fraction of rays that find the surface; the others pass through it without an event (cut-outs).";
    geometry_thin_walled: Bool(false) "An infinitely thin shell: subsurface becomes translucency, glass does not bend light.";
    specular_color_f0_only: Bool(false) "Lightpath's, not OpenPBR's: specular_color tints the dielectric's reflectance at normal incidence only, fading to white at grazing, as glTF's KHR_materials_specular and Blender's Principled BSDF do (the glTF importer sets it).";
}

/// The input named `name`, if OpenPBR has one.
pub fn input(name: &str) -> Option<&'static Input> {
    INPUTS.iter().find(|i| i.name == name)
}

/// Which lobes a material carries: decided once, at scene build, from its untextured
/// parameters and which of them are textured.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LobeSet {
    pub fuzz: bool,
    pub coat: bool,
    /// Dielectric specular over the opaque base.
    pub specular: bool,
    pub metal: bool,
    pub glass: bool,
    pub subsurface: bool,
    pub translucency: bool,
    pub diffuse: bool,
    /// The diffuse is rough (EON) rather than Lambertian.
    pub rough_diffuse: bool,
    /// Filmed (`RS5`) copies of the specular and metal lobes.
    pub film: bool,
}

impl LobeSet {
    /// The lobes of `p`; `textured(name)` tells whether input `name` varies over the
    /// surface (its lobe is kept even where its untextured weight is zero).
    pub fn of(p: &OpenPbr, textured: impl Fn(&str) -> bool) -> LobeSet {
        let live = |weight: f32, name: &str| weight > 0.0 || textured(name);
        let metal = live(p.base_metalness, "base_metalness");
        let dielectric = p.base_metalness < 1.0 || textured("base_metalness");
        let glass = dielectric && live(p.transmission_weight, "transmission_weight");
        let opaque = dielectric && (p.transmission_weight < 1.0 || textured("transmission_weight"));
        let sss = opaque && live(p.subsurface_weight, "subsurface_weight");
        let diffuse_part = opaque && (p.subsurface_weight < 1.0 || textured("subsurface_weight"));
        let base = live(p.base_weight, "base_weight");
        LobeSet {
            fuzz: live(p.fuzz_weight, "fuzz_weight"),
            coat: live(p.coat_weight, "coat_weight"),
            specular: opaque && live(p.specular_weight, "specular_weight"),
            metal: metal && base,
            glass,
            subsurface: sss && !p.geometry_thin_walled,
            translucency: sss && p.geometry_thin_walled,
            diffuse: base && diffuse_part,
            rough_diffuse: live(p.base_diffuse_roughness, "base_diffuse_roughness"),
            film: live(p.thin_film_weight, "thin_film_weight"),
        }
    }
}

/// Thin-film thickness in nanometres from OpenPBR's micrometres.
const NM_PER_UM: f32 = 1000.0;

impl Bsdf {
    /// The lobes of set `set` for parameters `p` (see the module's table).
    pub fn openpbr(p: &OpenPbr, set: &LobeSet) -> Bsdf {
        let mut b = BsdfBuilder::default();
        let base_w = p.base_weight.clamp(0.0, 1.0);
        let metalness = p.base_metalness.clamp(0.0, 1.0);
        let dielectric = 1.0 - metalness;
        let transmission = p.transmission_weight.clamp(0.0, 1.0);
        let opaque = dielectric * (1.0 - transmission);
        let sss = p.subsurface_weight.clamp(0.0, 1.0);
        let film = if set.film {
            p.thin_film_weight.clamp(0.0, 1.0)
        } else {
            0.0
        };
        let thickness = p.thin_film_thickness * NM_PER_UM;
        let alpha =
            roughness_anisotropy_to_alpha(p.specular_roughness, p.specular_roughness_anisotropy);
        let eta = modulated_ior(p.specular_ior.max(1.0), p.specular_weight);
        // The opaque dielectric base: diffuse, and subsurface (translucency when thin).
        if set.diffuse && set.rough_diffuse {
            b.push(RoughDiffuse {
                color: p.base_color,
                weight: base_w * opaque * (1.0 - sss),
                roughness: p.base_diffuse_roughness,
            });
        } else if set.diffuse {
            b.push(Lambert {
                albedo: p.base_color * (base_w * opaque * (1.0 - sss)),
            });
        }
        if set.translucency {
            b.push(DiffuseTransmission {
                transmit: p.subsurface_color * (base_w * opaque * sss),
            });
        }
        if set.subsurface {
            b.push(Subsurface {
                weight: base_w * opaque * sss,
                color: p.subsurface_color,
                radius: p.subsurface_radius_scale * p.subsurface_radius,
                anisotropy: p.subsurface_scatter_anisotropy,
                ior: eta,
                alpha: (alpha.x * alpha.y).sqrt(),
            });
        }
        if set.specular {
            // The dielectric's reflection over the opaque base, bare and filmed; the base
            // lies under what the bare one reflects.
            let below = b.len();
            let specular = Specular::new(SpecularParams {
                eta,
                tint: p.specular_color,
                tint_f0_only: p.specular_color_f0_only,
                weight: 1.0,
                alpha,
                lobe: 2,
            });
            b.push(specular.with_weight(opaque * (1.0 - film)));
            if set.film {
                b.push(Iridescence::on_dielectric(
                    eta,
                    p.thin_film_ior,
                    thickness,
                    p.specular_color,
                    opaque * film,
                    alpha,
                ));
            }
            if below > 0 {
                b.layer(Layer::Specular(specular), below);
            }
        }
        if set.glass {
            // With a depth, the colour is the interior's absorption (a medium's), not a
            // tint of the interface.
            let tint = if p.transmission_depth > 0.0 {
                Vec3A::ONE
            } else {
                p.transmission_color
            };
            b.push(Dielectric {
                compensate: true,
                eta,
                alpha,
                tint: tint * (dielectric * transmission),
                // OpenPBR's specular colour tints the dielectric's reflection over glass
                // as over the opaque base; a tint on F0 only (glTF) is left out here.
                reflect_tint: if p.specular_color_f0_only {
                    Vec3A::ONE
                } else {
                    p.specular_color
                } * (dielectric * transmission),
            });
        }
        if set.metal {
            push_metal(&mut b, p, set, metalness, film, thickness, alpha);
        }
        push_layers(&mut b, p, set);
        // The `U2` albedo: the colours of the lobes by their weights.
        let albedo = base_w
            * (metalness * p.base_color
                + opaque * ((1.0 - sss) * p.base_color + sss * p.subsurface_color))
            + dielectric * transmission * p.transmission_color;
        Bsdf::from_builder(b, albedo)
    }
}

/// OpenPBR's modulated IOR (the specification's equation 26): `specular_weight` scales
/// the dielectric's reflectance at normal incidence, F0 = ((η − 1)/(η + 1))², by way of its
/// index, so the Fresnel curve still reaches 1 at grazing and the base beneath keeps
/// what the interface does not reflect; Blender's Specular IOR Level does the same.
fn modulated_ior(ior: f32, weight: f32) -> f32 {
    let f0 = ((ior - 1.0) / (ior + 1.0)).powi(2);
    if f0 <= 0.0 || weight == 1.0 {
        return ior;
    }
    // Clamped so that F0 stays below 1 (an index of at most ~2000).
    let eps = (weight.clamp(0.0, 1.0 / f0) * f0).sqrt().min(0.999);
    (1.0 + eps) / (1.0 - eps)
}

/// The metal (`RS2`) and, with a thin film, its filmed copy (`RS5`); `metalness` is the
/// metal's share of the base.
fn push_metal(
    b: &mut BsdfBuilder,
    p: &OpenPbr,
    set: &LobeSet,
    metalness: f32,
    film: f32,
    thickness: f32,
    alpha: glam::Vec2,
) {
    let f0 = p.base_color * p.base_weight.clamp(0.0, 1.0);
    b.push(Conductor {
        f0,
        f82_tint: p.specular_color,
        weight: p.specular_weight * metalness * (1.0 - film),
        alpha,
        lobe: 2,
    });
    if set.film {
        b.push(Iridescence::on_metal(
            f0,
            p.specular_color,
            p.thin_film_ior,
            thickness,
            p.specular_weight * metalness * film,
            alpha,
        ));
    }
}

/// The coat and the fuzz over everything pushed so far.
fn push_layers(b: &mut BsdfBuilder, p: &OpenPbr, set: &LobeSet) {
    let base_w = p.base_weight.clamp(0.0, 1.0);
    if set.coat {
        let below = b.len();
        let coat = Coat {
            eta: p.coat_ior.max(1.0),
            alpha: roughness_anisotropy_to_alpha(p.coat_roughness, p.coat_roughness_anisotropy),
            weight: p.coat_weight.clamp(0.0, 1.0),
        };
        let base_albedo = crate::light::luminance(p.base_color * base_w);
        b.push(coat);
        b.layer(
            Layer::coat(coat, p.coat_color, p.coat_darkening, base_albedo),
            below,
        );
    }
    if set.fuzz {
        let below = b.len();
        let fuzz = Fuzz {
            color: p.fuzz_color,
            weight: p.fuzz_weight.clamp(0.0, 1.0),
            roughness: p.fuzz_roughness.clamp(0.0, 1.0),
        };
        b.push(fuzz);
        b.layer(Layer::Fuzz(fuzz), below);
    }
}

/// Lobes and layers as `Bsdf::openpbr` assembles them, bottom up.
#[derive(Default)]
pub(super) struct BsdfBuilder {
    pub lobes: Vec<Lobe>,
    /// Each layer and how many lobes lie beneath it.
    pub layers: Vec<(Layer, usize)>,
}

impl BsdfBuilder {
    fn push(&mut self, lobe: impl Into<Lobe>) {
        self.lobes.push(lobe.into());
    }
    fn len(&self) -> usize {
        self.lobes.len()
    }
    fn layer(&mut self, layer: Layer, below: usize) {
        self.layers.push((layer, below));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_input_has_a_default_within_its_range() {
        let mut p = OpenPbr::default();
        for input in INPUTS {
            match (input.kind, (input.get)(&mut p)) {
                (InputKind::Scalar { default, min, max }, InputMut::Scalar(v)) => {
                    assert_eq!(*v, default, "{}", input.name);
                    assert!((min..=max).contains(&default), "{}", input.name);
                }
                (InputKind::Color { default }, InputMut::Color(v)) => {
                    assert_eq!(*v, Vec3A::from(default), "{}", input.name)
                }
                (InputKind::Bool { default }, InputMut::Bool(v)) => {
                    assert_eq!(*v, default, "{}", input.name)
                }
                _ => panic!("{}: kind and value disagree", input.name),
            }
        }
        assert_eq!(INPUTS.len(), 38);
    }

    #[test]
    fn specular_weight_scales_f0_through_the_index() {
        let f0 = |eta: f32| ((eta - 1.0) / (eta + 1.0)).powi(2);
        assert_eq!(modulated_ior(1.5, 1.0), 1.5);
        assert_eq!(modulated_ior(1.5, 0.0), 1.0);
        assert_eq!(modulated_ior(1.0, 2.0), 1.0);
        for (ior, weight) in [(1.5, 0.5), (1.5, 2.0), (1.33, 0.1), (2.4, 1.7)] {
            let got = f0(modulated_ior(ior, weight));
            assert!(
                (got - weight * f0(ior)).abs() < 1e-6,
                "{ior} {weight}: {got}"
            );
        }
        // Clamped where F0 would pass 1: a finite index, F0 below 1.
        let top = modulated_ior(1.5, 1e6);
        assert!(top.is_finite() && f0(top) < 1.0, "{top}");
    }

    #[test]
    fn glass_reflects_in_the_specular_colour_and_transmits_in_the_transmission_colour() {
        let p = OpenPbr {
            transmission_weight: 1.0,
            transmission_color: Vec3A::new(0.9, 0.5, 0.2),
            specular_color: Vec3A::new(1.0, 0.8, 0.6),
            ..OpenPbr::default()
        };
        let bsdf = Bsdf::openpbr(&p, &LobeSet::of(&p, |_| false));
        let glass = bsdf.lobes[..bsdf.n_lobes]
            .iter()
            .find_map(|l| match l {
                Lobe::Dielectric(d) => Some(*d),
                _ => None,
            })
            .expect("a glass lobe");
        assert_eq!(glass.tint, p.transmission_color);
        assert_eq!(glass.reflect_tint, p.specular_color);
        let gltf = OpenPbr {
            specular_color_f0_only: true,
            ..p
        };
        let bsdf = Bsdf::openpbr(&gltf, &LobeSet::of(&gltf, |_| false));
        assert!(bsdf.lobes[..bsdf.n_lobes]
            .iter()
            .any(|l| matches!(l, Lobe::Dielectric(d) if d.reflect_tint == Vec3A::ONE)));
    }

    #[test]
    fn a_pure_diffuse_material_is_one_lambert_lobe() {
        let p = OpenPbr {
            specular_weight: 0.0,
            ..OpenPbr::default()
        };
        let set = LobeSet::of(&p, |_| false);
        let bsdf = Bsdf::openpbr(&p, &set);
        assert_eq!(bsdf, Bsdf::diffuse(Vec3A::splat(0.8)));
    }
}
