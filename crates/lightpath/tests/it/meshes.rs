//! Scenes people already have: OBJ with MTL, PLY, mesh lights, and TOML scenes that
//! include such files and override their objects by name. Every test writes its own
//! small files in a temporary directory.

use crate::common::index;
use glam::Vec3A;
use lightpath::aov::{self, AovSpec};
use lightpath::film::Film;
use lightpath::light::luminance;
use lightpath::scene::desc::{LightKind, MaterialKind, SceneDesc, ShapeDesc};
use lightpath::{render, RenderOptions, Scene, Source};
use std::path::{Path, PathBuf};

/// A fresh directory for one test's files.
fn temp_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lightpath-meshes-{test}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn write(dir: &Path, name: &str, text: impl AsRef<[u8]>) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// The Cornell box as an OBJ: the 2 × 2 × 2 room of the built-in `cornell` scene, open
/// towards +z, with a quad light just under the ceiling (`light` faces down).
const CORNELL_ROOM: &str = "\
# Cornell box
mtllib cornell.mtl
v -1 -1  1
v  1 -1  1
v  1 -1 -1
v -1 -1 -1
v -1  1  1
v  1  1  1
v  1  1 -1
v -1  1 -1
o floor
usemtl white
f 1 2 3 4
o ceiling
usemtl white
f 5 8 7 6
o backWall
usemtl white
f 4 3 7 8
o leftWall
usemtl red
f 1 4 8 5
o rightWall
usemtl green
f 2 6 7 3
";

const CORNELL_LIGHT: &str = "\
v -0.25 0.98 -0.25
v  0.25 0.98 -0.25
v  0.25 0.98  0.25
v -0.25 0.98  0.25
o light
usemtl light
f -4 -3 -2 -1
";

const CORNELL_MTL: &str = "\
newmtl white
Kd 0.8 0.8 0.8
newmtl red
Kd 0.57 0.043 0.044
newmtl green
Kd 0.105 0.378 0.076
newmtl light
Kd 0.78 0.78 0.78
Ke 17 12 4
";

/// The same light declared in TOML: a two-sided quad light with the light's surface.
const QUAD_LIGHT: &str = "
[materials.lightSurface]
type = \"diffuse\"
albedo = [0.78, 0.78, 0.78]

[[lights]]
type = \"quad\"
corners = [[-0.25, 0.98, -0.25], [0.25, 0.98, -0.25], [0.25, 0.98, 0.25], [-0.25, 0.98, 0.25]]
radiance = [17, 12, 4]
two_sided = true
material = \"lightSurface\"
groups = [\"light\"]
";

const CAMERA: &str = "
[camera]
position = [0, 0, 3.9]
look_at = [0, 0, 0]
fov = 39.3077
";

/// Writes the Cornell box OBJ (with its light) and MTL; returns the OBJ's path.
fn cornell_files(dir: &Path) -> PathBuf {
    write(dir, "cornell.mtl", CORNELL_MTL);
    write(dir, "room.obj", CORNELL_ROOM);
    write(dir, "cornell.obj", format!("{CORNELL_ROOM}{CORNELL_LIGHT}"))
}

fn render_desc(
    mut desc: SceneDesc,
    res: u32,
    spp: u32,
    seed: u64,
    extra: Vec<AovSpec>,
) -> (Scene, Film) {
    desc.render.resolution = [res, res];
    desc.render.spp = spp;
    desc.render.max_depth = 4;
    desc.render.seed = seed;
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

fn parse(path: &Path) -> Result<SceneDesc, lightpath::SceneError> {
    Source::from_file(path)?.parse()
}

#[test]
fn a_cornell_box_obj_renders_with_its_mtl_colours_groups_and_light() {
    let dir = temp_dir("cornell");
    let obj = cornell_files(&dir);
    let desc = parse(&obj).unwrap();
    // No camera and no TOML: a framing camera, said in a warning; the Ke light is a
    // mesh light whose light group is its object's name.
    assert!(
        desc.warnings.iter().any(|w| w.contains("no camera")),
        "{:?}",
        desc.warnings
    );
    assert_eq!(desc.lights.len(), 1);
    assert!(matches!(desc.lights[0].kind, LightKind::Mesh { .. }));
    assert_eq!(desc.lights[0].groups, ["light"]);
    let names: Vec<&str> = desc
        .objects
        .iter()
        .filter_map(|o| o.name.as_deref())
        .collect();
    assert_eq!(
        names,
        [
            "floor",
            "ceiling",
            "backWall",
            "leftWall",
            "rightWall",
            "light"
        ]
    );
    let extra = vec![
        AovSpec::new("leftDirect", "C<RD'leftWall'><L'light'>"),
        AovSpec::new("rightAll", "C<R.'rightWall'>.*[<L.>O]"),
    ];
    let (scene, film) = render_desc(desc, 24, 16, 0, extra);
    // The framing camera sees the left wall at the left edge, the right wall at the right.
    let mean = |x0: u32, x1: u32, k: usize| -> Vec3A {
        let mut sum = Vec3A::ZERO;
        for y in 9..15 {
            for x in x0..x1 {
                sum += film.pixel(k, x, y);
            }
        }
        sum / ((x1 - x0) * 6) as f32
    };
    let (left, right) = (mean(5, 7, 0), mean(17, 19, 0));
    assert!(
        left.x > 2.0 * left.y && left.x > 0.05,
        "left wall is red: {left}"
    );
    assert!(
        right.y > 1.5 * right.x && right.y > 0.02,
        "right wall is green: {right}"
    );
    // The object names are LPE groups: each AOV sees only its wall.
    let (ld, ra) = (index(&scene, "leftDirect"), index(&scene, "rightAll"));
    assert!(mean(5, 7, ld).x > 0.0 && mean(17, 19, ld) == Vec3A::ZERO);
    assert!(mean(17, 19, ra).y > 0.0 && mean(5, 7, ra) == Vec3A::ZERO);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// RMS over pixels of the difference of two renders' beauty luminance (seeds 1 and 2), /√2:
/// the per-pixel standard deviation; and the mean luminance.
fn noise_and_mean(toml: &Path, res: u32, spp: u32) -> (f64, f64) {
    let lum = |seed| {
        let (_, film) = render_desc(parse(toml).unwrap(), res, spp, seed, vec![]);
        let mut v = Vec::new();
        for y in 0..film.height {
            for x in 0..film.width {
                v.push(luminance(film.pixel(0, x, y)) as f64);
            }
        }
        v
    };
    let (a, b) = (lum(1), lum(2));
    let n = a.len() as f64;
    let var: f64 = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        / (2.0 * n);
    let mean = a.iter().chain(&b).sum::<f64>() / (2.0 * n);
    (var.sqrt(), mean)
}

/// The MTL's `Ke` light is sampled like a declared light: at equal samples the box lit by
/// it is no noisier than the same box with a declared quad light (within 1.5×, the
/// issue's bound), and as bright.
#[test]
fn an_obj_ke_light_is_sampled_as_well_as_a_declared_quad_light() {
    let dir = temp_dir("noise");
    cornell_files(&dir);
    let mesh = write(
        &dir,
        "mesh.toml",
        format!("{CAMERA}\n[[include]]\nfile = \"cornell.obj\"\n"),
    );
    let quad = write(
        &dir,
        "quad.toml",
        format!("{CAMERA}{QUAD_LIGHT}\n[[include]]\nfile = \"room.obj\"\n"),
    );
    let (res, spp) = (32, 8);
    let (noise_mesh, mean_mesh) = noise_and_mean(&mesh, res, spp);
    let (noise_quad, mean_quad) = noise_and_mean(&quad, res, spp);
    let ratio = noise_mesh / noise_quad;
    eprintln!("noise at {spp} spp: mesh light {noise_mesh:.4}, quad light {noise_quad:.4} ({ratio:.3}x); means {mean_mesh:.4}, {mean_quad:.4}");
    assert!(
        ratio < 1.5,
        "mesh light noise {noise_mesh} vs quad light {noise_quad}: {ratio}x"
    );
    // Means of 2·32² pixel values whose spread is the noise: agree to a few standard errors.
    let se = (noise_mesh.powi(2) + noise_quad.powi(2)).sqrt() / (2.0 * (res * res) as f64).sqrt();
    assert!(
        (mean_mesh - mean_quad).abs() < 6.0 * se + 1e-3 * mean_quad,
        "{mean_mesh} vs {mean_quad} (se {se})"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The error of loading `name` with `text` as a scene file.
fn load_error(dir: &Path, name: &str, text: impl AsRef<[u8]>) -> lightpath::SceneError {
    let path = write(dir, name, text);
    parse(&path)
        .err()
        .unwrap_or_else(|| panic!("{name} loaded"))
}

#[test]
fn obj_and_mtl_errors_name_the_file_line_column_and_what_was_expected() {
    let dir = temp_dir("obj-errors");
    let e = load_error(&dir, "nan.obj", "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n");
    assert_eq!((e.line, e.column), (2, 5), "{e}");
    assert!(e.message.contains("not a finite number"), "{e}");
    let e = load_error(&dir, "range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    assert_eq!((e.line, e.column), (4, 7), "{e}");
    assert!(
        e.message.contains("out of range") && e.message.contains("3 vertices"),
        "{e}"
    );
    let e = load_error(&dir, "word.obj", "v 0 0 zero\n");
    assert!(
        e.to_string().starts_with(&format!(
            "{}:1:7: expected a number",
            dir.join("word.obj").display()
        )),
        "{e}"
    );
    // A glTF, binary or JSON, given as an OBJ says so.
    let e = load_error(&dir, "model.obj", b"glTF\x02\x00\x00\x00rest");
    assert!(e.message.contains("binary glTF"), "{e}");
    let e = load_error(&dir, "scene.obj", "{\"asset\": {\"version\": \"2.0\"}}");
    assert!(e.message.contains("JSON"), "{e}");
    let e = load_error(&dir, "text.obj", "hello world\n");
    assert!(
        e.message.contains("no faces") && e.message.contains("'hello'"),
        "{e}"
    );
    // MTL errors point into the MTL file.
    write(&dir, "bad.mtl", "newmtl a\nKd 0.5 x 0.5\n");
    let e = load_error(
        &dir,
        "uses.obj",
        "mtllib bad.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n",
    );
    assert!(
        e.file.ends_with("bad.mtl") && (e.line, e.column) == (2, 8),
        "{e}"
    );
    // A missing MTL is a warning: the faces render grey.
    let path = write(
        &dir,
        "nomtl.obj",
        "mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n",
    );
    let desc = parse(&path).unwrap();
    assert!(
        desc.warnings.iter().any(|w| w.contains("gone.mtl")),
        "{:?}",
        desc.warnings
    );
    // A missing OBJ named by a TOML scene: the TOML's line and the OS reason.
    let toml = write(&dir, "scene.toml", "[[include]]\nfile = \"missing.obj\"\n");
    let e = parse(&toml).unwrap_err();
    assert!(e.file.ends_with("scene.toml") && e.line == 2, "{e}");
    assert!(
        e.message.contains("missing.obj") && e.message.contains("No such file"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn obj_objects_groups_polygons_normals_and_materials() {
    let dir = temp_dir("obj-parts");
    write(
        &dir,
        "m.mtl",
        "newmtl glass\nNi 1.45\nd 0.2\nnewmtl shiny\nKd 0.2 0.3 0.4\nKs 0.5 0.5 0.5\nNs 250\nmap_Kd -s 1 1 tex.png\nnewmtl metal\nKd 0 0 0\nKs 0.9 0.8 0.7\nNs 1000\n",
    );
    let path = write(
        &dir,
        "parts.obj",
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nvt 0 0\n\
         o table\ng top legs\nusemtl shiny\nf 1/1/1 2/1/1 3/1/1 4/1/1\nusemtl glass\nf 1//1 3//1 4//1\n\
         o lamp\nusemtl metal\nf 1 2 3\n",
    );
    let desc = parse(&path).unwrap();
    let o: Vec<_> = desc
        .objects
        .iter()
        .map(|o| {
            (
                o.name.clone().unwrap(),
                o.lpegroups.clone().unwrap(),
                o.material.as_ref().unwrap().name.clone(),
            )
        })
        .collect();
    assert_eq!(
        o,
        [
            (
                "top legs".into(),
                vec!["top".to_string(), "legs".into(), "table".into()],
                "shiny".to_string()
            ),
            (
                "top legs".into(),
                vec!["top".to_string(), "legs".into(), "table".into()],
                "glass".to_string()
            ),
            ("lamp".into(), vec!["lamp".to_string()], "metal".to_string()),
        ]
    );
    // The quad is two triangles sharing the vertices of equal (v, vt, vn).
    let ShapeDesc::Mesh { parts } = &desc.objects[0].shape else {
        panic!()
    };
    assert_eq!((parts[0].positions.len(), parts[0].indices.len()), (4, 2));
    assert!(parts[0].normals.is_some() && parts[0].uvs.is_some());
    let m = &desc.materials;
    assert!(matches!(m["glass"].kind, MaterialKind::Dielectric { ior: Some(i), .. } if i == 1.45));
    assert!(
        matches!(m["shiny"].kind, MaterialKind::Plastic { albedo, .. } if albedo == [0.2, 0.3, 0.4])
    );
    // Blender's mapping of the Phong exponent: 1 − √(250/1000) = 0.5.
    assert!((m["shiny"].roughness - 0.5).abs() < 1e-6);
    assert_eq!(
        m["shiny"].base_color_map.as_ref().unwrap().path,
        dir.join("tex.png")
    );
    assert!(matches!(m["metal"].kind, MaterialKind::Conductor { f0 } if f0 == [0.9, 0.8, 0.7]));
    assert_eq!(m["metal"].roughness, 0.0);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A unit quad as PLY: four vertices with normals and UVs, one polygon face.
fn ply_header(format: &str, extra_face: &str) -> String {
    format!(
        "ply\nformat {format} 1.0\ncomment a quad\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\nproperty float s\nproperty float t\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\n\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        1 + extra_face.len().min(1)
    )
}

const QUAD: [[f32; 3]; 4] = [
    [-1.0, -1.0, 0.0],
    [1.0, -1.0, 0.0],
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
];

fn binary_ply(big_endian: bool) -> Vec<u8> {
    let mut b = ply_header(
        if big_endian {
            "binary_big_endian"
        } else {
            "binary_little_endian"
        },
        "",
    )
    .into_bytes();
    let f = |b: &mut Vec<u8>, x: f32| {
        b.extend(if big_endian {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        })
    };
    for (k, p) in QUAD.iter().enumerate() {
        for c in p {
            f(&mut b, *c);
        }
        for c in [0.0, 0.0, 1.0, (k % 2) as f32, (k / 2) as f32] {
            f(&mut b, c);
        }
        b.extend([255, 128, 0]);
    }
    b.push(4);
    for i in [0i32, 1, 2, 3] {
        b.extend(if big_endian {
            i.to_be_bytes()
        } else {
            i.to_le_bytes()
        });
    }
    b
}

#[test]
fn ply_ascii_and_binary_load_the_same_mesh_and_errors_name_the_element() {
    let dir = temp_dir("ply");
    let mut ascii = ply_header("ascii", "");
    for (k, p) in QUAD.iter().enumerate() {
        ascii += &format!(
            "{} {} {} 0 0 1 {} {} 255 128 0\n",
            p[0],
            p[1],
            p[2],
            k % 2,
            k / 2
        );
    }
    ascii += "4 0 1 2 3\n";
    let mut meshes = Vec::new();
    for (name, bytes) in [
        ("a.ply", ascii.clone().into_bytes()),
        ("le.ply", binary_ply(false)),
        ("be.ply", binary_ply(true)),
    ] {
        let desc = parse(&write(&dir, name, bytes)).unwrap();
        let ShapeDesc::Mesh { parts } = &desc.objects[0].shape else {
            panic!()
        };
        assert_eq!(
            desc.objects[0].name.as_deref(),
            Some(&name[..name.len() - 4])
        );
        meshes.push(parts[0].clone());
        // A PLY has no camera and no light: both defaults, both said.
        assert!(
            desc.warnings.iter().any(|w| w.contains("no light")),
            "{:?}",
            desc.warnings
        );
    }
    for m in &meshes {
        assert_eq!(m.positions, QUAD);
        assert_eq!(m.indices, [[0, 1, 2], [0, 2, 3]]);
        assert_eq!(m.normals.as_deref(), Some(&[[0.0, 0.0, 1.0]; 4][..]));
        // (s, t) = (1, 1): the top-right corner, (1, 0) in our top-down UVs.
        assert_eq!(m.uvs.as_ref().unwrap()[3], [1.0, 0.0]);
    }
    // It renders: lit by the default dome, the quad seen face-on fills the middle.
    let desc = parse(&dir.join("le.ply")).unwrap();
    let (_, film) = render_desc(desc, 8, 4, 0, vec![]);
    assert!(film.pixel(0, 4, 4).x > 0.1);
    // ASCII: the element's line; binary: the element's number.
    let bad = ascii.replace("1 1 0 0 0 1", "1 1 nope 0 0 1");
    let e = load_error(&dir, "bad.ply", bad);
    let header_lines = ply_header("ascii", "").lines().count();
    assert_eq!(e.line, header_lines + 3, "{e}");
    assert!(e.message.contains("'vertex' 3 of 4"), "{e}");
    assert!(
        e.message.contains("'1 1 nope 0 0 1 0 1 255 128 0'") && e.message.contains("x (float)"),
        "{e}"
    );
    // A non-finite vertex: an error with its element.
    let mut nan = binary_ply(false);
    let y_of_vertex_3 = ply_header("binary_little_endian", "").len() + 2 * (8 * 4 + 3) + 4;
    nan[y_of_vertex_3..y_of_vertex_3 + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    let e = load_error(&dir, "nan.ply", nan);
    assert!(
        e.message.contains("'vertex' 3 of 4") && e.message.contains("not finite"),
        "{e}"
    );
    let range = ascii.replace("4 0 1 2 3", "4 0 1 2 7");
    let e = load_error(&dir, "range.ply", range);
    assert!(
        e.message.contains("'face' 1 of 1") && e.message.contains("out of range"),
        "{e}"
    );
    let mut cut = binary_ply(false);
    cut.truncate(cut.len() - 30);
    let e = load_error(&dir, "cut.ply", cut);
    assert!(e.message.contains("'vertex' 4 of 4"), "{e}");
    let e = load_error(&dir, "obj.ply", "v 0 0 0\n");
    assert!(e.message.contains("not a PLY file"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn ply_vertex_colours_multiply_the_albedo() {
    // The quad of the PLY tests, red (255, 128, 0) on its left edge and blue (0, 128, 255)
    // on its right, under the PLY's grey 0.8. Byte colours are sRGB (128 → 0.2158 linear),
    // interpolated as linear values: red + blue is 0.8 everywhere on the quad, green
    // 0.8 × 0.2158, and red falls from left to right.
    let dir = temp_dir("plycolor");
    let mut ascii = ply_header("ascii", "");
    for (k, p) in QUAD.iter().enumerate() {
        let rgb = if p[0] < 0.0 { "255 128 0" } else { "0 128 255" };
        ascii += &format!(
            "{} {} {} 0 0 1 {} {} {rgb}\n",
            p[0],
            p[1],
            p[2],
            k % 2,
            k / 2
        );
    }
    ascii += "4 0 1 2 3\n";
    let desc = parse(&write(&dir, "colours.ply", ascii)).unwrap();
    assert!(
        !desc.warnings.iter().any(|w| w.contains("vertex colours")),
        "{:?}",
        desc.warnings
    );
    let res = 17;
    let (scene, film) = render_desc(desc, res, 4, 0, vec![AovSpec::new("albedo", "lpe:albedo")]);
    let k = index(&scene, "albedo");
    let green = 0.8 * 0.2158605;
    // The default camera stands 4.135 away with a 40° field: the quad's ±1 spans
    // (1/4.135)/tan 20° = 0.665 of the half-width, pixels 2.85 to 14.15 of 17, so pixels
    // 3 to 13 of the middle row see only the quad.
    let mut last_red = f32::INFINITY;
    for x in 3..=13 {
        let a = film.pixel(k, x, res / 2);
        assert!((a.x + a.z - 0.8).abs() < 1e-4, "pixel {x}: {a}");
        assert!((a.y - green).abs() < 1e-4, "pixel {x}: {a}");
        assert!(a.x < last_red, "pixel {x}: red {} after {last_red}", a.x);
        last_red = a.x;
    }
    // The centre pixel is the middle of the gradient (a pixel's samples straddle it
    // symmetrically; they are 1/17 of the image apart from the next pixel's).
    let c = film.pixel(k, res / 2, res / 2);
    assert!((c.x - 0.4).abs() < 0.05 && (c.z - 0.4).abs() < 0.05, "{c}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// An 8×8 RGB PNG, red in its top four rows and blue in the bottom four.
fn red_over_blue_png() -> Vec<u8> {
    let mut image = image::RgbImage::new(8, 8);
    for (_, y, p) in image.enumerate_pixels_mut() {
        *p = if y < 4 {
            image::Rgb([255, 0, 0])
        } else {
            image::Rgb([0, 0, 255])
        };
    }
    let mut png = Vec::new();
    image
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    png
}

#[test]
fn an_obj_texture_is_upright_as_blender_maps_it() {
    // OBJ's vt (0, 0) is the image's bottom-left corner: the quad's top edge (vt v = 1)
    // shows the image's top rows (red), its bottom edge the bottom rows (blue).
    let dir = temp_dir("obj-texture");
    write(&dir, "tex.png", red_over_blue_png());
    write(
        &dir,
        "quad.mtl",
        "newmtl m\nKd 1 1 1\nillum 1\nmap_Kd tex.png\n",
    );
    let obj = write(
        &dir,
        "quad.obj",
        "mtllib quad.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n\
         vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\nusemtl m\nf 1/1/1 2/2/1 3/3/1 4/4/1\n",
    );
    let res = 17;
    let (scene, film) = render_desc(
        parse(&obj).unwrap(),
        res,
        4,
        0,
        vec![AovSpec::new("albedo", "lpe:albedo")],
    );
    let k = index(&scene, "albedo");
    // Pixels 3 to 13 see only the quad (as in the PLY test above); row 4 is its upper
    // part, row 12 its lower part.
    let (top, bottom) = (film.pixel(k, res / 2, 4), film.pixel(k, res / 2, 12));
    assert!(top.x > 0.9 && top.z < 0.01, "top {top}");
    assert!(bottom.z > 0.9 && bottom.x < 0.01, "bottom {bottom}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_toml_scene_includes_files_and_overrides_their_objects_by_name() {
    let dir = temp_dir("include");
    cornell_files(&dir);
    let scene = format!(
        "{CAMERA}
[materials.blue]
type = \"diffuse\"
albedo = [0.1, 0.1, 0.8]

[materials.white]
type = \"diffuse\"
albedo = [0.5, 0.5, 0.5]

[[include]]
file = \"cornell.obj\"
translate = [0, 0, -1]

[include.objects.leftWall]
material = \"blue\"
lpegroups = [\"walls\", \"left\"]

[include.objects.backWall]
holdout = true
visible_camera = false

[include.objects.light]
light = false
"
    );
    let desc = parse(&write(&dir, "scene.toml", &scene)).unwrap();
    let by_name = |n: &str| {
        desc.objects
            .iter()
            .find(|o| o.name.as_deref() == Some(n))
            .unwrap()
    };
    assert_eq!(by_name("leftWall").material.as_ref().unwrap().name, "blue");
    assert_eq!(
        by_name("leftWall").lpegroups.as_deref(),
        Some(&["walls".to_string(), "left".into()][..])
    );
    assert!(by_name("backWall").holdout && !by_name("backWall").visible_camera);
    // The TOML keeps its 'white'; the OBJ's is renamed, and its objects follow it.
    assert!(
        matches!(desc.materials["white"].kind, MaterialKind::Diffuse { albedo } if albedo == [0.5; 3])
    );
    let floor_material = &by_name("floor").material.as_ref().unwrap().name;
    assert_ne!(floor_material, "white");
    assert!(
        matches!(desc.materials[floor_material].kind, MaterialKind::Diffuse { albedo } if albedo == [0.8; 3])
    );
    // light = false: the Ke surface glows (an O event) instead of being a mesh light.
    assert!(desc.lights.is_empty());
    assert_eq!(by_name("light").emission, Some([17.0, 12.0, 4.0]));
    // Placement moves the imported geometry.
    assert_eq!(by_name("floor").transform.translation.z, -1.0);
    // A TOML mesh light over a named object: the author's choice, the other way round.
    let toml_light = scene.replace(
        "light = false",
        "light = false\n\n[[lights]]\ntype = \"mesh\"\nobject = \"floor\"\nradiance = [1, 1, 1]\n",
    );
    let desc = parse(&write(&dir, "floorlight.toml", toml_light)).unwrap();
    assert_eq!(desc.lights.len(), 1);
    assert_eq!(desc.lights[0].groups, ["floor"]);
    Scene::build(&desc, &aov::assemble(vec![])).unwrap();
    // An override of an object the file does not have names the file's objects.
    let e = parse(&write(
        &dir,
        "typo.toml",
        scene.replace("objects.leftWall", "objects.leftwall"),
    ))
    .unwrap_err();
    assert!(
        e.message.contains("'leftwall'") && e.message.contains("leftWall") && e.line > 0,
        "{e}"
    );
    let e = parse(&write(
        &dir,
        "nolight.toml",
        scene.replace(
            "[[include]]",
            "[[lights]]\ntype = \"mesh\"\nobject = \"lamp\"\nradiance = [1, 1, 1]\n\n[[include]]",
        ),
    ))
    .unwrap_err();
    assert!(e.message.contains("no object named 'lamp'"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn rendering_an_obj_directly_warns_about_the_defaults_it_adds() {
    let dir = temp_dir("direct");
    let path = write(&dir, "tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let mut job = lightpath::RenderJob::new(path.display().to_string());
    job.overrides.spp = Some(1);
    job.overrides.resolution = Some([4, 4]);
    job.output = Some(dir.join("tri.exr"));
    let prepared = job.prepare().unwrap();
    let w = prepared.warnings.join("\n");
    assert!(w.contains("no camera") && w.contains("no light"), "{w}");
    // A TOML scene without any light says it renders black.
    let toml = write(&dir, "dark.toml", "[[include]]\nfile = \"tri.obj\"\n");
    let prepared = lightpath::RenderJob::new(toml.display().to_string())
        .prepare()
        .unwrap();
    assert!(
        prepared
            .warnings
            .iter()
            .any(|w| w.contains("renders black")),
        "{:?}",
        prepared.warnings
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The lights-only test finds mesh lights through their own BVH: with a concave mesh
/// light (it shadows itself) and the room's walls in the way, `plain + shadows =
/// unoccluded` pixel by pixel, as for the other lights.
#[test]
fn unoccluded_sees_mesh_lights_and_plain_plus_shadows_is_unoccluded() {
    let dir = temp_dir("unoccluded");
    cornell_files(&dir);
    // A folded strip of light (a 'V', concave) in the room.
    write(
        &dir,
        "fold.obj",
        "v -0.4 0.2 0\nv 0 -0.1 0\nv 0.4 0.2 0\nv -0.4 0.2 -0.4\nv 0 -0.1 -0.4\nv 0.4 0.2 -0.4\n\
         o fold\nf 1 2 5 4\nf 2 3 6 5\n",
    );
    let scene = write(
        &dir,
        "scene.toml",
        format!(
            "{CAMERA}\n[[include]]\nfile = \"room.obj\"\n\n[[include]]\nfile = \"fold.obj\"\n\n\
             [[lights]]\ntype = \"mesh\"\nobject = \"fold\"\nradiance = [2, 2, 2]\ntwo_sided = true\n"
        ),
    );
    let desc = parse(&scene).unwrap();
    let expr = "C<RD>[<L.>O]";
    let aovs = vec![
        AovSpec::new("plain", expr),
        AovSpec::new("shadows", format!("shadows;{expr}")),
        AovSpec::new("unoccluded", format!("unoccluded;{expr}")),
    ];
    let (scene, film) = render_desc(desc, 16, 4, 0, aovs);
    let (p, s, u) = (
        index(&scene, "plain"),
        index(&scene, "shadows"),
        index(&scene, "unoccluded"),
    );
    let (mut worst, mut peak, mut shadow) = (0.0f32, 0.0f32, 0.0f32);
    for y in 0..film.height {
        for x in 0..film.width {
            let un = film.pixel(u, x, y);
            worst = worst.max(
                (film.pixel(p, x, y) + film.pixel(s, x, y) - un)
                    .abs()
                    .max_element(),
            );
            peak = peak.max(un.max_element());
            shadow += film.pixel(s, x, y).x;
        }
    }
    assert!(peak > 0.0 && shadow > 0.0, "peak {peak}, shadows {shadow}");
    assert!(worst <= 1e-5 * peak, "off by {worst} of {peak}");
    std::fs::remove_dir_all(&dir).unwrap();
}
