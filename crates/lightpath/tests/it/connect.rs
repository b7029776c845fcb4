//! Bidirectional path tracing (`--light-connections on`, crates/lightpath/src/integrator/
//! connect.rs): light subpaths joined to camera paths make the same paths in more ways,
//! weighted by MIS, so the image converges to path tracing's mean (per bounce, too, and
//! through transmitting and regularised lobes), partitions still sum to the beauty,
//! renders stay deterministic across thread counts and sample ranges, and scenes the
//! strategy does not apply to render exactly as without it.

use crate::common::{assert_sums_to_beauty, image_mean, index, mean_and_se, render_spp, Scratch};
use lightpath::aov::{self, AovSpec};
use lightpath::integrator::connect::LightConnections;
use lightpath::{Scene, Source};

/// A room lit around a plate just under a lamp that faces the ceiling 0.09 above it: the room sees the
/// lamp's light after one bounce or more, a vertex on the plate's top or on the lamp's
/// own surface (it has a material) joins the ceiling a hair above the lamp's plane, at
/// grazing angles too. A glass ball (delta lobes: never joined) and a glossy block (two
/// lobes at each end of a connection).
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
corners = [[-0.4, 0.9, -0.4], [-0.4, 0.9, 0.4], [0.4, 0.9, 0.4], [0.4, 0.9, -0.4]]
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
material = "white"
corners = [[-0.2, 0.91, -0.2], [-0.2, 0.91, 0.2], [0.2, 0.91, 0.2], [0.2, 0.91, -0.2]]
"#;

fn scene_in(text: &str, res: u32, on: bool, seed: u64, extra: Vec<AovSpec>) -> Scene {
    let src = Source {
        name: "room.toml".into(),
        text: text.into(),
        dir: Default::default(),
    };
    let mut desc = src.parse().unwrap();
    desc.render.resolution = [res, res];
    desc.render.seed = seed;
    desc.render.guiding = lightpath::guiding::GuidingMode::Off;
    desc.render.light_connections = if on {
        LightConnections::On
    } else {
        LightConnections::Off
    };
    Scene::build(&desc, &aov::assemble(extra)).unwrap()
}

fn bounces() -> Vec<AovSpec> {
    vec![
        AovSpec::new("b0", "C[<L.>O]"),
        AovSpec::new("b1", "C[DS]{1}[<L.>O]"),
        AovSpec::new("b2", "C[DS]{2}[<L.>O]"),
        AovSpec::new("b3", "C[DS]{3,}[<L.>O]"),
        // Joined at the plate's top or the lamp's own surface (next to the lamp's plane).
        AovSpec::new("near", "C.*<RD('plate'|'lamp')><RD'ceiling'><L.>"),
    ]
}

/// The image means of AOVs `names` over independent renders of `text` (seeds 1…16) agree
/// with and without connections within 5 standard errors of their difference (estimated
/// from the runs' spread); returns each run's means, without and with.
fn assert_means_agree(
    scene: &str,
    text: &str,
    names: &[&str],
    extra: Vec<AovSpec>,
) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let runs = 16;
    let means = |on: bool| -> Vec<Vec<f64>> {
        (1..=runs)
            .map(|seed| {
                let s = scene_in(text, 32, on, seed, extra.clone());
                let film = render_spp(&s, 32, 0);
                names
                    .iter()
                    .map(|n| image_mean(&film, index(&s, n)))
                    .collect()
            })
            .collect()
    };
    let (plain, joined) = (means(false), means(true));
    for (k, name) in names.iter().enumerate() {
        let column = |runs: &[Vec<f64>]| runs.iter().map(|r| r[k]).collect::<Vec<_>>();
        let (p, se_p) = mean_and_se(&column(&plain));
        let (j, se_j) = mean_and_se(&column(&joined));
        let se = (se_p * se_p + se_j * se_j).sqrt();
        assert!(p > 1e-4, "{scene} {name} is lit: {p}");
        assert!(
            (p - j).abs() <= 5.0 * se,
            "{scene} {name}: path tracing {p} ± {se_p}, with connections {j} ± {se_j}"
        );
    }
    (plain, joined)
}

/// The image means of independent renders (seeds 1…runs) agree with and without
/// connections within 5 standard errors of their difference (estimated from the runs'
/// spread), for the beauty, each bounce count, and the paths joined next to the lamp's
/// plane (a connection ending a fixed length short of its end crossed the ceiling at
/// grazing angles there: 3–14 % of that light was lost).
#[test]
fn connected_renders_converge_to_the_unconnected_mean() {
    let names = ["beauty", "b1", "b2", "b3", "near"];
    let (plain, joined) = assert_means_agree("room", ROOM, &names, bounces());
    // Connections did change the render: light after two bounces, which a connection
    // at the first vertex finds by itself, has a fifth of path tracing's spread (the
    // runs' means; ~10× lower here).
    let spread = |runs: &[Vec<f64>]| mean_and_se(&runs.iter().map(|r| r[2]).collect::<Vec<_>>()).1;
    assert!(
        spread(&joined) < 0.2 * spread(&plain),
        "two bounces' standard error with connections {} against {}",
        spread(&joined),
        spread(&plain)
    );
}

/// The light subpath scatters through rough glass and a translucent sheet (lobes that
/// transmit, valued as the camera sees them: a subpath sampled from the light's side must
/// still weigh the path as path tracing does), and stops at a ball regularised after a
/// diffuse bounce (which Bsdf the path tracer uses there depends on the camera's side)
/// while still being joined to it: each scene's means, per bounce and through the
/// transmitting lobes, agree with path tracing's as in the test above.
#[test]
fn light_subpaths_through_transmission_and_regularised_glass_converge() {
    let rough = ROOM
        .replace(
            "[materials.glass]\ntype = \"dielectric\"\nior = 1.5",
            "[materials.glass]\ntype = \"dielectric\"\nior = 1.5\nroughness = 0.3\n\
             [materials.leaf]\ntype = \"translucent\"\nreflect = [0.3, 0.4, 0.2]\n\
             transmit = [0.5, 0.5, 0.3]",
        )
        .replace(
            "[[lights]]",
            "[[objects]]\nname = \"sheet\"\nshape = \"quad\"\nmaterial = \"leaf\"\n\
             corners = [[0.6, -1, -0.6], [0.6, -1, 0.3], [0.6, 0.5, 0.3], [0.6, 0.5, -0.6]]\n\
             [[lights]]",
        );
    let regularised = ROOM.replace("[render]\n", "[render]\nregularize = 0.5\n");
    let mut extra = bounces();
    extra.push(AovSpec::new("through", "C.*<T.>.*<L.>"));
    let names = ["beauty", "b1", "b2", "b3", "through"];
    for (scene, text) in [
        ("rough", rough.as_str()),
        ("regularised", regularised.as_str()),
    ] {
        assert_means_agree(scene, text, &names, extra.clone());
    }
}

/// The room without its glass ball and lamp, lit by `lights` (TOML). Without the ball:
/// through smooth glass only light tracing makes a point or one direction's caustic
/// (`light_subpaths_through_smooth_glass_and_mirrors_converge`), so path tracing's mean
/// would lack it.
fn room_lit_by(lights: &str) -> String {
    let without_ball = ROOM.replace(
        "[[objects]]\nname = \"ball\"\nshape = \"sphere\"\nmaterial = \"glass\"\n\
         center = [0.4, -0.6, 0.2]\nradius = 0.35\n",
        "",
    );
    assert!(!without_ball.contains("\"ball\""));
    let start = without_ball.find("[[lights]]").unwrap();
    format!("{}{}", &without_ball[..start], lights)
}

/// The room lit as `lit` (named `scene` in messages) agrees with path tracing per bounce
/// and per light of `lights` (their `L` events), and light after two bounces has at most
/// `ratio` of path tracing's standard error with the joins.
fn assert_lights_converge(scene: &str, lit: &str, lights: &[&str], ratio: f64) {
    let mut extra = bounces();
    let mut names = vec!["beauty", "b1", "b2", "b3"];
    for &light in lights {
        extra.push(AovSpec::new(light, format!("C.*<L.'{light}'>")));
        names.push(light);
    }
    let (plain, joined) = assert_means_agree(scene, lit, &names, extra);
    let spread = |runs: &[Vec<f64>]| mean_and_se(&runs.iter().map(|r| r[2]).collect::<Vec<_>>()).1;
    assert!(
        spread(&joined) < ratio * spread(&plain),
        "{scene}: two bounces' standard error with connections {} against {}",
        spread(&joined),
        spread(&plain)
    );
}

/// Sphere lights start subpaths as area lights do (a point uniform on the sphere, a
/// cosine direction outwards): a room lit by a small bulb under the plate and a larger
/// one in a corner agrees per bounce and per light with path tracing, and light after
/// two bounces is less noisy with the joins.
#[test]
fn sphere_light_subpaths_converge() {
    let lit = room_lit_by(
        "[[lights]]\ntype = \"sphere\"\nname = \"bulb\"\ncenter = [0, 0.8, 0]\nradius = 0.05\n\
         radiance = [60, 60, 60]\n\
         [[lights]]\ntype = \"sphere\"\nname = \"globe\"\ncenter = [0.7, -0.7, -0.7]\n\
         radius = 0.2\nradiance = [2, 2, 2]\n",
    );
    // Measured 0.15.
    assert_lights_converge("sphere lights", &lit, &["bulb", "globe"], 0.5);
}

/// Light subpaths start at point and spot lights too: the room (without its glass ball)
/// lit by a spot aimed at the ceiling above the plate and a bare bulb in a corner (no ray finds either, so a
/// path ending there is made by light sampling and the joins alone): the means per
/// bounce and per light agree with path tracing's, and the two-bounce light off the
/// spot-lit ceiling is less noisy with the joins.
#[test]
fn point_and_spot_light_subpaths_converge() {
    let lit = room_lit_by(
        "[[lights]]\ntype = \"spot\"\nname = \"spot\"\nposition = [0, 0.92, 0]\n\
         direction = [0, 1, 0]\ncone_angle = 120\ncone_softness = 30\n\
         intensity = [6, 6, 6]\n\
         [[lights]]\ntype = \"point\"\nname = \"bulb\"\nposition = [0.7, -0.7, -0.7]\n\
         intensity = [0.4, 0.4, 0.4]\n",
    );
    assert_lights_converge("point lights", &lit, &["spot", "bulb"], 0.5);
}

/// Distant lights start subpaths on a disc round the scene (connect.rs): the room, its
/// lamp put out, lit through its open sides by a sun with an 8° disc (which BSDF rays that
/// leave the room find too) and by a light from one direction (which only light sampling
/// and the joins find): the means per bounce and per light agree with path tracing's,
/// and light after two bounces is less noisy with the joins.
#[test]
fn distant_light_subpaths_converge() {
    let lit = room_lit_by(
        "[[lights]]\ntype = \"distant\"\nname = \"sun\"\ndirection = [-1, -0.6, -0.4]\n\
         irradiance = [2, 2, 2]\nangle = 8\n\
         [[lights]]\ntype = \"distant\"\nname = \"key\"\ndirection = [-0.3, -0.5, -1]\n\
         irradiance = [0.5, 0.5, 0.5]\n",
    );
    // Measured 0.41.
    assert_lights_converge("distant lights", &lit, &["sun", "key"], 0.7);
}

/// A dome starts subpaths as a distant light does, its direction drawn by its map (so
/// the start's density varies with it): the room lit through its open sides by a sky
/// map with a bright patch agrees per bounce with path tracing, and light after two
/// bounces is less noisy with the joins.
#[test]
fn dome_light_subpaths_converge() {
    let scratch = Scratch::new("connect-dome");
    let (w, h) = (32usize, 16usize);
    // Dim blue overhead, a bright patch low in the sky towards +x (through the open side).
    let texel = |x: usize, y: usize, c: usize| -> f32 {
        let patch = (20..23).contains(&x) && (6..8).contains(&y);
        let base = [0.3, 0.4, 0.6][c] * (1.0 - y as f32 / h as f32 * 0.5);
        if patch {
            40.0
        } else {
            base
        }
    };
    let planes = ["R", "G", "B", "A"].map(|name| {
        let c = ["R", "G", "B", "A"]
            .iter()
            .position(|n| *n == name)
            .unwrap();
        let values = (0..w * h)
            .map(|i| if c == 3 { 1.0 } else { texel(i % w, i / w, c) })
            .collect();
        (name.to_string(), values)
    });
    let map = scratch.join("sky.exr");
    lightpath::output::write_channels(&map, w, h, planes.to_vec(), &[], Default::default())
        .unwrap();
    let lit = room_lit_by(&format!(
        "[[lights]]\ntype = \"dome\"\nname = \"sky\"\nmap = {:?}\ncamera_visible = false\n",
        map.to_str().unwrap()
    ));
    // Measured 0.55.
    assert_lights_converge("dome", &lit, &["sky"], 0.85);
}

/// Connections add paths through every lobe pair's own events: the standard partition
/// and per-bounce AOVs still sum to the beauty.
#[test]
fn connected_partitions_sum_to_beauty() {
    let mut extra = aov::standard();
    extra.extend(bounces());
    let scene = scene_in(ROOM, 32, true, 0, extra);
    let film = render_spp(&scene, 4, 0);
    for parts in [&lpe::BEAUTY_PARTITION[..], &["b0", "b1", "b2", "b3"][..]] {
        assert_sums_to_beauty(&scene, &film, parts);
    }
}

/// A light subpath's numbers depend only on (seed, pixel, sample): one thread and two
/// give the same bits, sample ranges merge into the whole, for both samplers.
#[test]
fn connected_renders_are_deterministic_and_merge() {
    let independent = ROOM.replace("[render]\n", "[render]\nsampler = \"independent\"\n");
    for text in [ROOM, independent.as_str()] {
        let run_in = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let s = scene_in(text, 24, true, 3, vec![]);
            pool.install(|| render_spp(&s, 4, 0).planes.concat())
        };
        let one = run_in(1);
        assert!(one
            .iter()
            .zip(&run_in(2))
            .all(|(a, b)| a.to_bits() == b.to_bits()));
        let s = scene_in(text, 24, true, 3, vec![]);
        let mut parts = render_spp(&s, 2, 0);
        parts.merge(&render_spp(&s, 2, 2)).unwrap();
        for (x, y) in one.iter().zip(&parts.planes.concat()) {
            assert!((x - y).abs() <= 1e-5 * x.abs().max(1.0), "{x} {y}");
        }
        let plain = render_spp(&scene_in(text, 24, false, 3, vec![]), 4, 0);
        assert!(plain.planes.concat() != one, "the setting is not ignored");
    }
}

/// Where connections do not apply (a medium, path guiding) the render is path
/// tracing's, bit for bit.
#[test]
fn connections_stay_off_where_they_do_not_apply() {
    let fog = ROOM.replace(
        "[render]\n",
        "[media.fog]\nsigma_a = [0.05, 0.05, 0.05]\nsigma_s = [0.3, 0.3, 0.3]\n[render]\natmosphere = \"fog\"\n",
    );
    let bits = |text: &str, on: bool| render_spp(&scene_in(text, 16, on, 2, vec![]), 2, 0).planes;
    assert_eq!(bits(&fog, true), bits(&fog, false));
    let guided = |on: bool| {
        let src = Source {
            name: "room.toml".into(),
            text: ROOM.into(),
            dir: Default::default(),
        };
        let mut desc = src.parse().unwrap();
        desc.render.resolution = [16, 16];
        desc.render.guiding = lightpath::guiding::GuidingMode::On;
        desc.render.guiding_passes = 3;
        desc.render.light_connections = if on {
            LightConnections::On
        } else {
            LightConnections::Off
        };
        let s = Scene::build(&desc, &aov::assemble(vec![])).unwrap();
        render_spp(&s, 2, 0).planes
    };
    assert_eq!(guided(true), guided(false));
}

/// A one-sided rect light with a material, seen from behind: what reflects off its back
/// is light from elsewhere, never its own (a hit rounded to a hair in front of its plane
/// used to see the whole light as a hemisphere).
#[test]
fn a_light_does_not_light_its_own_surface() {
    let text = ROOM
        .replace(
            "[[objects]]\nname = \"plate\"",
            "[[objects]]\nname = \"unused\"",
        )
        .replace(
            "corners = [[-0.4, 0.9, -0.4], [-0.4, 0.9, 0.4], [0.4, 0.9, 0.4], [0.4, 0.9, -0.4]]",
            "corners = [[-0.4, -0.99, -0.4], [-0.4, -0.99, 0.4], [0.4, -0.99, 0.4], [0.4, -0.99, -0.4]]",
        );
    let extra = vec![AovSpec::new("own", "C<RD'lamp'><L'lamp'>")];
    let s = scene_in(&text, 32, false, 1, extra);
    let film = render_spp(&s, 8, 0);
    assert_eq!(image_mean(&film, index(&s, "own")), 0.0);
    assert!(image_mean(&film, index(&s, "beauty")) > 0.01);
}

/// Light tracing (every light vertex joined to the camera, splatted into the pixels whose
/// filter reaches it: connect/light_tracing.rs) under each pixel filter and behind a thin
/// lens (where it does not apply): the beauty's mean over each 8 × 8 block of pixels
/// agrees with path tracing's over 16 seeds, within 5 standard errors of the difference.
/// A filter density that is wrong or off by a pixel moves light between blocks.
#[test]
fn light_tracing_converges_under_every_pixel_filter() {
    let lens = ROOM.replace(
        "fov = 40\n",
        "fov = 40\naperture_radius = 0.05\nfocus_distance = 3.5\n",
    );
    let filtered = |filter: &str| format!("{ROOM}\n[film]\nfilter = \"{filter}\"\n");
    for (name, text) in [
        ("box", ROOM.to_string()),
        ("gaussian", filtered("gaussian")),
        ("blackman-harris", filtered("blackman-harris")),
        ("thin lens", lens),
    ] {
        let blocks = |on: bool| -> Vec<Vec<f64>> {
            (1..=16)
                .map(|seed| {
                    let s = scene_in(&text, 32, on, seed, vec![]);
                    let film = render_spp(&s, 16, 0);
                    let mut sums = vec![0.0; 16];
                    for y in 0..32 {
                        for x in 0..32 {
                            let v = lightpath::light::luminance(film.pixel(0, x, y)) as f64;
                            sums[(y / 8 * 4 + x / 8) as usize] += v / 64.0;
                        }
                    }
                    sums
                })
                .collect()
        };
        let (plain, joined) = (blocks(false), blocks(true));
        for b in 0..16 {
            let column = |runs: &[Vec<f64>]| runs.iter().map(|r| r[b]).collect::<Vec<_>>();
            let (p, se_p) = mean_and_se(&column(&plain));
            let (j, se_j) = mean_and_se(&column(&joined));
            let se = (se_p * se_p + se_j * se_j).sqrt();
            assert!(
                (p - j).abs() <= 5.0 * se,
                "{name} block {b}: path tracing {p} ± {se_p}, with light tracing {j} ± {se_j}"
            );
        }
    }
}

/// A window's pixels are the whole frame's bit for bit with light tracing too: the
/// window traces the light subpaths of the pixels outside it and keeps what lands in it.
/// So are a cancelled render's, resumed from its rows, splats and film.
#[test]
fn light_traced_windows_and_resumed_renders_equal_the_whole_frame() {
    use lightpath::film::PixelWindow;
    use lightpath::integrator::{render_frame, render_resumable, FrameRequest, Resumable};
    use lightpath::progress::Silent;
    use std::sync::atomic::{AtomicBool, Ordering};
    let s = scene_in(ROOM, 24, true, 5, bounces());
    let options = lightpath::RenderOptions {
        spp: 4,
        first_sample: 0,
    };
    let whole = render_spp(&s, 4, 0);
    for window in [
        PixelWindow {
            x0: 0,
            y0: 0,
            x1: 24,
            y1: 10,
        },
        PixelWindow {
            x0: 5,
            y0: 3,
            x1: 15,
            y1: 20,
        },
    ] {
        let request = FrameRequest {
            window,
            mattes: None,
        };
        let (part, _) = render_frame(&s, &options, &request, &Silent);
        for (k, plane) in part.planes.iter().enumerate() {
            for y in 0..window.height() {
                for x in 0..window.width() {
                    let a = plane[(y * window.width() + x) as usize];
                    let b = whole.planes[k][((y + window.y0) * 24 + x + window.x0) as usize];
                    assert_eq!(a.to_bits(), b.to_bits(), "{window} plane {k} ({x}, {y})");
                }
            }
        }
    }
    // Cancelled after the first band of 8 rows, then resumed.
    let cancel = AtomicBool::new(false);
    let mut stop = |_: &lightpath::integrator::Snapshot| cancel.store(true, Ordering::SeqCst);
    let first = render_resumable(
        &s,
        &options,
        &FrameRequest::whole(&s),
        &Silent,
        Resumable {
            cancel: Some(&cancel),
            after_band: Some(&mut stop),
            max_band_rows: Some(8),
            ..Default::default()
        },
    );
    assert!(!first.finished());
    let units = first.splats.as_ref().map(|s| s.units());
    assert!(units.is_some(), "an unfinished render hands its splats on");
    let resumed = render_resumable(
        &s,
        &options,
        &FrameRequest::whole(&s),
        &Silent,
        Resumable {
            film: Some(first.film),
            rows_done: first.rows_done,
            splats: units,
            ..Default::default()
        },
    );
    assert!(resumed.finished() && resumed.splats.is_none());
    assert_eq!(resumed.film.planes, whole.planes);
}

/// With light tracing the beauty's variance (`--variance`) counts the splats too (their
/// squares, film/splats.rs): over 16 seeds of independent samples, the spread of each
/// pixel's mean matches the variance the renders estimated, summed over the image,
/// within a quarter.
#[test]
fn light_traced_variance_estimates_the_spread_of_the_pixel_means() {
    let text = ROOM.replace("[render]\n", "[render]\nsampler = \"independent\"\n");
    let (res, spp, runs) = (24u32, 8u32, 16);
    let pixels = (res * res) as usize;
    let mut values = vec![Vec::new(); pixels];
    let mut estimated = 0.0;
    for seed in 1..=runs {
        let mut s = scene_in(&text, res, true, seed, vec![]);
        s.variance_aovs = vec![0]; // the beauty's (`--variance beauty`)
        let film = render_spp(&s, spp, 0);
        let squares = &film.planes[3 * film.aovs + 1];
        for (i, v) in values.iter_mut().enumerate() {
            let mean = film.planes[1][i] / spp as f32;
            let mean_square = squares[i] / spp as f32;
            estimated += lightpath::film::variance_of_mean(mean, mean_square, spp) as f64;
            v.push(mean as f64);
        }
    }
    estimated /= runs as f64;
    let measured: f64 = values
        .iter()
        .map(|v| {
            let m = v.iter().sum::<f64>() / v.len() as f64;
            v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (v.len() - 1) as f64
        })
        .sum();
    let ratio = estimated / measured;
    assert!(
        (0.75..1.33).contains(&ratio),
        "estimated {estimated}, measured {measured}: {ratio}"
    );
}

/// A floor under a smooth glass ball and a mirror ball, lit by a lamp above them: their
/// caustics on the floor are made by BSDF rays from the floor that find the lamp through
/// the balls and, with connections, by light subpaths that pass through the balls' delta
/// lobes and are joined to the camera. The means agree with path tracing's, per bounce
/// and for the caustics. With a bulb (a point light) instead no BSDF ray finds the light,
/// so path tracing has no caustic at all and light tracing alone makes it.
const CAUSTICS: &str = r#"
[camera]
position = [0, 0.8, 3.0]
look_at = [0, -0.7, 0]
fov = 40
[render]
max_depth = 8
[materials.white]
type = "diffuse"
albedo = [0.8, 0.8, 0.8]
[materials.glass]
type = "dielectric"
ior = 1.5
[materials.mirror]
type = "conductor"
f0 = [0.9, 0.9, 0.9]
roughness = 0
[[objects]]
name = "floor"
shape = "quad"
material = "white"
corners = [[-1.5, -1, 1.5], [1.5, -1, 1.5], [1.5, -1, -1.5], [-1.5, -1, -1.5]]
[[objects]]
name = "ball"
shape = "sphere"
material = "glass"
center = [-0.35, -0.6, 0]
radius = 0.3
[[objects]]
name = "chrome"
shape = "sphere"
material = "mirror"
center = [0.45, -0.75, 0.1]
radius = 0.22
"#;

#[test]
fn light_subpaths_through_smooth_glass_and_mirrors_converge() {
    let lamp = |half: f32, height: f32, radiance: f32| {
        format!(
            "{CAUSTICS}[[lights]]\ntype = \"quad\"\nname = \"lamp\"\n\
             radiance = [{radiance}, {radiance}, {radiance}]\nmaterial = \"white\"\n\
             corners = [[-{half}, {height}, -{half}], [{half}, {height}, -{half}], \
             [{half}, {height}, {half}], [-{half}, {height}, {half}]]\n"
        )
    };
    let mut extra = bounces();
    extra.push(AovSpec::new("caustic", "C<RD'floor'><.S>+<L.>"));
    let names = ["beauty", "b1", "b2", "caustic"];
    // A small lamp high up, whose caustics light subpaths make best, and a wide one just
    // above the balls, which BSDF rays find as often.
    assert_means_agree("caustics", &lamp(0.3, 0.8, 20.0), &names, extra.clone());
    assert_means_agree("wide lamp", &lamp(1.4, 0.0, 2.0), &names, extra.clone());
    let bulb = format!(
        "{CAUSTICS}[[lights]]\ntype = \"point\"\nname = \"bulb\"\nposition = [0, 0.8, 0]\n\
         intensity = [2, 2, 2]\n"
    );
    let caustic = |on: bool| {
        let s = scene_in(&bulb, 32, on, 1, extra.clone());
        image_mean(&render_spp(&s, 16, 0), index(&s, "caustic"))
    };
    assert_eq!(caustic(false), 0.0, "no BSDF ray finds a point light");
    assert!(caustic(true) > 1e-3, "light tracing makes the caustic");
}
