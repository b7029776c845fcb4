//! The artist's workflow: every prefix, holdouts, data lobes, light-group splits, trace
//! sets, light linking, clamping, and relighting from AOVs — each test fails if the
//! feature it names were missing.

use glam::Vec3A;
use lightpath::aov::{self, AovSpec};
use lightpath::film::Film;
use lightpath::scene::desc::SceneDesc;
use lightpath::{render, RenderOptions, RenderStats, Scene, Source};

fn source(text: &str) -> Source {
    Source {
        name: "test.toml".into(),
        text: text.into(),
        dir: Default::default(),
    }
}

fn run(
    src: &Source,
    edit: impl FnOnce(&mut SceneDesc),
    aovs: Vec<AovSpec>,
) -> (Scene, Film, RenderStats) {
    let mut desc = src.parse().unwrap();
    edit(&mut desc);
    let scene = Scene::build(&desc, &aov::assemble(aovs)).unwrap();
    let (film, stats) = render(
        &scene,
        &RenderOptions {
            spp: desc.render.spp,
            first_sample: 0,
        },
    );
    (scene, film, stats)
}

fn small(res: u32, spp: u32) -> impl FnOnce(&mut SceneDesc) {
    move |d: &mut SceneDesc| {
        d.render.resolution = [res, res];
        d.render.spp = spp;
    }
}

fn idx(scene: &Scene, name: &str) -> usize {
    scene
        .aovs
        .iter()
        .position(|a| a.name == name)
        .unwrap_or_else(|| panic!("no AOV {name}"))
}

fn sum(film: &Film, k: usize) -> Vec3A {
    Vec3A::new(
        film.channel(k, 0).iter().sum(),
        film.channel(k, 1).iter().sum(),
        film.channel(k, 2).iter().sum(),
    )
}

const TWO_ROOMS: &str = include_str!("../../../../scenes/two-rooms.toml");

type Pixels = Vec<(u32, u32)>;

/// Pixels on the floor left (key side) and right (fill side) of the divider, away
/// from its edge.
fn halves(film: &Film) -> (Pixels, Pixels) {
    let (mut left, mut right) = (Vec::new(), Vec::new());
    let alpha = film.alpha();
    for y in 0..film.height {
        for x in 0..film.width {
            if alpha[(y * film.width + x) as usize] < 1.0 {
                continue;
            }
            if x + 3 < film.width / 2 {
                left.push((x, y));
            } else if x > film.width / 2 + 2 {
                right.push((x, y));
            }
        }
    }
    (left, right)
}

#[test]
fn unoccluded_and_shadows_recover_the_blocked_light() {
    let aovs = vec![
        AovSpec::new("occ", "C<RD><L.'key'>"),
        AovSpec::new("unocc", "unoccluded;C<RD><L.'key'>"),
        AovSpec::new("shadow", "shadows;C<RD><L.'key'>"),
    ];
    // Every light equally likely (the light tree would mostly pick the near fill light on
    // the right, and 4 samples of a pixel would often hold no key sample to route).
    let setup = |d: &mut SceneDesc| {
        small(32, 4)(d);
        d.render.light_selection = lightpath::light::select::LightSelection::Uniform;
    };
    let (scene, film, _) = run(&source(TWO_ROOMS), setup, aovs);
    let (occ, unocc, shadow) = (
        idx(&scene, "occ"),
        idx(&scene, "unocc"),
        idx(&scene, "shadow"),
    );
    let (left, right) = halves(&film);
    // A pixel whose samples all chose the fill light has no key sample at all.
    let lit = |px: &[(u32, u32)], k: usize| {
        px.iter()
            .filter(|&&(x, y)| film.pixel(k, x, y).x > 0.0)
            .count()
    };
    for &(x, y) in &right {
        // The divider blocks the key light: only the unoccluded AOV sees it, and the
        // shadows AOV holds exactly what was blocked.
        assert_eq!(film.pixel(occ, x, y), Vec3A::ZERO);
        assert_eq!(film.pixel(shadow, x, y), film.pixel(unocc, x, y));
    }
    assert!(
        lit(&right, unocc) * 10 > right.len() * 9,
        "unoccluded misses the key light"
    );
    for &(x, y) in &left {
        assert_eq!(
            film.pixel(shadow, x, y),
            Vec3A::ZERO,
            "nothing blocks the key on its own side"
        );
    }
    assert!(lit(&left, occ) * 10 > left.len() * 9);
    assert!(sum(&film, unocc).x > sum(&film, occ).x);
}

#[test]
fn overwrite_keeps_the_last_value_and_nothruput_skips_the_throughput() {
    let src = lightpath::load_source("cornell-classic").unwrap();
    let aovs = vec![
        AovSpec::new("last", "nothruput;overwrite;C.*<RU2>L"),
        AovSpec::new("every", "nothruput;C.*<RU2>L"),
        AovSpec::new("albedo", "lpe:albedo"),
        AovSpec::new("second", "nothruput;overwrite;C<RD><RU2>L"),
        AovSpec::new("secondThru", "overwrite;C<RD><RU2>L"),
    ];
    let (scene, film, _) = run(&src, small(24, 4), aovs);
    let white = Vec3A::new(0.885809, 0.698859, 0.666422);
    // The back wall, seen in the middle of the image: the albedo is exactly its colour.
    let centre = film.pixel(idx(&scene, "albedo"), 12, 8);
    assert!(
        (centre - white).abs().max_element() < 1e-6,
        "albedo {centre}"
    );
    for y in 0..film.height {
        for x in 0..film.width {
            let last = film.pixel(idx(&scene, "last"), x, y);
            let every = film.pixel(idx(&scene, "every"), x, y);
            // An albedo never exceeds one; summed over every vertex it does.
            assert!(
                last.max_element() <= 0.886,
                "overwrite left {last} at {x},{y}"
            );
            assert!(every.max_element() >= last.max_element() - 1e-6);
            let second = film.pixel(idx(&scene, "second"), x, y);
            assert!(
                second.max_element() <= 0.886,
                "nothruput value {second} at {x},{y}"
            );
        }
    }
    assert!(sum(&film, idx(&scene, "every")).x > 1.5 * sum(&film, idx(&scene, "last")).x);
    // With the throughput the second surface's albedo is scaled by the first's.
    assert!(sum(&film, idx(&scene, "secondThru")).x < 0.95 * sum(&film, idx(&scene, "second")).x);
}

#[test]
fn data_lobes_report_normals_and_never_leak_into_lighting() {
    let src = source(TWO_ROOMS);
    let aovs = vec![
        AovSpec::new(
            "normal",
            "nothruput;noinfinitecheck;noclamp;unoccluded;overwrite;CU6L",
        ),
        AovSpec::new("everything", "C.*"),
    ];
    let (scene, film, _) = run(&src, small(16, 2), aovs.clone());
    let (x, y) = (film.width / 4, film.height / 2);
    let n = film.pixel(idx(&scene, "normal"), x, y);
    assert!((n - Vec3A::Y).length() < 1e-5, "floor normal {n}");
    // `.` never matches U lobes, so `C.*` receives lighting only: the same as beauty.
    let (b, e) = (sum(&film, 0), sum(&film, idx(&scene, "everything")));
    assert!(
        (b - e).abs().max_element() <= 1e-4 * b.max_element(),
        "{b} vs {e}"
    );
}

#[test]
fn holdouts_make_a_matte_and_collect_its_shadows() {
    let src = lightpath::load_source("cornell-classic").unwrap();
    let aovs = vec![
        AovSpec::new("occluded", "holdouts;C[DS]+[LO]"),
        AovSpec::new("unoccluded", "holdouts;unoccluded;C[DS]+[LO]"),
        AovSpec::new("floorSeen", "holdouts;nothruput;overwrite;C<RU2'floor'>L"),
    ];
    let floor_holdout = |d: &mut SceneDesc| {
        d.render.resolution = [32, 32];
        d.render.spp = 16;
        for o in &mut d.objects {
            if o.name.as_deref() == Some("floor") {
                o.holdout = true;
            }
        }
    };
    let (scene, film, _) = run(&src, floor_holdout, aovs);
    let alpha = film.alpha();
    let derived = lightpath::output::derived_aovs(&film, &scene.aovs);
    let shadow = &derived
        .iter()
        .find(|d| d.name == "shadow")
        .expect("a derived shadow AOV")
        .rgb;
    let (occ, unocc) = (idx(&scene, "occluded"), idx(&scene, "unoccluded"));
    let mut floor_pixels = 0;
    let mut shadowed = 0;
    for y in 0..film.height {
        for x in 0..film.width {
            let i = (y * film.width + x) as usize;
            let seen = film.pixel(idx(&scene, "floorSeen"), x, y);
            if seen.x > 0.885 {
                assert_eq!(alpha[i], 0.0, "a matte has alpha 0");
                floor_pixels += 1;
                // The matte is absent from beauty but its light is in the holdout AOVs.
                assert_eq!(film.pixel(0, x, y), Vec3A::ZERO);
                assert!(
                    film.pixel(unocc, x, y).x > 0.0,
                    "no unoccluded light on the matte at {x},{y}"
                );
                assert!(film.pixel(unocc, x, y).x >= film.pixel(occ, x, y).x * 0.5);
                assert!((0.0..=1.0).contains(&shadow[0][i]));
                shadowed += (shadow[0][i] > 0.5) as u32;
            }
        }
    }
    assert!(floor_pixels > 50, "the floor should be seen as a matte");
    assert!(shadowed > 3, "the boxes cast shadows on the holdout floor");
    // Paths that touch the floor are gone from beauty elsewhere too, and only there.
    assert!(sum(&film, occ).x > 0.0);
}

#[test]
fn light_group_splits_sum_to_any_split_aov() {
    let src = lightpath::load_source("cornell").unwrap();
    let aovs = vec![
        AovSpec::new("dd", "lpe:directDiffuse").split(),
        AovSpec::new("beauty", "lpe:beauty").split(),
    ];
    let (scene, film, _) = run(&src, small(24, 2), aovs);
    for whole in ["beauty", "dd"] {
        let parts: Vec<usize> = scene
            .aovs
            .iter()
            .enumerate()
            .filter(|(_, a)| a.part_of == Some(idx(&scene, whole) as u32))
            .map(|(k, _)| k)
            .collect();
        assert_eq!(parts.len(), 3, "key, fill and the default group");
        let total: Vec3A = parts.iter().map(|&k| sum(&film, k)).sum();
        let w = sum(&film, idx(&scene, whole));
        assert!(
            (total - w).abs().max_element() <= 1e-5 * w.max_element(),
            "{whole}: {total} vs {w}"
        );
    }
    // The glowing ball belongs to no light group.
    assert!(sum(&film, idx(&scene, "beauty__default")).x > 0.0);
}

/// `albedo` is an `overwrite` AOV that both an emitter (`O`, in the light's group) and the
/// data lobe of the emitter's own material (no group) reach in the same sample: the last
/// one wins in the whole, and must win in the parts too.
#[test]
fn overwritten_split_aovs_still_sum() {
    let src = lightpath::load_source("cornell-classic").unwrap();
    let aovs = vec![AovSpec::new("albedo", "lpe:albedo").split()];
    let (scene, film, _) = run(&src, small(32, 2), aovs);
    let whole = idx(&scene, "albedo");
    let parts: Vec<usize> = (0..scene.aovs.len())
        .filter(|&k| scene.aovs[k].part_of == Some(whole as u32))
        .collect();
    assert_eq!(parts.len(), 2, "the light's group and the default part");
    for c in 0..3 {
        for (i, &w) in film.channel(whole, c).iter().enumerate() {
            let total: f32 = parts.iter().map(|&k| film.channel(k, c)[i]).sum();
            assert!(
                (total - w).abs() <= 1e-5 * w.abs().max(1.0),
                "pixel {i} channel {c}: parts {total} vs albedo {w}"
            );
        }
    }
}

/// Exact under uniform light selection, where no sampling decision depends on a light's
/// colour (with the default light tree the two agree within noise: tests/it/sampling.rs).
#[test]
fn relighting_from_aovs_equals_re_rendering() {
    let src = lightpath::load_source("cornell").unwrap();
    let aovs = || vec![AovSpec::new("beauty", "lpe:beauty").split()];
    // Clamping is not linear in a light's intensity: off, as in a relighting workflow.
    let uniform = |d: &mut SceneDesc| {
        small(20, 3)(d);
        d.render.light_selection = lightpath::light::select::LightSelection::Uniform;
        d.render.clamp_indirect = 0.0;
    };
    let (scene, film, _) = run(&src, uniform, aovs());
    let brighter = |d: &mut SceneDesc| {
        d.render.resolution = [20, 20];
        d.render.spp = 3;
        d.render.light_selection = lightpath::light::select::LightSelection::Uniform;
        d.render.clamp_indirect = 0.0;
        for l in &mut d.lights {
            if l.groups == ["key"] {
                l.strength = 1.5;
            }
        }
    };
    let (_, rerendered, _) = run(&src, brighter, aovs());
    let key = idx(&scene, "beauty_key");
    for y in 0..film.height {
        for x in 0..film.width {
            let relit = film.pixel(0, x, y) + 0.5 * film.pixel(key, x, y);
            let truth = rerendered.pixel(0, x, y);
            assert!(
                (relit - truth).abs().max_element() <= 1e-5 * truth.max_element().max(1.0),
                "{relit} vs {truth} at {x},{y}"
            );
        }
    }
}

#[test]
fn trace_sets_and_light_linking_change_what_rays_see() {
    let aovs = || vec![AovSpec::new("key", "C<RD><L.'key'>")];
    let src = source(TWO_ROOMS);
    let (_, base, _) = run(&src, small(24, 2), aovs());
    let (_, right) = halves(&base);
    let on_right = |f: &Film| right.iter().map(|&(x, y)| f.pixel(1, x, y).x).sum::<f32>();
    assert_eq!(on_right(&base), 0.0);

    // A divider that casts no shadow lets the key light through.
    let (_, no_shadow, _) = run(
        &src,
        |d| {
            small(24, 2)(d);
            d.objects[1].casts_shadows = false;
        },
        aovs(),
    );
    assert!(on_right(&no_shadow) > 0.0);

    // Light linking: the key light excluded from the floor lights nothing.
    let (_, unlinked, _) = run(
        &src,
        |d| {
            small(24, 2)(d);
            d.lights[0].exclude = vec!["floor".into()];
        },
        aovs(),
    );
    assert_eq!(sum(&unlinked, 1), Vec3A::ZERO);

    // Hidden from indirect rays, the divider no longer bounces light onto the floor.
    let bounce = || {
        vec![AovSpec::new(
            "viaDivider",
            "C<RD'floor'><RD'divider'>[<L.>O]",
        )]
    };
    let depth3 = |d: &mut SceneDesc| {
        small(24, 4)(d);
        d.render.max_depth = 3;
    };
    let (_, seen, _) = run(&src, depth3, bounce());
    assert!(sum(&seen, 1).x > 0.0);
    let (_, unseen, _) = run(
        &src,
        |d| {
            depth3(d);
            d.objects[1].visible_indirect = false;
        },
        bounce(),
    );
    assert_eq!(sum(&unseen, 1), Vec3A::ZERO);

    // Hidden from the camera, the floor leaves the image empty (alpha 0).
    let (_, hidden, _) = run(
        &src,
        |d| {
            small(24, 2)(d);
            d.objects[0].visible_camera = false;
        },
        aovs(),
    );
    assert!(hidden.alpha().iter().filter(|a| **a == 0.0).count() > 400);
}

#[test]
fn clamping_and_the_infinite_check_spare_their_exempt_aovs() {
    let src = lightpath::load_source("cornell").unwrap();
    let aovs = || vec![AovSpec::new("raw", "noclamp;C[DS]*[<L.>O]")];
    let (_, plain, _) = run(&src, small(20, 2), aovs());
    let (_, clamped, _) = run(
        &src,
        |d| {
            small(20, 2)(d);
            d.render.clamp_direct = 0.5;
            d.render.clamp_indirect = 0.05;
        },
        aovs(),
    );
    // The noclamp AOV is the unclamped beauty, bit for bit; the clamped beauty is less.
    assert_eq!(clamped.channel(1, 0), plain.channel(0, 0));
    assert!(sum(&clamped, 0).x < 0.95 * sum(&plain, 0).x);

    let glow_inf = r#"
[camera]
position = [0, 0, 3]
[materials.m]
type = "diffuse"
albedo = [0.5, 0.5, 0.5]
[[objects]]
shape = "sphere"
material = "m"
radius = 0.5
emission = [inf, 1, 1]
"#;
    let aovs = vec![AovSpec::new("kept", "noinfinitecheck;CO")];
    let (_, film, stats) = run(&source(glow_inf), small(8, 1), aovs);
    assert!(stats.nonfinite > 0);
    assert!(film.channel(0, 0).iter().all(|v| v.is_finite()));
    assert!(film.channel(1, 0).iter().any(|v| v.is_infinite()));
}

#[test]
fn user_colour_lobes_report_the_material_colour() {
    let text = TWO_ROOMS.replace(
        "albedo = [0.8, 0.8, 0.8]",
        "albedo = [0.8, 0.8, 0.8]\nuser_color = [0.1, 0.2, 0.3]",
    );
    let aovs = vec![AovSpec::new("user", "nothruput;overwrite;unoccluded;CU4L")];
    let (scene, film, _) = run(&source(&text), small(16, 2), aovs);
    let v = film.pixel(idx(&scene, "user"), film.width / 4, film.height / 2);
    assert!(
        (v - Vec3A::new(0.1, 0.2, 0.3)).abs().max_element() < 1e-6,
        "{v}"
    );
    // Materials without a user colour emit no U4 event at all.
    let (scene, film, _) = run(
        &source(TWO_ROOMS),
        small(16, 2),
        vec![AovSpec::new("user", "nothruput;CU4L")],
    );
    assert_eq!(sum(&film, idx(&scene, "user")), Vec3A::ZERO);
}
