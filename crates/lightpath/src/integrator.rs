//! Unidirectional path tracing with light sampling and MIS (power heuristic), Russian
//! roulette and depth limits, feeding the LPE automaton one event per vertex (DESIGN.md):
//! the camera event, the sampled lobe's event at each scattering vertex, every lobe of a
//! light sample through its own event then `L`, light hits through `L` with the
//! complementary weight, emission through `O`. A dead automaton state ends the path.

use crate::film::{Film, SampleAccumulator};
use crate::geometry::{Hit, Prim, Ray, Visibility};
use crate::light::{luminance, LightShape};
use crate::material::Shading;
use crate::sampling::{power_heuristic, Rng};
use crate::scene::{DataLobe, Scene};
use glam::{Vec2, Vec3A};
use lpe::{Prefix, ScatterClass, StateId};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// How a contribution reached the camera: decides what prefixed AOVs receive.
#[derive(Clone, Copy, Debug)]
enum Via {
    /// Emission found by a ray. `light_sampled`: light sampling covers it too (so it
    /// carries an MIS weight); `light_after_scatter`: a light reached after a scatter,
    /// which `unoccluded` and `shadows` AOVs take from light samples (or, behind a delta
    /// lobe, from the lights-only test) instead.
    Hit {
        light_sampled: bool,
        light_after_scatter: bool,
    },
    /// A light sample, with its shadow-ray result.
    LightSample { visible: bool },
    /// A delta lobe's direction tested against the lights alone (for `unoccluded` and
    /// `shadows` AOVs only), and whether the real ray was blocked before the light.
    LightsOnly { occluded: bool },
    /// A user (data) lobe.
    Data,
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
    ];
    const COUNT: usize = 9;

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
        }
    }
}

/// What a rule takes of a contribution.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
enum Take {
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
fn take(unoccluded: bool, shadows: bool, via: Via) -> Take {
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
        Via::LightSample { visible } => {
            if shadows {
                if visible {
                    Take::Skip
                } else {
                    Take::Whole
                }
            } else if unoccluded {
                Take::Whole
            } else if visible {
                Take::Weighted
            } else {
                Take::Skip
            }
        }
        Via::LightsOnly { occluded } => {
            if unoccluded || (shadows && occluded) {
                Take::Whole
            } else {
                Take::Skip
            }
        }
        Via::Data => Take::Whole,
    }
}

/// Per-rule routing flags, unpacked from the prefixes for the hot loop.
#[derive(Clone, Copy, Debug, Default)]
struct Route {
    /// What the rule takes of a contribution, by `Via::index`, outside holdouts (row 0)
    /// and inside (row 1): a lookup instead of the prefix logic per rule.
    take: [[Take; Via::COUNT]; 2],
    nothruput: bool,
    overwrite: bool,
    noclamp: bool,
    noinfinitecheck: bool,
    /// First part of this AOV's light-group split, or `u32::MAX`.
    split_base: u32,
    /// Number of parts of the split (light groups + the default part).
    split_parts: u32,
}

#[derive(Clone, Debug, Default)]
pub struct RenderStats {
    pub samples: u64,
    pub rays: u64,
    /// Contributions dropped by the NaN/Inf filter.
    pub nonfinite: u64,
    pub seconds: f64,
}

/// Options of one render call.
#[derive(Clone, Debug)]
pub struct RenderOptions {
    /// Samples per pixel to take, starting at sample index `first_sample`.
    pub spp: u32,
    pub first_sample: u32,
    pub progress: bool,
}

struct Tracer<'a> {
    scene: &'a Scene,
    routes: Vec<Route>,
    /// Split part of glowing objects and of lights without a group.
    default_part: u32,
}

struct PathCounters {
    rays: u64,
    nonfinite: u64,
    holdout: bool,
}

/// Where a path is when a ray finds a light.
struct Seen {
    state: StateId,
    throughput: Vec3A,
    depth: u32,
    prev_pdf: f32,
    prev_delta: bool,
}

/// What one contribution carries besides its value.
#[derive(Clone, Copy)]
struct Origin {
    via: Via,
    /// Scattering events before the light (for direct/indirect clamping).
    scatters: u32,
    /// The light-group part it belongs to in split AOVs.
    part: u32,
}

impl<'a> Tracer<'a> {
    fn new(scene: &'a Scene) -> Tracer<'a> {
        let routes = scene
            .aovs
            .iter()
            .map(|a| Route {
                take: {
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
                    [row(false), row(true)]
                },
                nothruput: a.flags.contains(Prefix::NoThruput),
                overwrite: a.flags.contains(Prefix::Overwrite),
                noclamp: a.flags.contains(Prefix::NoClamp),
                noinfinitecheck: a.flags.contains(Prefix::NoInfiniteCheck),
                split_base: a.split_base.unwrap_or(u32::MAX),
                split_parts: scene.light_groups.len() as u32 + 1,
            })
            .collect();
        Tracer {
            scene,
            routes,
            default_part: scene.light_groups.len() as u32,
        }
    }

    /// Adds `throughput × local × weight` to every AOV whose rule accepts `state`.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    fn contribute(
        &self,
        acc: &mut SampleAccumulator,
        counters: &mut PathCounters,
        state: StateId,
        throughput: Vec3A,
        local: Vec3A,
        mis: f32,
        origin: Origin,
    ) {
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
        let takes = counters.holdout as usize;
        let case = origin.via.index();
        // The four values a rule can take: with or without the throughput, whole or
        // weighted.
        let full = throughput * local;
        let values = [[local, local * mis], [full, full * mis]];
        for rule in rules {
            let k = rule.0 as usize;
            let r = &self.routes[k];
            let take = r.take[takes][case];
            if take == Take::Skip {
                continue;
            }
            let mut v = values[!r.nothruput as usize][(take == Take::Weighted) as usize];
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
            acc.add(k, v, r.overwrite);
            if r.split_base != u32::MAX {
                if r.overwrite {
                    // The whole now holds only `v`, so its parts must too: clear the
                    // part an earlier contribution of another group went to.
                    for part in 0..r.split_parts {
                        if part != origin.part {
                            acc.add((r.split_base + part) as usize, Vec3A::ZERO, true);
                        }
                    }
                }
                acc.add((r.split_base + origin.part) as usize, v, r.overwrite);
            }
        }
        counters.nonfinite += dropped as u64;
    }

    /// Light `li` found by a ray with radiance `le`: an `O` event seen from the camera,
    /// else an `L` event weighted against light sampling (`light_pdf`: the solid-angle pdf
    /// light sampling would have had for this direction).
    fn light_seen(
        &self,
        acc: &mut SampleAccumulator,
        counters: &mut PathCounters,
        seen: &Seen,
        li: u32,
        le: Vec3A,
        light_pdf: impl FnOnce(&crate::light::Light) -> f32,
    ) {
        let scene = self.scene;
        let light = &scene.lights[li as usize];
        let (l_class, o_class) = scene.light_classes[li as usize];
        let part = scene.light_parts[li as usize];
        let (class, weight, origin) = if seen.depth == 0 {
            if !light.camera_visible {
                return;
            }
            let via = Via::Hit {
                light_sampled: false,
                light_after_scatter: false,
            };
            (
                o_class,
                1.0,
                Origin {
                    via,
                    scatters: 0,
                    part,
                },
            )
        } else {
            let w = if seen.prev_delta {
                1.0
            } else {
                power_heuristic(
                    seen.prev_pdf,
                    scene.light_select.pmf(li as usize) * light_pdf(light),
                )
            };
            let via = Via::Hit {
                light_sampled: !seen.prev_delta,
                light_after_scatter: true,
            };
            (
                l_class,
                w,
                Origin {
                    via,
                    scatters: seen.depth,
                    part,
                },
            )
        };
        let s = scene.automaton.step(seen.state, class);
        self.contribute(acc, counters, s, seen.throughput, le, weight, origin);
    }

    fn spawn(&self, hit: &Hit, dir: Vec3A, tmax: f32) -> Ray {
        let side = if dir.dot(hit.ng) >= 0.0 { 1.0 } else { -1.0 };
        Ray {
            origin: hit.p + hit.ng * (self.scene.epsilon * side),
            dir,
            tmax,
        }
    }

    /// The nearest light surface along `ray`, ignoring everything else: (light, t,
    /// normal). For `unoccluded` AOVs behind delta lobes.
    fn nearest_light(&self, ray: &Ray) -> Option<(usize, f32, Vec3A)> {
        let mut best: Option<(usize, f32, Vec3A)> = None;
        for (li, light) in self.scene.lights.iter().enumerate() {
            let tmax = best.map_or(f32::INFINITY, |b| b.1);
            match &light.shape {
                LightShape::Triangles { prims, .. } => {
                    for &i in prims {
                        let p = &self.scene.accel.prims()[i as usize];
                        let t = p.intersect(ray.origin, ray.dir, 0.0, tmax);
                        if t < best.map_or(f32::INFINITY, |b| b.1) {
                            if let Prim::Triangle { e1, e2, .. } = p {
                                best = Some((li, t, e1.cross(*e2).normalize()));
                            }
                        }
                    }
                }
                LightShape::Sphere { center, radius } => {
                    let sphere = Prim::Sphere {
                        center: *center,
                        radius: *radius,
                    };
                    let t = sphere.intersect(ray.origin, ray.dir, 0.0, tmax);
                    if t.is_finite() {
                        best = Some((li, t, (ray.origin + ray.dir * t - *center) / *radius));
                    }
                }
                _ => {}
            }
        }
        best
    }

    /// Traces one camera path; returns its alpha.
    fn trace(
        &self,
        mut ray: Ray,
        rng: &mut Rng,
        acc: &mut SampleAccumulator,
        counters: &mut PathCounters,
    ) -> f32 {
        let scene = self.scene;
        let a = &scene.automaton;
        let settings = &scene.settings;
        let mut state = a.step(a.start(), scene.camera_class);
        let mut throughput = Vec3A::ONE;
        let mut eta_scale = 1.0f32;
        let (mut prev_p, mut prev_pdf, mut prev_delta) = (ray.origin, 0.0f32, true);
        let mut prev_object = u32::MAX;
        let (mut diffuse, mut specular) = (0u32, 0u32);
        let mut alpha = 0.0;
        let mut depth = 0u32;
        counters.holdout = false;
        let lit = |object: u32, light: u32| {
            object == u32::MAX || !scene.objects[object as usize].unlit_by.contains(&light)
        };
        loop {
            counters.rays += 1;
            let mask = if depth == 0 {
                Visibility::CAMERA
            } else {
                Visibility::INDIRECT
            };
            // Where the path is, should the ray find a light.
            let seen = Seen {
                state,
                throughput,
                depth,
                prev_pdf,
                prev_delta,
            };
            let Some(hit) = scene.accel.intersect(&ray, 0.0, mask) else {
                for &li in &scene.escape_lights {
                    let le = scene.lights[li as usize].emitted_escaped(ray.dir);
                    if le != Vec3A::ZERO && lit(prev_object, li) {
                        self.light_seen(acc, counters, &seen, li, le, |light| {
                            light.pdf_hit(prev_p, ray.dir, f32::INFINITY, Vec3A::ZERO)
                        });
                    }
                }
                break;
            };
            let obj = &scene.objects[hit.object as usize];
            if depth == 0 {
                alpha = if obj.holdout { 0.0 } else { 1.0 };
            }
            counters.holdout |= obj.holdout;

            // Emission arriving along the ray.
            if let Some(li) = obj.light {
                let light = &scene.lights[li as usize];
                let le = light.emitted_at(hit.ng, ray.dir);
                if le != Vec3A::ZERO && lit(prev_object, li) {
                    self.light_seen(acc, counters, &seen, li, le, |light| {
                        light.pdf_hit(prev_p, ray.dir, hit.t, hit.ng)
                    });
                }
            } else if let Some(glow) = obj.glow_class {
                let s = a.step(state, glow);
                let via = Via::Hit {
                    light_sampled: false,
                    light_after_scatter: false,
                };
                let origin = Origin {
                    via,
                    scatters: depth,
                    part: self.default_part,
                };
                self.contribute(acc, counters, s, throughput, obj.emission, 1.0, origin);
            }

            // Mitsuba's convention: `max_depth` counts segments; scattering here adds one.
            if depth + 1 >= settings.max_depth {
                break;
            }
            let Some(material) = obj.material.map(|m| &scene.materials[m as usize]) else {
                break;
            };
            let bsdf = &material.bsdf;
            let sh = Shading::new(bsdf, hit.ns, hit.ng, -ray.dir);
            if sh.wo.z == 0.0 {
                break;
            }

            // Data lobes, each as if lit by a unit light (LPE.md §1).
            let data_lobes = if scene.data_live[a.state_index(state)] {
                &obj.data_lobes[..]
            } else {
                &[]
            };
            for &(kind, class) in data_lobes {
                let s1 = a.step(state, class);
                if a.is_dead(s1) {
                    continue;
                }
                let s2 = a.step(s1, scene.data_light_class);
                if a.accepting(s2).is_empty() {
                    continue;
                }
                let value = match kind {
                    DataLobe::Albedo => bsdf.albedo(),
                    DataLobe::Position => hit.p,
                    DataLobe::Normal => sh.frame.n,
                    DataLobe::UserColor => material.user_color.unwrap_or(Vec3A::ZERO),
                };
                let origin = Origin {
                    via: Via::Data,
                    scatters: depth + 1,
                    part: self.default_part,
                };
                self.contribute(acc, counters, s2, throughput, value, 1.0, origin);
            }

            // Light sampling: every non-delta lobe through its own event, then `L`.
            let lobes = bsdf.lobes();
            let u_light = rng.next_f32();
            let u_point = rng.next_2d();
            if !scene.lights.is_empty() && lobes.iter().any(|l| !l.delta) {
                let (li, select_pmf, _) = scene.light_select.sample(u_light);
                let light = &scene.lights[li];
                let sample = if lit(hit.object, li as u32) {
                    light.sample(hit.p, u_point, scene.accel.prims())
                } else {
                    None
                };
                if let Some(ls) = sample {
                    let wi = sh.frame.to_local(ls.wi);
                    let l_class = scene.light_classes[li].0;
                    let part = scene.light_parts[li];
                    let light_pdf = select_pmf * ls.pdf;
                    let mut visible: Option<bool> = None;
                    for (k, tag) in lobes.iter().enumerate() {
                        if tag.delta {
                            continue;
                        }
                        let s_lobe = a.step(state, obj.lobe_classes[k]);
                        if a.is_dead(s_lobe) {
                            continue;
                        }
                        let s_light = a.step(s_lobe, l_class);
                        if a.accepting(s_light).is_empty() {
                            continue;
                        }
                        let (f, lobe_pdf) = bsdf.eval_lobe(k, &sh, wi);
                        if f == Vec3A::ZERO {
                            continue;
                        }
                        let w = if ls.delta {
                            1.0
                        } else {
                            power_heuristic(light_pdf, lobe_pdf)
                        };
                        let vis = *visible.get_or_insert_with(|| {
                            counters.rays += 1;
                            let tmax = if ls.dist.is_finite() {
                                ls.dist - 2.0 * scene.epsilon
                            } else {
                                f32::INFINITY
                            };
                            let ignore = light.object.unwrap_or(u32::MAX);
                            tmax <= 0.0
                                || !scene.accel.occluded(
                                    &self.spawn(&hit, ls.wi, tmax),
                                    0.0,
                                    ignore,
                                )
                        });
                        let origin = Origin {
                            via: Via::LightSample { visible: vis },
                            scatters: depth + 1,
                            part,
                        };
                        self.contribute(
                            acc,
                            counters,
                            s_light,
                            throughput,
                            f * ls.radiance / light_pdf,
                            w,
                            origin,
                        );
                    }
                }
            }

            // Continue the path through one sampled lobe.
            let u_lobe = rng.next_f32();
            let u_dir = rng.next_2d();
            let Some(bs) = bsdf.sample(&sh, u_lobe, u_dir) else {
                break;
            };
            let tag = lobes[bs.lobe];
            match tag.scatter.class {
                ScatterClass::Diffuse => {
                    diffuse += 1;
                    if diffuse > settings.max_diffuse_depth {
                        break;
                    }
                }
                _ => {
                    specular += 1;
                    if specular > settings.max_specular_depth {
                        break;
                    }
                }
            }
            state = a.step(state, obj.lobe_classes[bs.lobe]);
            if a.is_dead(state) {
                break;
            }
            throughput *= bs.weight;
            eta_scale *= bs.eta;
            prev_p = hit.p;
            prev_pdf = bs.pdf;
            prev_delta = bs.delta;
            prev_object = hit.object;
            ray = self.spawn(&hit, bs.wi, f32::INFINITY);
            depth += 1;

            // Behind a delta lobe, `unoccluded` AOVs see the lights as if nothing else
            // were there (LPE.md §6).
            if bs.delta && scene.any_unoccluded {
                if let Some((li, t, n)) = self.nearest_light(&ray) {
                    let light = &scene.lights[li];
                    let le = light.emitted_at(n, ray.dir);
                    if le != Vec3A::ZERO && lit(hit.object, li as u32) {
                        counters.rays += 1;
                        let blocked = Ray {
                            tmax: t - 2.0 * scene.epsilon,
                            ..ray
                        };
                        let occluded =
                            scene
                                .accel
                                .occluded(&blocked, 0.0, light.object.unwrap_or(u32::MAX));
                        let s = a.step(state, scene.light_classes[li].0);
                        let origin = Origin {
                            via: Via::LightsOnly { occluded },
                            scatters: depth,
                            part: scene.light_parts[li],
                        };
                        self.contribute(acc, counters, s, throughput, le, 1.0, origin);
                    }
                }
            }

            // Russian roulette as Mitsuba does it: from `rr_depth` on, continue with
            // probability max(throughput)·η², at most 0.95.
            let t_max = throughput.max_element();
            if t_max <= 0.0 || !t_max.is_finite() {
                break;
            }
            if depth >= settings.rr_depth {
                let q = (t_max * eta_scale * eta_scale).min(0.95);
                if rng.next_f32() >= q {
                    break;
                }
                throughput /= q;
            }
        }
        alpha
    }
}

/// Size of the band of rows rendered between two moves into the film's planes: large
/// enough that threads rarely wait for each other at a band's end, small next to a film.
const BAND_BYTES: usize = 16 << 20;

/// Renders the scene into a film holding every AOV.
pub fn render(scene: &Scene, options: &RenderOptions) -> (Film, RenderStats) {
    let start = std::time::Instant::now();
    let cam = &scene.camera;
    let (w, h) = (cam.width, cam.height);
    let stride = Film::stride_for(scene.aovs.len());
    let tracer = Tracer::new(scene);
    let rays = AtomicU64::new(0);
    let nonfinite = AtomicU64::new(0);
    let bar = if options.progress {
        let bar = indicatif::ProgressBar::new(h as u64);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} rendering [{bar:40}] {pos}/{len} rows {elapsed_precise} (eta {eta})",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
            .progress_chars("=> "),
        );
        bar
    } else {
        indicatif::ProgressBar::hidden()
    };
    // Rows are rendered a band at a time into one reused interleaved buffer (a sample
    // writes one contiguous run), and each band is moved into the film's planes: the
    // peak memory is the film plus one band, with no allocation churn.
    let row_len = stride * w as usize;
    let band_rows = (BAND_BYTES / (4 * row_len)).clamp(8, h.max(1) as usize);
    let mut band = vec![0.0f32; band_rows * row_len];
    let mut film = Film::new(w, h, scene.aovs.len(), options.spp);
    for first_row in (0..h as usize).step_by(band_rows) {
        let rows_here = band_rows.min(h as usize - first_row);
        let band = &mut band[..rows_here * row_len];
        band.fill(0.0);
        band.par_chunks_mut(row_len).enumerate().for_each_init(
            || SampleAccumulator::new(scene.aovs.len()),
            |acc, (i, row)| {
                let y = (first_row + i) as u32;
                let mut counters = PathCounters {
                    rays: 0,
                    nonfinite: 0,
                    holdout: false,
                };
                for x in 0..w {
                    let pixel = &mut row[x as usize * stride..(x as usize + 1) * stride];
                    let index = y as u64 * w as u64 + x as u64;
                    for s in options.first_sample..options.first_sample + options.spp {
                        let mut rng = Rng::for_sample(scene.settings.seed, index, s as u64);
                        let offset = scene.filter.offset(rng.next_2d());
                        let film_pos = Vec2::new(x as f32 + 0.5, y as f32 + 0.5) + offset;
                        let ray = cam.ray(film_pos, rng.next_2d());
                        let alpha = tracer.trace(ray, &mut rng, acc, &mut counters);
                        acc.flush(pixel);
                        pixel[stride - 1] += alpha;
                    }
                }
                rays.fetch_add(counters.rays, Ordering::Relaxed);
                nonfinite.fetch_add(counters.nonfinite, Ordering::Relaxed);
                bar.inc(1);
            },
        );
        film.store_rows(first_row, band);
    }
    bar.finish_and_clear();
    let stats = RenderStats {
        samples: w as u64 * h as u64 * options.spp as u64,
        rays: rays.into_inner(),
        nonfinite: nonfinite.into_inner(),
        seconds: start.elapsed().as_secs_f64(),
    };
    (film, stats)
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

    /// Spot checks of the prefix rules (docs/lpe.md): plain AOVs take visible light
    /// samples weighted, `shadows` only blocked ones, `unoccluded` all of them whole.
    #[test]
    fn prefixes_take_what_the_docs_say() {
        let sample = |visible| Via::LightSample { visible };
        assert_eq!(take(false, false, sample(true)), Take::Weighted);
        assert_eq!(take(false, false, sample(false)), Take::Skip);
        assert_eq!(take(false, true, sample(false)), Take::Whole);
        assert_eq!(take(false, true, sample(true)), Take::Skip);
        assert_eq!(take(true, false, sample(false)), Take::Whole);
        let emitter_after_scatter = Via::Hit {
            light_sampled: true,
            light_after_scatter: true,
        };
        assert_eq!(take(false, false, emitter_after_scatter), Take::Weighted);
        assert_eq!(take(true, false, emitter_after_scatter), Take::Skip);
        assert_eq!(take(false, false, Via::Data), Take::Whole);
    }
}
