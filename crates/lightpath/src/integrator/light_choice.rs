//! Which light, and which point of it, a scattering vertex samples for direct light:
//! one candidate from the light selector, or the best of several by resampled importance
//! sampling (Talbot, Cline & Egbert 2005, "Importance Resampling for Global
//! Illumination"): `--light-candidates M` draws M (light, point) candidates from the
//! selector, weighs each by its unshadowed contribution here (every non-delta lobe's
//! BSDF value times the light's radiance, as luminance) over its pdf, keeps one in
//! proportion to that weight, and scales its estimate by the mean weight over the kept
//! candidate's contribution. That estimate is unbiased for any M ≥ 1 (the contribution
//! is positive wherever a lobe can carry light), and with many lights it puts the
//! shadow ray where the light actually is bright from this point, which the selector's
//! bounds can only guess.
//!
//! The MIS weight against BSDF sampling uses the selector's pdf for the kept point (the
//! same function a BSDF ray's weight uses, so the two weights still sum to one and the
//! combination stays unbiased, though less than optimal for M > 1: the resampled pdf has
//! no closed form).

use super::path::{PathState, Vertex};
use super::Tracer;
use crate::light::{luminance, LightModel, LightSample, LightShape};
use glam::{Vec2, Vec3A};

/// The light sample a vertex keeps.
pub(super) struct Chosen {
    pub li: usize,
    pub ls: LightSample,
    /// `ls.wi` in the shading frame.
    pub wi: Vec3A,
    /// The selector's pdf of this point (selection times the light's own pdf): the
    /// light strategy's pdf in MIS weights.
    pub mis_pdf: f32,
    /// What the estimate divides by: `mis_pdf` for one candidate; for several, the
    /// kept candidate's contribution over the candidates' mean weight.
    pub estimate_pdf: f32,
}

impl Tracer<'_> {
    /// The light sample for direct light at `v`: from (`u_light`, `u_point`) alone, or
    /// resampled from `settings.light_candidates` candidates (the first from those
    /// numbers, the others from the path's own stream, so each sample's numbers still
    /// depend only on its seed, pixel and index). `None`: no light reaches `v`.
    /// Always inlined (the resampling kept apart), so that one candidate costs no call
    /// and no copy of the `Chosen` it returns: it was a call of ~250 instructions a
    /// vertex on cornell-classic.
    #[inline(always)]
    pub(super) fn choose_light(
        &self,
        path: &mut PathState,
        v: &Vertex,
        u_light: f32,
        u_point: Vec2,
    ) -> Option<Chosen> {
        let scene = self.scene;
        let m = scene.settings.light_candidates.max(1);
        if m == 1 || scene.lights.len() < 2 {
            // `candidate` sets `estimate_pdf` to `mis_pdf`.
            return self.candidate(v, u_light, u_point);
        }
        self.resample(path, v, u_light, u_point, m)
    }

    /// `m` candidates, one kept by reservoir sampling.
    fn resample(
        &self,
        path: &mut PathState,
        v: &Vertex,
        u_light: f32,
        u_point: Vec2,
        m: u32,
    ) -> Option<Chosen> {
        let mut kept: Option<(Chosen, f32)> = None;
        let mut weight_sum = 0.0f32;
        for j in 0..m {
            let (u_l, u_p) = if j == 0 {
                (u_light, u_point)
            } else {
                (path.rng.next_f32(), path.rng.next_2d())
            };
            let Some(c) = self.candidate(v, u_l, u_p) else {
                continue;
            };
            let target = self.target(v, &c);
            if !(target > 0.0 && target.is_finite()) {
                continue;
            }
            let w = target / c.mis_pdf;
            if !w.is_finite() {
                continue;
            }
            weight_sum += w;
            // Reservoir sampling: the j-th candidate replaces the kept one with
            // probability w / Σw, one number each from the path's stream.
            if kept.is_none() || path.rng.next_f32() * weight_sum < w {
                kept = Some((c, target));
            }
        }
        let (c, target) = kept?;
        let mean = weight_sum / m as f32;
        Some(Chosen {
            estimate_pdf: target / mean,
            ..c
        })
    }

    /// One (light, point) candidate from the selector, if the light lights `v`.
    /// Always inlined, like `choose_light`: a call returning the `Chosen` through memory.
    #[inline(always)]
    fn candidate(&self, v: &Vertex, u_light: f32, u_point: Vec2) -> Option<Chosen> {
        let scene = self.scene;
        let (li, select_pmf) = scene.light_select.sample(u_light, v.hit.p, v.sh.frame.n)?;
        if !self.lit(v.hit.object, li as u32) {
            return None;
        }
        let light = &scene.lights[li];
        // Triangle lights (quads, rects, disks, meshes of a few triangles) sampled
        // inline: through `LightShape`'s match of every kind the sample was a call.
        let ls = match &light.shape {
            LightShape::Triangles(t) => t.sample(
                light.color,
                v.hit.p,
                v.sh.frame.n,
                u_point,
                scene.accel.prims(),
            ),
            _ => light.sample(v.hit.p, v.sh.frame.n, u_point, scene.accel.prims()),
        }?;
        let mis_pdf = select_pmf * ls.pdf;
        Some(Chosen {
            li,
            wi: v.sh.frame.to_local(ls.wi),
            ls,
            mis_pdf,
            estimate_pdf: mis_pdf,
        })
    }

    /// The resampling target: the candidate's unshadowed contribution through every
    /// non-delta lobe, as luminance.
    fn target(&self, v: &Vertex, c: &Chosen) -> f32 {
        let mut f = Vec3A::ZERO;
        for (k, tag) in v.bsdf.lobes().iter().enumerate() {
            if !tag.delta {
                f += v.bsdf.eval_lobe_at(k, &v.sh, v.at_wo.as_ref(), c.wi).0;
            }
        }
        luminance(f * c.ls.radiance)
    }
}
