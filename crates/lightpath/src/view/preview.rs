//! `render --preview`: the viewer's page while a render runs. The render loop stores a
//! band of rows at a time into the film and tells its [`Progress`] reporter; the
//! [`LivePreview`] reporter copies each band's means into the data the server shows and
//! bumps its generation, and the page, polling `/api/info`, reloads what it shows. When
//! the render has written its EXR, the viewer shows that file (partition checks, comps).

use super::{Shared, ViewData};
use crate::aov::naming::{self, channel_names};
use crate::film::Film;
use crate::output::ExrContents;
use crate::progress::Progress;
use crate::scene::Scene;
use std::ops::Range;
use std::sync::Arc;

/// Bands a preview asks the render loop for: rows show up about this many times.
const PREVIEW_BANDS: usize = 32;

/// The data of a render that has not started: every AOV's channels (zero, in the film's
/// plane order) and alpha, with the header a written EXR will have.
pub fn live_data(scene: &Scene, title: impl Into<String>) -> ViewData {
    let n = scene.camera.width as usize * scene.camera.height as usize;
    let mut channels: Vec<(String, Vec<f32>)> = scene
        .aovs
        .iter()
        .flat_map(|a| channel_names(&a.name))
        .map(|c| (c, vec![0.0; n]))
        .collect();
    channels.push((naming::ALPHA.to_string(), vec![0.0; n]));
    let exr = ExrContents {
        width: scene.camera.width as usize,
        height: scene.camera.height as usize,
        channels,
        attributes: crate::output::aov_attributes(&scene.aovs),
        frame: [scene.camera.width, scene.camera.height],
        origin: [0, 0],
        world_to_camera: None,
        world_to_ndc: None,
        capture_date: None,
    };
    let mut data = ViewData::new(exr, title);
    data.live = true;
    data
}

/// A progress reporter that also feeds a viewer: it passes everything on to `inner`.
pub struct LivePreview<'a> {
    inner: &'a dyn Progress,
    shared: Arc<Shared>,
    band_rows: usize,
}

impl<'a> LivePreview<'a> {
    /// A reporter for a render of `height` rows into the data of `shared` (from
    /// [`live_data`]).
    pub fn new(inner: &'a dyn Progress, shared: Arc<Shared>, height: u32) -> LivePreview<'a> {
        LivePreview {
            inner,
            shared,
            band_rows: (height as usize).div_ceil(PREVIEW_BANDS).max(1),
        }
    }
}

impl Progress for LivePreview<'_> {
    fn start(&self, total: u64, samples: u64) {
        self.inner.start(total, samples);
    }
    fn advance(&self, units: u64, samples: u64) {
        self.inner.advance(units, samples);
    }
    fn finish(&self) {
        self.inner.finish();
    }
    fn band_rows(&self) -> Option<usize> {
        Some(self.band_rows)
    }
    fn rows_done(&self, film: &Film, rows: Range<usize>) {
        let w = film.width as usize;
        let pixels = rows.start * w..rows.end * w;
        self.shared.update(|data| {
            if (data.exr.width, data.exr.height) != (w, film.height as usize) {
                return; // not the film this preview was made for
            }
            for (plane, (_, channel)) in film.planes.iter().zip(data.exr.channels.iter_mut()) {
                if let (Some(src), Some(dst)) =
                    (plane.get(pixels.clone()), channel.get_mut(pixels.clone()))
                {
                    // Adaptive sampling: each pixel's own count (the pilot's, mid-render).
                    for ((d, s), i) in dst.iter_mut().zip(src).zip(pixels.clone()) {
                        *d = s * (1.0 / film.samples_at(i).max(1) as f32);
                    }
                }
            }
            data.generation += 1;
        });
    }
}
