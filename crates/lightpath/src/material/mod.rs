//! Materials as small lists of lobes. Each lobe event is reflection or transmission,
//! diffuse or specular, with RenderMan's lobe number (docs/lpe.md#paths-and-events), so that light sampling
//! can send every lobe's contribution through its own LPE event.
//!
//! ```toml
//! [materials.white]
//! type = "diffuse"          # diffuse | translucent | conductor | dielectric | plastic
//! albedo = [0.8, 0.8, 0.8]
//! ```
//!
//! Conventions: directions point away from the surface; `f` values include the cosine
//! of the incoming direction (`f · |cos θi|`); every pdf is in solid angle and includes
//! the probability of choosing the lobe. Transmission through a dielectric scales
//! radiance by 1/η² (η the relative index crossed, reported as `BsdfSample::eta`).
//!
//! Layout: [`lobe`] defines the lobe interface ([`LobeModel`]) and the [`Lobe`] enum;
//! one file per lobe kind; [`microfacet`] (GGX and the reflection every specular lobe
//! shares), [`fresnel`] and [`albedo`] (energy-compensation tables) are shared. A [`Bsdf`]
//! holds up to [`MAX_LOBES`] lobes inline, optionally under a [`Coat`] layer.

pub mod albedo;
mod albedo_tables;
pub mod anisotropy;
mod coat;
mod conductor;
mod dielectric;
pub mod fresnel;
mod fuzz;
mod fuzz_table;
mod iridescence;
mod lambert;
pub mod layer;
pub mod lobe;
pub mod microfacet;
pub mod openpbr;
pub mod pbr;
pub mod presence;
mod rough_diffuse;
mod specular;
mod subsurface;
pub mod texture;
pub mod textured;
pub mod thin_film;
mod translucent;

#[cfg(test)]
pub(crate) mod tests;
#[cfg(test)]
mod tests_fuzz;
#[cfg(test)]
mod tests_thin_film;

pub use coat::Coat;
pub use conductor::Conductor;
pub use dielectric::Dielectric;
pub use fresnel::fresnel_dielectric;
pub use fuzz::Fuzz;
pub use iridescence::Iridescence;
pub use lambert::Lambert;
pub use layer::Layer;
pub use lobe::{Lobe, LobeModel, LobeTag};
pub use pbr::PbrParams;
pub use rough_diffuse::RoughDiffuse;
pub use specular::{Specular, SpecularParams};
pub use subsurface::Subsurface;
pub use thin_film::{conductor_ior_from_colors, thin_film_fresnel, FilmBase};
pub use translucent::DiffuseTransmission;

use crate::sampling::Frame;
use glam::{Vec2, Vec3A};
use lobe::SampleCtx;
use openpbr::BsdfBuilder;

/// Lobes a Bsdf can hold, and LPE events they can emit.
pub const MAX_LOBES: usize = 10;
const MAX_TAGS: usize = 2 * MAX_LOBES;
/// Layers a Bsdf can hold (specular, coat, fuzz).
pub const MAX_LAYERS: usize = 3;

/// A fixed-capacity list of lobes, bottom up, and the layers among them: layer `j` is
/// lobe `layer_at[j]`, and attenuates every lobe before it.
#[derive(Clone, Debug, PartialEq)]
pub struct Bsdf {
    lobes: [Lobe; MAX_LOBES],
    n_lobes: usize,
    tags: [LobeTag; MAX_TAGS],
    /// For each event: (lobe index, `sub` within the lobe).
    tag_lobe: [(u8, u8); MAX_TAGS],
    n_tags: usize,
    layers: [Layer; MAX_LAYERS],
    layer_at: [u8; MAX_LAYERS],
    n_layers: usize,
    albedo: Vec3A,
    two_sided: bool,
}

pub struct BsdfSample {
    pub lobe: usize,
    pub wi: Vec3A,
    /// `f · |cos θi| / pdf`.
    pub weight: Vec3A,
    pub pdf: f32,
    pub delta: bool,
    /// Relative index of refraction crossed (1 for reflection), for Russian roulette.
    pub eta: f32,
}

/// Where and how a surface is shaded.
#[derive(Clone, Copy, Debug)]
pub struct Shading {
    pub frame: Frame,
    /// The outgoing direction in the local frame.
    pub wo: Vec3A,
}

/// What a Bsdf of several lobes makes of the outgoing direction alone: its lobe choice
/// and what each layer lets through towards `wo` (a specular layer's or a fuzz's
/// directional albedo, from tables). Every light sample, BSDF sample and pdf at a vertex
/// needs them for the same `wo`; looked up at each of those they were 36 % of the
/// instructions of a glTF shot of layered materials (docs/performance.md). The
/// integrator works them out once a vertex ([`Bsdf::at_wo`]) and passes them to the
/// `_at` forms of `eval_lobe` and `sample`; kept out of [`Shading`], whose copies every
/// vertex makes.
#[derive(Clone, Copy, Debug)]
pub struct AtWo {
    selection: [f32; MAX_LOBES],
    through: [f32; MAX_LAYERS],
}

impl Shading {
    /// A frame around the shading normal. Two-sided materials (all but glass) flip it
    /// towards `wo`, so reflection is `wi.z > 0` and transmission `wi.z < 0`;
    /// dielectrics keep the geometric orientation (it tells inside from outside).
    pub fn new(bsdf: &Bsdf, ns: Vec3A, ng: Vec3A, wo_world: Vec3A) -> Shading {
        let n = if bsdf.two_sided && wo_world.dot(ng) < 0.0 {
            -ns
        } else {
            ns
        };
        let frame = Frame::new(n);
        Shading {
            frame,
            wo: frame.to_local(wo_world),
        }
    }

    /// The same shading point with its first axis along `tangent` (projected onto the
    /// normal's plane), which anisotropic lobes stretch along; a tangent along the normal
    /// leaves the frame as it is.
    pub fn along(self, tangent: Vec3A) -> Shading {
        let n = self.frame.n;
        let s = tangent - n * n.dot(tangent);
        let len = s.length();
        // Also NaN: a degenerate tangent keeps the frame.
        if len.is_nan() || len <= 1e-6 {
            return self;
        }
        let s = s / len;
        let frame = Frame {
            s,
            t: n.cross(s),
            n,
        };
        Shading {
            frame,
            wo: frame.to_local(self.frame.to_world(self.wo)),
        }
    }
}

/// Roughness as artists write it (0 smooth … 1 rough) to GGX alpha.
pub fn roughness_to_alpha(r: f32) -> f32 {
    let r = r.clamp(0.0, 1.0);
    if r < 1e-3 {
        0.0
    } else {
        r * r
    }
}

impl Bsdf {
    /// A Bsdf of `base` lobes, optionally under `coat`; `albedo` is what the `U2` lobe
    /// reports.
    ///
    /// # Panics
    /// With no lobes or more than [`MAX_LOBES`] (a bug in a constructor below).
    pub fn layered(base: &[Lobe], coat: Option<Coat>, albedo: Vec3A) -> Bsdf {
        let mut b = BsdfBuilder {
            lobes: base.to_vec(),
            layers: Vec::new(),
        };
        if let Some(coat) = coat {
            b.layers
                .push((Layer::coat(coat, Vec3A::ONE, 0.0, 0.0), b.lobes.len()));
            b.lobes.push(coat.into());
        }
        Bsdf::from_builder(b, albedo)
    }

    /// The Bsdf of lobes and layers assembled by a builder.
    ///
    /// # Panics
    /// With no lobes, more than [`MAX_LOBES`] or more than [`MAX_LAYERS`] (a bug in a
    /// constructor).
    fn from_builder(b: BsdfBuilder, albedo: Vec3A) -> Bsdf {
        let filler = Lobe::Lambert(Lambert {
            albedo: Vec3A::ZERO,
        });
        let mut bsdf = Bsdf {
            lobes: [filler; MAX_LOBES],
            n_lobes: 0,
            tags: [lambert::RD2; MAX_TAGS],
            tag_lobe: [(0, 0); MAX_TAGS],
            n_tags: 0,
            layers: [Layer::Fuzz(Fuzz {
                color: Vec3A::ZERO,
                weight: 0.0,
                roughness: 0.0,
            }); MAX_LAYERS],
            layer_at: [0; MAX_LAYERS],
            n_layers: 0,
            albedo,
            two_sided: true,
        };
        assert!(b.lobes.len() <= MAX_LOBES, "too many lobes");
        assert!(b.layers.len() <= MAX_LAYERS, "too many layers");
        for lobe in b.lobes {
            for (sub, t) in lobe.tags().iter().enumerate() {
                bsdf.tags[bsdf.n_tags] = *t;
                bsdf.tag_lobe[bsdf.n_tags] = (bsdf.n_lobes as u8, sub as u8);
                bsdf.n_tags += 1;
            }
            bsdf.two_sided &= lobe.two_sided();
            bsdf.lobes[bsdf.n_lobes] = lobe;
            bsdf.n_lobes += 1;
        }
        for (layer, at) in b.layers {
            bsdf.layers[bsdf.n_layers] = layer;
            bsdf.layer_at[bsdf.n_layers] = at as u8;
            bsdf.n_layers += 1;
        }
        assert!(bsdf.n_lobes > 0, "a Bsdf needs a lobe");
        bsdf
    }

    /// Lambertian reflection (RD2).
    pub fn diffuse(albedo: Vec3A) -> Bsdf {
        Bsdf::layered(&[Lambert { albedo }.into()], None, albedo)
    }

    /// Diffuse reflection (RD2) and diffuse transmission (TD2): thin translucent sheets.
    pub fn translucent(reflect: Vec3A, transmit: Vec3A) -> Bsdf {
        Bsdf::layered(
            &[
                Lambert { albedo: reflect }.into(),
                DiffuseTransmission { transmit }.into(),
            ],
            None,
            reflect + transmit,
        )
    }

    /// Metal (RS2): a mirror when `alpha` is 0, GGX otherwise; Schlick Fresnel.
    pub fn conductor(f0: Vec3A, alpha: f32) -> Bsdf {
        Bsdf::layered(&[Conductor::schlick(f0, alpha).into()], None, f0)
    }

    /// Glass (RS8 + TS8), smooth or rough.
    pub fn dielectric(eta: f32, alpha: f32, tint: Vec3A) -> Bsdf {
        let alpha = Vec2::splat(alpha);
        Bsdf::layered(
            &[Dielectric {
                eta,
                alpha,
                tint,
                reflect_tint: Vec3A::ONE,
                compensate: true,
            }
            .into()],
            None,
            tint,
        )
    }

    /// A diffuse base (RD2) under a dielectric clear coat (RS4).
    pub fn plastic(albedo: Vec3A, eta: f32, alpha: f32) -> Bsdf {
        Bsdf::layered(
            &[Lambert { albedo }.into()],
            Some(Coat {
                eta,
                alpha: Vec2::splat(alpha),
                weight: 1.0,
            }),
            albedo,
        )
    }

    /// This Bsdf with its glass uncompensated, for path regularisation: a regularised
    /// glass stands in for a smooth one so that caustics can be light-sampled, and the
    /// multiple scattering of its borrowed roughness would add light along exactly the
    /// paths it is there to tame (on the built-in `cornell`, isolated fireflies at its
    /// defaults went from ~23 to 51 with it).
    pub fn regularized_glass(mut self) -> Bsdf {
        for lobe in &mut self.lobes[..self.n_lobes] {
            if let Lobe::Dielectric(d) = lobe {
                d.compensate = false;
            }
        }
        self
    }

    /// The LPE events of the lobes, in the order `eval_lobe` and `BsdfSample::lobe` use.
    pub fn lobes(&self) -> &[LobeTag] {
        &self.tags[..self.n_tags]
    }

    /// Whether nothing leaves it on the other side of its shading normal from `wo`: it
    /// is two-sided (the frame turns towards `wo`) and no lobe transmits, so every lobe
    /// evaluates to zero for `wi.z <= 0`.
    pub fn reflects_only(&self) -> bool {
        self.two_sided && self.lobes().iter().all(|t| !t.transmit)
    }

    /// The albedo of a Bsdf that is one two-sided Lambert lobe and nothing else: its
    /// value and pdf need no frame (`Lambert::eval`: `albedo / π · cos θi` and
    /// `cos θi / π` about the normal turned towards `wo`).
    pub fn lone_lambert(&self) -> Option<Vec3A> {
        match &self.lobes[0] {
            Lobe::Lambert(l) if self.n_lobes == 1 && self.n_layers == 0 && self.two_sided => {
                Some(l.albedo)
            }
            _ => None,
        }
    }

    /// Whether the Bsdf is one lobe under no layer: its lobe choice is certain from either
    /// side, so a delta sample's pdf (a dielectric's Fresnel choice, F(θi) = F(θt)) is
    /// the same both ways (light subpaths through delta lobes, integrator/connect.rs).
    pub fn lone_lobe(&self) -> bool {
        self.n_lobes == 1 && self.n_layers == 0
    }

    /// The colour the `U2` albedo lobe reports.
    pub fn albedo(&self) -> Vec3A {
        self.albedo
    }

    /// Probability of choosing each lobe when sampling: in proportion to each lobe's
    /// selection weight times what the layers above it let through towards `wo`, mixed
    /// with a uniform choice (one tenth) so that no lobe with a small estimate starves.
    fn selection(&self, sh: &Shading, at: Option<&AtWo>) -> [f32; MAX_LOBES] {
        match at {
            Some(at) => at.selection,
            None => self.selection_through(sh.wo, &self.through(sh.wo)),
        }
    }

    /// What each layer lets through towards `wo`.
    fn through(&self, wo: Vec3A) -> [f32; MAX_LAYERS] {
        let mut through = [1.0; MAX_LAYERS];
        for (t, layer) in through.iter_mut().zip(&self.layers[..self.n_layers]) {
            *t = layer.transmission_towards(wo);
        }
        through
    }

    /// The terms of the local outgoing direction `wo` alone (see [`AtWo`]), for the
    /// `_at` forms of [`eval_lobe`](Self::eval_lobe) and [`sample`](Self::sample) at
    /// that `wo`; `None` for one lobe (no choice, no layer).
    #[inline]
    pub fn at_wo(&self, wo: Vec3A) -> Option<AtWo> {
        (self.n_lobes > 1).then(|| self.work_out(wo))
    }

    #[inline(never)]
    fn work_out(&self, wo: Vec3A) -> AtWo {
        let through = self.through(wo);
        AtWo {
            selection: self.selection_through(wo, &through),
            through,
        }
    }

    /// [`selection`](Self::selection), the layers letting `through` through.
    fn selection_through(&self, wo: Vec3A, through: &[f32; MAX_LAYERS]) -> [f32; MAX_LOBES] {
        let mut p = [0.0; MAX_LOBES];
        let n = self.n_lobes;
        if n == 1 {
            p[0] = 1.0;
            return p;
        }
        let mut sum = 0.0;
        for (l, (pk, lobe)) in p.iter_mut().zip(&self.lobes[..n]).enumerate() {
            let mut w = lobe.selection_weight(wo);
            for (j, t) in through.iter().enumerate().take(self.n_layers) {
                if l < self.layer_at[j] as usize {
                    w *= t;
                }
            }
            *pk = w.max(0.0);
            sum += *pk;
        }
        let uniform = 1.0 / n as f32;
        for pk in &mut p[..n] {
            *pk = if sum > 0.0 {
                0.9 * *pk / sum + 0.1 * uniform
            } else {
                uniform
            };
        }
        p
    }

    /// The product of the attenuations of the layers above lobe `l`.
    #[inline(always)]
    fn attenuation(&self, l: usize, sh: &Shading, at: Option<&AtWo>, wi: Vec3A) -> Vec3A {
        if self.n_layers == 0 {
            return Vec3A::ONE;
        }
        self.layered_attenuation(l, sh, at, wi)
    }

    fn layered_attenuation(&self, l: usize, sh: &Shading, at: Option<&AtWo>, wi: Vec3A) -> Vec3A {
        let mut a = Vec3A::ONE;
        for j in 0..self.n_layers {
            if l < self.layer_at[j] as usize {
                a *= match at {
                    Some(at) => self.layers[j].attenuation_through(at.through[j], sh.wo, wi),
                    None => self.layers[j].attenuation(sh.wo, wi),
                };
            }
        }
        a
    }

    /// `f · |cos θi|` of lobe event `k` for the local directions, and its pdf
    /// (selection included). Delta lobes evaluate to zero.
    pub fn eval_lobe(&self, k: usize, sh: &Shading, wi: Vec3A) -> (Vec3A, f32) {
        self.eval_lobe_at(k, sh, None, wi)
    }

    /// [`eval_lobe`](Self::eval_lobe) with the terms of `sh.wo` worked out (`at`, from
    /// [`at_wo`](Self::at_wo)).
    #[inline]
    pub fn eval_lobe_at(
        &self,
        k: usize,
        sh: &Shading,
        at: Option<&AtWo>,
        wi: Vec3A,
    ) -> (Vec3A, f32) {
        let wo = sh.wo;
        let (l, sub) = self.tag_lobe[k];
        // One lobe (no layer without a second): chosen always, attenuated by nothing.
        if self.n_lobes == 1 {
            return self.lobes[0].eval(sub as usize, wo, wi, 1.0);
        }
        let sel = self.selection(sh, at);
        let l = l as usize;
        let (f, pdf) = self.lobes[l].eval(sub as usize, wo, wi, sel[l]);
        (f * self.attenuation(l, sh, at, wi), pdf)
    }

    /// Samples a lobe and a direction: `u_lobe` chooses the lobe, `u` the direction.
    pub fn sample(&self, sh: &Shading, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        self.sample_at(sh, None, u_lobe, u)
    }

    /// [`sample`](Self::sample) with the terms of `sh.wo` worked out (`at`).
    pub fn sample_at(
        &self,
        sh: &Shading,
        at: Option<&AtWo>,
        u_lobe: f32,
        u: Vec2,
    ) -> Option<BsdfSample> {
        let wo = sh.wo;
        // One Lambertian lobe and no layer (the commonest material): its own sample,
        // without the lobe kinds' dispatch, the event lookup and the layers' attenuation
        // (one: `weight` is the albedo the lobe returns). The same sample as below.
        if self.n_lobes == 1 && self.n_layers == 0 && self.n_tags == 1 {
            if let Lobe::Lambert(lambert) = &self.lobes[0] {
                let ctx = SampleCtx {
                    sel: 1.0,
                    u_lobe,
                    alone: true,
                };
                let s = lambert.sample(wo, ctx, u)?;
                if let Some((weight, pdf, delta)) = s.value {
                    return Some(BsdfSample {
                        lobe: 0,
                        wi: sh.frame.to_world(s.wi),
                        weight,
                        pdf,
                        delta,
                        eta: s.eta,
                    });
                }
            }
        }
        let (l, u_rest, sel_l) = if self.n_lobes == 1 {
            (0, u_lobe, 1.0)
        } else {
            let sel = self.selection(sh, at);
            let mut lo = 0.0;
            let mut l = self.n_lobes - 1;
            for (k, &pk) in sel[..self.n_lobes - 1].iter().enumerate() {
                if u_lobe < lo + pk {
                    l = k;
                    break;
                }
                lo += pk;
            }
            let u_rest = ((u_lobe - lo) / sel[l]).min(1.0 - f32::EPSILON / 2.0);
            (l, u_rest, sel[l])
        };
        self.sample_lobe(sh, at, l, sel_l, u_rest, u)
    }

    /// What [`sample_at`](Self::sample_at) draws when its `u_lobe` picks the lobe of
    /// event `k` and falls `u_rest` of the way through that lobe's share: the same
    /// sample, weight and pdf (the lobe's choice included), whichever of the lobe's
    /// events it is. Glint sampling (integrator/glints.rs) follows a chain of delta
    /// events with it.
    pub fn sample_event_at(
        &self,
        sh: &Shading,
        at: Option<&AtWo>,
        k: usize,
        u_rest: f32,
    ) -> Option<BsdfSample> {
        let (l, _) = *self.tag_lobe[..self.n_tags].get(k)?;
        let l = l as usize;
        let sel_l = if self.n_lobes == 1 {
            1.0
        } else {
            self.selection(sh, at)[l]
        };
        if sel_l <= 0.0 {
            return None;
        }
        self.sample_lobe(
            sh,
            at,
            l,
            sel_l,
            u_rest.min(1.0 - f32::EPSILON / 2.0),
            Vec2::ZERO,
        )
    }

    /// Samples lobe `l`, chosen with probability `sel_l`, with `u_rest` its share of
    /// `u_lobe`. Inlined: `sample_at`'s body, as it was before glint sampling shared it.
    #[inline(always)]
    fn sample_lobe(
        &self,
        sh: &Shading,
        at: Option<&AtWo>,
        l: usize,
        sel_l: f32,
        u_rest: f32,
        u: Vec2,
    ) -> Option<BsdfSample> {
        let wo = sh.wo;
        let ctx = SampleCtx {
            sel: sel_l,
            u_lobe: u_rest,
            alone: self.n_lobes == 1,
        };
        let s = self.lobes[l].sample(wo, ctx, u)?;
        let k = self.tag_index(l, s.sub);
        if let Some((weight, pdf, delta)) = s.value {
            // A subsurface walk comes back out on the side it went in: the layers above
            // see it leave there (the inward direction mirrored stands for the exit's,
            // both cosine-distributed), and its exit lobe is under none of them.
            let wi_layers = match self.lobes[l] {
                Lobe::Subsurface(_) => Vec3A::new(s.wi.x, s.wi.y, -s.wi.z),
                _ => s.wi,
            };
            return Some(BsdfSample {
                lobe: k,
                wi: sh.frame.to_world(s.wi),
                weight: weight * self.attenuation(l, sh, at, wi_layers),
                pdf,
                delta,
                eta: s.eta,
            });
        }
        let (f, pdf) = self.eval_lobe_at(k, sh, at, s.wi);
        if pdf <= 0.0 || f == Vec3A::ZERO {
            return None;
        }
        Some(BsdfSample {
            lobe: k,
            wi: sh.frame.to_world(s.wi),
            weight: f / pdf,
            pdf,
            delta: false,
            eta: s.eta,
        })
    }

    /// The subsurface lobe behind lobe event `k`, if it is one: a sample of it is the
    /// entry of a random walk (integrator/subsurface.rs), not a direction to trace.
    pub fn subsurface(&self, k: usize) -> Option<&Subsurface> {
        let (l, _) = *self.tag_lobe[..self.n_tags].get(k)?;
        match &self.lobes[l as usize] {
            Lobe::Subsurface(s) => Some(s),
            _ => None,
        }
    }

    fn tag_index(&self, lobe: usize, sub: usize) -> usize {
        self.tag_lobe[..self.n_tags]
            .iter()
            .position(|&(l, s)| l as usize == lobe && s as usize == sub)
            .expect("a lobe samples one of its own events")
    }
}
