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
mod routing;

use crate::film::{Film, Mattes, PixelWindow, SampleAccumulator};
use crate::geometry::{Hit, Ray};
use crate::post::cryptomatte::{MatteTable, PixelMatte};
use crate::progress::{Progress, Silent};
use crate::sampler::{dim, IndependentSampler, Sampler};
use crate::scene::Scene;
use glam::{Vec2, Vec3A};
use rayon::prelude::*;
use routing::Route;
use std::sync::atomic::{AtomicU64, Ordering};

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
    let samples = w as u64 * h as u64 * options.spp as u64;
    progress.start(h as u64, samples);
    // Rows are rendered a band at a time into one reused interleaved buffer (a sample
    // writes one contiguous run), and each band is moved into the film's planes: the
    // peak memory is the film plus one band, with no allocation churn.
    let row_len = stride * w as usize;
    // At least 8 rows (or the whole window when it is shorter).
    let band_rows = (BAND_BYTES / (4 * row_len)).max(8).min(h.max(1) as usize);
    let mut band = vec![0.0f32; band_rows * row_len];
    let mut film = Film::for_window(win, [fw, fh], scene.aovs.len(), options.spp)
        .summing_squares(scene.variance_aovs.clone());
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
        let band = &mut band[..rows_here * row_len];
        band.fill(0.0);
        let matte_band = &mut matte_band[..rows_here * matte_row];
        band.par_chunks_mut(row_len)
            .zip(matte_band.par_chunks_mut(matte_row))
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
                |(acc, matte), (i, (row, matte_row))| {
                    let y = win.y0 + (first_row + i) as u32;
                    let mut out = Sink {
                        acc,
                        rays: 0,
                        nonfinite: 0,
                        holdout: false,
                        first_object: None,
                    };
                    for (col, x) in (win.x0..win.x1).enumerate() {
                        let pixel = &mut row[col * stride..(col + 1) * stride];
                        let index = y as u64 * fw as u64 + x as u64;
                        for s in options.first_sample..options.first_sample + options.spp {
                            let mut sampler =
                                IndependentSampler::new(scene.settings.seed, index, s as u64);
                            let offset = scene.filter.offset(sampler.get_2d(dim::FILTER));
                            let film_pos = Vec2::new(x as f32 + 0.5, y as f32 + 0.5) + offset;
                            let ray = cam.ray(film_pos, sampler.get_2d(dim::LENS));
                            let alpha = tracer.trace(ray, &mut sampler, &mut out);
                            out.acc.flush(pixel);
                            pixel[Film::alpha_slot(stride)] += alpha;
                            if let Some(t) = table {
                                matte.add(t, out.first_object);
                            }
                        }
                        if let Some(t) = table {
                            let run = col * matte_stride..(col + 1) * matte_stride;
                            matte.flush(t, &mut matte_row[run]);
                        }
                    }
                    rays.fetch_add(out.rays, Ordering::Relaxed);
                    nonfinite.fetch_add(out.nonfinite, Ordering::Relaxed);
                    progress.advance(1);
                },
            );
        film.store_rows(first_row, band);
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
    }
    if let Some(t) = table {
        film.mattes = Some(Mattes {
            table: t.clone(),
            planes: matte_planes,
        });
    }
    progress.finish();
    let stats = RenderStats {
        samples,
        rays: rays.into_inner(),
        nonfinite: nonfinite.into_inner(),
        seconds: start.elapsed().as_secs_f64(),
    };
    (film, stats)
}
