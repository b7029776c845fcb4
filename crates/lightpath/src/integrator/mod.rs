//! Unidirectional path tracing with light sampling and MIS (power heuristic), Russian
//! roulette and depth limits, feeding the LPE automaton one event per vertex (DESIGN.md):
//! the camera event, the sampled lobe's event at each scattering vertex, every lobe of a
//! light sample through its own event then `L`, light hits through `L` with the
//! complementary weight, emission through `O`. A dead automaton state ends the path.
//!
//! `path.rs` holds the named steps of one path, `direct.rs` light sampling and MIS,
//! `routing.rs` what each AOV takes of a contribution; this module runs the render loop.

mod direct;
mod path;
mod pixel;
mod routing;
mod shading;

use crate::film::{Film, Mattes, PixelWindow, SampleAccumulator};
use crate::geometry::{Hit, Ray};
use crate::post::cryptomatte::{MatteTable, PixelMatte};
use crate::progress::{Progress, Silent};
use crate::scene::Scene;
use glam::Vec3A;
use pixel::PixelJob;
use rayon::prelude::*;
use routing::Route;
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
    /// When set, rows not yet started are skipped: the render ends with the rows in
    /// flight (a row is never left half-rendered).
    pub cancel: Option<&'a AtomicBool>,
    /// Called after each band with the film and the rows finished so far (checkpoints).
    pub after_band: Option<AfterBand<'a>>,
    /// At most this many rows per band (at least 8), so `after_band` comes often enough
    /// on a small film; `None`: bands as large as `BAND_BYTES` allows.
    pub max_band_rows: Option<usize>,
}

/// What `Resumable::after_band` is given: the film, and which rows are finished.
pub type AfterBand<'a> = &'a mut dyn FnMut(&Film, &[bool]);

/// A render that may have stopped early.
pub struct Rendered {
    pub film: Film,
    pub stats: RenderStats,
    /// One entry per row of the window: finished? All true unless the render was
    /// cancelled.
    pub rows_done: Vec<bool>,
}

/// [`render_frame`] of the rows `resume` does not already hold, stopping early if its
/// `cancel` flag is set. Each row's sums start from zero and add its samples in order,
/// so a row is the same whichever run renders it.
pub fn render_resumable(
    scene: &Scene,
    options: &RenderOptions,
    request: &FrameRequest,
    progress: &dyn Progress,
    resume: Resumable,
) -> Rendered {
    let Resumable {
        film: resumed,
        rows_done: resumed_rows,
        cancel,
        mut after_band,
        max_band_rows,
    } = resume;
    let start = std::time::Instant::now();
    let cam = &scene.camera;
    let (fw, fh) = (cam.width, cam.height);
    let win = request.window;
    debug_assert!(win.check(fw, fh).is_ok());
    let (w, h) = (win.width(), win.height());
    let stride = Film::stride_with(scene.aovs.len(), scene.variance_aovs.len());
    let tracer = Tracer::new(scene);
    let rays = AtomicU64::new(0);
    let nonfinite = AtomicU64::new(0);
    let done: Vec<AtomicBool> = (0..h as usize)
        .map(|y| AtomicBool::new(resumed_rows.get(y).copied().unwrap_or(false)))
        .collect();
    let rows_before = done.iter().filter(|d| d.load(Ordering::Relaxed)).count() as u64;
    let samples_taken = AtomicU64::new(0);
    progress.start(h as u64, w as u64 * h as u64 * options.spp as u64);
    progress.advance(rows_before);
    let stopped = || cancel.is_some_and(|c| c.load(Ordering::Relaxed));
    // Rows are rendered a band at a time into one reused interleaved buffer (a sample
    // writes one contiguous run), and each band is moved into the film's planes: the
    // peak memory is the film plus one band, with no allocation churn.
    let row_len = stride * w as usize;
    // At least 8 rows (or the whole window when it is shorter).
    let band_rows = (BAND_BYTES / (4 * row_len))
        .min(max_band_rows.unwrap_or(usize::MAX))
        .max(8)
        .min(h.max(1) as usize);
    // A live preview asks for smaller bands, to show rows sooner; pixels do not depend on it.
    let band_rows = progress
        .band_rows()
        .map_or(band_rows, |r| r.clamp(1, band_rows));
    let mut band = vec![0.0f32; band_rows * row_len];
    let adaptive = scene.settings.noise_threshold > 0.0;
    let mut counts = vec![0u32; if adaptive { band_rows * w as usize } else { 0 }];
    let mut film = resumed
        .filter(|f| {
            (f.width, f.height, f.aovs, &f.squared)
                == (w, h, scene.aovs.len(), &scene.variance_aovs)
        })
        .map(|f| Film {
            window: win,
            frame: [fw, fh],
            ..f
        })
        .unwrap_or_else(|| {
            Film::for_window(win, [fw, fh], scene.aovs.len(), options.spp)
                .summing_squares(scene.variance_aovs.clone())
        });
    if adaptive && film.sample_counts.is_none() {
        film.sample_counts = Some(vec![0; w as usize * h as usize]);
    }
    // Cryptomatte values, band by band beside the AOVs' (one dummy value per row without).
    let table = request.mattes.as_ref();
    let matte_stride = table.map_or(0, |t| t.stride());
    let matte_row = (matte_stride * w as usize).max(1);
    let mut matte_band = vec![0.0f32; band_rows * matte_row];
    let mut matte_planes: Vec<Vec<f32>> = (0..matte_stride)
        .map(|_| vec![0.0; w as usize * h as usize])
        .collect();
    for first_row in (0..h as usize).step_by(band_rows) {
        let rows_here = band_rows.min(h as usize - first_row);
        let band_done = &done[first_row..first_row + rows_here];
        if stopped() || band_done.iter().all(|d| d.load(Ordering::Relaxed)) {
            continue;
        }
        let band = &mut band[..rows_here * row_len];
        // The band starts as the film holds it: zero, or a resumed row's finished sums,
        // which the skipped row leaves as they are.
        if band_done.iter().any(|d| d.load(Ordering::Relaxed)) {
            film.load_rows(first_row, band);
        } else {
            band.fill(0.0);
        }
        let matte_band = &mut matte_band[..rows_here * matte_row];
        // Per row: its sample counts (adaptive sampling), or nothing.
        // A finished (resumed) row keeps its counts; a row left unrendered keeps the film's.
        if let Some(film_counts) = &film.sample_counts {
            let start = first_row * w as usize;
            let n = rows_here * w as usize;
            counts[..n].copy_from_slice(&film_counts[start..start + n]);
        }
        let count_rows: Vec<&mut [u32]> = if adaptive {
            counts[..rows_here * w as usize]
                .chunks_mut(w as usize)
                .collect()
        } else {
            (0..rows_here).map(|_| &mut [][..]).collect()
        };
        band.par_chunks_mut(row_len)
            .zip(matte_band.par_chunks_mut(matte_row))
            .zip(count_rows)
            .enumerate()
            .for_each_init(
                || {
                    (
                        SampleAccumulator::with_squares(
                            scene.aovs.len(),
                            scene.variance_aovs.clone(),
                        ),
                        PixelMatte::new(table.map_or(0, |t| t.layers.len())),
                    )
                },
                |(acc, matte), (i, ((row, matte_row), row_counts))| {
                    if band_done[i].load(Ordering::Relaxed) || stopped() {
                        return;
                    }
                    let y = win.y0 + (first_row + i) as u32;
                    let mut out = Sink {
                        acc,
                        rays: 0,
                        nonfinite: 0,
                        holdout: false,
                        first_object: None,
                    };
                    let mut row_samples = 0u64;
                    for (col, x) in (win.x0..win.x1).enumerate() {
                        let mut after_sample = |out: &Sink| {
                            if let Some(t) = table {
                                matte.add(t, out.first_object);
                            }
                        };
                        let job = PixelJob {
                            x,
                            y,
                            run: &mut row[col * stride..(col + 1) * stride],
                            first_sample: options.first_sample,
                            spp: options.spp,
                            after_sample: &mut after_sample,
                        };
                        let taken = tracer.render_pixel(job, &mut out);
                        row_samples += taken as u64;
                        if let Some(c) = row_counts.get_mut(col) {
                            *c = taken;
                        }
                        if let Some(t) = table {
                            let run = col * matte_stride..(col + 1) * matte_stride;
                            matte.flush(t, &mut matte_row[run]);
                        }
                    }
                    rays.fetch_add(out.rays, Ordering::Relaxed);
                    nonfinite.fetch_add(out.nonfinite, Ordering::Relaxed);
                    band_done[i].store(true, Ordering::Relaxed);
                    samples_taken.fetch_add(row_samples, Ordering::Relaxed);
                    progress.advance(1);
                },
            );
        film.store_rows(first_row, band);
        if adaptive {
            film.store_counts(first_row, &counts[..rows_here * w as usize]);
        }
        if matte_stride > 0 {
            let start = first_row * w as usize;
            for (c, plane) in matte_planes.iter_mut().enumerate() {
                for (d, px) in plane[start..start + rows_here * w as usize]
                    .iter_mut()
                    .zip(matte_band.chunks_exact(matte_stride))
                {
                    *d = px[c];
                }
            }
        }
        progress.rows_done(&film, first_row..first_row + rows_here);
        if let Some(f) = after_band.as_mut() {
            let rows: Vec<bool> = done.iter().map(|d| d.load(Ordering::Relaxed)).collect();
            f(&film, &rows);
        }
    }
    if let Some(t) = table {
        film.mattes = Some(Mattes {
            table: t.clone(),
            planes: matte_planes,
        });
    }
    progress.finish();
    let stats = RenderStats {
        samples: samples_taken.into_inner(),
        rays: rays.into_inner(),
        nonfinite: nonfinite.into_inner(),
        seconds: start.elapsed().as_secs_f64(),
    };
    Rendered {
        film,
        stats,
        rows_done: done.into_iter().map(AtomicBool::into_inner).collect(),
    }
}
