//! The OpenPBR material as a scene writes it: its parameters and their checks, the
//! presets it replaces, its lobes' events, and energy in a white furnace.

use glam::Vec3A;
use lightpath::aov::{self, AovSpec};
use lightpath::film::Film;
use lightpath::{render, RenderOptions, Scene, Source};

fn source(text: &str) -> Source {
    Source {
        name: "openpbr.toml".into(),
        text: text.into(),
        dir: Default::default(),
    }
}

const FURNACE: &str = r#"
[camera]
position = [0, 0, 4]
look_at = [0, 0, 0]
fov = 30
[render]
max_depth = 64
[materials.m]
type = "openpbr"
PARAMS
[[objects]]
name = "ball"
shape = "sphere"
material = "m"
radius = 1
[[lights]]
type = "dome"
radiance = [1, 1, 1]
"#;

fn render_text(text: &str, res: u32, spp: u32, extra: Vec<AovSpec>) -> (Scene, Film) {
    let mut desc = source(text).parse().unwrap_or_else(|e| panic!("{e}"));
    desc.render.resolution = [res, res];
    desc.render.spp = spp;
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

/// Mean and standard error over the ball's pixels of the beauty's red channel, for an
/// OpenPBR sphere with `params` in a white dome.
fn furnace(params: &str, spp: u32) -> (f64, f64) {
    let (_, film) = render_text(&FURNACE.replace("PARAMS", params), 24, spp, vec![]);
    let r = film.channel(0, 0);
    let a = film.alpha();
    let vals: Vec<f64> = r
        .iter()
        .zip(&a)
        .filter(|(_, a)| **a > 0.999)
        .map(|(v, _)| *v as f64)
        .collect();
    assert!(vals.len() > 100);
    let n = vals.len() as f64;
    let mean = vals.iter().sum::<f64>() / n;
    let var = vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

fn parse_error(params: &str) -> String {
    match source(&FURNACE.replace("PARAMS", params)).parse() {
        Ok(desc) => match Scene::build(&desc, &aov::assemble(vec![])) {
            Ok(_) => panic!("accepted {params}"),
            Err(e) => e.to_string(),
        },
        Err(e) => e.to_string(),
    }
}

#[test]
fn parameters_are_checked_against_the_specification() {
    let e = parse_error("specular_roughness = 2");
    assert!(
        e.contains("openpbr.toml:10:1")
            && e.contains("specular_roughness must be a number from 0 to 1, got 2"),
        "{e}"
    );
    let e = parse_error("base_colour = [1, 0, 0]");
    assert!(
        e.contains("unknown OpenPBR parameter 'base_colour'")
            && e.contains("did you mean 'base_color'"),
        "{e}"
    );
    let e = parse_error("roughness = 0.2");
    assert!(
        e.contains("'roughness' is not an OpenPBR parameter: write specular_roughness"),
        "{e}"
    );
    let e = parse_error("coat_color = [1, -1, 0]");
    assert!(e.contains("coat_color must be [r, g, b]"), "{e}");
    let e = parse_error("geometry_thin_walled = 1");
    assert!(
        e.contains("geometry_thin_walled must be true or false"),
        "{e}"
    );
    // An OpenPBR key on an older type says how to use it.
    let text = FURNACE
        .replace(
            "type = \"openpbr\"",
            "type = \"diffuse\"\nalbedo = [1, 1, 1]",
        )
        .replace("PARAMS", "coat_weight = 1");
    let e = source(&text).parse().unwrap_err().to_string();
    assert!(
        e.contains("unknown key 'coat_weight' for type 'diffuse'")
            && e.contains("write type = \"openpbr\""),
        "{e}"
    );
}

#[test]
fn a_diffuse_openpbr_is_the_diffuse_material() {
    // OpenPBR with no specular is one Lambert lobe: the same image, bit for bit.
    let (_, a) = render_text(
        &FURNACE.replace(
            "PARAMS",
            "specular_weight = 0\nbase_color = [0.5, 0.6, 0.7]",
        ),
        16,
        4,
        vec![],
    );
    let text = FURNACE
        .replace("type = \"openpbr\"", "type = \"diffuse\"")
        .replace("PARAMS", "albedo = [0.5, 0.6, 0.7]");
    let (_, b) = render_text(&text, 16, 4, vec![]);
    assert_eq!(a.channel(0, 0), b.channel(0, 0));
}

#[test]
fn a_white_base_under_its_default_specular_keeps_the_dome_white() {
    // Default specular (ior 1.5, roughness 0.3) over a white diffuse base: what the
    // specular reflects, the base does not get, so the sum stays one.
    let (mean, se) = furnace("base_color = [1, 1, 1]\nspecular_roughness = 0", 16);
    assert!((mean - 1.0).abs() < 5.0 * se + 5e-3, "mean {mean} ± {se}");
}

#[test]
fn fuzz_over_a_white_base_keeps_the_dome_white() {
    for roughness in [0.3, 1.0] {
        let params = format!("base_color = [1, 1, 1]\nspecular_weight = 0\nfuzz_weight = 1\nfuzz_roughness = {roughness}");
        let (mean, se) = furnace(&params, 16);
        assert!(
            (mean - 1.0).abs() < 5.0 * se + 1e-3,
            "roughness {roughness}: mean {mean} ± {se}"
        );
    }
}

#[test]
fn a_coat_over_a_white_base_keeps_the_dome_white() {
    // Smooth: exact in expectation (the coat reflects F(μo), the base gets the rest).
    let (mean, se) = furnace(
        "base_color = [1, 1, 1]\nspecular_weight = 0\ncoat_weight = 1",
        16,
    );
    assert!(
        (mean - 1.0).abs() < 5.0 * se + 1e-3,
        "smooth coat: mean {mean} ± {se}"
    );
    // Rough: issue 26's band, [0.98, 1.01], beyond the noise.
    let (mean, se) = furnace(
        "base_color = [1, 1, 1]\nspecular_weight = 0\ncoat_weight = 1\ncoat_roughness = 0.4",
        16,
    );
    assert!(
        mean > 0.98 - 5.0 * se && mean < 1.01 + 5.0 * se,
        "rough coat: mean {mean} ± {se}"
    );
}

#[test]
fn an_emissive_openpbr_glows() {
    let text = FURNACE.replace("PARAMS", "emission_luminance = 2\nemission_color = [1, 0.5, 0]\nbase_color = [0, 0, 0]\nspecular_weight = 0")
        .replace("radiance = [1, 1, 1]", "radiance = [0, 0, 0]");
    let (scene, film) = render_text(&text, 16, 2, vec![]);
    let beauty = scene.aovs.iter().position(|a| a.name == "beauty").unwrap();
    let c = film.pixel(beauty, 8, 8);
    assert!(
        (c - Vec3A::new(2.0, 1.0, 0.0)).abs().max_element() < 1e-4,
        "{c}"
    );
}

#[test]
fn openpbr_lobes_emit_renderman_events() {
    // A coated, metallic-and-dielectric, partly transmissive material: each lobe's
    // AOV sees light, and the standard partition still sums to the beauty.
    let params = "base_color = [0.8, 0.3, 0.2]\nbase_metalness = 0.3\ntransmission_weight = 0.3\ncoat_weight = 0.5\ncoat_roughness = 0.2\nspecular_roughness = 0.4\nfuzz_weight = 0.5\nthin_film_weight = 0.5";
    let text = FURNACE.replace("PARAMS", params);
    let extra = vec![
        AovSpec::new("coat", "C<RS4>.*[<L.>O]"),
        AovSpec::new("spec", "C<RS2>.*[<L.>O]"),
        AovSpec::new("glass", "C<[RT]S8>.*[<L.>O]"),
        AovSpec::new("diffuse", "C<RD2>.*[<L.>O]"),
        AovSpec::new("fuzz", "C<RS6>.*[<L.>O]"),
        AovSpec::new("film", "C<RS5>.*[<L.>O]"),
    ];
    let mut aovs = extra;
    aovs.extend(aov::standard().into_iter().filter(|a| a.name != "fuzz"));
    let (scene, film) = render_text(&text, 16, 8, aovs);
    let beauty = scene.aovs.iter().position(|a| a.name == "beauty").unwrap();
    let parts: Vec<usize> = lpe::BEAUTY_PARTITION
        .iter()
        .map(|p| scene.aovs.iter().position(|a| a.name == *p).unwrap())
        .collect();
    for y in 0..16 {
        for x in 0..16 {
            let b = film.pixel(beauty, x, y);
            let sum: Vec3A = parts.iter().map(|&k| film.pixel(k, x, y)).sum();
            let err = ((sum - b).abs() / b.abs().max(Vec3A::splat(1e-3))).max_element();
            // NaN fails too.
            assert!(err <= 1e-5, "partition off by {err} at {x},{y}");
        }
    }
    for name in ["coat", "spec", "glass", "diffuse", "fuzz", "film"] {
        let k = scene.aovs.iter().position(|a| a.name == name).unwrap();
        let sum: f32 = (0..16)
            .flat_map(|y| (0..16).map(move |x| (x, y)))
            .map(|(x, y)| film.pixel(k, x, y).x)
            .sum();
        assert!(sum > 0.0, "{name} is black");
    }
}
