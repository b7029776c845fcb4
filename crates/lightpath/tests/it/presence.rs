//! Presence (OpenPBR `geometry_opacity`): a surface of opacity `a` is found by a
//! fraction `a` of the rays reaching it, camera and shadow rays alike, and passing it is
//! no LPE event (docs/lpe.md#presence).

use lightpath::aov::{self, AovSpec};
use lightpath::film::Film;
use lightpath::{render, RenderOptions, Scene, Source};

/// A grey floor (albedo 0.5) under a sun of irradiance 1 straight down, seen from
/// above through a black sheet of opacity OPACITY at height 1 that covers the frame.
const SHEET: &str = r#"
[camera]
position = [0, 0, 5]
look_at = [0, 0, 0]
fov = 20
[render]
max_depth = 6
[materials.grey]
type = "openpbr"
base_color = [0.5, 0.5, 0.5]
specular_weight = 0
[materials.sheet]
type = "openpbr"
base_color = [0, 0, 0]
specular_weight = 0
geometry_opacity = OPACITY
[[objects]]
name = "floor"
shape = "rectangle"
material = "grey"
scale = 20
[[objects]]
name = "sheet"
shape = "rectangle"
material = "sheet"
scale = 20
translate = [0, 0, 1]
[[lights]]
type = "distant"
direction = [0, 0, -1]
irradiance = [1, 1, 1]
"#;

fn render_sheet(opacity: f32, res: u32, spp: u32) -> (Scene, Film) {
    let text = SHEET.replace("OPACITY", &opacity.to_string());
    let mut desc = Source {
        name: "presence.toml".into(),
        text,
        dir: Default::default(),
    }
    .parse()
    .unwrap_or_else(|e| panic!("{e}"));
    desc.render.resolution = [res, res];
    desc.render.spp = spp;
    let extra = vec![AovSpec::new("direct", "C<RD>L")];
    let scene = Scene::build(&desc, &aov::assemble(extra)).unwrap_or_else(|e| panic!("{e}"));
    let (film, _) = render(
        &scene,
        &RenderOptions {
            spp,
            first_sample: 0,
        },
    );
    (scene, film)
}

fn mean(v: &[f32]) -> f64 {
    v.iter().map(|&x| x as f64).sum::<f64>() / v.len() as f64
}

#[test]
fn a_half_present_sheet_passes_half_the_camera_rays_and_half_the_light() {
    // Each sample sees the floor only if its camera ray passes the sheet (1/2), and the
    // floor is lit only if the shadow ray passes it too (1/2): radiance 0.5/π with
    // probability 1/4, else 0 (the sheet is black, the floor's bounces escape or die on
    // it). The mean is 0.125/π; one sample's variance is L²·p(1 − p), L = 0.5/π, p = 1/4.
    let (res, spp) = (16, 64);
    let (scene, film) = render_sheet(0.5, res, spp);
    let l = 0.5 / std::f64::consts::PI;
    let want = 0.25 * l;
    let n = (res * res * spp) as f64;
    let se = l * (0.25f64 * 0.75 / n).sqrt();
    let got = mean(&film.channel(0, 0));
    assert!(
        (got - want).abs() < 5.0 * se,
        "mean {got} vs {want} (standard error {se})"
    );
    // Passing the sheet is no event: everything is the floor's direct diffuse `C<RD>L`
    // (an event on the way would put it elsewhere), sample by sample.
    let k = scene.aovs.iter().position(|a| a.name == "direct").unwrap();
    let direct = film.channel(k, 0);
    for (d, b) in direct.iter().zip(film.channel(0, 0)) {
        assert!(
            (d - b).abs() <= 1e-5 * b.abs().max(1e-3),
            "C<RD>L {d} vs beauty {b}"
        );
    }
}

#[test]
fn opacity_zero_is_no_surface_and_one_is_a_full_one() {
    let l = 0.5 / std::f64::consts::PI;
    let (_, film) = render_sheet(0.0, 8, 4);
    let got = mean(&film.channel(0, 0));
    assert!((got - l).abs() < 1e-3 * l, "opacity 0: {got} vs {l}");
    let (_, film) = render_sheet(1.0, 8, 4);
    let got = mean(&film.channel(0, 0));
    assert!(got.abs() < 1e-9, "opacity 1: {got}");
}
