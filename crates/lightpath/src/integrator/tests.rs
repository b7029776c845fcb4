//! The neighbour rule of adaptive sampling (`adaptive.rs`) against each pixel deciding
//! alone (radius 0), on sub-pixel lamps seen by the camera.

use super::*;
use crate::aov;
use crate::scene::Source;

/// `lamps` sphere lights of about 0.3 pixel radius over a black background, seen by the
/// camera at 96 × 96 (432 make enough lamp pixels to tell rules apart beyond noise): each covers parts of one to four pixels, and a pixel's first
/// samples may all miss the part it covers (the per-pixel rule's blind spot).
fn lamps_scene(lamps: usize, radius: f32) -> Scene {
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
    for _ in 0..lamps {
        let (x, y) = (next() * 2.6 - 1.3, next() * 2.6 - 1.3);
        text += &format!(
            "[[lights]]\ntype = \"sphere\"\ncenter = [{x}, {y}, 0]\nradius = {radius}\n\
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

/// Lamp radii: 0.3 pixel (a lamp may lie inside one pixel), and 0.7 pixel (wider than a
/// pixel, as `scenes/many-lights.toml`'s lamps are: its neighbours see its edge).
const SUB_PIXEL: f32 = 0.0084;
const PIXEL_WIDE: f32 = 0.02;

/// An adaptive render (a threshold of 0: every pixel takes `spp`) with this radius.
fn render_with(scene: &mut Scene, spp: u32, threshold: f32, radius: u32) -> Rendered {
    scene.settings.noise_threshold = threshold;
    scene.settings.min_spp = Some(MIN_SPP);
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

/// Every pixel takes, after its pilot, the largest count its neighbours predicted — so a
/// pixel whose pilot saw no variance (all its first samples missed the lamp, or all hit
/// it) takes the samples a neighbour asks for — and the lamps' pixels end closer to a
/// 4096-spp reference than a fixed-count render taking at least as many samples in all,
/// beyond the noise of that comparison, where the lamps are few and wider than a pixel.
/// (With `NEIGHBOUR_RADIUS = 0` both fail.)
#[test]
fn neighbours_of_pixels_that_need_samples_take_them_too() {
    let mut scene = lamps_scene(432, SUB_PIXEL);
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
            let most = (y.saturating_sub(1)..(y + 2).min(h))
                .flat_map(|yy| (x.saturating_sub(1)..(x + 2).min(w)).map(move |xx| (xx, yy)))
                .filter(|&p| p != (x, y))
                .map(|(xx, yy)| predicted[yy * w + xx])
                .fold(MIN_SPP, u32::max);
            let i = y * w + x;
            assert_eq!(counts[i], most, "({x}, {y})");
            if rule.pilot_moments(pilot.sums[i]).error() == 0.0 && most > MIN_SPP {
                lent += 1;
            }
        }
    }
    assert!(
        lent >= 200,
        "only {lent} pixels without variance next to ones with"
    );

    // Paired per lamp pixel: how much larger a fixed count's squared error is.
    let mut scene = lamps_scene(96, PIXEL_WIDE);
    let neighbours = render_with(&mut scene, 1024, threshold, adaptive::NEIGHBOUR_RADIUS);
    let reference = luminances(&render_with(&mut scene, 4096, 0.0, 0).film);
    let fixed_spp = (mean_spp(&neighbours.film).ceil() as u32).next_power_of_two();
    let fixed = render_with(&mut scene, fixed_spp, 0.0, 0);
    let (a, b) = (luminances(&fixed.film), luminances(&neighbours.film));
    let excess: Vec<f64> = (0..w * h)
        .filter(|&i| reference[i] > 0.0)
        .map(|i| (a[i] - reference[i]).powi(2) - (b[i] - reference[i]).powi(2))
        .collect();
    let n = excess.len() as f64;
    let mean = excess.iter().sum::<f64>() / n;
    let var = excess.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (n - 1.0);
    let se = (var / n).sqrt();
    eprintln!(
        "lamp pixels {n}: excess {mean:.5} ± {se:.5}; mean spp {:.1} (adaptive) vs {fixed_spp}",
        mean_spp(&neighbours.film),
    );
    assert!(
        mean > 5.0 * se,
        "excess squared error {mean} vs its standard error {se}"
    );
}

/// A pixel's count never depends on its own samples, so adaptive sampling stays
/// unbiased: over several seeds the lamps' mean brightness agrees with a 4096-spp render
/// within the noise of both. (Letting each pixel's own pilot set its count —
/// `NEIGHBOUR_RADIUS = 0` with the pixel included — reads 3.6 % dark here, 80 standard
/// errors; run by hand.)
#[test]
fn adaptive_sampling_is_unbiased() {
    let mut scene = lamps_scene(432, SUB_PIXEL);
    let mean_of = |film: &Film| luminances(film).iter().sum::<f64>() / (96.0 * 96.0);
    let reference = mean_of(&render_with(&mut scene, 4096, 0.0, 0).film);
    let (mut means, mut spp) = (Vec::new(), 0.0);
    for seed in 1..=6 {
        scene.settings.seed = seed;
        let r = render_with(&mut scene, 1024, 0.1, adaptive::NEIGHBOUR_RADIUS);
        means.push(mean_of(&r.film));
        spp += mean_spp(&r.film) / 6.0;
    }
    let k = means.len() as f64;
    let mean = means.iter().sum::<f64>() / k;
    let sd = (means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (k - 1.0)).sqrt();
    // The reference's own noise, as one adaptive run's scaled to 4096 samples (1/n).
    let se = sd * (1.0 / k + spp / 4096.0).sqrt();
    eprintln!("mean {mean:.6} ± {se:.6} (sd {sd:.6}, {spp:.0} spp) vs reference {reference:.6}");
    assert!(
        (mean - reference).abs() <= 4.0 * se,
        "adaptive mean {mean} vs reference {reference}: {:.1} standard errors",
        (mean - reference).abs() / se
    );
}
