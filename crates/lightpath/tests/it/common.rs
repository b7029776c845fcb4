//! What several integration test modules share.

use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Scratch folders of one test binary are told apart by a counter: every module runs in
/// the same process, so the process id alone no longer makes a folder's name unique.
static SCRATCH_COUNT: AtomicUsize = AtomicUsize::new(0);

/// A scratch folder for one test, removed when the test ends, passing or not.
pub struct Scratch(pub PathBuf);

impl Scratch {
    pub fn new(tag: &str) -> Scratch {
        let n = SCRATCH_COUNT.fetch_add(1, Ordering::Relaxed);
        let pid = std::process::id();
        let dir = std::env::temp_dir().join(format!("lightpath-{tag}-{pid}-{n}"));
        std::fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }

    pub fn join(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The position of AOV `name` in a built scene's AOV list (panics naming it if absent).
pub fn index(scene: &lightpath::Scene, name: &str) -> usize {
    scene
        .aovs
        .iter()
        .position(|a| a.name == name)
        .unwrap_or_else(|| panic!("no AOV {name}"))
}

/// The first `spp` samples from `first_sample` on of `scene`.
pub fn render_spp(scene: &lightpath::Scene, spp: u32, first_sample: u32) -> lightpath::film::Film {
    lightpath::render(scene, &lightpath::RenderOptions { spp, first_sample }).0
}

/// An AOV's mean luminance over the image.
pub fn image_mean(film: &lightpath::film::Film, aov: usize) -> f64 {
    let mut sum = 0.0;
    for y in 0..film.height {
        for x in 0..film.width {
            sum += lightpath::light::luminance(film.pixel(aov, x, y)) as f64;
        }
    }
    sum / (film.width * film.height) as f64
}

/// Mean and standard error of the mean of independent estimates.
pub fn mean_and_se(vals: &[f64]) -> (f64, f64) {
    let n = vals.len() as f64;
    let mean = vals.iter().sum::<f64>() / n;
    let var = vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// Every pixel of AOVs `parts` sums to the beauty's (to 1e-5 of the beauty, or of 1e-3
/// where the beauty is darker).
pub fn assert_sums_to_beauty(
    scene: &lightpath::Scene,
    film: &lightpath::film::Film,
    parts: &[&str],
) {
    let beauty = index(scene, "beauty");
    let ids: Vec<usize> = parts.iter().map(|p| index(scene, p)).collect();
    for y in 0..film.height {
        for x in 0..film.width {
            let b = film.pixel(beauty, x, y);
            let sum: glam::Vec3A = ids.iter().map(|&k| film.pixel(k, x, y)).sum();
            let err = (sum - b).abs() / b.abs().max(glam::Vec3A::splat(1e-3));
            assert!(
                err.max_element() <= 1e-5,
                "{parts:?} off by {err} at {x},{y}"
            );
        }
    }
}
