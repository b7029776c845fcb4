//! Random-walk subsurface in whole renders (OpenPBR's `subsurface_*`): its one `TD3`
//! event per entry keeps the standard partition and the bounce partition summing to
//! beauty, direct subsurface is `C<TD3>[<L.>O]`, and a white subsurface ball in a white
//! furnace neither gains nor loses light.

use crate::common::index;
use glam::Vec3A;
use lightpath::aov::{self, AovSpec};
use lightpath::film::Film;
use lightpath::{render, RenderOptions, Scene, Source};

fn render_aovs(text: &str, res: u32, spp: u32, extra: Vec<AovSpec>) -> (Scene, Film) {
    let src = Source {
        name: "subsurface".into(),
        text: text.into(),
        dir: Default::default(),
    };
    let mut desc = src.parse().unwrap();
    desc.render.resolution = [res, res];
    desc.render.spp = spp;
    let scene = Scene::build(&desc, &aov::assemble(extra)).unwrap();
    let options = RenderOptions {
        spp,
        first_sample: 0,
    };
    let (film, _) = render(&scene, &options);
    (scene, film)
}

/// Max over pixels of |Σ parts − whole| / max(whole, 1e-3).
fn partition_error(scene: &Scene, film: &Film, whole: &str, parts: &[&str]) -> f32 {
    let whole = index(scene, whole);
    let ids: Vec<usize> = parts.iter().map(|p| index(scene, p)).collect();
    let mut worst = 0.0f32;
    for y in 0..film.height {
        for x in 0..film.width {
            let b = film.pixel(whole, x, y);
            let sum: Vec3A = ids.iter().map(|&k| film.pixel(k, x, y)).sum();
            let err = (sum - b).abs() / b.abs().max(Vec3A::splat(1e-3));
            worst = worst.max(err.max_element());
        }
    }
    worst
}

fn total(scene: &Scene, film: &Film, name: &str) -> f32 {
    film.channel(index(scene, name), 0).iter().sum()
}

/// A subsurface ball with OpenPBR's default specular on a diffuse floor, under a disk
/// light (MIS with the exit lobe) and a point light (light sampling only).
const BALL: &str = r#"
[camera]
position = [0, -4, 2]
look_at = [0, 0, 0.5]
up = [0, 0, 1]
fov = 30
[render]
max_depth = 12
[materials.skin]
type = "openpbr"
subsurface_weight = 1
subsurface_color = [0.9, 0.5, 0.3]
subsurface_radius = 0.3
[materials.floor]
type = "diffuse"
albedo = [0.5, 0.5, 0.5]
[[objects]]
name = "ball"
shape = "sphere"
radius = 0.6
translate = [0, 0, 0.6]
material = "skin"
[[objects]]
name = "floor"
shape = "rectangle"
scale = 6
material = "floor"
[[lights]]
type = "disk"
groups = ["key"]
radiance = [6, 6, 6]
rotate = [180, 0, 0]
translate = [0, 0, 3]
[[lights]]
type = "point"
groups = ["rim"]
position = [2, 2, 2]
intensity = [8, 8, 8]
"#;

#[test]
fn standard_partition_sums_to_beauty_with_subsurface() {
    let (scene, film) = render_aovs(BALL, 24, 4, aov::standard());
    let err = partition_error(&scene, &film, "beauty", &lpe::BEAUTY_PARTITION);
    assert!(err <= 1e-5, "standard partition is off by {err}");
    assert!(total(&scene, &film, "subsurface") > 0.1);
}

#[test]
fn direct_subsurface_is_one_td3_event_then_the_light() {
    let extra = vec![
        AovSpec::new("subsurface", "lpe:subsurface"),
        AovSpec::new("td3_direct", "C<TD3>[<L.>O]"),
        AovSpec::new("td3_indirect", "C<TD3>[DS]+[<L.>O]"),
        AovSpec::new("td_any", "C<TD>.*"),
        AovSpec::new("td3_key", "C<TD3><L.'key'>"),
        AovSpec::new("td3_rim", "C<TD3><L.'rim'>"),
        AovSpec::new("b0", "C[<L.>O]"),
        AovSpec::new("b1", "C[DS]{1}[<L.>O]"),
        AovSpec::new("b2", "C[DS]{2}[<L.>O]"),
        AovSpec::new("b3", "C[DS]{3,}[<L.>O]"),
    ];
    let (scene, film) = render_aovs(BALL, 24, 4, extra);
    assert!(total(&scene, &film, "td3_direct") > 0.1);
    assert!(total(&scene, &film, "td3_indirect") > 0.0);
    assert!(total(&scene, &film, "td3_key") > 0.0 && total(&scene, &film, "td3_rim") > 0.0);
    // Without thin translucency (`TD2`), every `TD` path is a `TD3` one.
    let err = partition_error(&scene, &film, "subsurface", &["td3_direct", "td3_indirect"]);
    assert!(err <= 1e-5, "TD3 direct + indirect vs subsurface: {err}");
    let err = partition_error(&scene, &film, "td_any", &["subsurface"]);
    assert!(err <= 1e-5, "C<TD>.* vs subsurface: {err}");
    // Light groups through the walk: key and rim are every light of direct subsurface.
    let err = partition_error(&scene, &film, "td3_direct", &["td3_key", "td3_rim"]);
    assert!(err <= 1e-5, "TD3 by light group: {err}");
    // One bounce for the walk: the bounce AOVs still partition beauty.
    let err = partition_error(&scene, &film, "beauty", &["b0", "b1", "b2", "b3"]);
    assert!(err <= 1e-5, "bounces off by {err}");
}

/// A white, lossless subsurface ball (no specular layer) in a white dome: the walk and
/// its Lambertian exit lose nothing but what the step cap drops, which for mean free
/// paths of a quarter to all of the ball's radius (OpenPBR's default radius scale) is
/// below the noise.
#[test]
fn white_subsurface_ball_in_a_furnace_returns_the_dome() {
    let text = r#"
[camera]
position = [0, 0, 4]
look_at = [0, 0, 0]
fov = 30
[render]
max_depth = 64
rr_depth = 5
[materials.m]
type = "openpbr"
specular_weight = 0
subsurface_weight = 1
subsurface_color = [1, 1, 1]
subsurface_radius = 1
[[objects]]
name = "ball"
shape = "sphere"
radius = 1
material = "m"
[[lights]]
type = "dome"
radiance = [1, 1, 1]
"#;
    let (_, film) = render_aovs(text, 24, 16, vec![]);
    let a = film.alpha();
    for c in 0..3 {
        let vals: Vec<f64> = film
            .channel(0, c)
            .iter()
            .zip(&a)
            .filter(|(_, a)| **a > 0.999)
            .map(|(v, _)| f64::from(*v))
            .collect();
        assert!(vals.len() > 100);
        let n = vals.len() as f64;
        let mean = vals.iter().sum::<f64>() / n;
        let var = vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
        let se = (var / n).sqrt();
        assert!(
            (mean - 1.0).abs() < 5.0 * se + 1e-3,
            "channel {c}: mean {mean} ± {se}"
        );
    }
}
