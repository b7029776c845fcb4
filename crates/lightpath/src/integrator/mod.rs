//! Unidirectional path tracing with light sampling and MIS (power heuristic), Russian
//! roulette and depth limits, feeding the LPE automaton one event per vertex (docs/architecture.md):
//! the camera event, the sampled lobe's event at each scattering vertex, every lobe of a
//! light sample through its own event then `L`, light hits through `L` with the
//! complementary weight, emission through `O`. A dead automaton state ends the path.
//!
//! `path.rs` holds the named steps of one path, `direct.rs` light sampling and MIS,
//! `routing.rs` what each AOV takes of a contribution; this module runs the render loop.

pub mod adaptive;
pub mod connect;
mod direct;
pub mod glints;
mod guided;
mod light_choice;
mod path;
mod pixel;
mod routing;
mod shading;
pub mod subsurface;
mod volume;

use crate::film::mattes::{MatteTable, PixelMatte};
use crate::film::splats::Splats;
use crate::film::{Film, Mattes, PixelWindow, SampleAccumulator};
use crate::geometry::{Hit, Ray};
use crate::progress::{Progress, Silent};
use crate::scene::Scene;
use adaptive::{Moments, Pilot, Rule};
use glam::Vec3A;
use pixel::PixelJob;
use rayon::prelude::*;
use routing::Route;
use std::ops::Range;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

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
}

/// What a render needs besides the path: the scene and each AOV's routing.
struct Tracer<'a> {
    scene: &'a Scene,
    routes: Vec<Route>,
    /// Split part of glowing objects and of lights without a group.
    default_part: u32,
    /// Per light, what flights through media aim equiangular distances at (volume.rs);
    /// empty: none.
    aims: Vec<Option<volume::Aim>>,
    /// The SD-tree paths sample from (guided.rs), if the render guides.
    guide: Option<&'a crate::guiding::SdTree>,
    /// Whether paths record into the guide (training passes).
    learn: bool,
    /// The seed of the sample numbers (the render's; a training pass's own).
    seed: u64,
    /// Whether paths draw numbers from their own stream (`PathState::rng`): through
    /// media, or to resample light candidates. Other scenes skip seeding it.
    path_rng: bool,
    /// Boxes around the declared triangle lights, for the lights-only test (direct.rs).
    light_boxes: Vec<Option<(Vec3A, Vec3A)>>,
    /// Bidirectional path tracing's light subpaths, if the render traces them (connect.rs).
    connect: Option<connect::Connect>,
    /// Light tracing's film, if the render joins light subpaths to the camera
    /// (connect/light_tracing.rs).
    splats: Option<&'a Splats>,
    /// The lights glint sampling aims at (small distant and sphere lights, glints.rs);
    /// empty: none.
    glint_lights: Vec<u32>,
}

/// Where a worker's paths put what they find: the sample's AOV values and counters.
struct Sink<'b> {
    acc: &'b mut SampleAccumulator,
    rays: u64,
    nonfinite: u64,
    /// Whether the current path has touched a holdout (routes to `holdouts` AOVs).
    holdout: bool,
    /// The object the camera ray hit, unless it is a holdout (Cryptomatte).
    first_object: Option<u32>,
    /// The current path's vertices recorded for training the guide (guided.rs).
    record: guided::PathRecord,
    /// The Sobol sampler's pixel state, made over for each pixel (`SobolPixel::reset`):
    /// a new one for every pixel was ~2 % of the indirect box's instructions (clearing
    /// and copying its ~2.4 KB).
    sobol: Option<Box<crate::sampler::SobolPixel>>,
    /// The current sample's light subpath (connect.rs), its buffers reused.
    light_path: connect::LightPath,
    /// What one join of a light vertex to the camera adds to one pixel, before it goes
    /// to the splat film (connect/light_tracing.rs); sized on first use.
    splat_acc: SampleAccumulator,
    /// The current camera sample's film position, where its pixel samples glints
    /// (glints.rs), and that pixel's chains.
    glint: Option<glints::GlintSample>,
    glint_pixel: glints::GlintPixel,
}

impl<'b> Sink<'b> {
    /// A sink adding to `acc`, its counters at zero.
    fn new(acc: &'b mut SampleAccumulator) -> Sink<'b> {
        Sink {
            acc,
            rays: 0,
            nonfinite: 0,
            holdout: false,
            first_object: None,
            record: guided::PathRecord::default(),
            sobol: None,
            light_path: connect::LightPath::default(),
            splat_acc: SampleAccumulator::new(0),
            glint: None,
            glint_pixel: glints::GlintPixel::default(),
        }
    }
}

impl<'a> Tracer<'a> {
    fn new(scene: &'a Scene) -> Tracer<'a> {
        Tracer {
            scene,
            routes: scene
                .aovs
                .iter()
                .map(|a| Route::for_aov(a, scene))
                .collect(),
            default_part: scene.light_groups.len() as u32,
            aims: volume::aims(scene),
            guide: None,
            learn: false,
            seed: scene.settings.seed,
            path_rng: scene.has_media
                || (scene.settings.light_candidates > 1 && scene.lights.len() > 1),
            light_boxes: direct::light_boxes(scene),
            connect: None,
            splats: None,
            glint_lights: glints::glint_lights(scene),
        }
    }

    fn spawn(&self, hit: &Hit, dir: Vec3A, tmax: f32) -> Ray {
        let side = if dir.dot(hit.ng) >= 0.0 { 1.0 } else { -1.0 };
        Ray {
            origin: hit.p + hit.ng * (self.scene.epsilon * side),
            dir,
            tmax,
        }
    }
}

/// Size of the band of rows rendered between two moves into the film's planes: large
/// enough that threads rarely wait for each other at a band's end, small next to a film.
const BAND_BYTES: usize = 16 << 20;

/// Renders the scene into a film holding every AOV, reporting nothing.
pub fn render(scene: &Scene, options: &RenderOptions) -> (Film, RenderStats) {
    render_with_progress(scene, options, &Silent)
}

/// Renders the scene into a film holding every AOV, reporting each finished row.
pub fn render_with_progress(
    scene: &Scene,
    options: &RenderOptions,
    progress: &dyn Progress,
) -> (Film, RenderStats) {
    render_frame(scene, options, &FrameRequest::whole(scene), progress)
}

/// What of the frame a render produces besides the AOVs of the whole frame: a window of
/// it (`--crop`) and Cryptomatte layers.
#[derive(Clone, Debug)]
pub struct FrameRequest {
    pub window: PixelWindow,
    pub mattes: Option<MatteTable>,
}

impl FrameRequest {
    /// The whole frame, no Cryptomatte.
    pub fn whole(scene: &Scene) -> FrameRequest {
        FrameRequest {
            window: PixelWindow::full(scene.camera.width, scene.camera.height),
            mattes: None,
        }
    }
}

/// Renders the pixels of `request.window` (every pixel with the sample numbers it has in
/// the whole frame), and the Cryptomatte layers if asked.
pub fn render_frame(
    scene: &Scene,
    options: &RenderOptions,
    request: &FrameRequest,
    progress: &dyn Progress,
) -> (Film, RenderStats) {
    let done = render_resumable(scene, options, request, progress, Resumable::default());
    (done.film, done.stats)
}

/// How a render can be stopped and continued (`job.rs` drives it from signals and
/// checkpoints). The default renders every row, as [`render_frame`].
#[derive(Default)]
pub struct Resumable<'a> {
    /// A film whose rows marked in `rows_done` are finished (a checkpoint's): those rows
    /// are kept as they are, the others rendered. Not with Cryptomatte layers (a
    /// checkpoint does not hold them; `job.rs` refuses the combination).
    pub film: Option<Film>,
    pub rows_done: Vec<bool>,
    /// An adaptive render's pilot pass (a checkpoint's): once it is complete, `rows_done`
    /// are rows of the second pass. An adaptive render resumed without it starts afresh.
    pub pilot: Option<Pilot>,
    /// Light tracing's splat sums of the finished rows (a checkpoint's; film/splats.rs),
    /// which `film` does not hold. A render that traces light to the camera resumed
    /// without them, or one that does not resumed with them, starts afresh.
    pub splats: Option<Vec<i64>>,
    /// When set, rows not yet started are skipped: the render ends with the rows in
    /// flight (a row is never left half-rendered).
    pub cancel: Option<&'a AtomicBool>,
    /// Called after each band with what the render holds so far (checkpoints).
    pub after_band: Option<AfterBand<'a>>,
    /// At most this many rows per band (at least 8), so `after_band` comes often enough
    /// on a small film; `None`: bands as large as `BAND_BYTES` allows.
    pub max_band_rows: Option<usize>,
}

/// What a render holds between two bands: enough to write a checkpoint.
pub struct Snapshot<'s> {
    pub film: &'s Film,
    /// Rows finished in the current pass.
    pub rows_done: &'s [bool],
    /// An adaptive render's pilot.
    pub pilot: Option<&'s Pilot>,
    /// Light tracing's splats of the finished rows, which `film` does not hold yet.
    pub splats: Option<&'s Splats>,
}

/// What `Resumable::after_band` is given.
pub type AfterBand<'a> = &'a mut dyn FnMut(&Snapshot);

/// A render that may have stopped early.
pub struct Rendered {
    pub film: Film,
    pub stats: RenderStats,
    /// One entry per row of the window: finished in the current pass? All true unless the
    /// render was cancelled.
    pub rows_done: Vec<bool>,
    /// An adaptive render's pilot (complete unless it was cancelled during the pilot).
    pub pilot: Option<Pilot>,
    /// Light tracing's splats, when the render did not finish: `film` does not hold
    /// them (a checkpoint keeps them apart; `Splats::add_to` for a picture). A finished
    /// film holds its splats.
    pub splats: Option<Splats>,
}

impl Rendered {
    /// Whether every pixel has all its samples.
    pub fn finished(&self) -> bool {
        self.pilot.as_ref().is_none_or(|p| p.complete) && self.rows_done.iter().all(|d| *d)
    }
}

/// [`render_frame`] of the rows `resume` does not already hold, stopping early if its
/// `cancel` flag is set. Each row's sums start from zero (or from its pilot samples) and
/// add its samples in order, so a row is the same whichever run renders it. An adaptive
/// render makes two passes over the window (`adaptive.rs`).
pub fn render_resumable(
    scene: &Scene,
    options: &RenderOptions,
    request: &FrameRequest,
    progress: &dyn Progress,
    resume: Resumable,
) -> Rendered {
    render_passes(
        scene,
        options,
        request,
        progress,
        resume,
        adaptive::NEIGHBOUR_RADIUS,
    )
}

/// [`render_resumable`] with the adaptive neighbourhood's radius as a parameter (tests
/// compare it with 0, each pixel deciding alone).
fn render_passes(
    scene: &Scene,
    options: &RenderOptions,
    request: &FrameRequest,
    progress: &dyn Progress,
    resume: Resumable,
    radius: u32,
) -> Rendered {
    let Resumable {
        film: mut resumed,
        rows_done: mut resumed_rows,
        pilot,
        splats: resumed_splats,
        cancel,
        mut after_band,
        max_band_rows,
    } = resume;
    let start = std::time::Instant::now();
    let win = request.window;
    debug_assert!(win.check(scene.camera.width, scene.camera.height).is_ok());
    let (w, h) = (win.width() as usize, win.height() as usize);
    let adaptive = scene.settings.noise_threshold > 0.0;
    let mut pilot = adaptive.then(|| match pilot.filter(|p| p.sums.len() == w * h) {
        Some(p) => p,
        None => {
            // Rows finished without their pilot's moments cannot be continued.
            (resumed, resumed_rows) = (None, Vec::new());
            Pilot::new(w * h)
        }
    });
    // Path guiding trains first, over the whole frame (guided.rs): every window, part
    // and resumed run of a frame samples from the same tree.
    let guide = guided::train(scene);
    let mut tracer = Tracer::new(scene);
    tracer.guide = guide.as_ref();
    tracer.connect = connect::Connect::new(scene, tracer.guide.is_some());
    // Light tracing's splats (connect/light_tracing.rs).
    let splats = (tracer.connect.is_some() && connect::traces_to_camera(scene))
        .then(|| Splats::new(win, scene.aovs.len(), &scene.variance_aovs));
    // Finished rows carry on only with the splats they made.
    let splats_resumed = match (&splats, &resumed_splats) {
        (Some(s), Some(units)) => s.set_units(units),
        (None, None) => true,
        _ => false,
    };
    if !splats_resumed {
        (resumed, resumed_rows) = (None, Vec::new());
    }
    tracer.splats = splats.as_ref();
    let frame = FrameRender {
        tracer,
        options,
        rule: Rule::new(&scene.settings, options.spp),
        window: win,
        stride: Film::stride_with(scene.aovs.len(), scene.variance_aovs.len()),
        table: request.mattes.as_ref(),
        done: (0..h)
            .map(|y| AtomicBool::new(resumed_rows.get(y).copied().unwrap_or(false)))
            .collect(),
        cancel,
        progress,
        counters: Counters::default(),
    };
    let pilot_rows = match &pilot {
        Some(p) if p.complete => h,
        _ => 0,
    };
    let passes = if adaptive { 2 } else { 1 };
    progress.start((h * passes) as u64, (w * h) as u64 * options.spp as u64);
    progress.advance(
        (pilot_rows + frame.rows_done().iter().filter(|d| **d).count()) as u64,
        0,
    );
    let mut film = starting_film(scene, options, win, resumed);
    let mut bands = Bands::new(
        &frame,
        band_rows(frame.stride * w, h, max_band_rows, progress),
    );
    let mut output = PassOutput {
        film: &mut film,
        bands: &mut bands,
        after_band: &mut after_band,
    };
    match &mut pilot {
        None => frame.run_pass(&mut Pass::All, &mut output),
        Some(p) => frame.run_adaptive(p, &mut output, radius),
    }
    if let Some(t) = frame.table {
        film.mattes = Some(Mattes {
            table: t.clone(),
            planes: std::mem::take(&mut bands.matte_planes),
        });
    }
    progress.finish();
    let rows_done = frame.rows_done();
    let c = frame.counters;
    let stats = RenderStats {
        samples: c.samples.into_inner(),
        rays: c.rays.into_inner(),
        nonfinite: c.nonfinite.into_inner(),
        seconds: start.elapsed().as_secs_f64(),
    };
    let finished = pilot.as_ref().is_none_or(|p| p.complete) && rows_done.iter().all(|d| *d);
    let splats = match splats {
        Some(s) if finished => {
            s.add_to(&mut film);
            None
        }
        unfinished => unfinished,
    };
    Rendered {
        film,
        stats,
        rows_done,
        pilot,
        splats,
    }
}

/// Rows per band: as many as `BAND_BYTES` holds, at least 8 (or the whole window when it
/// is shorter), at most what the caller or a live preview asks (pixels do not depend on
/// it).
fn band_rows(
    row_len: usize,
    height: usize,
    max_band_rows: Option<usize>,
    progress: &dyn Progress,
) -> usize {
    let rows = (BAND_BYTES / (4 * row_len))
        .min(max_band_rows.unwrap_or(usize::MAX))
        .max(8)
        .min(height.max(1));
    progress.band_rows().map_or(rows, |r| r.clamp(1, rows))
}

/// The film a render adds to: a resumed one of the same shape, or an empty one (with
/// per-pixel counts under adaptive sampling).
fn starting_film(
    scene: &Scene,
    options: &RenderOptions,
    win: PixelWindow,
    resumed: Option<Film>,
) -> Film {
    let (w, h) = (win.width(), win.height());
    let frame = [scene.camera.width, scene.camera.height];
    let mut film = resumed
        .filter(|f| {
            (f.width, f.height, f.aovs, &f.squared)
                == (w, h, scene.aovs.len(), &scene.variance_aovs)
        })
        .map(|f| Film {
            window: win,
            frame,
            ..f
        })
        .unwrap_or_else(|| {
            Film::for_window(win, frame, scene.aovs.len(), options.spp)
                .summing_squares(scene.variance_aovs.clone())
        });
    if scene.settings.noise_threshold > 0.0 && film.sample_counts.is_none() {
        film.sample_counts = Some(vec![0; w as usize * h as usize]);
    }
    film
}

/// One pass over the window's rows.
enum Pass<'p> {
    /// Every sample of the range (a render that is not adaptive).
    All,
    /// Adaptive sampling's pilot: `min_spp` samples a pixel, their moments kept.
    Pilot(&'p mut Pilot),
    /// Adaptive sampling's second pass: each pixel on from its pilot samples to its
    /// target (one per pixel of the window).
    Rest {
        pilot: &'p Pilot,
        targets: &'p [u32],
    },
}

impl Pass<'_> {
    fn pilot(&self) -> Option<&Pilot> {
        match self {
            Pass::All => None,
            Pass::Pilot(p) => Some(p),
            Pass::Rest { pilot, .. } => Some(pilot),
        }
    }

    /// What the pixels of rows `rows` (a band, `w` pixels a row) do, row by row, with
    /// the band's per-pixel `counts` (empty unless adaptive).
    fn rows<'r>(
        &'r mut self,
        rows: Range<usize>,
        w: usize,
        counts: &'r mut [u32],
    ) -> Vec<RowPass<'r>> {
        let pixels = rows.start * w..rows.end * w;
        match self {
            Pass::All => rows.map(|_| RowPass::All).collect(),
            Pass::Pilot(p) => p.sums[pixels]
                .chunks_mut(w)
                .zip(counts.chunks_mut(w))
                .map(|(sums, counts)| RowPass::Pilot { sums, counts })
                .collect(),
            Pass::Rest { targets, .. } => targets[pixels]
                .chunks(w)
                .zip(counts.chunks_mut(w))
                .map(|(targets, counts)| RowPass::Rest { targets, counts })
                .collect(),
        }
    }
}

/// What the pixels of one row do in a pass (see [`Pass`]), with the row's slices of the
/// pilot's sums, the targets and the sample counts.
enum RowPass<'r> {
    All,
    Pilot {
        sums: &'r mut [[f64; 2]],
        counts: &'r mut [u32],
    },
    Rest {
        targets: &'r [u32],
        counts: &'r mut [u32],
    },
}

/// Where a pass puts its rows, and whom it shows them to.
struct PassOutput<'o, 'a> {
    film: &'o mut Film,
    bands: &'o mut Bands,
    after_band: &'o mut Option<AfterBand<'a>>,
}

/// The buffers a pass reuses band after band, and the Cryptomatte planes.
struct Bands {
    rows: usize,
    /// Interleaved sums of a band (a sample writes one contiguous run).
    sums: Vec<f32>,
    /// Per-pixel sample counts of a band (adaptive sampling; else empty).
    counts: Vec<u32>,
    /// Cryptomatte values of a band beside the AOVs' (one dummy value per row without).
    mattes: Vec<f32>,
    matte_row: usize,
    matte_planes: Vec<Vec<f32>>,
}

impl Bands {
    fn new(frame: &FrameRender, rows: usize) -> Bands {
        let (w, h) = (
            frame.window.width() as usize,
            frame.window.height() as usize,
        );
        let adaptive = frame.tracer.scene.settings.noise_threshold > 0.0;
        let matte_stride = frame.table.map_or(0, |t| t.stride());
        let matte_row = (matte_stride * w).max(1);
        Bands {
            rows,
            sums: vec![0.0; rows * frame.stride * w],
            counts: vec![0; if adaptive { rows * w } else { 0 }],
            mattes: vec![0.0; rows * matte_row],
            matte_row,
            matte_planes: (0..matte_stride).map(|_| vec![0.0; w * h]).collect(),
        }
    }

    /// Copies the band's Cryptomatte values between the band and the planes: into the
    /// planes when `store`, else back into the band.
    fn move_mattes(&mut self, rows: Range<usize>, w: usize, store: bool) {
        let stride = self.matte_planes.len();
        let band = &mut self.mattes[..rows.len() * self.matte_row];
        for (c, plane) in self.matte_planes.iter_mut().enumerate() {
            let plane = &mut plane[rows.start * w..rows.end * w];
            for (d, px) in plane.iter_mut().zip(band.chunks_exact_mut(stride)) {
                if store {
                    *d = px[c];
                } else {
                    px[c] = *d;
                }
            }
        }
    }
}

/// What every row of one render shares: the tracer, the window, which rows are done,
/// and the counters the rows add to.
struct FrameRender<'a> {
    tracer: Tracer<'a>,
    options: &'a RenderOptions,
    /// Adaptive sampling's numbers (unused when it is off).
    rule: Rule,
    window: PixelWindow,
    /// Values per pixel in a row (Film::stride_with).
    stride: usize,
    table: Option<&'a MatteTable>,
    done: Vec<AtomicBool>,
    cancel: Option<&'a AtomicBool>,
    progress: &'a dyn Progress,
    counters: Counters,
}

#[derive(Default)]
struct Counters {
    samples: AtomicU64,
    rays: AtomicU64,
    nonfinite: AtomicU64,
}

impl FrameRender<'_> {
    fn stopped(&self) -> bool {
        self.cancel.is_some_and(|c| c.load(Ordering::Relaxed))
    }

    fn rows_done(&self) -> Vec<bool> {
        self.done
            .iter()
            .map(|d| d.load(Ordering::Relaxed))
            .collect()
    }

    /// An adaptive render's passes still to do: the pilot's rows not yet done, then (if
    /// not cancelled) the second pass from the targets the pilot gives.
    fn run_adaptive(&self, pilot: &mut Pilot, output: &mut PassOutput, radius: u32) {
        if !pilot.complete {
            self.run_pass(&mut Pass::Pilot(&mut *pilot), output);
            if self.rows_done().iter().all(|d| *d) {
                pilot.complete = true;
                self.done
                    .iter()
                    .for_each(|d| d.store(false, Ordering::Relaxed));
            }
        }
        if pilot.complete && !self.stopped() {
            let targets = self.targets(pilot, radius);
            let mut pass = Pass::Rest {
                pilot,
                targets: &targets,
            };
            self.run_pass(&mut pass, output);
        }
    }

    /// Renders the rows of `pass` not yet done, a band at a time: each band is moved into
    /// the film's planes, shown to the progress reporter and to `after_band`. The peak
    /// memory is the film plus one band, with no allocation churn.
    fn run_pass(&self, pass: &mut Pass, output: &mut PassOutput) {
        let PassOutput {
            film,
            bands,
            after_band,
        } = output;
        let w = self.window.width() as usize;
        let h = self.window.height() as usize;
        let row_len = self.stride * w;
        let continues = matches!(pass, Pass::Rest { .. });
        for first_row in (0..h).step_by(bands.rows) {
            let rows = first_row..first_row + bands.rows.min(h - first_row);
            let band_done = &self.done[rows.clone()];
            if self.stopped() || band_done.iter().all(|d| d.load(Ordering::Relaxed)) {
                continue;
            }
            if continues {
                bands.move_mattes(rows.clone(), w, false);
            }
            let band = &mut bands.sums[..rows.len() * row_len];
            // The band starts as the film holds it: zero, a resumed row's finished sums
            // (which the skipped row leaves as they are), or the pilot's samples.
            if continues || band_done.iter().any(|d| d.load(Ordering::Relaxed)) {
                film.load_rows(first_row, band);
            } else {
                band.fill(0.0);
            }
            // A finished (resumed) row keeps its counts, a pixel of the second pass starts
            // from its pilot's, and a row left unrendered keeps the film's.
            let counted = if bands.counts.is_empty() {
                0
            } else {
                rows.len() * w
            };
            let counts = &mut bands.counts[..counted];
            if let (false, Some(film_counts)) = (counts.is_empty(), &film.sample_counts) {
                counts.copy_from_slice(&film_counts[first_row * w..rows.end * w]);
            }
            let matte_band = &mut bands.mattes[..rows.len() * bands.matte_row];
            let plans = pass.rows(rows.clone(), w, counts);
            self.render_band(rows.clone(), band, matte_band, plans);
            film.store_rows(first_row, band);
            film.store_counts(first_row, &bands.counts[..counted]);
            bands.move_mattes(rows.clone(), w, true);
            self.progress.rows_done(film, rows);
            if let Some(f) = after_band.as_mut() {
                f(&Snapshot {
                    film,
                    rows_done: &self.rows_done(),
                    pilot: pass.pilot(),
                    splats: self.tracer.splats,
                });
            }
        }
    }

    /// Renders the unfinished rows `rows` of the window into `band` (interleaved sums)
    /// and `mattes` (Cryptomatte values), a row per task, each as `plans` says.
    fn render_band(
        &self,
        rows: Range<usize>,
        band: &mut [f32],
        mattes: &mut [f32],
        plans: Vec<RowPass>,
    ) {
        let scene = self.tracer.scene;
        let w = self.window.width() as usize;
        band.par_chunks_mut(self.stride * w)
            .zip(mattes.par_chunks_mut(mattes.len() / rows.len()))
            .zip(plans)
            .enumerate()
            .for_each_init(
                || {
                    (
                        SampleAccumulator::with_squares(
                            scene.aovs.len(),
                            scene.variance_aovs.clone(),
                        ),
                        PixelMatte::new(self.table.map_or(0, |t| t.layers.len())),
                    )
                },
                |(acc, matte), (i, ((row, matte_row), plan))| {
                    let y = rows.start + i;
                    if self.done[y].load(Ordering::Relaxed) || self.stopped() {
                        return;
                    }
                    let taken = self.render_row(y, row, (matte, matte_row), plan, acc);
                    self.done[y].store(true, Ordering::Relaxed);
                    self.progress.advance(1, taken);
                },
            );
    }

    /// Renders row `y` of the window as `plan` says: its pixels' sums into `row`, their
    /// Cryptomatte values into `mattes.1`, their moments and counts into `plan`'s slices.
    /// Returns the samples it took.
    fn render_row(
        &self,
        y: usize,
        row: &mut [f32],
        mattes: (&mut PixelMatte, &mut [f32]),
        mut plan: RowPass,
        acc: &mut SampleAccumulator,
    ) -> u64 {
        let (matte, matte_row) = mattes;
        let matte_stride = self.table.map_or(0, |t| t.stride());
        let mut out = Sink::new(acc);
        let mut samples = 0u64;
        let row_index = y;
        let y = self.window.y0 + y as u32;
        let rule = self.rule;
        for (col, x) in (self.window.x0..self.window.x1).enumerate() {
            let matte_run = col * matte_stride..(col + 1) * matte_stride;
            // The pilot keeps each pixel's moments; the second pass takes it to its target.
            let mut moments = Moments::default();
            let (taken, spp, keep) = match &plan {
                RowPass::All => (0, self.options.spp, false),
                RowPass::Pilot { .. } => (0, rule.pilot, true),
                RowPass::Rest { targets, .. } => {
                    if let Some(t) = self.table {
                        matte.resume(t, &matte_row[matte_run.clone()], rule.pilot);
                    }
                    (rule.pilot, targets[col], false)
                }
            };
            let mut after_sample = |out: &Sink| {
                if let Some(t) = self.table {
                    matte.add(t, out.first_object);
                }
            };
            let job = PixelJob {
                x,
                y,
                run: &mut row[col * self.stride..(col + 1) * self.stride],
                first_sample: self.options.first_sample,
                taken,
                spp,
                after_sample: &mut after_sample,
                moments: keep.then_some(&mut moments),
            };
            let held = self.tracer.render_pixel(job, &mut out);
            samples += (held - taken) as u64;
            match &mut plan {
                RowPass::All => {}
                RowPass::Pilot { sums, counts } => {
                    sums[col] = [moments.sum, moments.sum2];
                    counts[col] = held;
                }
                RowPass::Rest { counts, .. } => counts[col] = held,
            }
            if let Some(t) = self.table {
                matte.flush(t, &mut matte_row[matte_run]);
            }
        }
        // A window's splats come from the whole frame's light subpaths: this row also
        // traces its share of those of the pixels outside it (connect/light_tracing.rs).
        if self.tracer.splats.is_some() {
            let scene = self.tracer.scene;
            let frame = [scene.camera.width, scene.camera.height];
            let first = self.options.first_sample;
            for (x, y) in connect::outside_pixels(frame, self.window, row_index) {
                self.tracer
                    .splat_pixel(x, y, first..first + self.options.spp, &mut out);
            }
        }
        let c = &self.counters;
        c.rays.fetch_add(out.rays, Ordering::Relaxed);
        c.nonfinite.fetch_add(out.nonfinite, Ordering::Relaxed);
        c.samples.fetch_add(samples, Ordering::Relaxed);
        samples
    }

    /// Each pixel's target after the pilot (`adaptive.rs`): the largest count its
    /// neighbours within `radius` predicted, from the pilot's moments and, for a crop,
    /// from pilot samples of the pixels around the window.
    fn targets(&self, pilot: &Pilot, radius: u32) -> Vec<u32> {
        let scene = self.tracer.scene;
        let frame = [scene.camera.width, scene.camera.height];
        let win = self.window;
        let region = adaptive::neighbourhood(win, frame, radius);
        let region_width = region.width() as usize;
        let predicted: Vec<u32> = (0..region_width * region.height() as usize)
            .into_par_iter()
            .map_init(
                || self.scratch_pixel(),
                |scratch, i| {
                    let x = region.x0 + (i % region_width) as u32;
                    let y = region.y0 + (i / region_width) as u32;
                    let inside = (win.x0..win.x1).contains(&x) && (win.y0..win.y1).contains(&y);
                    let moments = if inside {
                        let i =
                            (y - win.y0) as usize * win.width() as usize + (x - win.x0) as usize;
                        self.rule.pilot_moments(pilot.sums[i])
                    } else {
                        self.pilot_outside(x, y, scratch)
                    };
                    self.rule.predicted_count(&moments)
                },
            )
            .collect();
        adaptive::targets(&predicted, region, win, radius, self.rule.pilot)
    }

    /// An accumulator and a pixel run for samples whose values are not kept.
    fn scratch_pixel(&self) -> (SampleAccumulator, Vec<f32>) {
        let scene = self.tracer.scene;
        (
            SampleAccumulator::with_squares(scene.aovs.len(), scene.variance_aovs.clone()),
            vec![0.0; self.stride],
        )
    }

    /// The pilot moments of pixel (x, y) of the frame outside the window: its pilot
    /// samples taken again, their values dropped (the pixel is another part's).
    fn pilot_outside(
        &self,
        x: u32,
        y: u32,
        scratch: &mut (SampleAccumulator, Vec<f32>),
    ) -> Moments {
        let (acc, run) = scratch;
        run.fill(0.0);
        let mut out = Sink::new(acc);
        let mut moments = Moments::default();
        let mut no_mattes = |_: &Sink| {};
        let job = PixelJob {
            x,
            y,
            run,
            first_sample: self.options.first_sample,
            taken: 0,
            spp: self.rule.pilot,
            after_sample: &mut no_mattes,
            moments: Some(&mut moments),
        };
        self.tracer.render_pixel(job, &mut out);
        moments
    }
}

#[cfg(test)]
mod tests;
