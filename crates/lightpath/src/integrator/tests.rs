//! The neighbour rule of adaptive sampling (`adaptive.rs`) against each pixel deciding
//! alone (radius 0), on sub-pixel lamps seen by the camera.

use super::*;
use crate::aov;
use crate::scene::Source;

/// 432 sphere lights of about 0.3 pixel radius over a black background, seen by the
/// camera at 96 × 96 (enough lamp pixels to tell the rules apart beyond noise): each covers parts of one to four pixels, and a pixel's first
/// samples may all miss the part it covers (the per-pixel rule's blind spot).
fn lamps_scene() -> Scene {
    let mut text = String::from(
        "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\nfov = 30\n\
         [film]\nresolution = [96, 96]\n[render]\nmax_depth = 1\n",
    );
    // A fixed scatter (an LCG), so every run renders the same scene.
    let mut state = 12345u32;
    let mut next = || {
        state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (state >> 8) as f32 / (1 << 24) as f32
    };
    for _ in 0..432 {
        let (x, y) = (next() * 2.6 - 1.3, next() * 2.6 - 1.3);
        text += &format!(
            "[[lights]]\ntype = \"sphere\"\ncenter = [{x}, {y}, 0]\nradius = 0.0084\n\
             radiance = [20, 20, 20]\n"
        );
    }
    let desc = Source {
        name: "lamps.toml".into(),
        text,
        dir: Default::default(),
    }
    .parse()
    .unwrap();
    Scene::build(&desc, &aov::assemble(vec![])).unwrap()
}

const MIN_SPP: u32 = 16;

/// An adaptive render (a threshold of 0: every pixel takes `spp`) with this radius.
fn render_with(scene: &mut Scene, spp: u32, threshold: f32, radius: u32) -> Rendered {
    scene.settings.noise_threshold = threshold;
    scene.settings.min_spp = MIN_SPP;
    let options = RenderOptions {
        spp,
        first_sample: 0,
    };
    let request = FrameRequest::whole(scene);
    render_passes(
        scene,
        &options,
        &request,
        &Silent,
        Resumable::default(),
        radius,
    )
}

/// Beauty luminance of every pixel.
fn luminances(film: &Film) -> Vec<f64> {
    (0..film.height)
        .flat_map(|y| (0..film.width).map(move |x| (x, y)))
        .map(|(x, y)| crate::light::luminance(film.pixel(0, x, y)) as f64)
        .collect()
}

fn mean_spp(film: &Film) -> f64 {
    let counts = film.sample_counts.as_ref().unwrap();
    counts.iter().map(|&n| n as f64).sum::<f64>() / counts.len() as f64
}

/// Pixels whose pilot saw no variance (all their first samples missed the lamp, or all
/// hit it) take the samples a neighbour predicts, where the per-pixel rule (radius 0)
/// stops them at `min_spp`; and the lamps' pixels end closer to a 4096-spp reference than
/// under the per-pixel rule at a 4× lower threshold, beyond the noise of that comparison.
/// (With `NEIGHBOUR_RADIUS = 0` the first fails: pixel (24, 0) took 16 samples, not 1024.)
#[test]
fn neighbours_of_pixels_that_need_samples_take_them_too() {
    let mut scene = lamps_scene();
    let threshold = 0.1;
    let neighbours = render_with(&mut scene, 1024, threshold, adaptive::NEIGHBOUR_RADIUS);
    let (w, h) = (96usize, 96usize);
    let rule = Rule::new(&scene.settings, 1024);
    let pilot = neighbours.pilot.as_ref().unwrap();
    let predicted: Vec<u32> = pilot
        .sums
        .iter()
        .map(|&s| rule.predicted_count(&rule.pilot_moments(s)))
        .collect();
    let counts = neighbours.film.sample_counts.as_ref().unwrap();
    let mut lent = 0;
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            if rule.pilot_moments(pilot.sums[i]).relative_error() != 0.0 {
                continue;
            }
            let most = (y.saturating_sub(1)..(y + 2).min(h))
                .flat_map(|yy| (x.saturating_sub(1)..(x + 2).min(w)).map(move |xx| yy * w + xx))
                .map(|j| predicted[j])
                .max()
                .unwrap();
            if most > MIN_SPP {
                lent += 1;
                assert!(counts[i] >= most, "({x}, {y}): {} < {most}", counts[i]);
            }
        }
    }
    assert!(
        lent >= 200,
        "only {lent} pixels without variance next to ones with"
    );

    // Paired per lamp pixel: how much larger the per-pixel rule's squared error is.
    let reference = luminances(&render_with(&mut scene, 4096, 0.0, 0).film);
    let alone = render_with(&mut scene, 1024, threshold / 4.0, 0);
    let (a, b) = (luminances(&alone.film), luminances(&neighbours.film));
    let excess: Vec<f64> = (0..w * h)
        .filter(|&i| reference[i] > 0.0)
        .map(|i| (a[i] - reference[i]).powi(2) - (b[i] - reference[i]).powi(2))
        .collect();
    let n = excess.len() as f64;
    let mean = excess.iter().sum::<f64>() / n;
    let var = excess.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (n - 1.0);
    let se = (var / n).sqrt();
    eprintln!(
        "lamp pixels {n}: excess {mean:.5} ± {se:.5}; mean spp {:.1} (neighbours) vs {:.1}",
        mean_spp(&neighbours.film),
        mean_spp(&alone.film)
    );
    assert!(
        mean > 5.0 * se,
        "excess squared error {mean} vs its standard error {se}"
    );
}
