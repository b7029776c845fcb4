//! Glint sampling (integrator/glints.rs): a chrome ball, a glass ball and a lacquered
//! one (a smooth coat over a diffuse base) under two suns, one behind the camera (glints
//! in every ball) and one behind the balls (seen through the glass, and through the
//! glass in the chrome), and a small sphere light (a bulb, glinting in the chrome).

use crate::common::{assert_sums_to_beauty, image_mean, index, mean_and_se, render_spp};
use lightpath::aov::{self, AovSpec};
use lightpath::{Scene, Source};

/// The balls and suns, each sun's disc `angle` degrees across; `glints` on or off;
/// the camera's lens `aperture` wide (0: a pinhole).
fn balls(angle: f32, glints: &str, aperture: f32) -> String {
    format!(
        r#"
[camera]
position = [0, 0, 5]
look_at = [0, 0, 0]
fov = 40
aperture_radius = {aperture}
[render]
max_depth = 8
glint_sampling = "{glints}"
[materials.chrome]
type = "conductor"
f0 = [0.9, 0.9, 0.9]
roughness = 0
[materials.glass]
type = "dielectric"
ior = 1.5
[materials.lacquer]
type = "plastic"
albedo = [0.6, 0.1, 0.1]
roughness = 0
[[objects]]
shape = "sphere"
material = "chrome"
center = [-0.5, 0, 0]
radius = 1
[[objects]]
shape = "sphere"
material = "glass"
center = [1.0, 0.3, 1.2]
radius = 0.4
[[objects]]
name = "lacquered"
shape = "sphere"
material = "lacquer"
center = [1.1, -0.7, 0.6]
radius = 0.35
[[lights]]
type = "distant"
name = "front"
direction = [-0.3, -0.4, -1]
irradiance = [1, 1, 1]
angle = {angle}
[[lights]]
type = "distant"
name = "back"
direction = [0.15, -0.1, 1]
irradiance = [1, 0.8, 0.6]
angle = {angle}
[[lights]]
type = "sphere"
name = "bulb"
center = [0.8, 1.6, 3.0]
radius = 0.04
radiance = [300, 300, 300]
"#
    )
}

/// The balls at 24 × 16 pixels through a pinhole with AOVs `extra`, seeded `seed`.
fn scene(angle: f32, glints: &str, seed: u64, extra: Vec<AovSpec>) -> Scene {
    scene_through(0.0, angle, glints, seed, extra)
}

/// [`scene`] through a lens `aperture` wide.
fn scene_through(aperture: f32, angle: f32, glints: &str, seed: u64, extra: Vec<AovSpec>) -> Scene {
    let src = Source {
        name: "balls.toml".into(),
        text: balls(angle, glints, aperture),
        dir: Default::default(),
    };
    let mut desc = src.parse().unwrap();
    desc.render.resolution = [24, 16];
    desc.render.seed = seed;
    Scene::build(&desc, &aov::assemble(extra)).unwrap()
}

/// The glint AOVs: the front sun in any ball (one reflection) and in the lacquered one's
/// coat (its one delta event beside a diffuse one), the back sun through
/// the glass ball, and every path through delta events alone to a light (with the back
/// sun's grazing glints at the chrome ball's rim, which Newton from a pixel centre on
/// the ball often cannot reach, so camera samples make most of them).
const GLINT_AOVS: [(&str, &str); 5] = [
    ("front", "C<RS><L.'front'>"),
    // A sphere light's glints: drawn as points on it, not directions.
    ("bulb", "C<RS><L.'bulb'>"),
    ("lacquer", "C<RS'lacquered'><L.'front'>"),
    ("through", "C<TS><TS><L.'back'>"),
    ("all", "C<.S>+L"),
];

/// Each seed's image mean of each of `GLINT_AOVS` through a lens `aperture` wide.
fn glint_means(aperture: f32, glints: &str, spp: u32, seeds: u64) -> Vec<Vec<f64>> {
    let aovs = || {
        GLINT_AOVS
            .iter()
            .map(|(n, d)| AovSpec::new(*n, *d))
            .collect()
    };
    let mut means = vec![Vec::new(); GLINT_AOVS.len()];
    for seed in 1..=seeds {
        let scene = scene_through(aperture, 3.0, glints, seed, aovs());
        let film = render_spp(&scene, spp, 0);
        for (k, (name, _)) in GLINT_AOVS.iter().enumerate() {
            means[k].push(image_mean(&film, index(&scene, name)));
        }
    }
    means
}

/// Glints sampled in film space converge to what camera samples alone make, for glints
/// of one reflection and of chains through glass, and with far less noise per sample.
#[test]
fn glint_sampling_converges_to_camera_sampling_with_less_noise() {
    assert_glints_converge(0.0, 100.0);
}

/// Through a thin lens (the balls a little out of focus) glints are sampled for each
/// lens position: the same convergence (measured gains ~6·10⁶×, 3·10⁵×, 5·10⁴× and 2·10⁴×;
/// asserted ≥ 10×, as a lens may blur a glint past the filter's reach, where camera
/// samples make it alone).
#[test]
fn glint_sampling_converges_through_a_lens() {
    assert_glints_converge(0.04, 10.0);
}

/// Glint sampling against camera samples alone through a lens `aperture` wide: the
/// means agree, and glint sampling's variance per sample is at least `least_gain` times
/// less (but for `all`).
fn assert_glints_converge(aperture: f32, least_gain: f64) {
    let (seeds, spp_on, spp_off) = (16, 16, 512);
    let on = glint_means(aperture, "on", spp_on, seeds);
    let off = glint_means(aperture, "off", spp_off, seeds);
    for (k, (name, _)) in GLINT_AOVS.iter().enumerate() {
        let (m_on, se_on) = mean_and_se(&on[k]);
        let (m_off, se_off) = mean_and_se(&off[k]);
        // The lacquer's coat reflects 4 %: its glints' mean is ~9·10⁻⁵.
        assert!(m_off > 5e-5, "{name}: the scene shows glints ({m_off})");
        let tol = 4.0 * (se_on * se_on + se_off * se_off).sqrt();
        assert!(
            (m_on - m_off).abs() <= tol,
            "{name}: glint sampling {m_on} ± {se_on}, camera samples {m_off} ± {se_off}"
        );
        let per_sample = |se: f64, spp: u32| se * se * spp as f64;
        let gain = per_sample(se_off, spp_off) / per_sample(se_on, spp_on);
        // Variance per sample, measured: ~2·10⁶× less (front), ~5·10⁵× (bulb), ~2·10⁵×
        // (lacquer) and ~6·10³× (through); not asserted for `all`, whose rim glints
        // camera samples make.
        if *name != "all" {
            assert!(
                gain >= least_gain,
                "{name}: {gain}× less variance per sample"
            );
        }
    }
}

/// With glints sampled, the standard AOVs still partition the beauty, pixel by pixel.
#[test]
fn sampled_glints_keep_the_partition() {
    let scene = scene(0.53, "on", 1, aov::standard());
    let film = render_spp(&scene, 8, 0);
    assert_sums_to_beauty(&scene, &film, &lpe::BEAUTY_PARTITION);
    // The glints themselves are in it.
    assert!(image_mean(&film, index(&scene, "beauty")) > 0.0);
}

/// Glint sampling's numbers depend on the pixel and sample alone: one thread and two
/// give the same bits, and sample ranges merge into the whole frame.
#[test]
fn sampled_glints_are_deterministic_and_merge() {
    let scene = scene(0.53, "on", 3, vec![]);
    let run_in = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| render_spp(&scene, 8, 0).planes.concat())
    };
    let one = run_in(1);
    assert!(one
        .iter()
        .zip(&run_in(2))
        .all(|(a, b)| a.to_bits() == b.to_bits()));
    let mut parts = render_spp(&scene, 3, 0);
    parts.merge(&render_spp(&scene, 5, 3)).unwrap();
    for (x, y) in one.iter().zip(&parts.planes.concat()) {
        assert!((x - y).abs() <= 1e-5 * x.abs().max(1.0), "{x} {y}");
    }
    let off = render_spp(&scene_off(), 8, 0).planes.concat();
    assert!(off != one, "the setting is not ignored");
}

fn scene_off() -> Scene {
    scene(0.53, "off", 3, vec![])
}
