//! Path guiding (`--guiding on|off|auto`, crates/lightpath/src/guiding/): it changes
//! sampling densities only, so the image converges to the same mean, every partition
//! still sums to the beauty, and renders stay deterministic across thread counts and
//! sample ranges; `auto` renders exactly as `on` or as `off`, as its pilot decides.

use crate::common::{assert_sums_to_beauty, image_mean, index, mean_and_se, render_spp};
use glam::Vec3A;
use lightpath::aov::{self, AovSpec};
use lightpath::guiding::GuidingMode;
use lightpath::{Scene, Source};

/// A room lit only around a baffle: a lamp under the ceiling faces it, a plate below the
/// lamp hides it from the floor, so the floor sees light after a bounce (the kind of
/// scene guiding is for), plus a glass ball and a glossy plastic block (lobes guiding
/// leaves to BSDF sampling, and a mixture of both).
const ROOM: &str = r#"
[camera]
position = [0, 0, 3.5]
look_at = [0, 0, 0]
fov = 40
[render]
max_depth = 6
[materials.white]
type = "diffuse"
albedo = [0.8, 0.8, 0.8]
[materials.red]
type = "diffuse"
albedo = [0.8, 0.2, 0.2]
[materials.glass]
type = "dielectric"
ior = 1.5
[materials.plastic]
type = "plastic"
albedo = [0.2, 0.4, 0.8]
roughness = 0.2
[[objects]]
name = "floor"
shape = "quad"
material = "white"
corners = [[-1, -1, 1], [1, -1, 1], [1, -1, -1], [-1, -1, -1]]
[[objects]]
name = "ceiling"
shape = "quad"
material = "white"
corners = [[-1, 1, -1], [1, 1, -1], [1, 1, 1], [-1, 1, 1]]
[[objects]]
name = "back"
shape = "quad"
material = "white"
corners = [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1]]
[[objects]]
name = "left"
shape = "quad"
material = "red"
corners = [[-1, -1, 1], [-1, -1, -1], [-1, 1, -1], [-1, 1, 1]]
[[objects]]
name = "plate"
shape = "quad"
material = "white"
corners = [[-0.4, 0.6, -0.4], [0.4, 0.6, -0.4], [0.4, 0.6, 0.4], [-0.4, 0.6, 0.4]]
[[objects]]
name = "ball"
shape = "sphere"
material = "glass"
center = [0.4, -0.6, 0.2]
radius = 0.35
[[objects]]
name = "block"
shape = "sphere"
material = "plastic"
center = [-0.4, -0.7, -0.2]
radius = 0.3
[[lights]]
type = "quad"
name = "lamp"
radiance = [30, 30, 30]
corners = [[-0.2, 0.62, -0.2], [-0.2, 0.62, 0.2], [0.2, 0.62, 0.2], [0.2, 0.62, -0.2]]
"#;

/// The room with guiding on (`passes` > 0) or off.
fn scene(res: u32, passes: u32, seed: u64, extra: Vec<AovSpec>) -> Scene {
    let mode = if passes > 0 {
        GuidingMode::On
    } else {
        GuidingMode::Off
    };
    scene_in(ROOM, res, mode, passes, seed, extra)
}

fn scene_in(
    text: &str,
    res: u32,
    mode: GuidingMode,
    passes: u32,
    seed: u64,
    extra: Vec<AovSpec>,
) -> Scene {
    let src = Source {
        name: "room.toml".into(),
        text: text.into(),
        dir: Default::default(),
    };
    let mut desc = src.parse().unwrap();
    desc.render.resolution = [res, res];
    desc.render.guiding = mode;
    desc.render.guiding_passes = passes;
    desc.render.seed = seed;
    Scene::build(&desc, &aov::assemble(extra)).unwrap()
}

/// The image means of independent renders (seeds 1…runs; a guided render trains its
/// own tree from its seed) agree with and without guiding within 5 standard errors of
/// their difference, estimated from the spread of the runs themselves.
#[test]
fn guided_renders_converge_to_the_unguided_mean() {
    let runs = 8;
    let means = |passes: u32| -> Vec<f64> {
        (1..=runs)
            .map(|seed| image_mean(&render_spp(&scene(48, passes, seed, vec![]), 4, 0), 0))
            .collect()
    };
    let (plain, se_plain) = mean_and_se(&means(0));
    let (guided, se_guided) = mean_and_se(&means(5));
    let se = (se_plain * se_plain + se_guided * se_guided).sqrt();
    assert!(plain > 0.01, "the room is lit: {plain}");
    assert!(
        (plain - guided).abs() <= 5.0 * se,
        "unguided {plain} ± {se_plain}, guided {guided} ± {se_guided}"
    );
    // The renders did guide (a tree whose leaves all chose BSDF sampling is dropped;
    // at 48² five passes give the room a few cells that guide).
    let guided = render_spp(&scene(48, 5, 1, vec![]), 2, 0).planes;
    assert!(guided != render_spp(&scene(48, 0, 1, vec![]), 2, 0).planes);
}

/// Guiding changes how lobes and directions are sampled, never which events a path
/// takes: the standard partition and per-bounce AOVs still sum to the beauty.
#[test]
fn guided_partitions_sum_to_beauty() {
    let mut extra = aov::standard();
    extra.extend([
        AovSpec::new("b1", "C[DS]{1}[<L.>O]"),
        AovSpec::new("b2", "C[DS]{2}[<L.>O]"),
        AovSpec::new("b3", "C[DS]{3,}[<L.>O]"),
        AovSpec::new("b0", "C[<L.>O]"),
    ]);
    let scene = scene(48, 5, 0, extra);
    let film = render_spp(&scene, 4, 0);
    for parts in [&lpe::BEAUTY_PARTITION[..], &["b0", "b1", "b2", "b3"][..]] {
        assert_sums_to_beauty(&scene, &film, parts);
    }
}

/// The tree is trained from integer sums: one thread and two give the same bits, on
/// and auto.
#[test]
fn guided_renders_are_bit_identical_for_any_thread_count() {
    let run_in = |threads: usize, mode: GuidingMode| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let s = scene_in(ROOM, 48, mode, 5, 3, vec![]);
        pool.install(|| render_spp(&s, 3, 0).planes.concat())
    };
    let auto = run_in(1, GuidingMode::Auto);
    assert_eq!(auto, run_in(2, GuidingMode::Auto));
    // The fog's guide too (its medium vertices' records and their free flights).
    let fog_in = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let s = scene_in(FOG_ROOM, 32, GuidingMode::On, 5, 3, vec![]);
        pool.install(|| render_spp(&s, 2, 0).planes.concat())
    };
    let fog = fog_in(1);
    assert!(fog
        .iter()
        .zip(&fog_in(2))
        .all(|(a, b)| a.to_bits() == b.to_bits()));
    // The independent sampler checks (in debug builds) that a guided fog vertex asks
    // for its numbers in the layout's order.
    let independent = FOG_ROOM.replace("[render]\n", "[render]\nsampler = \"independent\"\n");
    assert_ne!(independent, FOG_ROOM);
    let s = scene_in(&independent, 16, GuidingMode::On, 5, 3, vec![]);
    assert!(render_spp(&s, 2, 0)
        .planes
        .concat()
        .iter()
        .all(|v| v.is_finite()));
    let run = |threads: usize| run_in(threads, GuidingMode::On);
    let one = run(1);
    let two = run(2);
    assert_eq!(one.len(), two.len());
    assert!(one
        .iter()
        .zip(&two)
        .all(|(a, b)| a.to_bits() == b.to_bits()));
    // And guiding did change the render (the setting is not ignored).
    let plain = render_spp(&scene(48, 0, 3, vec![]), 3, 0).planes.concat();
    assert!(plain.iter().zip(&one).any(|(a, b)| a != b));
}

/// Farm parts (sample ranges) each train the same tree and take the same auto
/// decision, so they merge into the whole.
#[test]
fn guided_sample_ranges_merge_into_the_whole_render() {
    for (text, mode) in [
        (ROOM, GuidingMode::On),
        (ROOM, GuidingMode::Auto),
        (FOG_ROOM, GuidingMode::On),
    ] {
        let s = scene_in(text, 48, mode, 5, 5, vec![]);
        let whole = render_spp(&s, 4, 0);
        let mut a = render_spp(&s, 2, 0);
        a.merge(&render_spp(&s, 2, 2)).unwrap();
        for (x, y) in whole.planes.concat().iter().zip(&a.planes.concat()) {
            assert!(
                (x - y).abs() <= 1e-5 * x.abs().max(1.0),
                "{mode:?}: {x} {y}"
            );
        }
    }
}

/// `auto` renders bit for bit as `on` or as `off` (its pilot is `on`'s first two
/// passes), in the room and in the room lit directly (no plate under the lamp): it
/// never makes an image of its own, so `on`'s and `off`'s tests cover its mean.
#[test]
fn auto_renders_exactly_as_on_or_as_off() {
    let lit = ROOM.replace(
        "corners = [[-0.4, 0.6, -0.4], [0.4, 0.6, -0.4], [0.4, 0.6, 0.4], [-0.4, 0.6, 0.4]]",
        "corners = [[5, 5, 5], [5.1, 5, 5], [5.1, 5, 5.1], [5, 5, 5.1]]",
    );
    assert_ne!(lit, ROOM);
    for text in [ROOM, lit.as_str()] {
        for seed in [1, 2] {
            let render_in = |mode| render_spp(&scene_in(text, 48, mode, 5, seed, vec![]), 2, 0);
            let auto = render_in(GuidingMode::Auto).planes;
            let on = render_in(GuidingMode::On).planes;
            let off = render_in(GuidingMode::Off).planes;
            assert!(auto == on || auto == off, "seed {seed}");
        }
    }
}

/// A fog-filled room lit only past a plate under its lamp, whose surfaces are all
/// glossy metal (which guiding leaves to BSDF sampling): whatever guiding changes here,
/// it changes at scattering vertices in the fog.
const FOG_ROOM: &str = r#"
[camera]
position = [0, 0, 3.5]
look_at = [0, 0, 0]
fov = 40
[render]
max_depth = 6
atmosphere = "fog"
[media.fog]
sigma_a = [0.05, 0.05, 0.05]
sigma_s = [0.8, 0.6, 0.5]
g = 0.3
[materials.metal]
type = "conductor"
f0 = [0.8, 0.8, 0.8]
roughness = 0.4
[[objects]]
name = "floor"
shape = "quad"
material = "metal"
corners = [[-1, -1, 1], [1, -1, 1], [1, -1, -1], [-1, -1, -1]]
[[objects]]
name = "ceiling"
shape = "quad"
material = "metal"
corners = [[-1, 1, -1], [1, 1, -1], [1, 1, 1], [-1, 1, 1]]
[[objects]]
name = "back"
shape = "quad"
material = "metal"
corners = [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1]]
[[objects]]
name = "plate"
shape = "quad"
material = "metal"
corners = [[-0.4, 0.6, -0.4], [0.4, 0.6, -0.4], [0.4, 0.6, 0.4], [-0.4, 0.6, 0.4]]
[[lights]]
type = "quad"
name = "lamp"
radiance = [30, 30, 30]
corners = [[-0.2, 0.62, -0.2], [-0.2, 0.62, 0.2], [0.2, 0.62, 0.2], [0.2, 0.62, -0.2]]
"#;

/// Guiding in media: the fog's scattering vertices sample their own leaves (the metal
/// room guides nowhere else), the image converges to the unguided mean within 5
/// standard errors over independent seeds, and the `V` partition still sums to the
/// beauty.
#[test]
fn guided_media_converge_to_the_unguided_mean_and_partitions_sum() {
    let fog = |mode, seed, extra| scene_in(FOG_ROOM, 32, mode, 5, seed, extra);
    // The render did guide, and only the fog could have.
    let guided = render_spp(&fog(GuidingMode::On, 1, vec![]), 2, 0).planes;
    assert!(guided != render_spp(&fog(GuidingMode::Off, 1, vec![]), 2, 0).planes);

    let runs = 8;
    let means = |mode| -> Vec<f64> {
        (1..=runs)
            .map(|seed| image_mean(&render_spp(&fog(mode, seed, vec![]), 4, 0), 0))
            .collect()
    };
    let (plain, se_plain) = mean_and_se(&means(GuidingMode::Off));
    let (guided, se_guided) = mean_and_se(&means(GuidingMode::On));
    let se = (se_plain * se_plain + se_guided * se_guided).sqrt();
    assert!(plain > 0.01, "the fog is lit: {plain}");
    assert!(
        (plain - guided).abs() <= 5.0 * se,
        "unguided {plain} ± {se_plain}, guided {guided} ± {se_guided}"
    );

    let parts = [
        AovSpec::new("surface_first", "C<[RT].>.*[<L.>O]"),
        AovSpec::new("fog_first", "CV.*[<L.>O]"),
        AovSpec::new("seen", "C[<L.>O]"),
    ];
    let scene = fog(GuidingMode::On, 2, parts.to_vec());
    let film = render_spp(&scene, 4, 0);
    let beauty = index(&scene, "beauty");
    let ids: Vec<usize> = parts.iter().map(|p| index(&scene, &p.name)).collect();
    let mut fog_light = 0.0;
    for y in 0..film.height {
        for x in 0..film.width {
            let b = film.pixel(beauty, x, y);
            let sum: Vec3A = ids.iter().map(|&k| film.pixel(k, x, y)).sum();
            let err = (sum - b).abs() / b.abs().max(Vec3A::splat(1e-3));
            assert!(err.max_element() <= 1e-5, "off by {err} at {x},{y}");
            fog_light += film.pixel(ids[1], x, y).x;
        }
    }
    assert!(fog_light > 0.0);
}
