//! Properties of rendered images that users rely on: AOV partitions sum to beauty,
//! furnaces conserve energy, the guide's example expressions select what they say, and
//! renders are deterministic.

use crate::common::{index, mean_and_se};
use glam::Vec3A;
use lightpath::aov::{self, AovSpec};
use lightpath::film::Film;
use lightpath::{render, RenderOptions, Scene, Source};

fn source(name: &str, text: &str) -> Source {
    Source {
        name: name.into(),
        text: text.into(),
        dir: Default::default(),
    }
}

/// Renders `src` at a small size with the given AOVs (beauty first).
fn render_aovs(
    src: &Source,
    res: u32,
    spp: u32,
    max_depth: Option<u32>,
    extra: Vec<AovSpec>,
) -> (Scene, Film) {
    let mut desc = src.parse().unwrap();
    desc.render.resolution = [res, res];
    desc.render.spp = spp;
    if let Some(d) = max_depth {
        desc.render.max_depth = d;
    }
    let scene = Scene::build(&desc, &aov::assemble(extra)).unwrap();
    let (film, _) = render(
        &scene,
        &RenderOptions {
            spp,
            first_sample: 0,
        },
    );
    (scene, film)
}

fn cornell() -> Source {
    lightpath::load_source("cornell").unwrap()
}

/// Max over pixels of |Σ parts − beauty| / max(beauty, floor); infinite when any pixel's
/// error is not a number (`f32::max` skips a NaN, so a NaN image would otherwise pass).
fn partition_error(scene: &Scene, film: &Film, parts: &[&str]) -> f32 {
    let beauty = index(scene, "beauty");
    let ids: Vec<usize> = parts.iter().map(|p| index(scene, p)).collect();
    let mut worst = 0.0f32;
    for y in 0..film.height {
        for x in 0..film.width {
            let b = film.pixel(beauty, x, y);
            let sum: Vec3A = ids.iter().map(|&k| film.pixel(k, x, y)).sum();
            let err = (sum - b).abs() / b.abs().max(Vec3A::splat(1e-3));
            if !err.is_finite() {
                return f32::INFINITY;
            }
            worst = worst.max(err.max_element());
        }
    }
    worst
}

/// Rounding of a pixel's value: `spp` samples summed in f32, each off by at most a few
/// ulps (relative `f32::EPSILON` per addition), then divided; for values near 1.
fn f32_slack(spp: u32) -> f64 {
    spp as f64 * f32::EPSILON as f64
}

/// K standard errors: a test of an unbiased estimate fails by chance once in ~1.7 million
/// runs at 5 (a normal tail), while any bias above a few standard errors shows.
const K: f64 = 5.0;

#[test]
fn the_partition_check_fails_on_a_nan_pixel() {
    let (scene, mut film) = render_aovs(&cornell(), 8, 1, None, aov::standard());
    assert!(partition_error(&scene, &film, &lpe::BEAUTY_PARTITION) <= 1e-5);
    // A NaN in one part of one pixel, then in the beauty of another: both must fail.
    let part = index(&scene, lpe::BEAUTY_PARTITION[0]);
    let mut nan_part = film.clone();
    nan_part.planes[3 * part][5] = f32::NAN;
    let err = partition_error(&scene, &nan_part, &lpe::BEAUTY_PARTITION);
    assert!(err.is_nan() || err > 1e-5, "a NaN part passed: {err}");
    film.planes[0][9] = f32::NAN;
    let err = partition_error(&scene, &film, &lpe::BEAUTY_PARTITION);
    assert!(err.is_nan() || err > 1e-5, "a NaN beauty passed: {err}");
}

#[test]
fn standard_partition_sums_to_beauty() {
    let (scene, film) = render_aovs(&cornell(), 40, 4, None, aov::standard());
    let err = partition_error(&scene, &film, &lpe::BEAUTY_PARTITION);
    assert!(err <= 1e-5, "standard partition is off by {err}");
    // And it is not trivially zero: direct diffuse carries light.
    let dd = index(&scene, "directDiffuse");
    let total: f32 = film.channel(dd, 0).iter().sum();
    assert!(total > 1.0);
}

#[test]
fn light_groups_and_bounces_sum_to_beauty() {
    let mut extra = aov::light_group_split(&["fill".into(), "key".into()]);
    extra.extend([
        AovSpec::new("b0", "C[<L.>O]"),
        AovSpec::new("b1", "C[DS]{1}[<L.>O]"),
        AovSpec::new("b2", "C[DS]{2}[<L.>O]"),
        AovSpec::new("b3", "C[DS]{3,}[<L.>O]"),
    ]);
    let (scene, film) = render_aovs(&cornell(), 32, 4, None, extra);
    let err = partition_error(
        &scene,
        &film,
        &["beauty_key", "beauty_fill", "beauty__default"],
    );
    assert!(err <= 1e-5, "light groups off by {err}");
    let err = partition_error(&scene, &film, &["b0", "b1", "b2", "b3"]);
    assert!(err <= 1e-5, "bounces off by {err}");
    // The glowing ball has no light group: it lands in the default group.
    let default: f32 = film
        .channel(index(&scene, "beauty__default"), 0)
        .iter()
        .sum();
    assert!(default > 0.0);
}

const FURNACE: &str = r#"
[camera]
position = [0, 0, 4]
look_at = [0, 0, 0]
fov = 30
[render]
max_depth = 64
rr_depth = 5
[materials.m]
type = "MATERIAL"
albedo = [1, 1, 1]
ior = 1.5
[[objects]]
name = "ball"
shape = "sphere"
material = "m"
radius = 1
[[lights]]
type = "dome"
radiance = [1, 1, 1]
"#;

/// Mean and standard error of the beauty's red channel over pixels where the ball is seen.
fn furnace(material: &str, spp: u32) -> (f64, f64) {
    let text = FURNACE.replace("MATERIAL", material).replace(
        "albedo = [1, 1, 1]\nior = 1.5",
        if material == "diffuse" {
            "albedo = [1, 1, 1]"
        } else {
            "ior = 1.5"
        },
    );
    let (_, film) = render_aovs(&source("furnace", &text), 24, spp, None, vec![]);
    let r = film.channel(0, 0);
    let a = film.alpha();
    let vals: Vec<f64> = r
        .iter()
        .zip(&a)
        .filter(|(_, a)| **a > 0.999)
        .map(|(v, _)| *v as f64)
        .collect();
    assert!(vals.len() > 100);
    mean_and_se(&vals)
}

#[test]
fn white_diffuse_sphere_in_a_furnace_returns_the_dome() {
    let (mean, se) = furnace("diffuse", 16);
    // Unbiased estimate of exactly 1: K standard errors plus the f32 rounding of a pixel.
    assert!(
        (mean - 1.0).abs() <= K * se + f32_slack(16),
        "mean {mean} ± {se}"
    );
}

#[test]
fn glass_sphere_in_a_furnace_neither_gains_nor_loses_energy() {
    let (mean, se) = furnace("dielectric", 16);
    // A lossless sphere reflects or transmits all it receives; paths cut at max_depth 64
    // lose (Fresnel reflectance inside)^64, far below the noise.
    assert!(
        (mean - 1.0).abs() <= K * se + f32_slack(16),
        "mean {mean} ± {se}"
    );
}

#[test]
fn guide_examples_select_what_they_say() {
    let extra = vec![
        AovSpec::new("cube", "C<[RT][DS]'scatterCube'>.*[<L.>O]"),
        AovSpec::new("seesCube", "nothruput;overwrite;C<RU2'scatterCube'>L"),
        AovSpec::new("cubeToWall", "C<..'scatterCube'>+<..'rightWall'>[<L.>O]"),
    ];
    let (scene, film) = render_aovs(&cornell(), 48, 8, None, extra);
    let (cube, sees, wall) = (
        index(&scene, "cube"),
        index(&scene, "seesCube"),
        index(&scene, "cubeToWall"),
    );
    let mut lit_on_cube = 0;
    for y in 0..film.height {
        for x in 0..film.width {
            let c = film.pixel(cube, x, y);
            if film.pixel(sees, x, y) == Vec3A::ZERO {
                assert_eq!(c, Vec3A::ZERO, "cube AOV is lit off the cube at {x},{y}");
            } else if c.max_element() > 0.0 {
                lit_on_cube += 1;
            }
        }
    }
    assert!(lit_on_cube > 50, "the cube AOV is empty");
    let sum: Vec3A = (0..3)
        .map(|c| film.channel(wall, c).iter().sum::<f32>())
        .collect::<Vec<_>>()
        .try_into()
        .map(|a: [f32; 3]| Vec3A::from(a))
        .unwrap();
    assert!(
        sum.y > 2.0 * sum.x && sum.y > 2.0 * sum.z && sum.y > 0.0,
        "light from the cube via the right wall should be green: {sum}"
    );
}

const TWO_ROOMS: &str = include_str!("../../../../scenes/two-rooms.toml");

#[test]
fn a_light_group_is_zero_where_only_the_other_light_reaches() {
    let extra = vec![
        AovSpec::new("key", "C<.>*[<L.'key'>O]"),
        AovSpec::new("fill", "C<.>*[<L.'fill'>O]"),
    ];
    // Depth 2: direct light only, so the divider blocks each light from the other half.
    let (scene, film) = render_aovs(&source("two rooms", TWO_ROOMS), 32, 4, Some(2), extra);
    let (key, fill) = (index(&scene, "key"), index(&scene, "fill"));
    let (mut key_left, mut fill_right) = (0.0, 0.0);
    for y in 4..film.height - 4 {
        for x in 0..film.width {
            // Image x grows with world x: the key light is on the left half.
            if x < film.width / 2 - 2 {
                assert_eq!(
                    film.pixel(fill, x, y),
                    Vec3A::ZERO,
                    "fill reaches the key side at {x},{y}"
                );
                key_left += film.pixel(key, x, y).x;
            } else if x > film.width / 2 + 2 {
                assert_eq!(
                    film.pixel(key, x, y),
                    Vec3A::ZERO,
                    "key reaches the fill side at {x},{y}"
                );
                fill_right += film.pixel(fill, x, y).x;
            }
        }
    }
    assert!(key_left > 0.0 && fill_right > 0.0);
}

#[test]
fn renders_are_bit_identical_for_any_thread_count() {
    let src = cornell();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            render_aovs(&src, 24, 3, None, aov::standard())
                .1
                .planes
                .concat()
        })
    };
    let one = run(1);
    let two = run(2);
    assert!(one
        .iter()
        .zip(&two)
        .all(|(a, b)| a.to_bits() == b.to_bits()));
}

#[test]
fn sample_ranges_merge_into_the_whole_render() {
    let src = cornell();
    let mut desc = src.parse().unwrap();
    desc.render.resolution = [16, 16];
    let scene = Scene::build(&desc, &aov::assemble(vec![])).unwrap();
    let (whole, _) = render(
        &scene,
        &RenderOptions {
            spp: 4,
            first_sample: 0,
        },
    );
    let (mut a, _) = render(
        &scene,
        &RenderOptions {
            spp: 2,
            first_sample: 0,
        },
    );
    let (b, _) = render(
        &scene,
        &RenderOptions {
            spp: 2,
            first_sample: 2,
        },
    );
    a.merge(&b).unwrap();
    for (x, y) in whole.planes.concat().iter().zip(&a.planes.concat()) {
        assert!((x - y).abs() <= 1e-5 * x.abs().max(1.0));
    }
}

#[test]
fn exr_round_trips_channels_values_and_expressions() {
    let (scene, film) = render_aovs(
        &cornell(),
        12,
        2,
        None,
        vec![AovSpec::new("key", "C<.>*[<L.'key'>O]")],
    );
    let dir = std::env::temp_dir().join(format!("lightpath-exr-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("t.exr");
    lightpath::output::write_exr(
        &path,
        film.clone(),
        &scene.aovs,
        vec![],
        Default::default(),
        &[],
    )
    .unwrap();
    let back = lightpath::output::read_exr(&path).unwrap();
    let mut names: Vec<&str> = back.channels.iter().map(|(n, _)| n.as_str()).collect();
    names.sort();
    assert_eq!(names, ["A", "B", "G", "R", "key.B", "key.G", "key.R"]);
    assert_eq!(back.channel("R").unwrap(), film.channel(0, 0).as_slice());
    assert_eq!(
        back.channel("key.G").unwrap(),
        film.channel(1, 1).as_slice()
    );
    let aovs = back.aovs();
    assert!(
        aovs.contains(&("key".to_string(), "C<.>*[<L.'key'>O]".to_string())),
        "{aovs:?}"
    );
    // Every compression is lossless.
    for name in ["none", "rle", "zips", "zip", "piz"] {
        let compression = lightpath::output::ExrCompression::parse(name).unwrap();
        let options = lightpath::output::ExrOptions {
            half: false,
            compression,
        };
        lightpath::output::write_exr(&path, film.clone(), &scene.aovs, vec![], options, &[])
            .unwrap();
        let again = lightpath::output::read_exr(&path).unwrap();
        for (channel, values) in &back.channels {
            assert_eq!(
                again.channel(channel),
                Some(values.as_slice()),
                "{name} {channel}"
            );
        }
    }
    // Nothing but the final file is left behind.
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(leftovers.len(), 1);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn scene_errors_name_the_file_line_and_what_was_expected() {
    let text =
        "[camera]\nfov = 40\n\n[[objects]]\nshape = \"sphere\"\nmaterial = \"nope\"\nradius = 1\n";
    let src = source("bad.toml", text);
    let desc = src.parse().unwrap();
    let err = Scene::build(&desc, &aov::assemble(vec![])).err().unwrap();
    assert_eq!((err.file.as_str(), err.line), ("bad.toml", 6), "{err}");
    assert!(err.message.contains("unknown material 'nope'"), "{err}");

    let src = source("typo.toml", "[render]\nspp = \"many\"\n");
    let err = src.parse().unwrap_err();
    assert_eq!(err.line, 2, "{err}");

    let src = source("shape.toml", "[[objects]]\nshape = \"cone\"\n");
    let err = src
        .parse()
        .and_then(|desc| Scene::build(&desc, &aov::assemble(vec![])))
        .err()
        .unwrap();
    assert!(
        err.to_string()
            .starts_with("shape.toml:2:9: unknown shape 'cone'"),
        "{err}"
    );

    for (text, line, what) in [
        (
            "[camera]\nposition = [0, 0, 1]\nlook_at = [0, 0, 1]\n",
            1,
            "look_at must differ",
        ),
        ("\n[camera]\nfov = 0\n", 2, "fov must be between"),
        (
            "[[objects]]\nshape = \"sphere\"\nradius = -1\n",
            1,
            "radius must be positive",
        ),
        (
            "[materials.g]\ntype = \"dielectric\"\nior = 0\n",
            1,
            "ior must be positive",
        ),
    ] {
        let src = source("v.toml", text);
        let desc = src.parse().unwrap();
        let err = Scene::build(&desc, &aov::assemble(vec![])).err().unwrap();
        assert!(err.message.contains(what), "{err}");
        assert_eq!(err.line, line, "{err}");
    }

    let bad_aov = aov::assemble(vec![AovSpec::new("x", "C<RD")]);
    let src = cornell();
    let err = Scene::build(&src.parse().unwrap(), &bad_aov).err().unwrap();
    assert!(
        err.message.contains("AOV 'x'") && err.message.contains('^'),
        "{err}"
    );
}

/// Mean beauty over the pixels where the plane is seen head-on (the image centre).
fn centre_mean(text: &str, spp: u32) -> Vec3A {
    let (_, film) = render_aovs(&source("lights", text), 16, spp, Some(2), vec![]);
    let mut sum = Vec3A::ZERO;
    let mut n = 0.0;
    for y in 6..10 {
        for x in 6..10 {
            sum += film.pixel(0, x, y);
            n += 1.0;
        }
    }
    sum / n
}

const PLANE: &str = r#"
[camera]
position = [0, 0, 5]
look_at = [0, 0, 0]
fov = 2
[materials.grey]
type = "diffuse"
albedo = [0.5, 0.5, 0.5]
[[objects]]
name = "plane"
shape = "rectangle"
material = "grey"
scale = 10
"#;

#[test]
fn delta_lights_match_their_analytic_radiance() {
    // A Lambertian plane of albedo ρ under irradiance E reflects ρE/π.
    let rho_over_pi = 0.5 / std::f32::consts::PI;
    // Point light of intensity 4 at distance 2 along the normal: E = I / d² = 1.
    let point = format!(
        "{PLANE}\n[[lights]]\ntype = \"point\"\nposition = [0, 0, 2]\nintensity = [4, 4, 4]\n"
    );
    let l = centre_mean(&point, 4);
    assert!((l.x - rho_over_pi).abs() < 1e-3 * rho_over_pi, "point: {l}");
    // Distant light of irradiance 2 at 60° from the normal: E = 2 cos 60° = 1.
    let distant = format!(
        "{PLANE}\n[[lights]]\ntype = \"distant\"\ndirection = [0, {}, -0.5]\nirradiance = [2, 2, 2]\n",
        -(0.75f32.sqrt())
    );
    let l = centre_mean(&distant, 4);
    assert!(
        (l.x - rho_over_pi).abs() < 1e-3 * rho_over_pi,
        "distant: {l}"
    );
    // A spot light is a point light inside its cone and dark outside it.
    let spot = format!("{PLANE}\n[[lights]]\ntype = \"spot\"\nposition = [0, 0, 2]\ndirection = [0, 0, -1]\ncone_angle = 40\nintensity = [4, 4, 4]\n");
    let l = centre_mean(&spot, 4);
    assert!((l.x - rho_over_pi).abs() < 1e-3 * rho_over_pi, "spot: {l}");
    let away = format!("{PLANE}\n[[lights]]\ntype = \"spot\"\nposition = [0, 0, 2]\ndirection = [0, 0, 1]\nintensity = [4, 4, 4]\n");
    assert_eq!(centre_mean(&away, 2), Vec3A::ZERO);
}

#[test]
fn area_lights_match_their_analytic_irradiance() {
    // A disk of radiance L and radius r at height h over a point: E = π L r² / (h² + r²).
    let (radiance, r, h) = (3.0f32, 1.0f32, 2.0f32);
    let expected =
        0.5 / std::f32::consts::PI * std::f32::consts::PI * radiance * r * r / (h * h + r * r);
    let disk = format!(
        "{PLANE}\n[[lights]]\ntype = \"disk\"\nradiance = [{radiance}, {radiance}, {radiance}]\nrotate = [180, 0, 0]\ntranslate = [0, 0, {h}]\nsegments = 256\ncamera_visible = false\n"
    );
    let l = centre_mean(&disk, 256);
    // 256 spp × 16 pixels of MIS-weighted samples: a 2 % band is over five standard errors.
    assert!(
        (l.x - expected).abs() < 0.02 * expected,
        "disk: {l} vs {expected}"
    );
    // A sphere light of radius r at distance d subtends sin²θ = r²/d²: E = π L r² / d².
    let sphere = format!(
        "{PLANE}\n[[lights]]\ntype = \"sphere\"\nradiance = [{radiance}, {radiance}, {radiance}]\ncenter = [0, 0, 3]\nradius = 0.5\ncamera_visible = false\n"
    );
    let expected = 0.5 * radiance * 0.25 / 9.0;
    let l = centre_mean(&sphere, 256);
    assert!(
        (l.x - expected).abs() < 0.02 * expected,
        "sphere: {l} vs {expected}"
    );
}

/// A cylinder light over a plane lights it as the integral over its side says: the
/// irradiance at the centre, ∫ L cos θr cos θl / d² dA by a 2000 × 2000 midpoint rule,
/// times ρ/π, is the rendered centre within 5 standard errors of its 16 pixels (their
/// sample sequences are independent). Light samples and BSDF rays that hit the tube are
/// weighed by MIS, so a pdf that disagreed between them would show here.
#[test]
fn a_cylinder_light_matches_its_integrated_irradiance() {
    let (radiance, r, half, h) = (4.0f64, 0.2f64, 1.0f64, 1.0f64);
    let n = 2000;
    let mut irradiance = 0.0;
    for i in 0..n {
        let phi = (i as f64 + 0.5) / n as f64 * std::f64::consts::TAU;
        let (sin, cos) = phi.sin_cos();
        for j in 0..n {
            let x = ((j as f64 + 0.5) / n as f64 * 2.0 - 1.0) * half;
            // The point of the side and its outward normal (0, sin, cos); the receiver
            // is the origin, facing +z.
            let q = [x, r * sin, h + r * cos];
            let d2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2];
            let cos_l = -(q[1] * sin + q[2] * cos) / d2.sqrt();
            let cos_r = q[2] / d2.sqrt();
            if cos_l > 0.0 && cos_r > 0.0 {
                irradiance += radiance * cos_l * cos_r / d2;
            }
        }
    }
    irradiance *= (std::f64::consts::TAU / n as f64) * r * (2.0 * half / n as f64);
    let expected = 0.5 / std::f64::consts::PI * irradiance;
    let text = format!(
        "{PLANE}\n[[lights]]\ntype = \"cylinder\"\nradius = {r}\nlength = {}\n\
         radiance = [{radiance}, {radiance}, {radiance}]\ntranslate = [0, 0, {h}]\n\
         camera_visible = false\n",
        2.0 * half
    );
    let (_, film) = render_aovs(&source("cylinder", &text), 16, 256, Some(2), vec![]);
    let centre: Vec<f64> = (6..10)
        .flat_map(|y| (6..10).map(move |x| (x, y)))
        .map(|(x, y)| film.pixel(0, x, y).x as f64)
        .collect();
    let mean = centre.iter().sum::<f64>() / 16.0;
    let var = centre.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / 15.0;
    let se = (var / 16.0).sqrt();
    assert!(se > 0.0 && se < 0.05 * expected, "{mean} ± {se}");
    assert!(
        (mean - expected).abs() <= 5.0 * se,
        "cylinder: {mean} ± {se} vs {expected}"
    );
}

/// A floor, a box that shadows part of it, and a cylinder light in group `tube` above
/// them, turned and stretched by its transform; nothing else emits.
const CYLINDER_ROOM: &str = r#"
[camera]
position = [0, 3, 4]
look_at = [0, 0.3, 0]
fov = 45
[materials.white]
type = "diffuse"
albedo = [0.8, 0.8, 0.8]
[[objects]]
name = "floor"
shape = "rectangle"
rotate = [-90, 0, 0]
scale = 6
material = "white"
[[objects]]
name = "box"
shape = "cube"
scale = 0.4
translate = [0.3, 0.4, 0.2]
material = "white"
[[lights]]
type = "cylinder"
groups = ["tube"]
radius = 0.05
length = 1.0
scale = [1.5, 1, 1]
rotate = [0, 30, 10]
translate = [0, 1.3, 0]
radiance = [8, 7, 6]
"#;

/// A cylinder light's events carry its groups: the AOV of paths ending at a `'tube'`
/// light (its `L`, or its `O` seen directly) equals the beauty of a scene lit only by it,
/// and so does its part of the light-group split, while the default part is black.
#[test]
fn a_cylinder_lights_events_carry_its_groups() {
    let mut lit = AovSpec::new("lit", "C<.>*[<L.>O]");
    lit.split_light_groups = true;
    let extra = vec![AovSpec::new("tube", "C<.>*[<L.'tube'>O'tube']"), lit];
    let (scene, film) = render_aovs(&source("cylinder", CYLINDER_ROOM), 24, 4, None, extra);
    assert_eq!(scene.light_groups, ["tube"]);
    for part in ["tube", "lit_tube"] {
        let err = partition_error(&scene, &film, &[part]);
        assert!(err <= 1e-5, "{part} is off the beauty by {err}");
    }
    let beauty: f32 = film.channel(index(&scene, "beauty"), 1).iter().sum();
    assert!(beauty > 0.0, "the cylinder lights the room");
    let default = index(&scene, "lit__default");
    assert!((0..3).all(|c| film.channel(default, c).iter().all(|&v| v == 0.0)));
}

/// The lights-only test finds a cylinder light: plain + shadows = unoccluded pixel by
/// pixel, and the box's shadow shows in `shadows`.
#[test]
fn a_cylinder_lights_shadows_sum_to_unoccluded() {
    for expr in ["C<RD>[<L.>O]", "C.*<L.>"] {
        let (scene, film) = render_aovs(
            &source("cylinder", CYLINDER_ROOM),
            16,
            4,
            None,
            shadow_aovs(expr),
        );
        let err = shadow_identity_error(&scene, &film, expr);
        assert!(err <= 1e-5, "{expr}: off by {err} of the peak");
        let shadows: f32 = film.channel(index(&scene, "shadows"), 1).iter().sum();
        assert!(shadows > 0.0, "{expr}: the box casts a shadow");
    }
}

#[test]
fn an_environment_map_dome_lights_a_furnace() {
    // A constant EXR dome of radiance 1 around a white sphere: the furnace again, through
    // the importance-sampled map.
    let dir = std::env::temp_dir().join(format!("lightpath-env-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (w, h) = (32usize, 16usize);
    let planes = ["R", "G", "B", "A"].map(|c| (c.to_string(), vec![1.0f32; w * h]));
    lightpath::output::write_channels(
        &dir.join("sky.exr"),
        w,
        h,
        planes.to_vec(),
        &[],
        Default::default(),
    )
    .unwrap();
    let text = FURNACE
        .replace("MATERIAL", "diffuse")
        .replace("albedo = [1, 1, 1]\nior = 1.5", "albedo = [1, 1, 1]")
        .replace("radiance = [1, 1, 1]", "map = \"sky.exr\"");
    let src = Source {
        name: "env".into(),
        text,
        dir: dir.clone(),
    };
    let (_, film) = render_aovs(&src, 16, 16, None, vec![]);
    let r = film.channel(0, 0);
    let a = film.alpha();
    let seen: Vec<f64> = r
        .iter()
        .zip(&a)
        .filter(|(_, a)| **a > 0.999)
        .map(|(v, _)| *v as f64)
        .collect();
    assert!(seen.len() > 100);
    // The estimate of exactly 1 over the pixels that see the ball, K standard errors.
    let (mean, se) = mean_and_se(&seen);
    assert!(
        (mean - 1.0).abs() <= K * se + f32_slack(16),
        "{mean} ± {se}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn obj_meshes_load_relative_to_the_scene_file() {
    let dir = std::env::temp_dir().join(format!("lightpath-obj-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("quad.obj"),
        "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\nf 1//1 3//1 4//1\n",
    )
    .unwrap();
    let scene = format!(
        "{}\n[[lights]]\ntype = \"point\"\nposition = [0, 0, 2]\nintensity = [4, 4, 4]\n",
        PLANE.replace(
            "shape = \"rectangle\"",
            "shape = \"obj\"\nfile = \"quad.obj\""
        )
    );
    std::fs::write(dir.join("scene.toml"), &scene).unwrap();
    let src = Source::from_file(&dir.join("scene.toml")).unwrap();
    let (_, film) = render_aovs(&src, 16, 2, Some(2), vec![]);
    let l = film.pixel(0, 8, 8);
    let expected = 0.5 / std::f32::consts::PI;
    assert!((l.x - expected).abs() < 1e-3 * expected, "{l}");
    // A missing file is an error that names it.
    std::fs::write(
        dir.join("bad.toml"),
        scene.replace("quad.obj", "missing.obj"),
    )
    .unwrap();
    let src = Source::from_file(&dir.join("bad.toml")).unwrap();
    let err = src
        .parse()
        .and_then(|desc| Scene::build(&desc, &aov::assemble(vec![])))
        .err()
        .unwrap();
    assert!(
        err.to_string().contains("missing.obj") && err.line > 0,
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Max over pixels and channels of |plain + shadows − unoccluded|, relative to the peak
/// of `unoccluded`.
fn shadow_identity_error(scene: &Scene, film: &Film, expr: &str) -> f32 {
    let (p, s, u) = (
        index(scene, "plain"),
        index(scene, "shadows"),
        index(scene, "unoccluded"),
    );
    let (mut worst, mut peak) = (0.0f32, 0.0f32);
    for y in 0..film.height {
        for x in 0..film.width {
            let un = film.pixel(u, x, y);
            let sum = film.pixel(p, x, y) + film.pixel(s, x, y);
            worst = worst.max((sum - un).abs().max_element());
            peak = peak.max(un.max_element());
        }
    }
    assert!(peak > 0.0, "{expr}: unoccluded is black");
    worst / peak
}

fn shadow_aovs(expr: &str) -> Vec<AovSpec> {
    vec![
        AovSpec::new("plain", expr),
        AovSpec::new("shadows", format!("shadows;{expr}")),
        AovSpec::new("unoccluded", format!("unoccluded;{expr}")),
    ]
}

#[test]
fn plain_and_shadows_sum_to_unoccluded_pixel_by_pixel() {
    // One estimator for the three: every light sample and every BSDF ray's light lands in
    // exactly one of plain and shadows, and in unoccluded, with the same MIS weight, so
    // only float rounding of the sums separates them.
    for expr in ["C<RD>[<L.>O]", "C.*<L.>"] {
        let (scene, film) = render_aovs(&cornell(), 16, 2, None, shadow_aovs(expr));
        let err = shadow_identity_error(&scene, &film, expr);
        assert!(err <= 1e-5, "{expr}: off by {err} of the peak");
        let shadows: f32 = film.channel(index(&scene, "shadows"), 0).iter().sum();
        assert!(shadows > 0.0, "{expr}: cornell has shadows");
    }
}

/// Behind a delta lobe with nothing in the way, `unoccluded` sees exactly what the plain
/// AOV sees, whatever the light: a dome (which no surface carries), a sphere and a
/// rectangle light, seen in a mirror and through glass.
#[test]
fn unoccluded_behind_mirror_and_glass_equals_plain_for_every_light() {
    let lights = [
        "[[lights]]\ntype = \"dome\"\nradiance = [0.7, 0.7, 0.7]",
        "[[lights]]\ntype = \"sphere\"\ncenter = [0, 0, 6]\nradius = 2\nradiance = [3, 3, 3]",
        "[[lights]]\ntype = \"rect\"\ntranslate = [0, 0, 6]\nscale = 4\nrotate = [180, 0, 0]\ntwo_sided = true\nradiance = [3, 3, 3]",
    ];
    // The camera looks down -z at a surface filling the view; lights sit behind the
    // camera (+z), where the mirror sends its rays, or beyond the glass (-z).
    let surfaces = [
        (
            "mirror",
            "type = \"conductor\"\nf0 = [0.9, 0.9, 0.9]",
            "C<RS>[<L.>O]",
        ),
        (
            "glass",
            "type = \"dielectric\"\nior = 1.5",
            "C<TS><TS>[<L.>O]",
        ),
    ];
    for (kind, material, expr) in surfaces {
        for light in lights {
            let light = if kind == "glass" {
                light
                    .replace("[0, 0, 6]", "[0, 0, -6]")
                    .replace("[180, 0, 0]", "[0, 0, 0]")
            } else {
                light.to_string()
            };
            let text = format!(
                "[camera]\nposition = [0, 0, 3]\nlook_at = [0, 0, 0]\nfov = 30\n\n\
                 [materials.m]\n{material}\n\n\
                 [[objects]]\nshape = \"cube\"\nscale = [4, 4, 0.2]\nmaterial = \"m\"\n\n{light}\n"
            );
            let extra = vec![
                AovSpec::new("plain", expr),
                AovSpec::new("unocc", format!("unoccluded;{expr}")),
            ];
            let (scene, film) = render_aovs(&source(kind, &text), 8, 2, None, extra);
            let (plain, unocc) = (index(&scene, "plain"), index(&scene, "unocc"));
            let total: f32 = film.channel(plain, 1).iter().sum();
            assert!(
                total > 0.0,
                "{kind} with {light}: the plain AOV sees the light"
            );
            for c in 0..3 {
                let (a, b) = (film.channel(plain, c), film.channel(unocc, c));
                for (p, u) in a.iter().zip(b) {
                    assert!(
                        (p - u).abs() <= 1e-6 * p.abs().max(1.0),
                        "{kind} with {light}: unoccluded {u} vs plain {p}"
                    );
                }
            }
        }
    }
}

/// Where nothing can cast a shadow — a flat floor under one rectangle light, nothing
/// else — the shadow matte is exactly clear and `unoccluded` equals the plain AOV: the
/// three are one estimator, not two that agree on average.
#[test]
fn shadows_are_exactly_zero_where_nothing_occludes() {
    let text = "[camera]\nposition = [0, 3, 3]\nlook_at = [0, 0, 0]\nfov = 40\n\n\
        [materials.white]\ntype = \"diffuse\"\nalbedo = [0.8, 0.8, 0.8]\n\n\
        [[objects]]\nshape = \"rectangle\"\nrotate = [-90, 0, 0]\nscale = 10\nmaterial = \"white\"\n\n\
        [[lights]]\ntype = \"rect\"\ntranslate = [0, 2, 0]\nrotate = [90, 0, 0]\ntwo_sided = true\nradiance = [5, 5, 5]\n";
    for expr in ["C<RD>[<L.>O]", "C<RD>+[<L.>O]"] {
        let (scene, film) = render_aovs(&source("floor", text), 12, 4, None, shadow_aovs(expr));
        let (plain, shadows, unocc) = (
            index(&scene, "plain"),
            index(&scene, "shadows"),
            index(&scene, "unoccluded"),
        );
        assert!(
            film.channel(plain, 1).iter().sum::<f32>() > 0.0,
            "{expr}: the floor is lit"
        );
        for c in 0..3 {
            assert!(
                film.channel(shadows, c).iter().all(|&v| v == 0.0),
                "{expr}: a shadow where nothing occludes"
            );
            assert_eq!(film.channel(plain, c), film.channel(unocc, c), "{expr}");
        }
    }
}

#[test]
fn a_rotated_dome_turns_its_map() {
    // A map bright (radiance 1) where +Y is and black below the horizon, around the grey
    // plane facing +Z: unturned, half the plane's hemisphere is lit (ρ/2 = 0.25); turned
    // 90° about X the bright half faces the plane (ρ = 0.5), turned −90° it faces away (0);
    // turned about Y nothing changes.
    let dir = std::env::temp_dir().join(format!("lightpath-dome-rot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (w, h) = (32usize, 16usize);
    let half: Vec<f32> = (0..w * h)
        .map(|i| if i / w < h / 2 { 1.0 } else { 0.0 })
        .collect();
    let planes = ["R", "G", "B", "A"].map(|c| (c.to_string(), half.clone()));
    lightpath::output::write_channels(
        &dir.join("half.exr"),
        w,
        h,
        planes.to_vec(),
        &[],
        Default::default(),
    )
    .unwrap();
    let mean = |placement: &str| {
        let text = format!(
            "{PLANE}\n[[lights]]\ntype = \"dome\"\nmap = \"half.exr\"\ncamera_visible = false\n{placement}\n"
        );
        let src = Source {
            name: "dome".into(),
            text,
            dir: dir.clone(),
        };
        let (_, film) = render_aovs(&src, 16, 64, Some(2), vec![]);
        let mut sum = 0.0;
        for y in 6..10 {
            for x in 6..10 {
                sum += film.pixel(0, x, y).x;
            }
        }
        sum / 16.0
    };
    // 64 spp × 16 pixels of MIS-weighted dome samples: 3 % is many standard errors.
    for (placement, expected) in [
        ("", 0.25),
        ("rotate = [0, 70, 0]", 0.25),
        ("rotate = [90, 0, 0]", 0.5),
        ("matrix = [1,0,0,0, 0,0,-1,0, 0,1,0,0, 0,0,0,1]", 0.5),
    ] {
        let m = mean(placement);
        assert!((m - expected).abs() < 0.03 * expected, "{placement}: {m}");
    }
    let away = mean("rotate = [-90, 0, 0]");
    assert!(away.abs() < 1e-3, "{away}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn objects_naming_one_obj_file_are_instances_of_one_stored_mesh() {
    // A cube OBJ placed twice: through one file both objects are instances of one mesh;
    // through two copies of the file they are two flat meshes. Same picture, same
    // per-object AOV.
    let dir = std::env::temp_dir().join(format!("lightpath-inst-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cube = "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n\
                f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 4 8 7\nf 4 7 3\nf 1 5 8\nf 1 8 4\nf 2 3 7\nf 2 7 6\n";
    std::fs::write(dir.join("cube.obj"), cube).unwrap();
    std::fs::write(dir.join("copy.obj"), cube).unwrap();
    let scene = |second: &str| {
        format!(
            r#"
[camera]
position = [0, 1, 6]
look_at = [0, 0, 0]
fov = 45
[materials.white]
type = "diffuse"
albedo = [0.7, 0.7, 0.7]
[[objects]]
name = "floor"
shape = "rectangle"
material = "white"
rotate = [-90, 0, 0]
translate = [0, -1, 0]
scale = 5
[[objects]]
name = "left"
shape = "obj"
file = "cube.obj"
material = "white"
rotate = [0, 30, 0]
scale = [0.5, 0.8, 0.5]
translate = [-1.2, -0.2, 0]
[[objects]]
name = "right"
shape = "obj"
file = "{second}"
material = "white"
rotate = [20, -40, 10]
scale = -0.6
translate = [1.2, 0, 0.3]
[[lights]]
type = "rect"
radiance = [6, 6, 6]
rotate = [90, 0, 0]
translate = [0, 3, 0]
"#
        )
    };
    let render = |second: &str| {
        let src = Source {
            name: "inst".into(),
            text: scene(second),
            dir: dir.clone(),
        };
        let extra = vec![AovSpec::new("left", "C<RD'left'>[<L.>O]")];
        render_aovs(&src, 32, 8, None, extra)
    };
    let (shared, a) = render("cube.obj");
    let (flat, b) = render("copy.obj");
    assert_eq!(shared.accel.instances().len(), 2);
    assert_eq!(shared.accel.meshes().len(), 1);
    assert!(flat.accel.instances().is_empty());
    for aov in [0, index(&shared, "left")] {
        let (mut diff, mut sum) = (0.0f64, 0.0f64);
        for y in 0..32 {
            for x in 0..32 {
                let (p, q) = (a.pixel(aov, x, y), b.pixel(aov, x, y));
                diff += (p - q).abs().element_sum() as f64;
                sum += q.element_sum() as f64;
            }
        }
        // The paths are the same; the hit points differ by float rounding only (a path
        // that rounds differently diverges, hence not exactly zero).
        assert!(
            sum > 0.0 && diff <= 1e-2 * sum,
            "AOV {aov}: {diff} of {sum}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A room lit by a sky dome through one window, seen from inside, with the window given
/// as the dome's portal and without: the image means agree over 16 seeds (light sampled
/// through the portal, and BSDF rays that find the sky elsewhere: nothing is lost), and
/// a sample through the portal is far less noisy. A wide window: BSDF rays find the sky
/// through it often, so their weight against the portal's samples counts.
#[test]
fn a_dome_sampled_through_its_portal_converges_and_is_cleaner() {
    let room = |portal: bool| {
        let portals = if portal {
            "portals = [[[1, -0.6, -0.8], [1, -0.6, 0.8], [1, 0.6, 0.8], [1, 0.6, -0.8]]]\n"
        } else {
            ""
        };
        format!(
            r#"
[camera]
position = [-0.8, 0.2, 0.9]
look_at = [0.4, -0.4, -0.6]
fov = 70
[render]
max_depth = 5
[materials.white]
type = "diffuse"
albedo = [0.7, 0.7, 0.7]
[[objects]]
shape = "quad"
material = "white"
corners = [[-1, -1, 1], [1, -1, 1], [1, -1, -1], [-1, -1, -1]]
[[objects]]
shape = "quad"
material = "white"
corners = [[-1, 1, -1], [1, 1, -1], [1, 1, 1], [-1, 1, 1]]
[[objects]]
shape = "quad"
material = "white"
corners = [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1]]
[[objects]]
shape = "quad"
material = "white"
corners = [[1, -1, 1], [-1, -1, 1], [-1, 1, 1], [1, 1, 1]]
[[objects]]
shape = "quad"
material = "white"
corners = [[-1, -1, 1], [-1, -1, -1], [-1, 1, -1], [-1, 1, 1]]
[[objects]]
shape = "quad"
material = "white"
corners = [[1, -1, -1], [1, -1, 1], [1, -0.6, 1], [1, -0.6, -1]]
[[objects]]
shape = "quad"
material = "white"
corners = [[1, 0.6, -1], [1, 0.6, 1], [1, 1, 1], [1, 1, -1]]
[[objects]]
shape = "quad"
material = "white"
corners = [[1, -0.6, -1], [1, -0.6, -0.8], [1, 0.6, -0.8], [1, 0.6, -1]]
[[objects]]
shape = "quad"
material = "white"
corners = [[1, -0.6, 0.8], [1, -0.6, 1], [1, 0.6, 1], [1, 0.6, 0.8]]
[[lights]]
type = "dome"
radiance = [2, 2, 2]
camera_visible = false
{portals}"#
        )
    };
    let runs = |portal: bool| -> Vec<f64> {
        (1..=16u64)
            .map(|seed| {
                let mut desc = source("portal.toml", &room(portal)).parse().unwrap();
                desc.render.resolution = [16, 16];
                desc.render.seed = seed;
                let scene = Scene::build(&desc, &aov::assemble(vec![])).unwrap();
                // Path tracing without the portal needs many samples to be a reference
                // that finds a tenth of a percent.
                let options = RenderOptions {
                    spp: if portal { 64 } else { 1024 },
                    first_sample: 0,
                };
                crate::common::image_mean(&render(&scene, &options).0, 0)
            })
            .collect()
    };
    let (plain, ported) = (runs(false), runs(true));
    let (m0, se0) = mean_and_se(&plain);
    let (m1, se1) = mean_and_se(&ported);
    assert!(m0 > 0.01, "the room is lit: {m0}");
    assert!(
        (m0 - m1).abs() <= 5.0 * (se0 * se0 + se1 * se1).sqrt(),
        "without the portal {m0} ± {se0}, with it {m1} ± {se1}"
    );
    // The variance of a sample, with over without: measured 0.04.
    let per_sample = (se1 * se1 * 64.0) / (se0 * se0 * 1024.0);
    assert!(
        per_sample < 0.2,
        "a sample's variance with the portal over without: {per_sample}"
    );
}

/// A portal whose corners do not make a flat parallelogram is a scene error that names
/// the file, the light and the portal, not a panic or a silently wrong light; so are
/// more portals than a light sample should look at.
#[test]
fn a_bent_portal_is_a_scene_error() {
    let text = "[[lights]]\ntype = \"dome\"\n\
                portals = [[[1, 0, 0], [1, 0, 1], [1, 1, 1], [1, 1, 0]], \
                [[0, 0, 0], [1, 0, 0], [1, 1, 0.3], [0, 1, 0]]]\n";
    let desc = source("bent.toml", text).parse().unwrap();
    let err = match Scene::build(&desc, &aov::assemble(vec![])) {
        Ok(_) => panic!("a bent portal was accepted"),
        Err(e) => e.to_string(),
    };
    assert!(
        err.contains("bent.toml") && err.contains("portal 2"),
        "{err}"
    );
    let many = format!(
        "[[lights]]\ntype = \"dome\"\nportals = [{}]\n",
        vec!["[[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]"; 257].join(", ")
    );
    let desc = source("many.toml", &many).parse().unwrap();
    match Scene::build(&desc, &aov::assemble(vec![])) {
        Ok(_) => panic!("257 portals were accepted"),
        Err(e) => assert!(e.to_string().contains("at most 256"), "{e}"),
    }
}
