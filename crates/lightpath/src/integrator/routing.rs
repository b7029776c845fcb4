//! AOV routing: how a contribution reached the camera (`Via`), what each rule's prefixes
//! take of it (`take`, docs/lpe.md), and `contribute`, which adds it to every accepting
//! AOV. The prefix logic runs once per rule at setup; the hot loop does a table lookup.

use super::{Sink, Tracer};
use crate::light::luminance;
use crate::scene::{Aov, Scene};
use glam::Vec3A;
use lpe::{Prefix, StateId};

/// How a contribution reached the camera: decides what prefixed AOVs receive.
#[derive(Clone, Copy, Debug)]
pub(super) enum Via {
    /// Emission found by a ray. `light_sampled`: another strategy covers it too, so it
    /// carries an MIS weight (light sampling; or, through a delta lobe, a light subpath
    /// joined to the camera: connect.rs); `light_after_scatter`: a light reached after a scatter,
    /// which `unoccluded` and `shadows` AOVs take from the lights-only test instead.
    Hit {
        light_sampled: bool,
        light_after_scatter: bool,
    },
    /// A light sample, with its shadow-ray result.
    LightSample { visible: bool },
    /// A BSDF-sampled direction tested against the lights alone (for `unoccluded` and
    /// `shadows` AOVs only), and whether the real ray was blocked before the light.
    LightsOnly { occluded: bool },
    /// A user (data) lobe.
    Data,
    /// A glowing surface's emission (`O`, not a light: no shadows to speak of), found by
    /// a ray or by a light sample that reached it, with its MIS weight: plain and
    /// `unoccluded` AOVs take it, `shadows` AOVs do not.
    Glow,
}

impl Via {
    /// Every `Via`, in `index` order.
    const ALL: [Via; Via::COUNT] = [
        Via::Hit {
            light_sampled: false,
            light_after_scatter: false,
        },
        Via::Hit {
            light_sampled: true,
            light_after_scatter: false,
        },
        Via::Hit {
            light_sampled: false,
            light_after_scatter: true,
        },
        Via::Hit {
            light_sampled: true,
            light_after_scatter: true,
        },
        Via::LightSample { visible: false },
        Via::LightSample { visible: true },
        Via::LightsOnly { occluded: false },
        Via::LightsOnly { occluded: true },
        Via::Data,
        Via::Glow,
    ];
    const COUNT: usize = 10;

    #[inline(always)]
    fn index(self) -> usize {
        match self {
            Via::Hit {
                light_sampled,
                light_after_scatter,
            } => light_sampled as usize | (light_after_scatter as usize) << 1,
            Via::LightSample { visible } => 4 + visible as usize,
            Via::LightsOnly { occluded } => 6 + occluded as usize,
            Via::Data => 8,
            Via::Glow => 9,
        }
    }
}

/// What a rule takes of a contribution.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) enum Take {
    /// Nothing.
    #[default]
    Skip,
    /// The value as it is.
    Whole,
    /// The value times its MIS weight.
    Weighted,
}

/// The prefixes' routing rules (docs/lpe.md): what an AOV with these flags takes of a
/// contribution that came this way, outside holdouts.
pub(super) fn take(unoccluded: bool, shadows: bool, via: Via) -> Take {
    match via {
        Via::Hit {
            light_sampled,
            light_after_scatter,
        } => {
            if shadows || (unoccluded && light_after_scatter) {
                Take::Skip
            } else if unoccluded || !light_sampled {
                Take::Whole
            } else {
                Take::Weighted
            }
        }
        // Light samples keep their MIS weight whatever the shadow ray says: `unoccluded`
        // takes them all, `shadows` the blocked ones, so plain + shadows = unoccluded.
        Via::LightSample { visible } => {
            if unoccluded || (shadows && !visible) || (!shadows && visible) {
                Take::Weighted
            } else {
                Take::Skip
            }
        }
        // BSDF rays against the lights alone, with the weight the real hit would have.
        Via::LightsOnly { occluded } => {
            if unoccluded || (shadows && occluded) {
                Take::Weighted
            } else {
                Take::Skip
            }
        }
        Via::Data => Take::Whole,
        // As a glow seen by a ray was before glows were light-sampled (always `Whole`
        // then, now split between the two strategies by their weights).
        Via::Glow => {
            if shadows {
                Take::Skip
            } else {
                Take::Weighted
            }
        }
    }
}

/// Per-rule routing flags, unpacked from the prefixes for the hot loop.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Route {
    /// What the rule takes of a contribution, by `Via::index`, outside holdouts (row 0)
    /// and inside (row 1), with `nothruput` folded in: which of its four values
    /// (`Route::value_index`), or `SKIP`. One lookup instead of the prefix logic per rule.
    pick: [[u8; Via::COUNT]; 2],
    overwrite: bool,
    noclamp: bool,
    noinfinitecheck: bool,
    /// First part of this AOV's light-group split, or `u32::MAX`.
    split_base: u32,
    /// Number of parts of the split (light groups + the default part).
    split_parts: u32,
}

impl Route {
    /// The routing of one AOV, its prefixes unpacked.
    pub(super) fn for_aov(a: &Aov, scene: &Scene) -> Route {
        let unoccluded = a.flags.contains(Prefix::Unoccluded);
        let shadows = a.flags.contains(Prefix::Shadows);
        // `holdouts` AOVs take only what holdouts see, the others only the rest.
        let holdouts = a.flags.contains(Prefix::Holdouts);
        let row = |in_holdout: bool| {
            Via::ALL.map(|via| {
                if in_holdout == holdouts {
                    take(unoccluded, shadows, via)
                } else {
                    Take::Skip
                }
            })
        };
        let nothruput = a.flags.contains(Prefix::NoThruput);
        Route {
            pick: [row(false), row(true)].map(|row| row.map(|t| Route::value_index(nothruput, t))),
            overwrite: a.flags.contains(Prefix::Overwrite),
            noclamp: a.flags.contains(Prefix::NoClamp),
            noinfinitecheck: a.flags.contains(Prefix::NoInfiniteCheck),
            split_base: a.split_base.unwrap_or(u32::MAX),
            split_parts: scene.light_groups.len() as u32 + 1,
        }
    }

    /// Where in `[local, local × mis, full, full × mis]` (`contribute`'s values, `full`
    /// with the throughput) a rule with `nothruput` that takes `take` finds its value.
    fn value_index(nothruput: bool, take: Take) -> u8 {
        match take {
            Take::Skip => SKIP,
            Take::Whole | Take::Weighted => 2 * !nothruput as u8 + (take == Take::Weighted) as u8,
        }
    }
}

/// `Route::pick`'s "takes nothing".
const SKIP: u8 = u8::MAX;

/// What one contribution carries besides its value.
#[derive(Clone, Copy)]
pub(super) struct Origin {
    pub via: Via,
    /// Scattering events before the light (for direct/indirect clamping).
    pub scatters: u32,
    /// The light-group part it belongs to in split AOVs.
    pub part: u32,
}

impl Tracer<'_> {
    /// Adds `throughput × local × weight` to every AOV whose rule accepts `state`.
    #[inline]
    pub(super) fn contribute(
        &self,
        out: &mut Sink,
        state: StateId,
        throughput: Vec3A,
        local: Vec3A,
        mis: f32,
        origin: Origin,
    ) {
        self.contribute_inlined(out, state, throughput, local, mis, origin)
    }

    /// `contribute`, inlined: where the caller's `Via` and weight are constants (a data
    /// lobe's), the way's row and the weighted values fold away. Through the call a data
    /// lobe's contribution cost ~150 instructions, inlined ~75 fewer (indirect box with
    /// the standard AOVs, whose albedo, normal and depth are three per camera path:
    /// 8.6 % of the render's instructions before, 5.9 % after; callgrind).
    #[inline(always)]
    pub(super) fn contribute_inlined(
        &self,
        out: &mut Sink,
        state: StateId,
        throughput: Vec3A,
        local: Vec3A,
        mis: f32,
        origin: Origin,
    ) {
        if self.learn {
            // A training pass keeps only what its path records for the guide; its film
            // is thrown away (guided.rs, `train`), so nothing is routed to AOVs.
            if !out.record.is_empty()
                && matches!(
                    origin.via,
                    Via::Hit { .. } | Via::LightSample { visible: true } | Via::Glow
                )
            {
                out.record.add(throughput * local * mis);
            }
            return;
        }
        let rules = self.scene.automaton.accepting(state);
        if rules.is_empty() {
            return;
        }
        let settings = &self.scene.settings;
        let clamp = if origin.scatters <= 1 {
            settings.clamp_direct
        } else {
            settings.clamp_indirect
        };
        let mut dropped = false;
        let takes = out.holdout as usize;
        let case = origin.via.index();
        // The four values a rule can take: without or with the throughput, whole or
        // weighted (`Route::value_index`).
        let full = throughput * local;
        let values = [local, local * mis, full, full * mis];
        for rule in rules {
            let k = rule.0 as usize;
            let r = &self.routes[k];
            let pick = r.pick[takes][case];
            if pick == SKIP {
                continue;
            }
            let mut v = values[pick as usize & 3];
            if r.overwrite {
                // Data (`overwrite`) AOVs take emission as its colour, no channel above
                // 1: an emitter's albedo is its base colour, not its radiance.
                if let Via::Hit { .. } | Via::Glow = origin.via {
                    v *= 1.0 / local.max_element().max(1.0);
                }
            }
            if !r.noinfinitecheck && !v.is_finite() {
                dropped = true;
                continue;
            }
            if clamp > 0.0 && !r.noclamp {
                let l = luminance(v);
                if l > clamp {
                    v *= clamp / l;
                }
            }
            out.acc.add(k, v, r.overwrite);
            if r.split_base != u32::MAX {
                if r.overwrite {
                    // The whole now holds only `v`, so its parts must too: clear the
                    // part an earlier contribution of another group went to.
                    for part in 0..r.split_parts {
                        if part != origin.part {
                            out.acc
                                .add((r.split_base + part) as usize, Vec3A::ZERO, true);
                        }
                    }
                }
                out.acc
                    .add((r.split_base + origin.part) as usize, v, r.overwrite);
            }
        }
        out.nonfinite += dropped as u64;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The routing table is indexed by `Via::index`: `ALL` must list every way once, in
    /// that order.
    #[test]
    fn every_via_has_its_own_row() {
        for (i, via) in Via::ALL.iter().enumerate() {
            assert_eq!(via.index(), i, "{via:?}");
        }
    }

    /// `pick` is `take` with `nothruput` folded in: the value a rule finds is the one
    /// `take` and `nothruput` name, for every way and prefix.
    #[test]
    fn picks_name_the_value_take_and_nothruput_give() {
        for nothruput in [false, true] {
            for unoccluded in [false, true] {
                for shadows in [false, true] {
                    for via in Via::ALL {
                        let t = take(unoccluded, shadows, via);
                        let pick = Route::value_index(nothruput, t);
                        match t {
                            Take::Skip => assert_eq!(pick, SKIP),
                            _ => assert_eq!(
                                (pick >> 1 == 1, pick & 1 == 1),
                                (!nothruput, t == Take::Weighted),
                                "{via:?}"
                            ),
                        }
                    }
                }
            }
        }
    }

    /// Spot checks of the prefix rules (docs/lpe.md): plain AOVs take visible light
    /// samples weighted, `shadows` only blocked ones, `unoccluded` all of them, weighted
    /// too (one estimator, so plain + shadows = unoccluded); the lights-only test of a
    /// BSDF ray goes weighted to `unoccluded`, and to `shadows` when the ray was blocked.
    #[test]
    fn prefixes_take_what_the_docs_say() {
        let sample = |visible| Via::LightSample { visible };
        assert_eq!(take(false, false, sample(true)), Take::Weighted);
        assert_eq!(take(false, false, sample(false)), Take::Skip);
        assert_eq!(take(false, true, sample(false)), Take::Weighted);
        assert_eq!(take(false, true, sample(true)), Take::Skip);
        assert_eq!(take(true, false, sample(false)), Take::Weighted);
        assert_eq!(take(true, false, sample(true)), Take::Weighted);
        let emitter_after_scatter = Via::Hit {
            light_sampled: true,
            light_after_scatter: true,
        };
        assert_eq!(take(false, false, emitter_after_scatter), Take::Weighted);
        assert_eq!(take(true, false, emitter_after_scatter), Take::Skip);
        assert_eq!(take(false, true, emitter_after_scatter), Take::Skip);
        let lights_only = |occluded| Via::LightsOnly { occluded };
        assert_eq!(take(false, false, lights_only(false)), Take::Skip);
        assert_eq!(take(false, false, lights_only(true)), Take::Skip);
        assert_eq!(take(true, false, lights_only(true)), Take::Weighted);
        assert_eq!(take(true, false, lights_only(false)), Take::Weighted);
        assert_eq!(take(false, true, lights_only(true)), Take::Weighted);
        assert_eq!(take(false, true, lights_only(false)), Take::Skip);
        assert_eq!(take(false, false, Via::Data), Take::Whole);
        assert_eq!(take(false, false, Via::Glow), Take::Weighted);
        assert_eq!(take(true, false, Via::Glow), Take::Weighted);
        assert_eq!(take(false, true, Via::Glow), Take::Skip);
    }
}
