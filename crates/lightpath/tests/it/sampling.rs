//! Cleaner images sooner without changing what they converge to: lights chosen by the
//! light tree or by power give the same image as uniform selection within noise (and a
//! relit image the re-render's), adaptive sampling keeps partitions exact, is the same
//! for any thread count and merges by per-pixel counts, and the built-in `cornell` has
//! few fireflies at its defaults.

use crate::common::index;
use glam::Vec3A;
use lightpath::aov::{self, AovSpec};
use lightpath::film::Film;
use lightpath::light::select::LightSelection;
use lightpath::sampler::SamplerKind;
use lightpath::scene::desc::SceneDesc;
use lightpath::{render, RenderOptions, Scene};

const MANY_LIGHTS: &str = include_str!("../../../../scenes/many-lights.toml");

fn many_lights() -> lightpath::Source {
    lightpath::Source {
        name: "many-lights.toml".into(),
        text: MANY_LIGHTS.into(),
        dir: Default::default(),
    }
}

fn run(
    src: &lightpath::Source,
    edit: impl FnOnce(&mut SceneDesc),
    aovs: Vec<AovSpec>,
) -> (Scene, Film) {
    let mut desc = src.parse().unwrap();
    edit(&mut desc);
    let scene = Scene::build(&desc, &aov::assemble(aovs)).unwrap();
    let (film, _) = render(
        &scene,
        &RenderOptions {
            spp: desc.render.spp,
            first_sample: 0,
        },
    );
    (scene, film)
}

/// Two renders of the same image agree within their noise: in each of 4 × 4 blocks, the
/// mean per-pixel difference of luminance is within 5 standard errors of zero. Pixels
/// have independent sample sequences, so the spread of the differences over a block's
/// pixels estimates the standard error of their mean. Returns the largest |z|.
fn agree_within_noise(a: &[Vec3A], b: &[Vec3A], width: usize) -> f64 {
    let height = a.len() / width;
    let lum = |v: Vec3A| (0.2126 * v.x + 0.7152 * v.y + 0.0722 * v.z) as f64;
    let mut worst = 0.0f64;
    for by in 0..4 {
        for bx in 0..4 {
            let d: Vec<f64> = (by * height / 4..(by + 1) * height / 4)
                .flat_map(|y| (bx * width / 4..(bx + 1) * width / 4).map(move |x| y * width + x))
                .map(|i| lum(a[i]) - lum(b[i]))
                .collect();
            let n = d.len() as f64;
            let mean = d.iter().sum::<f64>() / n;
            let var = d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
            let se = (var / n).sqrt();
            let z = if se > 0.0 { mean / se } else { 0.0 };
            assert!(
                mean.abs() <= 5.0 * se,
                "block ({bx}, {by}): mean difference {mean} vs standard error {se}"
            );
            worst = worst.max(z.abs());
        }
    }
    worst
}

fn pixels(film: &Film, k: usize) -> Vec<Vec3A> {
    (0..film.height)
        .flat_map(|y| (0..film.width).map(move |x| (x, y)))
        .map(|(x, y)| film.pixel(k, x, y))
        .collect()
}

/// The many-light scene at 48², 24 spp, clamps off, with `selection`, `seed` and then
/// `edit`: its beauty's pixels.
fn many_lights_image(
    selection: LightSelection,
    seed: u64,
    edit: impl FnOnce(&mut SceneDesc),
) -> Vec<Vec3A> {
    let (_, film) = run(
        &many_lights(),
        |d| {
            d.render.resolution = [48, 48];
            d.render.spp = 24;
            d.render.seed = seed;
            d.render.light_selection = selection;
            d.render.clamp_direct = 0.0;
            d.render.clamp_indirect = 0.0;
            edit(d);
        },
        vec![],
    );
    pixels(&film, 0)
}

/// The summed squared difference of two images: of two seeds' images, their noise.
fn spread(a: &[Vec3A], b: &[Vec3A]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| ((*x - *y).length_squared()) as f64)
        .sum::<f64>()
}

/// The light tree and power selection are unbiased: on a scene with a key, a dim dome
/// and 48 small lamps (clamps off), their images agree with uniform selection's within
/// noise, block by block — and a selection pdf left out of a weight would not.
#[test]
fn light_selection_is_unbiased_against_uniform() {
    let render_with = |selection, seed| many_lights_image(selection, seed, |_| {});
    let uniform = render_with(LightSelection::Uniform, 1);
    for selection in [LightSelection::Tree, LightSelection::Power] {
        agree_within_noise(&render_with(selection, 2), &uniform, 48);
    }
}

/// Resampled light candidates (`--light-candidates`, integrator/light_choice.rs) are
/// unbiased: with 4 and 16 candidates from the tree or from uniform selection, the
/// images agree with one uniform candidate's within noise, block by block; and they are
/// less noisy than one candidate's from the same selection (the point of resampling):
/// the mean squared difference between two seeds' images is lower.
#[test]
fn resampled_light_candidates_are_unbiased_and_less_noisy() {
    let render_with = |selection, candidates, seed| {
        many_lights_image(selection, seed, |d| d.render.light_candidates = candidates)
    };
    let uniform = render_with(LightSelection::Uniform, 1, 1);
    for (selection, m) in [(LightSelection::Tree, 4), (LightSelection::Uniform, 16)] {
        agree_within_noise(&render_with(selection, m, 2), &uniform, 48);
    }
    let one = spread(
        &render_with(LightSelection::Uniform, 1, 3),
        &render_with(LightSelection::Uniform, 1, 4),
    );
    let eight = spread(
        &render_with(LightSelection::Uniform, 8, 3),
        &render_with(LightSelection::Uniform, 8, 4),
    );
    assert!(eight < one, "8 candidates {eight} vs 1 candidate {one}");
}

/// A glossy floor under a large lamp and beside a point light, a mirror on the wall.
const GLOSSY_UNDER_LAMPS: &str = r#"
[camera]
position = [0, 1.2, 3]
look_at = [0, -0.6, 0]
fov = 45
[render]
max_depth = 4
clamp_direct = 0
clamp_indirect = 0
[materials.floor]
type = "plastic"
albedo = [0.3, 0.3, 0.3]
roughness = 0.15
[materials.mirror]
type = "conductor"
f0 = [0.9, 0.9, 0.9]
roughness = 0
[[objects]]
name = "floor"
shape = "quad"
material = "floor"
corners = [[-2, -1, 2], [2, -1, 2], [2, -1, -2], [-2, -1, -2]]
[[objects]]
name = "mirror"
shape = "quad"
material = "mirror"
corners = [[-1.5, -1, -1.5], [1.5, -1, -1.5], [1.5, 1, -1.5], [-1.5, 1, -1.5]]
[[lights]]
type = "quad"
name = "lamp"
radiance = [4, 4, 4]
corners = [[-0.8, -0.2, -0.8], [0.8, -0.2, -0.8], [0.8, -0.2, 0.8], [-0.8, -0.2, 0.8]]
[[lights]]
type = "point"
name = "bulb"
position = [1.2, -0.5, 0.5]
intensity = [2, 2, 2]
"#;

/// Several light samples at the first rough vertex (`--light-samples`, direct.rs) are
/// unbiased: with 4 from the tree and 3 from uniform selection, the images agree with
/// one uniform sample's within noise, block by block (a BSDF ray's weight that left out
/// the samples' count would not: its weights and the light samples' would no longer sum
/// to one); and 4 samples are less noisy than one from the same selection.
#[test]
fn light_samples_are_unbiased_and_less_noisy() {
    let render_with = |selection, samples, seed| {
        many_lights_image(selection, seed, |d| d.render.light_samples = samples)
    };
    let uniform = render_with(LightSelection::Uniform, 1, 1);
    for (selection, n) in [(LightSelection::Tree, 4), (LightSelection::Uniform, 3)] {
        agree_within_noise(&render_with(selection, n, 2), &uniform, 48);
    }
    // Where BSDF rays find the lights as often as light samples do: a glossy floor
    // under a large lamp, seen directly and in a mirror.
    let glossy = lightpath::Source {
        name: "glossy.toml".into(),
        text: GLOSSY_UNDER_LAMPS.into(),
        dir: Default::default(),
    };
    let glossy_with = |samples: u32, seed: u64| {
        let (_, film) = run(
            &glossy,
            |d| {
                d.render.resolution = [48, 48];
                d.render.spp = 16;
                d.render.seed = seed;
                d.render.light_samples = samples;
            },
            vec![],
        );
        pixels(&film, 0)
    };
    agree_within_noise(&glossy_with(3, 2), &glossy_with(1, 1), 48);
    let one = spread(
        &render_with(LightSelection::Tree, 1, 3),
        &render_with(LightSelection::Tree, 1, 4),
    );
    let four = spread(
        &render_with(LightSelection::Tree, 4, 3),
        &render_with(LightSelection::Tree, 4, 4),
    );
    assert!(four < one, "4 light samples {four} vs 1 {one}");
}

/// Relighting from light-group AOVs: with uniform selection it is exact (see
/// tests/it/workflow.rs); with the tree, making the key 1.5× brighter changes which lights
/// are sampled, so relit and re-rendered images agree within their noise.
#[test]
fn relighting_with_the_tree_matches_a_re_render_within_noise() {
    let src = lightpath::load_source("cornell").unwrap();
    let aovs = || vec![AovSpec::new("beauty", "lpe:beauty").split()];
    let small = |d: &mut SceneDesc| {
        d.render.resolution = [40, 40];
        d.render.spp = 16;
        d.render.clamp_indirect = 0.0;
    };
    let (scene, film) = run(&src, small, aovs());
    let brighter = |d: &mut SceneDesc| {
        small(d);
        d.render.seed = 7;
        for l in &mut d.lights {
            if l.groups == ["key"] {
                l.strength = 1.5;
            }
        }
    };
    let (_, rerendered) = run(&src, brighter, aovs());
    let key = index(&scene, "beauty_key");
    let relit: Vec<Vec3A> = pixels(&film, 0)
        .iter()
        .zip(pixels(&film, key))
        .map(|(b, k)| *b + 0.5 * k)
        .collect();
    agree_within_noise(&relit, &pixels(&rerendered, 0), 40);
}

fn adaptive(threshold: f32, spp: u32) -> impl Fn(&mut SceneDesc) {
    move |d: &mut SceneDesc| {
        d.render.resolution = [32, 32];
        d.render.spp = spp;
        d.render.noise_threshold = threshold;
        d.render.min_spp = Some(8);
    }
}

/// Adaptive sampling: pixels stop at different counts between `min_spp` and `spp`, all
/// AOVs of a pixel share its samples (the standard partition and the light-group split
/// still sum to beauty within 1e-5), `sampleCount` adds up to the samples taken, and the
/// film is bit-identical for 1 and 2 threads.
#[test]
fn adaptive_sampling_keeps_partitions_exact_and_is_deterministic() {
    let src = lightpath::load_source("cornell").unwrap();
    let aovs = || {
        let mut a = aov::standard();
        a.push(AovSpec::new("beauty", "lpe:beauty").split());
        a
    };
    let mut desc = src.parse().unwrap();
    adaptive(0.05, 64)(&mut desc);
    let scene = Scene::build(&desc, &aov::assemble(aovs())).unwrap();
    let render_on = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                render(
                    &scene,
                    &RenderOptions {
                        spp: 64,
                        first_sample: 0,
                    },
                )
            })
    };
    let (film, stats) = render_on(2);
    let counts = film
        .sample_counts
        .clone()
        .expect("adaptive films count samples");
    let (lo, hi) = (*counts.iter().min().unwrap(), *counts.iter().max().unwrap());
    assert!(lo >= 8 && hi <= 64 && lo < hi, "counts {lo}..{hi}");
    assert!(counts.iter().all(|&n| n == 64 || n.is_power_of_two()));
    assert_eq!(
        counts.iter().map(|&n| n as u64).sum::<u64>(),
        stats.samples,
        "sampleCount is what was taken"
    );
    let beauty = index(&scene, "beauty");
    let partitions: Vec<Vec<usize>> = vec![
        lpe::BEAUTY_PARTITION
            .iter()
            .map(|n| index(&scene, n))
            .collect(),
        scene
            .aovs
            .iter()
            .enumerate()
            .filter(|(_, a)| a.part_of == Some(beauty as u32))
            .map(|(k, _)| k)
            .collect(),
    ];
    for parts in &partitions {
        assert!(parts.len() >= 2);
        for y in 0..film.height {
            for x in 0..film.width {
                let whole = film.pixel(beauty, x, y);
                let sum: Vec3A = parts.iter().map(|&k| film.pixel(k, x, y)).sum();
                assert!(
                    (sum - whole).abs().max_element() <= 1e-5 * whole.max_element().max(1.0),
                    "pixel {x},{y}: parts {sum} vs beauty {whole}"
                );
            }
        }
    }
    let (one, _) = render_on(1);
    assert_eq!(one.sample_counts, film.sample_counts);
    assert!(one
        .planes
        .concat()
        .iter()
        .zip(&film.planes.concat())
        .all(|(a, b)| a.to_bits() == b.to_bits()));
}

/// An adaptive render stopped in its pilot pass, right at its end, or in its second pass,
/// then resumed from its checkpoint file, is the uninterrupted render bit for bit: the
/// checkpoint holds the pass, the counts and the pilot's moments the targets come from.
#[test]
fn an_interrupted_adaptive_render_resumes_bit_for_bit() {
    use lightpath::checkpoint::{self, FilmShape};
    use lightpath::integrator::{FrameRequest, Snapshot};
    use lightpath::{render_resumable, Resumable};
    use std::sync::atomic::{AtomicBool, Ordering};
    let src = lightpath::load_source("cornell").unwrap();
    let mut desc = src.parse().unwrap();
    adaptive(0.05, 48)(&mut desc);
    desc.render.resolution = [24, 40];
    let scene = Scene::build(&desc, &aov::assemble(aov::standard())).unwrap();
    let options = RenderOptions {
        spp: 48,
        first_sample: 0,
    };
    let silent = lightpath::progress::Silent;
    let request = FrameRequest::whole(&scene);
    let whole = render_resumable(&scene, &options, &request, &silent, Resumable::default());
    let dir = std::env::temp_dir().join(format!("lightpath-adaptive-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("a.exr.checkpoint");
    // A checkpoint of some scene: its identity does not matter here.
    let identity = lightpath::identity::Identity::new(std::path::Path::new(""), &[], Vec::new());
    let stamp = lightpath::checkpoint::Stamp {
        identity: &identity,
        fingerprint: 7,
    };
    // 40 rows in bands of 8: bands 1–5 are the pilot's, 6–10 the second pass's.
    for stop_after in [2, 5, 7] {
        let cancel = AtomicBool::new(false);
        let mut bands = 0;
        let mut stop = |snapshot: &Snapshot| {
            bands += 1;
            if bands == stop_after {
                cancel.store(true, Ordering::SeqCst);
                checkpoint::write(&path, stamp, snapshot).unwrap();
            }
        };
        let part = render_resumable(
            &scene,
            &options,
            &request,
            &silent,
            Resumable {
                cancel: Some(&cancel),
                after_band: Some(&mut stop),
                max_band_rows: Some(8),
                ..Resumable::default()
            },
        );
        assert!(!part.finished(), "stopped after band {stop_after}");
        let shape = FilmShape {
            width: 24,
            height: 40,
            aovs: scene.aovs.len(),
            spp: 48,
            squared: Vec::new(),
            adaptive: true,
        };
        let back = checkpoint::read(&path, stamp, shape).unwrap();
        // After band 5 every pilot row is done, but the pass is not yet marked complete.
        assert_eq!(back.pilot.as_ref().unwrap().complete, stop_after > 5);
        let resumed = render_resumable(
            &scene,
            &options,
            &request,
            &silent,
            Resumable {
                film: Some(back.film),
                rows_done: back.rows_done,
                pilot: back.pilot,
                ..Resumable::default()
            },
        );
        assert!(resumed.finished());
        assert_eq!(resumed.film.sample_counts, whole.film.sample_counts);
        for (a, b) in resumed.film.planes.iter().zip(&whole.film.planes) {
            assert!(a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits()));
        }
        assert_eq!(
            resumed.stats.samples + part.stats.samples,
            whole.stats.samples,
            "stopped after band {stop_after}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Tiles of an adaptive render join into the whole frame exactly: a crop takes pilot
/// samples of the pixels around it, so its edge pixels see the neighbours the whole
/// frame's do.
#[test]
fn adaptive_tiles_equal_the_whole_frame() {
    use lightpath::film::PixelWindow;
    use lightpath::integrator::{render_frame, FrameRequest};
    let src = lightpath::load_source("cornell").unwrap();
    let mut desc = src.parse().unwrap();
    adaptive(0.2, 256)(&mut desc);
    desc.render.resolution = [20, 16];
    let scene = Scene::build(&desc, &aov::assemble(vec![])).unwrap();
    let options = RenderOptions {
        spp: 256,
        first_sample: 0,
    };
    let silent = lightpath::progress::Silent;
    let (whole, _) = render_frame(&scene, &options, &FrameRequest::whole(&scene), &silent);
    let tile = PixelWindow {
        x0: 7,
        y0: 5,
        x1: 13,
        y1: 11,
    };
    let request = FrameRequest {
        window: tile,
        mattes: None,
    };
    let (part, _) = render_frame(&scene, &options, &request, &silent);
    let counts = whole.sample_counts.as_ref().unwrap();
    for y in 0..tile.height() {
        for x in 0..tile.width() {
            let i = ((tile.y0 + y) * 20 + tile.x0 + x) as usize;
            let j = (y * tile.width() + x) as usize;
            assert_eq!(
                part.sample_counts.as_ref().unwrap()[j],
                counts[i],
                "({x}, {y})"
            );
            for (a, b) in part.planes.iter().zip(&whole.planes) {
                assert_eq!(a[j].to_bits(), b[i].to_bits(), "({x}, {y})");
            }
        }
    }
}

/// A lower threshold takes more samples and gives a less noisy image; the mean stays
/// that of a fixed-count render within noise.
#[test]
fn a_lower_noise_threshold_takes_more_samples() {
    let src = lightpath::load_source("cornell").unwrap();
    let total = |t: f32| {
        let (_, film) = run(&src, adaptive(t, 128), vec![]);
        film.sample_counts
            .unwrap()
            .iter()
            .map(|&n| n as u64)
            .sum::<u64>()
    };
    let (coarse, fine) = (total(0.2), total(0.02));
    assert!(coarse < fine, "{coarse} vs {fine}");
    let (_, a) = run(&src, adaptive(0.05, 128), vec![]);
    let (_, b) = run(
        &src,
        |d| {
            d.render.resolution = [32, 32];
            d.render.spp = 64;
            d.render.seed = 3;
        },
        vec![],
    );
    agree_within_noise(&pixels(&a, 0), &pixels(&b, 0), 32);
}

/// Adaptive sample ranges merge by their per-pixel counts: the merged film's pixel is
/// the count-weighted mean of the parts (the sum of their samples over the sum of their
/// counts), which is what `lightpath merge` computes from the `sampleCount` channels.
#[test]
fn adaptive_ranges_merge_by_per_pixel_counts() {
    let src = lightpath::load_source("cornell").unwrap();
    let mut desc = src.parse().unwrap();
    adaptive(0.05, 32)(&mut desc);
    let scene = Scene::build(&desc, &aov::assemble(vec![])).unwrap();
    let part = |first_sample| {
        render(
            &scene,
            &RenderOptions {
                spp: 32,
                first_sample,
            },
        )
        .0
    };
    let (a, b) = (part(0), part(32));
    let mut merged = a.clone();
    merged.merge(&b).unwrap();
    let (ca, cb) = (
        a.sample_counts.as_ref().unwrap(),
        b.sample_counts.as_ref().unwrap(),
    );
    for y in 0..a.height {
        for x in 0..a.width {
            let i = (y * a.width + x) as usize;
            let (na, nb) = (ca[i] as f32, cb[i] as f32);
            let expected = (a.pixel(0, x, y) * na + b.pixel(0, x, y) * nb) / (na + nb);
            let got = merged.pixel(0, x, y);
            assert!((got - expected).abs().max_element() <= 1e-5 * expected.max_element().max(1.0));
        }
    }
}

/// Determinism for the default sampler and selection, sample ranges included: two
/// halves of a Sobol render merged equal the whole render (each number depends only on
/// seed, pixel, sample index and dimension).
#[test]
fn sobol_ranges_merge_into_the_whole_render() {
    let src = lightpath::load_source("cornell").unwrap();
    let mut desc = src.parse().unwrap();
    desc.render.resolution = [16, 16];
    assert_eq!(desc.render.sampler, SamplerKind::Sobol);
    let scene = Scene::build(&desc, &aov::assemble(vec![])).unwrap();
    let range = |spp, first_sample| render(&scene, &RenderOptions { spp, first_sample }).0;
    let whole = range(8, 0);
    let mut a = range(4, 0);
    a.merge(&range(4, 4)).unwrap();
    for (x, y) in whole.planes.concat().iter().zip(&a.planes.concat()) {
        assert!((x - y).abs() <= 1e-5 * x.abs().max(1.0));
    }
}

/// A floor lit only by a small ball: as a glowing object or as a sphere light of the
/// same radiance.
fn small_ball_scene(emitter: &str) -> lightpath::Source {
    let text = format!(
        r#"
[camera]
position = [0, 1.2, 2.5]
look_at = [0, 0, 0]
fov = 40
[render]
max_depth = 2
clamp_indirect = 0
[materials.white]
type = "diffuse"
albedo = [0.8, 0.8, 0.8]
[[objects]]
name = "floor"
shape = "quad"
material = "white"
corners = [[-1, 0, 1], [1, 0, 1], [1, 0, -1], [-1, 0, -1]]
{emitter}
"#
    );
    lightpath::Source {
        name: "ball.toml".into(),
        text,
        dir: Default::default(),
    }
}

/// A glowing object is light-sampled with MIS, as a light is: the floor it lights is no
/// noisier than under a sphere light of the same size and radiance (within 1.5×; found by
/// BSDF rays alone it was 105× noisier here) and as bright, while its events stay
/// those of a glow: `C<RD>O` takes all of it, `C<RD>L` and `shadows` AOVs nothing, and
/// `unoccluded` the same as the plain AOV.
#[test]
fn a_glowing_object_is_light_sampled_under_its_own_events() {
    let glow = small_ball_scene(
        "[[objects]]\nname = \"ball\"\nshape = \"sphere\"\ncenter = [0, 0.25, 0]\n\
         radius = 0.08\nemission = [4, 4, 4]\n",
    );
    let light = small_ball_scene(
        "[[lights]]\ntype = \"sphere\"\nname = \"ball\"\ncenter = [0, 0.25, 0]\n\
         radius = 0.08\nradiance = [4, 4, 4]\n",
    );
    let aovs = || {
        vec![
            AovSpec::new("viaGlow", "C<RD>O"),
            AovSpec::new("viaLight", "C<RD>L"),
            AovSpec::new("shadowed", "shadows;C<RD>[LO]"),
            AovSpec::new("unoccluded", "unoccluded;C<RD>[LO]"),
        ]
    };
    let (res, spp) = (32usize, 8);
    let render_seed = |src: &lightpath::Source, seed| {
        run(
            src,
            |d| {
                d.render.resolution = [res as u32, res as u32];
                d.render.spp = spp;
                d.render.seed = seed;
            },
            aovs(),
        )
    };
    let lum = |v: Vec3A| (0.2126 * v.x + 0.7152 * v.y + 0.0722 * v.z) as f64;
    // Per-pixel standard deviation of the floor's luminance (AOV `k`) from two seeds.
    let noise = |a: &[Vec3A], b: &[Vec3A]| {
        let var: f64 = a
            .iter()
            .zip(b)
            .map(|(x, y)| (lum(*x) - lum(*y)).powi(2))
            .sum::<f64>()
            / (2.0 * a.len() as f64);
        var.sqrt()
    };
    let (scene, g1) = render_seed(&glow, 1);
    let (_, g2) = render_seed(&glow, 2);
    let (lscene, l1) = render_seed(&light, 1);
    let (_, l2) = render_seed(&light, 2);
    let (glow_k, light_k) = (index(&scene, "viaGlow"), index(&lscene, "viaLight"));
    let g = |f: &Film, k| pixels(f, k);
    let noise_glow = noise(&g(&g1, glow_k), &g(&g2, glow_k));
    let noise_light = noise(&g(&l1, light_k), &g(&l2, light_k));
    let ratio = noise_glow / noise_light;
    eprintln!(
        "noise at {spp} spp: glow {noise_glow:.4}, sphere light {noise_light:.4} ({ratio:.3}x)"
    );
    assert!(
        ratio < 1.5,
        "glow noise {noise_glow} vs sphere light {noise_light}: {ratio}x"
    );
    agree_within_noise(&g(&g1, glow_k), &g(&l1, light_k), res);
    assert_eq!(scene.lights.len(), 1, "the ball is sampled");
    assert_eq!(
        scene.first_glow_light, 0,
        "and it is a glow, not a declared light"
    );
    let total = |f: &Film, k| g(f, k).iter().map(|v| lum(*v)).sum::<f64>();
    assert!(total(&g1, glow_k) > 0.0);
    assert_eq!(total(&g1, index(&scene, "viaLight")), 0.0);
    assert_eq!(total(&g1, index(&scene, "shadowed")), 0.0);
    let unoccluded = index(&scene, "unoccluded");
    for (a, b) in g(&g1, unoccluded).iter().zip(g(&g1, glow_k)) {
        assert!((*a - b).abs().max_element() <= 1e-6 * b.max_element().max(1.0));
    }
}

/// Fireflies as `benches/sampling/fireflies.py` counts them (docs/performance.md,
/// "Fireflies on the built-in `cornell`"): a pixel whose beauty luminance exceeds 3× the
/// median of its 8 neighbours' is an outlier, isolated when no neighbour is one; border
/// pixels are not counted.
fn isolated_fireflies(film: &Film) -> usize {
    let (w, h) = (film.width as usize, film.height as usize);
    let lum: Vec<f32> = pixels(film, 0)
        .iter()
        .map(|v| 0.2126 * v.x + 0.7152 * v.y + 0.0722 * v.z)
        .collect();
    let mut outlier = vec![false; w * h];
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let mut around = [0.0f32; 8];
            let mut n = 0;
            for (dx, dy) in (-1i32..=1).flat_map(|dy| (-1i32..=1).map(move |dx| (dx, dy))) {
                if (dx, dy) != (0, 0) {
                    around[n] = lum[(y as i32 + dy) as usize * w + (x as i32 + dx) as usize];
                    n += 1;
                }
            }
            around.sort_by(f32::total_cmp);
            // numpy's median of 8 values: the mean of the middle two.
            let median = 0.5 * (around[3] + around[4]);
            outlier[y * w + x] = lum[y * w + x] > 3.0 * median;
        }
    }
    (1..h - 1)
        .flat_map(|y| (1..w - 1).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            outlier[y * w + x]
                && (y - 1..=y + 1)
                    .flat_map(|yy| (x - 1..=x + 1).map(move |xx| (xx, yy)))
                    .all(|(xx, yy)| (xx, yy) == (x, y) || !outlier[yy * w + xx])
        })
        .count()
}

/// The built-in `cornell` at its defaults (320², 32 spp, `clamp_indirect = 10`,
/// `regularize = 0.8`) has fewer than 30 isolated fireflies: issue 11's target, measured
/// at 20–26 over seeds 0–3 (docs/performance.md). Without the clamp and regularisation the
/// same render has ~480, so the count is what the settings buy, not luck.
#[test]
fn cornell_at_its_defaults_has_few_fireflies() {
    let src = lightpath::load_source("cornell").unwrap();
    let (_, film) = run(&src, |_| {}, vec![]);
    assert_eq!((film.width, film.height, film.spp), (320, 320, 32));
    let n = isolated_fireflies(&film);
    assert!(
        n < 30,
        "{n} isolated fireflies (issue 11's target: under 30)"
    );
    let (_, raw) = run(
        &src,
        |d| {
            d.render.clamp_indirect = 0.0;
            d.render.regularize = 0.0;
        },
        vec![],
    );
    let m = isolated_fireflies(&raw);
    assert!(m > 3 * n, "unclamped, unregularised: {m} against {n}");
}
