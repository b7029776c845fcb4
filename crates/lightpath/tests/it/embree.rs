//! `--accel embree` (cargo feature `embree`, Intel Embree 3): the same hits as the BVH up
//! to float rounding, so the same images; without the feature, an error that says how to
//! get it. CI runs this file with the feature where `libembree-dev` installs (`.ci/run`).

use crate::common;

use std::process::Command;

fn lightpath() -> Command {
    Command::new(env!("CARGO_BIN_EXE_lightpath"))
}

#[cfg(not(feature = "embree"))]
#[test]
fn a_build_without_embree_says_how_to_get_it() {
    let dir = common::Scratch::new("embree-missing");
    let out = dir.join("x.exr");
    let run = lightpath()
        .args(["render", "cornell-classic", "--quiet", "--accel", "embree"])
        .args(["--spp", "1", "--resolution", "8x8", "-o"])
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert!(
        stderr.contains("feature `embree`") && stderr.contains("libembree-dev"),
        "{stderr}"
    );
    assert!(!out.exists(), "nothing is rendered for nothing");
    // A name that is neither is refused by the parser, naming both.
    let run = lightpath()
        .args(["render", "cornell-classic", "--accel", "optix"])
        .output()
        .unwrap();
    assert!(!run.status.success());
    assert!(String::from_utf8_lossy(&run.stderr).contains("expected bvh or embree"));
}

#[cfg(feature = "embree")]
mod with_embree {
    use super::{common, lightpath};
    use glam::Vec3A;
    use lightpath::aov;
    use lightpath::geometry::{Hit, Ray, Visibility};
    use lightpath::sampling::{uniform_sphere, Rng};
    use lightpath::Scene;
    use std::fmt::Write;

    /// An OBJ of a bumpy, open half sphere: `n`² quads as two triangles each.
    fn bumpy_obj(n: usize) -> String {
        let mut s = String::new();
        for i in 0..=n {
            for j in 0..=n {
                let (th, ph) = (
                    std::f32::consts::FRAC_PI_2 * i as f32 / n as f32,
                    std::f32::consts::TAU * j as f32 / n as f32,
                );
                let r = 0.25 * (1.0 + 0.1 * (7.0 * th).sin() * (5.0 * ph).cos());
                let (x, y, z) = (
                    r * th.sin() * ph.cos(),
                    r * th.cos(),
                    r * th.sin() * ph.sin(),
                );
                writeln!(s, "v {x} {y} {z}").unwrap();
            }
        }
        let at = |i: usize, j: usize| i * (n + 1) + j + 1;
        for i in 0..n {
            for j in 0..n {
                let (a, b, c, d) = (at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j));
                writeln!(s, "f {a} {b} {c}\nf {a} {c} {d}").unwrap();
            }
        }
        s
    }

    /// cornell-classic with three instances of one OBJ (one mirrored, one hidden from
    /// camera rays), a fourth object of the same triangles not shared, and spheres (one
    /// that casts no shadow): every kind of primitive and trace set the seam handles.
    fn scene_file(dir: &common::Scratch) -> std::path::PathBuf {
        std::fs::write(dir.join("bump.obj"), bumpy_obj(24)).unwrap();
        let classic = lightpath::load_source("cornell-classic").unwrap().text;
        let extra = r#"
[materials.grey]
type = "diffuse"
albedo = [0.6, 0.6, 0.6]

[[objects]]
name = "a"
shape = "obj"
file = "bump.obj"
material = "grey"
translate = [-0.45, -0.6, 0.2]

[[objects]]
name = "b"
shape = "obj"
file = "bump.obj"
material = "grey"
scale = [-1, 1.3, 1]
rotate = [20, 30, 0]
translate = [0.4, -0.5, -0.3]

[[objects]]
name = "c"
shape = "obj"
file = "bump.obj"
material = "grey"
rotate = [180, 0, 0]
translate = [0.0, 0.55, 0.1]
visible_camera = false

[[objects]]
name = "ball"
shape = "sphere"
center = [0.35, 0.1, 0.4]
radius = 0.18
material = "grey"

[[objects]]
name = "ghost"
shape = "sphere"
center = [-0.3, 0.2, -0.2]
radius = 0.15
material = "grey"
casts_shadows = false
"#;
        let path = dir.join("scene.toml");
        std::fs::write(&path, format!("{classic}\n{extra}")).unwrap();
        path
    }

    fn build(path: &std::path::Path, embree: bool) -> Scene {
        let source = lightpath::load_source(path.to_str().unwrap()).unwrap();
        let desc = source.parse().unwrap();
        let mut scene = Scene::build(&desc, &aov::assemble(vec![])).unwrap();
        assert!(!scene.accel.instances().is_empty(), "the OBJ is shared");
        if embree {
            scene.accel.use_embree().unwrap();
            assert!(scene.accel.uses_embree());
        }
        scene
    }

    /// Both find a hit at distances within 1e-4 relative, on the same primitive and
    /// object with the same normal, or on two coincident surfaces (the boxes of
    /// cornell-classic stand on the floor: their bottoms and the floor are hit at the same
    /// distance, and either answer is right); or neither finds one.
    fn same(scene: &Scene, ray: &Ray, a: Option<Hit>, b: Option<Hit>) -> bool {
        match (a, b) {
            (None, None) => true,
            (Some(a), Some(b)) => {
                let close = |t: f32| (t - a.t).abs() <= 1e-4 * a.t.max(1e-3);
                if !close(b.t) {
                    return false;
                }
                if a.prim == b.prim && a.inner == b.inner {
                    return a.object == b.object && (a.ng - b.ng).length() < 1e-3;
                }
                // A tie: the other primitive lies at the same distance along the ray.
                let other = scene.accel.prims()[b.prim as usize];
                b.inner == u32::MAX
                    && close(other.intersect(ray.origin, ray.dir, 0.0, f32::INFINITY))
            }
            _ => false,
        }
    }

    #[test]
    fn embree_finds_the_bvh_hits() {
        let dir = common::Scratch::new("embree-hits");
        let path = scene_file(&dir);
        let (bvh, embree) = (build(&path, false), build(&path, true));
        let objects = bvh.accel.prims().len() as u32;
        let mut rng = Rng::for_sample(3, 1, 4);
        let rays = 20_000;
        let (mut hits, mut blocked, mut differ) = (0, 0, Vec::new());
        for k in 0..rays {
            let o = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 1.9
                - Vec3A::splat(0.95);
            let ray = Ray {
                origin: o,
                dir: uniform_sphere(rng.next_2d()),
                tmax: if k % 2 == 0 { f32::INFINITY } else { 0.7 },
            };
            for mask in [Visibility::CAMERA, Visibility::INDIRECT, Visibility::ALL] {
                let (a, b) = (
                    bvh.accel.intersect(&ray, 0.0, mask),
                    embree.accel.intersect(&ray, 0.0, mask),
                );
                hits += a.is_some() as u32;
                if !same(&bvh, &ray, a, b) {
                    differ.push(format!("ray {k} mask {mask}: bvh {a:?} embree {b:?}"));
                }
            }
            // Ignoring nothing, or the object the ray would hit first (a light's case).
            let first = bvh.accel.intersect(&ray, 0.0, Visibility::ALL);
            let ignore = match first {
                Some(h) if k % 3 != 0 => h.object,
                _ => (rng.next_f32() * objects as f32) as u32 % objects.max(1),
            };
            for ignore in [u32::MAX, ignore] {
                let (a, b) = (
                    bvh.accel.occluded(&ray, 0.0, ignore),
                    embree.accel.occluded(&ray, 0.0, ignore),
                );
                blocked += a as u32;
                if a != b {
                    differ.push(format!("ray {k} ignoring {ignore}: bvh {a} embree {b}"));
                }
            }
        }
        assert!(
            hits > rays && blocked > rays / 2,
            "{hits} hits, {blocked} blocked"
        );
        // A different answer needs a ray within float rounding of an edge shared by two
        // triangles (or of a box face): Möller–Trumbore and Embree's test can place such
        // a ray on either side. That is a few rays in a million, none expected here.
        assert!(
            differ.len() <= 2,
            "{} of {} queries differ:\n{}",
            differ.len(),
            5 * rays,
            differ.join("\n")
        );
    }

    /// The same render through the command line at both settings: the same sample
    /// streams meet the same surfaces, so pixels agree to float rounding, apart from the
    /// odd path that grazes an edge and goes elsewhere.
    #[test]
    fn renders_agree_with_the_bvh() {
        let dir = common::Scratch::new("embree-render");
        let path = scene_file(&dir);
        let mut images = Vec::new();
        for accel in ["bvh", "embree"] {
            let out = dir.join(&format!("{accel}.exr"));
            let run = lightpath()
                .arg("render")
                .arg(&path)
                .args([
                    "--quiet",
                    "--aovs",
                    "none",
                    "--spp",
                    "4",
                    "--resolution",
                    "48x48",
                ])
                .args(["--threads", "2", "--accel", accel, "-o"])
                .arg(&out)
                .output()
                .unwrap();
            assert!(
                run.status.success(),
                "{}",
                String::from_utf8_lossy(&run.stderr)
            );
            images.push(out);
        }
        let run = lightpath()
            .arg("diff")
            .args(&images)
            .args(["--tolerance", "1e-4"])
            .output()
            .unwrap();
        let said = String::from_utf8_lossy(&run.stdout).to_string()
            + &String::from_utf8_lossy(&run.stderr);
        assert!(run.status.success(), "{said}");
    }
}
