//! glTF scenes written by the tests themselves (JSON plus a .bin buffer, or one .glb):
//! the node hierarchy places meshes and names their LPE groups, cameras frame as the
//! file says, lights convert their photometric units as Blender's importer does,
//! textures are looked up as glTF defines them, and what Lightpath cannot read is an
//! error or a warning naming it.

use glam::{Affine3A, Quat, Vec3, Vec3A};
use lightpath::aov::{self, AovSpec};
use lightpath::film::Film;
use lightpath::scene::desc::{LightKind, MaterialKind, SceneDesc};
use lightpath::{render, RenderOptions, Scene};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// A glTF document under construction; accessors append to one binary buffer.
struct Doc {
    json: Value,
    bin: Vec<u8>,
}

impl Doc {
    fn new() -> Doc {
        Doc {
            json: json!({
                "asset": {"version": "2.0"},
                "scene": 0,
                "scenes": [{"nodes": []}],
                "nodes": [], "meshes": [], "accessors": [], "bufferViews": [],
                "buffers": [{"byteLength": 0}],
            }),
            bin: Vec::new(),
        }
    }

    fn push(&mut self, key: &str, v: Value) -> usize {
        let list = self.json[key].as_array_mut().expect("a list");
        list.push(v);
        list.len() - 1
    }

    fn view(&mut self, bytes: &[u8]) -> usize {
        while self.bin.len() % 4 != 0 {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.push(
            "bufferViews",
            json!({"buffer": 0, "byteOffset": offset, "byteLength": bytes.len()}),
        )
    }

    fn floats(&mut self, data: &[f32], comps: usize) -> usize {
        let bytes: Vec<u8> = data.iter().flat_map(|f| f.to_le_bytes()).collect();
        let view = self.view(&bytes);
        let ty = ["SCALAR", "VEC2", "VEC3", "VEC4"][comps - 1];
        let mut acc = json!({"bufferView": view, "componentType": 5126,
                             "count": data.len() / comps, "type": ty});
        if comps == 3 {
            let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
            for p in data.chunks_exact(3) {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
            acc["min"] = json!(lo);
            acc["max"] = json!(hi);
        }
        self.push("accessors", acc)
    }

    fn indices(&mut self, data: &[u32]) -> usize {
        let bytes: Vec<u8> = data.iter().flat_map(|i| i.to_le_bytes()).collect();
        let view = self.view(&bytes);
        self.push(
            "accessors",
            json!({"bufferView": view, "componentType": 5125, "count": data.len(), "type": "SCALAR"}),
        )
    }

    /// A mesh of one primitive; `uvs` per vertex, `material` by index.
    fn mesh(
        &mut self,
        positions: &[f32],
        indices: &[u32],
        uvs: Option<&[f32]>,
        material: Option<usize>,
    ) -> usize {
        let p = self.floats(positions, 3);
        let i = self.indices(indices);
        let mut prim = json!({"attributes": {"POSITION": p}, "indices": i});
        if let Some(uv) = uvs {
            prim["attributes"]["TEXCOORD_0"] = json!(self.floats(uv, 2));
        }
        if let Some(m) = material {
            prim["material"] = json!(m);
        }
        self.push("meshes", json!({"primitives": [prim]}))
    }

    /// The square [-s, s]² in z = 0 facing +z, UVs [0, k]² with v down the image.
    fn square(&mut self, s: f32, k: f32, material: Option<usize>) -> usize {
        let pos = [-s, -s, 0.0, s, -s, 0.0, s, s, 0.0, -s, s, 0.0];
        let uv = [0.0, k, k, k, k, 0.0, 0.0, 0.0];
        self.mesh(&pos, &[0, 1, 2, 0, 2, 3], Some(&uv), material)
    }

    fn node(&mut self, v: Value) -> usize {
        self.push("nodes", v)
    }

    fn root(&mut self, node: usize) {
        self.json["scenes"][0]["nodes"]
            .as_array_mut()
            .unwrap()
            .push(json!(node));
    }

    fn light(&mut self, v: Value) -> usize {
        let ext = &mut self.json["extensions"]["KHR_lights_punctual"]["lights"];
        if ext.is_null() {
            *ext = json!([]);
        }
        let list = ext.as_array_mut().unwrap();
        list.push(v);
        list.len() - 1
    }

    fn finish(&mut self) {
        self.json["buffers"][0]["byteLength"] = json!(self.bin.len());
        if self.json.get("extensions").is_some() {
            self.json["extensionsUsed"] = json!(["KHR_lights_punctual"]);
        }
    }

    /// Writes `<name>.gltf` and `<name>.bin` into `dir`.
    fn write(mut self, dir: &Path, name: &str) -> PathBuf {
        self.finish();
        self.json["buffers"][0]["uri"] = json!(format!("{name}.bin"));
        std::fs::write(dir.join(format!("{name}.bin")), &self.bin).unwrap();
        let path = dir.join(format!("{name}.gltf"));
        std::fs::write(&path, serde_json::to_vec_pretty(&self.json).unwrap()).unwrap();
        path
    }

    /// Writes one binary `.glb`: header, JSON chunk, BIN chunk.
    fn write_glb(mut self, path: &Path) {
        self.finish();
        let mut js = serde_json::to_vec(&self.json).unwrap();
        while js.len() % 4 != 0 {
            js.push(b' ');
        }
        while self.bin.len() % 4 != 0 {
            self.bin.push(0);
        }
        let total = 12 + 8 + js.len() + 8 + self.bin.len();
        let mut out = Vec::new();
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&(total as u32).to_le_bytes());
        out.extend_from_slice(&(js.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&js);
        out.extend_from_slice(&(self.bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&self.bin);
        std::fs::write(path, out).unwrap();
    }
}

fn temp_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lightpath-gltf-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn load(path: &Path) -> SceneDesc {
    lightpath::load_scene(path.to_str().unwrap()).unwrap()
}

fn render_desc(desc: &SceneDesc, res: u32, spp: u32, extra: Vec<AovSpec>) -> (Scene, Film) {
    let mut desc = desc.clone();
    desc.render.resolution = [res, res];
    desc.render.spp = spp;
    desc.render.max_depth = 2;
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

fn aov_sum(scene: &Scene, film: &Film, name: &str) -> f32 {
    let k = scene.aovs.iter().position(|a| a.name == name).unwrap();
    let mut s = 0.0;
    for y in 0..film.height {
        for x in 0..film.width {
            s += film.pixel(k, x, y).x;
        }
    }
    s
}

/// A camera at (0, 0, d) looking down −Z with the given vertical field of view.
fn camera_node(doc: &mut Doc, name: &str, d: f32, yfov: f32) -> usize {
    let cam = doc.push(
        "cameras",
        json!({"type": "perspective", "perspective": {"yfov": yfov, "znear": 0.01}}),
    );
    doc.node(json!({"name": name, "camera": cam, "translation": [0.0, 0.0, d]}))
}

impl Doc {
    fn with_cameras(mut self) -> Doc {
        self.json["cameras"] = json!([]);
        self
    }
}

#[test]
fn the_hierarchy_places_meshes_and_ancestors_are_lpe_groups() {
    let dir = temp_dir("hierarchy");
    let mut doc = Doc::new().with_cameras();
    let tri = doc.mesh(
        &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
        &[0, 1, 2],
        None,
        None,
    );
    let ball = doc.node(
        json!({"name": "ball", "mesh": tri, "translation": [0.0, 1.0, 0.0],
                               "extras": {"lpegroup": ["hero", "metal"]}}),
    );
    let props = doc.node(json!({"name": "props", "children": [ball],
                                "translation": [1.0, 0.0, 0.0], "scale": [2.0, 2.0, 2.0]}));
    // A rotated node: 90° about z takes x to y.
    let q = Quat::from_rotation_z(std::f32::consts::FRAC_PI_2);
    let turned = doc.node(json!({"name": "turned", "mesh": tri, "rotation": [q.x, q.y, q.z, q.w]}));
    doc.root(props);
    doc.root(turned);
    let path = doc.write(&dir, "hierarchy");
    let desc = load(&path);
    let ball = desc
        .objects
        .iter()
        .find(|o| o.name.as_deref() == Some("ball"))
        .unwrap();
    assert_eq!(
        ball.lpegroups.as_deref().unwrap(),
        ["ball", "props", "hero", "metal"].map(String::from)
    );
    // Parent (scale 2, then +x) after child (+y): (1, 0, 0) → (1, 1, 0) → (3, 2, 0).
    let p = ball.transform.transform_point3(Vec3::X);
    assert!((p - Vec3::new(3.0, 2.0, 0.0)).length() < 1e-5, "{p}");
    let turned = desc
        .objects
        .iter()
        .find(|o| o.name.as_deref() == Some("turned"))
        .unwrap();
    let p = turned.transform.transform_point3(Vec3::X);
    assert!((p - Vec3::Y).length() < 1e-5, "{p}");
    assert_eq!(turned.lpegroups.as_deref().unwrap(), ["turned".to_string()]);
    // Cryptomatte's asset (issue 14): the top-level node a mesh is under, or the mesh's
    // own node at the top.
    assert_eq!(ball.asset.as_deref(), Some("props"));
    assert_eq!(turned.asset.as_deref(), Some("turned"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn ancestor_groups_select_light_paths() {
    // A camera looking at a big square under 'props', lit by a point light: an AOV of
    // paths through 'props' is the whole beauty, one through another group is nothing.
    let dir = temp_dir("groups");
    let mut doc = Doc::new().with_cameras();
    let sq = doc.square(10.0, 1.0, None);
    let wall = doc.node(json!({"name": "wall", "mesh": sq}));
    let props = doc.node(json!({"name": "props", "children": [wall]}));
    let cam = camera_node(&mut doc, "cam", 5.0, 0.5);
    let l = doc.light(json!({"type": "point", "intensity": 1000.0}));
    let light = doc.node(json!({"name": "key", "translation": [0.0, 0.0, 2.0],
                                "extensions": {"KHR_lights_punctual": {"light": l}}}));
    for n in [props, cam, light] {
        doc.root(n);
    }
    let desc = load(&doc.write(&dir, "groups"));
    let (scene, film) = render_desc(
        &desc,
        8,
        1,
        vec![
            AovSpec::new("props", "C<..'props'>.*[<L.>O]"),
            AovSpec::new("key", "C.*<L.'key'>"),
            AovSpec::new("floor", "C<..'floor'>.*[<L.>O]"),
        ],
    );
    let beauty = aov_sum(&scene, &film, "beauty");
    assert!(beauty > 0.0);
    assert!((aov_sum(&scene, &film, "props") - beauty).abs() < 1e-4 * beauty);
    assert!((aov_sum(&scene, &film, "key") - beauty).abs() < 1e-4 * beauty);
    assert_eq!(aov_sum(&scene, &film, "floor"), 0.0);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cameras_frame_as_the_file_says_and_are_picked_by_name() {
    let dir = temp_dir("cameras");
    let mut doc = Doc::new().with_cameras();
    let wide = doc.push(
        "cameras",
        json!({"type": "perspective", "perspective": {"yfov": 1.0, "aspectRatio": 2.0, "znear": 0.1}}),
    );
    let n0 = doc.node(json!({"name": "wide", "camera": wide, "translation": [0.0, 0.0, 5.0]}));
    let q = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
    let n1 = doc.node(
        json!({"name": "side", "camera": wide, "translation": [5.0, 0.0, 0.0],
                             "rotation": [q.x, q.y, q.z, q.w]}),
    );
    let sq = doc.square(1.0, 1.0, None);
    let n2 = doc.node(json!({"name": "card", "mesh": sq}));
    for n in [n0, n1, n2] {
        doc.root(n);
    }
    let path = doc.write(&dir, "cameras");
    let mut desc = load(&path);
    let c = desc.camera.clone().unwrap();
    assert_eq!(c.position, [0.0, 0.0, 5.0]);
    assert!((Vec3::from(c.look_at) - Vec3::new(0.0, 0.0, 4.0)).length() < 1e-6);
    assert!((c.fov - 1.0f32.to_degrees()).abs() < 1e-4);
    assert_eq!(c.fov_axis, lightpath::camera::FovAxis::Y);
    assert_eq!(desc.render.resolution, [512, 256]);
    // A camera turned 90° about +y looks down −x.
    desc.use_camera("side").unwrap();
    let c = desc.camera.clone().unwrap();
    assert!(
        (Vec3::from(c.look_at) - Vec3::new(4.0, 0.0, 0.0)).length() < 1e-5,
        "{:?}",
        c.look_at
    );
    let e = desc.use_camera("top").unwrap_err().to_string();
    assert!(
        e.contains("top") && e.contains("wide") && e.contains("side"),
        "{e}"
    );
    // The card (half-height 1 at distance 5) fills tan⁻¹(1/5) / (yfov / 2) of the frame's
    // half-height: the rendered silhouette's rows say so.
    desc.use_camera("wide").unwrap();
    desc.render.resolution = [64, 64];
    desc.render.spp = 1;
    desc.render.max_depth = 1;
    let scene = Scene::build(&desc, &aov::assemble(vec![])).unwrap();
    let (film, _) = render(
        &scene,
        &RenderOptions {
            spp: 1,
            first_sample: 0,
        },
    );
    let alpha = film.alpha();
    let alpha_rows = (0..64).filter(|&y| alpha[y * 64 + 32] > 0.5).count() as f32;
    let want = 64.0 * (0.2f32.atan() / 0.5);
    assert!(
        (alpha_rows - want).abs() <= 1.5,
        "{alpha_rows} rows, want {want}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_file_without_camera_or_lights_gets_defaults_and_warnings() {
    let dir = temp_dir("defaults");
    let mut doc = Doc::new();
    let sq = doc.square(1.0, 1.0, None);
    let n = doc.node(json!({"name": "card", "mesh": sq, "translation": [10.0, 0.0, 0.0]}));
    doc.root(n);
    let desc = load(&doc.write(&dir, "defaults"));
    let c = desc.camera.as_ref().unwrap();
    assert!((Vec3::from(c.look_at) - Vec3::new(10.0, 0.0, 0.0)).length() < 1e-5);
    assert!(matches!(desc.lights[0].kind, LightKind::Dome { .. }));
    let w = desc.warnings.join("\n");
    assert!(w.contains("no camera") && w.contains("no light"), "{w}");
    // The default camera sees the card in the middle of the frame.
    let (_, film) = render_desc(&desc, 16, 1, vec![]);
    assert!(film.alpha()[8 * 16 + 8] > 0.5);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn light_units_convert_as_blenders_importer_does() {
    // A Lambertian plane (glTF base colour 0.5, metallic 0: albedo 0.5 under the specular
    // layer's attenuation, `material::Specular::base_attenuation`) under
    // a point light of 4 · 683 cd at 2 m: E = (4 · 683 / 683) / 2² = 1 W/m².
    let dir = temp_dir("units");
    let mut doc = Doc::new().with_cameras();
    doc.json["materials"] = json!([{"pbrMetallicRoughness":
        {"baseColorFactor": [0.5, 0.5, 0.5, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}}]);
    let sq = doc.square(10.0, 1.0, Some(0));
    let plane = doc.node(json!({"name": "plane", "mesh": sq}));
    let cam = camera_node(&mut doc, "cam", 5.0, 0.02);
    let l = doc.light(
        json!({"type": "point", "intensity": 4.0 * 683.0, "name": "bulb",
                            "extras": {"lightgroup": "practical"}}),
    );
    let bulb = doc.node(json!({"name": "bulbnode", "translation": [0.0, 0.0, 2.0],
                               "extensions": {"KHR_lights_punctual": {"light": l}}}));
    let s = doc.light(json!({"type": "directional", "intensity": 683.0}));
    let sun = doc.node(json!({"name": "sun", "extensions": {"KHR_lights_punctual": {"light": s}}}));
    let sp = doc.light(json!({"type": "spot", "intensity": 683.0,
                              "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.4}}));
    let spot =
        doc.node(json!({"name": "spot", "extensions": {"KHR_lights_punctual": {"light": sp}}}));
    for n in [plane, cam, bulb, sun, spot] {
        doc.root(n);
    }
    let mut desc = load(&doc.write(&dir, "units"));
    let light = |name: &str| {
        desc.lights
            .iter()
            .find(|l| l.name.as_deref() == Some(name))
            .unwrap()
    };
    assert_eq!(light("bulbnode").groups, ["practical".to_string()]);
    assert!((light("bulbnode").strength - 4.0).abs() < 1e-5);
    assert_eq!(light("sun").groups, ["sun".to_string()]);
    assert!((light("sun").strength - 1.0).abs() < 1e-6);
    // Blender's importer gives the sun it makes its default angular diameter, 0.526°.
    assert!(
        matches!(light("sun").kind, LightKind::Distant { angle, .. } if angle == 0.526),
        "{:?}",
        light("sun").kind
    );
    let LightKind::Spot {
        cone_angle,
        cone_softness,
        direction,
        ..
    } = light("spot").kind
    else {
        panic!("a spot light");
    };
    assert_eq!(direction, [0.0, 0.0, -1.0]);
    assert!((cone_angle - 0.8f32.to_degrees()).abs() < 1e-4);
    // Blender: blend = 1 − 0.2/0.4 = ½; Cycles' smooth edge ends at
    // cos = cos 0.4 + (1 − cos 0.4)·½.
    let inner = (0.4f32.cos() + (1.0 - 0.4f32.cos()) * 0.5).acos();
    assert!((cone_softness - (0.4 - inner).to_degrees()).abs() < 1e-3);
    // Only the bulb: the diffuse light of the plane under it is ρE/π (the pixels
    // straddle the axis within 0.05 m of 2 m, so E varies by under 10⁻³).
    desc.lights
        .retain(|l| l.name.as_deref() == Some("bulbnode"));
    let (scene, film) = render_desc(&desc, 4, 4, vec![AovSpec::new("dd", "C<RD>[<L.>O]")]);
    let k = scene.aovs.iter().position(|a| a.name == "dd").unwrap();
    let layer = lightpath::material::Specular::new(lightpath::material::SpecularParams {
        eta: 1.5,
        tint: Vec3A::ONE,
        tint_f0_only: true,
        weight: 1.0,
        alpha: glam::Vec2::ONE,
        lobe: 2,
    });
    let rho = 0.5 * layer.base_attenuation(Vec3A::Z);
    let want = rho / std::f32::consts::PI;
    let got = film.pixel(k, 2, 2).x;
    assert!((got - want).abs() < 2e-3 * want, "{got} vs {want}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A 2×2 RGBA PNG: red, (128, 128, 128); green, white (rows top to bottom).
fn png_2x2() -> Vec<u8> {
    let mut img = image::RgbaImage::new(2, 2);
    img.put_pixel(0, 0, image::Rgba([255, 0, 0, 255]));
    img.put_pixel(1, 0, image::Rgba([128, 128, 128, 255]));
    img.put_pixel(0, 1, image::Rgba([0, 255, 0, 255]));
    img.put_pixel(1, 1, image::Rgba([255, 255, 255, 255]));
    let mut out = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png)
        .unwrap();
    out
}

#[test]
fn base_colour_textures_are_srgb_and_repeat() {
    // A square filling the frame, UVs [0, 2]² with REPEAT: the 2×2 texture appears 2×2
    // times. The albedo AOV at each texel's centre is that texel, sRGB-decoded.
    let dir = temp_dir("texture");
    let mut doc = Doc::new().with_cameras();
    let png = png_2x2();
    let view = doc.view(&png);
    doc.json["images"] = json!([{"bufferView": view, "mimeType": "image/png"}]);
    doc.json["samplers"] = json!([{"wrapS": 10497, "wrapT": 10497}]);
    doc.json["textures"] = json!([{"source": 0, "sampler": 0}]);
    doc.json["materials"] = json!([{"pbrMetallicRoughness":
        {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0}}]);
    let sq = doc.square(1.0, 2.0, Some(0));
    let card = doc.node(json!({"name": "card", "mesh": sq}));
    // The square spans ±1 at distance 1/tan(0.25): exactly the 0.5 rad field of view.
    let cam = camera_node(&mut doc, "cam", 1.0 / 0.25f32.tan(), 0.5);
    doc.root(card);
    doc.root(cam);
    let path = dir.join("texture.glb");
    doc.write_glb(&path);
    let desc = load(&path);
    let (scene, film) = render_desc(&desc, 124, 1, vec![AovSpec::new("albedo", "lpe:albedo")]);
    let k = scene.aovs.iter().position(|a| a.name == "albedo").unwrap();
    let grey = 0.2158605; // sRGB 128 decoded
    let want = [
        [Vec3A::new(1.0, 0.0, 0.0), Vec3A::splat(grey)],
        [Vec3A::new(0.0, 1.0, 0.0), Vec3A::ONE],
    ];
    // The camera's square field maps the square's UV [0, 2] onto 124 px: each texel is
    // 31 px wide, its centre the centre of pixel 15 + 31·i. A sample jittered within that
    // pixel is at most half a pixel off in u and in v, so bilinear filtering mixes in at
    // most 1/62 of the neighbour along each: a channel in [0, 1] moves by under 2/62.
    for ty in 0..4 {
        for tx in 0..4 {
            let got = film.pixel(k, 15 + 31 * tx, 15 + 31 * ty);
            let w = want[ty as usize % 2][tx as usize % 2];
            let bound = 2.0 / 62.0 + 1e-4;
            assert!(
                (got - w).abs().max_element() < bound,
                "texel ({tx}, {ty}): {got} vs {w}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_base_colour_texture_tints_glass_as_the_factor_does() {
    // A glass pane in front of an emissive card, tinted once by a uniform grey: as its
    // base colour factor, or as a texture under a white factor. Blender tints by the
    // square root at each crossing; so must the texture, not by the whole colour.
    let grey = 0.2158605f32; // sRGB 128 decoded
    let mean_through = |textured: bool| {
        let dir = temp_dir(if textured { "tglass-t" } else { "tglass-f" });
        let mut doc = Doc::new().with_cameras();
        let mut img = image::RgbaImage::new(2, 2);
        for p in img.pixels_mut() {
            *p = image::Rgba([128, 128, 128, 255]);
        }
        let mut png = Vec::new();
        img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
        let view = doc.view(&png);
        doc.json["images"] = json!([{"bufferView": view, "mimeType": "image/png"}]);
        doc.json["textures"] = json!([{"source": 0}]);
        let pbr = if textured {
            json!({"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "baseColorTexture": {"index": 0},
                   "metallicFactor": 0.0, "roughnessFactor": 0.0})
        } else {
            json!({"baseColorFactor": [grey, grey, grey, 1.0],
                   "metallicFactor": 0.0, "roughnessFactor": 0.0})
        };
        doc.json["materials"] = json!([
            {"name": "glass", "pbrMetallicRoughness": pbr,
             "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0}}},
            {"name": "lamp", "emissiveFactor": [1.0, 1.0, 1.0]},
        ]);
        doc.json["extensionsUsed"] = json!(["KHR_materials_transmission"]);
        let pane = doc.square(1.0, 1.0, Some(0));
        let lamp = doc.square(2.0, 1.0, Some(1));
        let g = doc.node(json!({"name": "pane", "mesh": pane}));
        let l = doc.node(json!({"name": "card", "mesh": lamp, "translation": [0.0, 0.0, -1.0]}));
        let cam = camera_node(&mut doc, "cam", 1.0 / 0.25f32.tan(), 0.5);
        for n in [g, l, cam] {
            doc.root(n);
        }
        let path = dir.join("glass.glb");
        doc.write_glb(&path);
        let (scene, film) = render_desc(&load(&path), 16, 4, vec![]);
        let _ = std::fs::remove_dir_all(&dir);
        aov_sum(&scene, &film, "beauty")
    };
    let (factor, texture) = (mean_through(false), mean_through(true));
    assert!(factor > 0.0, "nothing seen through the pane");
    // Same samples, same tint: equal but for the texture filter's rounding (before,
    // the texture tinted by the whole grey: √0.216 = 0.46 of the factor's).
    assert!(
        (texture / factor - 1.0).abs() < 0.01,
        "textured {texture} against factor {factor}"
    );
}

#[test]
fn extensions_we_lack_are_errors_when_required_and_warnings_when_used() {
    let dir = temp_dir("extensions");
    let base = || {
        let mut doc = Doc::new();
        let sq = doc.square(1.0, 1.0, None);
        let n = doc.node(json!({"name": "card", "mesh": sq}));
        doc.root(n);
        doc
    };
    let mut doc = base();
    doc.json["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
    doc.json["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    let path = doc.write(&dir, "required");
    let e = lightpath::load_scene(path.to_str().unwrap())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("required.gltf")
            && e.contains("/extensionsRequired")
            && e.contains("KHR_draco_mesh_compression"),
        "{e}"
    );
    let mut doc = base();
    doc.json["extensionsUsed"] = json!(["EXT_mesh_gpu_instancing", "KHR_materials_clearcoat"]);
    doc.json["extensionsRequired"] = json!(["KHR_materials_clearcoat"]);
    doc.json["materials"] = json!([{"extensions": {"KHR_materials_clearcoat":
        {"clearcoatFactor": 0.75, "clearcoatRoughnessFactor": 0.25}}}]);
    doc.json["meshes"][0]["primitives"][0]["material"] = json!(0);
    let desc = load(&doc.write(&dir, "used"));
    let w = desc.warnings.join("\n");
    assert!(
        w.contains("EXT_mesh_gpu_instancing") && !w.contains("clearcoat"),
        "{w}"
    );
    let m = desc.materials.values().next().unwrap();
    let MaterialKind::OpenPbr(p) = &m.kind else {
        panic!("an OpenPBR material");
    };
    assert_eq!(
        (p.coat_weight, p.coat_roughness, p.coat_ior),
        (0.75, 0.25, 1.5)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_files_are_errors_naming_the_file_and_where() {
    let dir = temp_dir("errors");
    // Not glTF at all: an OBJ given a .gltf name.
    let obj = dir.join("cube.gltf");
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let e = lightpath::load_scene(obj.to_str().unwrap())
        .unwrap_err()
        .to_string();
    assert!(e.contains("cube.gltf") && e.contains("OBJ"), "{e}");
    // A vertex that is not finite.
    let mut doc = Doc::new();
    let m = doc.mesh(
        &[0.0, 0.0, 0.0, f32::NAN, 0.0, 0.0, 0.0, 1.0, 0.0],
        &[0, 1, 2],
        None,
        None,
    );
    let n = doc.node(json!({"mesh": m}));
    doc.root(n);
    let path = doc.write(&dir, "nan");
    let e = lightpath::load_scene(path.to_str().unwrap())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("nan.gltf")
            && e.contains("/meshes/0/primitives/0/attributes/POSITION")
            && e.contains("vertex 1"),
        "{e}"
    );
    // An index past the vertices.
    let mut doc = Doc::new();
    let m = doc.mesh(
        &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
        &[0, 1, 7],
        None,
        None,
    );
    let n = doc.node(json!({"mesh": m}));
    doc.root(n);
    let path = doc.write(&dir, "index");
    let e = lightpath::load_scene(path.to_str().unwrap())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("index.gltf") && e.contains("/meshes/0/primitives/0/indices") && e.contains("7"),
        "{e}"
    );
    // A node index out of range is caught by validation, with its JSON path.
    let mut doc = Doc::new();
    doc.root(5);
    let path = doc.write(&dir, "dangling");
    let e = lightpath::load_scene(path.to_str().unwrap())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("dangling.gltf") && e.contains("/scenes/0/nodes"),
        "{e}"
    );
    // A missing buffer file names the OS reason.
    let mut doc = Doc::new();
    let m = doc.mesh(
        &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
        &[0, 1, 2],
        None,
        None,
    );
    let n = doc.node(json!({"mesh": m}));
    doc.root(n);
    let path = doc.write(&dir, "nobuffer");
    std::fs::remove_file(dir.join("nobuffer.bin")).unwrap();
    let e = lightpath::load_scene(path.to_str().unwrap())
        .unwrap_err()
        .to_string();
    assert!(e.contains("nobuffer.gltf") && e.contains("/buffers"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn glb_and_gltf_of_one_document_load_alike() {
    let dir = temp_dir("glb");
    let build = || {
        let mut doc = Doc::new();
        let sq = doc.square(1.0, 1.0, None);
        let n = doc.node(json!({"name": "card", "mesh": sq, "translation": [0.0, 2.0, 0.0]}));
        doc.root(n);
        doc
    };
    let a = load(&build().write(&dir, "card"));
    let glb = dir.join("card.glb");
    build().write_glb(&glb);
    let b = load(&glb);
    assert_eq!(a.objects.len(), b.objects.len());
    let pos = |d: &SceneDesc| match d.objects[0].shape.mesh_parts() {
        Some(parts) => parts[0].positions.clone(),
        None => panic!("a mesh"),
    };
    assert_eq!(pos(&a), pos(&b));
    assert_eq!(a.objects[0].transform, b.objects[0].transform);
    assert_eq!(
        a.objects[0].transform,
        Affine3A::from_translation(Vec3::new(0.0, 2.0, 0.0))
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn nodes_sharing_a_textured_mesh_are_instances_that_shade_as_copies_do() {
    // Two placements of one textured square (one turned a quarter and scaled): stored once
    // as instances, they must read their texture exactly as two separate copies do.
    let dir = temp_dir("instances");
    let build = |shared: bool| {
        let mut doc = Doc::new().with_cameras();
        let png = png_2x2();
        let view = doc.view(&png);
        doc.json["images"] = json!([{"bufferView": view, "mimeType": "image/png"}]);
        doc.json["textures"] = json!([{"source": 0}]);
        doc.json["materials"] = json!([{"pbrMetallicRoughness":
            {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0}}]);
        let a = doc.square(0.4, 1.0, Some(0));
        let b = if shared {
            a
        } else {
            doc.square(0.4, 1.0, Some(0))
        };
        let left = doc.node(json!({"name": "left", "mesh": a, "translation": [-0.5, 0.0, 0.0]}));
        let right = doc.node(json!({"name": "right", "mesh": b,
            "translation": [0.5, 0.0, 0.0], "scale": [1.1, 1.1, 1.1],
            "rotation": [0.0, 0.0, 0.70710677, 0.70710677]}));
        let cam = camera_node(&mut doc, "cam", 3.0, 0.7);
        doc.root(left);
        doc.root(right);
        doc.root(cam);
        let path = dir.join(format!("shared{shared}.glb"));
        doc.write_glb(&path);
        render_desc(
            &load(&path),
            48,
            2,
            vec![AovSpec::new("albedo", "lpe:albedo")],
        )
    };
    let (shared_scene, shared) = build(true);
    let (copies_scene, copies) = build(false);
    assert_eq!(shared_scene.accel.instances().len(), 2);
    assert_eq!(copies_scene.accel.instances().len(), 0);
    let k = shared_scene
        .aovs
        .iter()
        .position(|a| a.name == "albedo")
        .unwrap();
    let mut textured = 0;
    for y in 0..48 {
        for x in 0..48 {
            let (a, b) = (shared.pixel(k, x, y), copies.pixel(k, x, y));
            // The same rays and texels; only the order of float operations differs.
            assert!(
                (a - b).abs().max_element() < 1e-3,
                "pixel ({x}, {y}): instance {a} vs copy {b}"
            );
            textured += usize::from(a.max_element() > 0.0);
        }
    }
    assert!(
        textured > 48 * 48 / 5,
        "only {textured} pixels see a square"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn color_0_multiplies_the_base_colour_linearly_and_interpolates() {
    // A square filling the frame (as in the texture test) whose COLOR_0 runs from red on
    // its left edge to blue on its right, with green 128/255 throughout, as normalised
    // RGBA bytes. glTF's vertex colours are linear: no sRGB decoding. They multiply the
    // base colour factor (here (1, 1, 0.5)).
    let dir = temp_dir("color0");
    let mut doc = Doc::new().with_cameras();
    doc.json["materials"] = json!([{"pbrMetallicRoughness":
        {"baseColorFactor": [1.0, 1.0, 0.5, 1.0], "metallicFactor": 0.0}}]);
    let pos = [
        -1.0, -1.0, 0.0, 1.0, -1.0, 0.0, 1.0, 1.0, 0.0, -1.0, 1.0, 0.0,
    ];
    let sq = doc.mesh(&pos, &[0, 1, 2, 0, 2, 3], None, Some(0));
    let colors: [u8; 16] = [
        255, 128, 0, 255, 0, 128, 255, 255, 0, 128, 255, 255, 255, 128, 0, 255,
    ];
    let view = doc.view(&colors);
    let acc = doc.push(
        "accessors",
        json!({"bufferView": view, "componentType": 5121, "normalized": true,
               "count": 4, "type": "VEC4"}),
    );
    doc.json["meshes"][sq]["primitives"][0]["attributes"]["COLOR_0"] = json!(acc);
    let card = doc.node(json!({"name": "card", "mesh": sq}));
    let cam = camera_node(&mut doc, "cam", 1.0 / 0.25f32.tan(), 0.5);
    doc.root(card);
    doc.root(cam);
    let path = dir.join("color0.glb");
    doc.write_glb(&path);
    let desc = load(&path);
    let res = 32;
    let (scene, film) = render_desc(&desc, res, 4, vec![AovSpec::new("albedo", "lpe:albedo")]);
    let k = scene.aovs.iter().position(|a| a.name == "albedo").unwrap();
    let green = 128.0 / 255.0;
    // The square's x runs across the image: at pixel x, u = (x + ½)/res of the way from
    // red to blue. Samples jitter within their pixel: u is off by at most ½/res.
    let bound = 0.5 / res as f32 + 1e-3;
    for y in [3, res / 2, res - 4] {
        for x in 0..res {
            let u = (x as f32 + 0.5) / res as f32;
            let want = Vec3A::new(1.0 - u, green, 0.5 * u);
            let got = film.pixel(k, x, y);
            assert!(
                (got - want).abs().max_element() < bound,
                "pixel ({x}, {y}): albedo {got}, expected {want}"
            );
        }
    }
    // A colour that is not finite is an error at its accessor.
    let mut bad = Doc::new();
    let sq = bad.mesh(&pos, &[0, 1, 2], None, None);
    let c = bad.floats(
        &[
            1.0,
            0.0,
            0.0,
            f32::NAN,
            0.0,
            0.0,
            1.0,
            1.0,
            1.0,
            0.0,
            0.0,
            0.0,
        ],
        3,
    );
    bad.json["meshes"][sq]["primitives"][0]["attributes"]["COLOR_0"] = json!(c);
    let n = bad.node(json!({"name": "card", "mesh": sq}));
    bad.root(n);
    let path = bad.write(&dir, "nan");
    let e = lightpath::load_scene(path.to_str().unwrap()).unwrap_err();
    assert!(
        e.to_string()
            .contains("/meshes/0/primitives/0/attributes/COLOR_0")
            && e.to_string().contains("colour 1"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_toml_scene_includes_a_glb_and_overrides_its_objects_by_name() {
    // A .glb with a card (filling the view of its camera) and a ball under a `props`
    // node; the TOML includes it, gives the card its own material and groups, and hides
    // the ball from the camera as a holdout.
    let dir = temp_dir("include");
    let mut doc = Doc::new().with_cameras();
    doc.json["materials"] = json!([{"pbrMetallicRoughness":
        {"baseColorFactor": [0.9, 0.9, 0.9, 1.0], "metallicFactor": 0.0}}]);
    let sq = doc.square(1.0, 1.0, Some(0));
    let small = doc.square(0.1, 1.0, Some(0));
    let card = doc.node(json!({"name": "card", "mesh": sq}));
    let ball = doc.node(json!({"name": "ball", "mesh": small, "translation": [0.0, 0.0, 0.5]}));
    let props = doc.node(json!({"name": "props", "children": [ball]}));
    let cam = camera_node(&mut doc, "cam", 1.0 / 0.25f32.tan(), 0.5);
    for n in [card, props, cam] {
        doc.root(n);
    }
    doc.write_glb(&dir.join("shot.glb"));
    let toml = "
[materials.blue]
type = \"diffuse\"
albedo = [0.1, 0.1, 0.8]

[[lights]]
type = \"dome\"
radiance = [1, 1, 1]

[[include]]
file = \"shot.glb\"

[include.objects.card]
material = \"blue\"
lpegroups = [\"hero\"]

[include.objects.ball]
holdout = true
visible_camera = false
casts_shadows = false
";
    let path = dir.join("scene.toml");
    std::fs::write(&path, toml).unwrap();
    let desc = lightpath::Source::from_file(&path)
        .and_then(|s| s.parse())
        .unwrap();
    let by_name = |n: &str| {
        desc.objects
            .iter()
            .find(|o| o.name.as_deref() == Some(n))
            .unwrap_or_else(|| panic!("no object {n}"))
    };
    assert_eq!(by_name("card").material.as_ref().unwrap().name, "blue");
    assert_eq!(
        by_name("card").lpegroups.as_deref().unwrap(),
        ["hero".to_string()]
    );
    let b = by_name("ball");
    assert!(b.holdout && !b.visible_camera && !b.casts_shadows && b.visible_indirect);
    // The ball keeps its imported material and its groups (its name and its parent's).
    assert_ne!(b.material.as_ref().unwrap().name, "blue");
    let groups = b.lpegroups.as_deref().unwrap();
    assert!(groups.contains(&"ball".to_string()) && groups.contains(&"props".to_string()));
    // The included camera is used: the card fills the frame, blue, in the 'hero' group;
    // the ball in front of it is not seen.
    let (scene, film) = render_desc(
        &desc,
        8,
        4,
        vec![
            AovSpec::new("albedo", "lpe:albedo"),
            AovSpec::new("hero", "C<RD'hero'>.*[<L.>O]"),
            AovSpec::new("props", "C<..'props'>.*[<L.>O]"),
        ],
    );
    let k = scene.aovs.iter().position(|a| a.name == "albedo").unwrap();
    for (x, y) in [(0, 0), (4, 4), (7, 3)] {
        let got = film.pixel(k, x, y);
        assert!(
            (got - Vec3A::new(0.1, 0.1, 0.8)).abs().max_element() < 1e-4,
            "pixel ({x}, {y}): {got}"
        );
    }
    assert!(aov_sum(&scene, &film, "hero") > 0.0);
    assert_eq!(aov_sum(&scene, &film, "props"), 0.0);
    // An override naming no object of the file lists the file's objects.
    std::fs::write(&path, toml.replace("objects.card", "objects.Card")).unwrap();
    let e = lightpath::Source::from_file(&path)
        .and_then(|s| s.parse())
        .unwrap_err();
    assert!(
        e.message.contains("'Card'") && e.message.contains("card"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn material_extensions_and_textures_map_to_the_pbr_material() {
    // Glass (transmission, ior), a coated metal with metallic-roughness and normal
    // textures, and an emissive card with KHR_materials_emissive_strength.
    let dir = temp_dir("materials");
    let mut doc = Doc::new().with_cameras();
    let png = png_2x2();
    let view = doc.view(&png);
    doc.json["images"] = json!([{"bufferView": view, "mimeType": "image/png"}]);
    doc.json["textures"] = json!([{"source": 0}]);
    doc.json["materials"] = json!([
        {"name": "glass", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 1.0, 0.9, 1.0],
            "metallicFactor": 0.0, "roughnessFactor": 0.0},
         "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0},
                        "KHR_materials_ior": {"ior": 1.33}}},
        {"name": "coated", "pbrMetallicRoughness": {"metallicFactor": 0.25,
            "roughnessFactor": 0.4, "metallicRoughnessTexture": {"index": 0}},
         "normalTexture": {"index": 0, "scale": 0.5},
         "extensions": {"KHR_materials_clearcoat": {"clearcoatFactor": 0.7,
                        "clearcoatRoughnessFactor": 0.2}}},
        {"name": "lamp", "emissiveFactor": [1.0, 0.5, 0.25],
         "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}}},
    ]);
    doc.json["extensionsUsed"] = json!([
        "KHR_materials_transmission",
        "KHR_materials_ior",
        "KHR_materials_clearcoat",
        "KHR_materials_emissive_strength"
    ]);
    let glass = doc.square(1.0, 1.0, Some(0));
    let coated = doc.square(0.2, 1.0, Some(1));
    let lamp = doc.square(0.2, 1.0, Some(2));
    let g = doc.node(json!({"name": "pane", "mesh": glass}));
    let c = doc.node(json!({"name": "coin", "mesh": coated, "translation": [5.0, 0.0, 0.0]}));
    // The lamp card behind the pane, seen through it.
    let l = doc.node(json!({"name": "lampcard", "mesh": lamp, "translation": [0.0, 0.0, -1.0]}));
    let cam = camera_node(&mut doc, "cam", 1.0 / 0.25f32.tan(), 0.5);
    for n in [g, c, l, cam] {
        doc.root(n);
    }
    let path = dir.join("materials.glb");
    doc.write_glb(&path);
    let desc = load(&path);
    assert!(
        !desc.warnings.iter().any(|w| w.contains("extension")),
        "{:?}",
        desc.warnings
    );
    let m = &desc.materials;
    let openpbr = |name: &str| match &m[name].kind {
        MaterialKind::OpenPbr(p) => **p,
        other => panic!("{name}: {other:?}"),
    };
    let glass = openpbr("glass");
    assert!(
        glass.transmission_weight == 1.0
            && (glass.specular_ior - 1.33).abs() < 1e-6
            && glass.base_color == Vec3A::new(0.9, 1.0, 0.9)
            // Blender's √(base colour) at each crossing.
            && (glass.transmission_color - glass.base_color.powf(0.5)).abs().max_element() < 1e-6,
        "{glass:?}"
    );
    let coated = openpbr("coated");
    assert!(
        coated.base_metalness == 0.25
            && coated.coat_weight == 0.7
            && coated.coat_roughness == 0.2
            && coated.specular_roughness == 0.4,
        "{coated:?}"
    );
    assert!((m["coated"].roughness - 0.4).abs() < 1e-6);
    let t = &m["coated"].textures;
    assert!(t.metallic_roughness.is_some() && t.base_color.is_none());
    assert_eq!(t.normal.as_ref().map(|(_, s)| *s), Some(0.5));
    // The emissive card is a mesh light of radiance factor × strength, named after it.
    let light = desc
        .lights
        .iter()
        .find(|l| l.name.as_deref() == Some("lampcard"))
        .expect("a mesh light");
    assert!(matches!(light.kind, LightKind::Mesh { .. }));
    assert_eq!(light.color, [4.0, 2.0, 1.0]);
    assert_eq!(light.groups, ["lampcard".to_string()]);
    // The pane fills the view: the lamp is seen through it, by specular transmission,
    // and no camera path starts with a diffuse bounce (glass has none).
    let (scene, film) = render_desc(
        &desc,
        8,
        4,
        vec![
            AovSpec::new("through", "C<TS>.*[<L.>O]"),
            AovSpec::new("diffuseFirst", "C<RD>.*[<L.>O]"),
        ],
    );
    assert!(aov_sum(&scene, &film, "through") > 0.0);
    assert_eq!(aov_sum(&scene, &film, "diffuseFirst"), 0.0);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn khr_material_extensions_map_to_openpbr_as_blender_does() {
    let dir = temp_dir("openpbr");
    let mut doc = Doc::new();
    let png = png_2x2();
    let view = doc.view(&png);
    doc.json["images"] = json!([{"bufferView": view, "mimeType": "image/png"}]);
    doc.json["textures"] = json!([{"source": 0}]);
    doc.json["materials"] = json!([
        {"name": "velvet", "extensions": {"KHR_materials_sheen": {"sheenColorFactor": [0.5, 0.1, 0.2],
            "sheenRoughnessFactor": 0.6, "sheenRoughnessTexture": {"index": 0}}}},
        {"name": "tinted", "extensions": {"KHR_materials_specular": {"specularFactor": 0.5,
            "specularColorFactor": [1.0, 0.5, 0.25], "specularColorTexture": {"index": 0,
            "extensions": {"KHR_texture_transform": {"scale": [2.0, 2.0]}}}}}},
        {"name": "bubble", "extensions": {"KHR_materials_iridescence": {"iridescenceFactor": 1.0,
            "iridescenceIor": 1.33, "iridescenceThicknessMaximum": 600.0}}},
        {"name": "leaf", "extensions": {"KHR_materials_diffuse_transmission": {
            "diffuseTransmissionFactor": 0.4, "diffuseTransmissionColorFactor": [0.2, 0.9, 0.1]}}},
        {"name": "brushed", "pbrMetallicRoughness": {"metallicFactor": 1.0, "roughnessFactor": 0.4},
         "extensions": {"KHR_materials_anisotropy": {"anisotropyStrength": 0.7}}},
    ]);
    doc.json["extensionsUsed"] = json!([
        "KHR_materials_sheen",
        "KHR_materials_specular",
        "KHR_materials_iridescence",
        "KHR_materials_diffuse_transmission",
        "KHR_materials_anisotropy",
        "KHR_texture_transform"
    ]);
    for (i, name) in ["velvet", "tinted", "bubble", "leaf", "brushed"]
        .iter()
        .enumerate()
    {
        let mesh = doc.square(1.0, 1.0, Some(i));
        let n = doc
            .node(json!({"name": name, "mesh": mesh, "translation": [i as f32 * 3.0, 0.0, 0.0]}));
        doc.root(n);
    }
    let desc = load(&doc.write(&dir, "openpbr"));
    let m = &desc.materials;
    let openpbr = |name: &str| match &m[name].kind {
        MaterialKind::OpenPbr(p) => **p,
        other => panic!("{name}: {other:?}"),
    };
    let velvet = openpbr("velvet");
    assert_eq!(
        (velvet.fuzz_weight, velvet.fuzz_color, velvet.fuzz_roughness),
        (1.0, Vec3A::new(0.5, 0.1, 0.2), 0.6)
    );
    let t = &m["velvet"].textures.inputs;
    assert!(
        t.len() == 1 && t[0].input == "fuzz_roughness" && t[0].channel == 3,
        "{t:?}"
    );
    let tinted = openpbr("tinted");
    assert_eq!(
        (tinted.specular_weight, tinted.specular_color),
        (0.5, Vec3A::new(1.0, 0.5, 0.25))
    );
    let t = &m["tinted"].textures.inputs;
    assert!(t[0].input == "specular_color" && t[0].srgb, "{t:?}");
    assert_ne!(
        t[0].texture.transform,
        Default::default(),
        "the texture transform is read"
    );
    let bubble = openpbr("bubble");
    assert_eq!(
        (
            bubble.thin_film_weight,
            bubble.thin_film_ior,
            bubble.thin_film_thickness
        ),
        (1.0, 1.33, 0.6)
    );
    let leaf = openpbr("leaf");
    assert!(
        leaf.geometry_thin_walled
            && leaf.subsurface_weight == 0.4
            && leaf.subsurface_color == Vec3A::new(0.2, 0.9, 0.1)
    );
    // The strength read as Blender's importer reads it (Principled "Anisotropic"), whose
    // alphas in Cycles are α/ρ and α·ρ, α = roughness², ρ = √(1 − 0.9 s).
    let brushed = openpbr("brushed");
    let alpha = lightpath::material::microfacet::roughness_anisotropy_to_alpha(
        brushed.specular_roughness,
        brushed.specular_roughness_anisotropy,
    );
    let rho = (1.0f32 - 0.9 * 0.7).sqrt();
    let want = glam::Vec2::new(0.16 / rho, 0.16 * rho);
    assert!(
        (alpha - want).abs().max_element() < 1e-5,
        "{alpha} vs {want}"
    );
    // A bad value names the file and where in it.
    let mut bad = Doc::new();
    bad.json["materials"] =
        json!([{"extensions": {"KHR_materials_sheen": {"sheenRoughnessFactor": -1}}}]);
    let sq = bad.square(1.0, 1.0, Some(0));
    let n = bad.node(json!({"name": "card", "mesh": sq}));
    bad.root(n);
    let path = bad.write(&dir, "bad");
    let e = lightpath::load_scene(path.to_str().unwrap())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("bad.gltf")
            && e.contains("/materials/0/extensions/KHR_materials_sheen/sheenRoughnessFactor"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn khr_materials_volume_with_a_thickness_is_an_absorbing_interior() {
    // A closed cube of glass with a volume (thickness 1), and the same material with
    // thickness 0 (thin-walled) on a second cube.
    let dir = temp_dir("volume");
    let mut doc = Doc::new().with_cameras();
    let volume = |thickness: f32| {
        json!({"KHR_materials_transmission": {"transmissionFactor": 1.0},
               "KHR_materials_volume": {"thicknessFactor": thickness,
                   "attenuationDistance": 2.0, "attenuationColor": [0.5, 0.25, 1.0]}})
    };
    doc.json["materials"] = json!([
        {"name": "thick", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 1.0, 0.9, 1.0],
            "metallicFactor": 0.0, "roughnessFactor": 0.0}, "extensions": volume(1.0)},
        {"name": "thin", "pbrMetallicRoughness": {"metallicFactor": 0.0, "roughnessFactor": 0.0},
            "extensions": volume(0.0)},
    ]);
    doc.json["extensionsUsed"] = json!(["KHR_materials_transmission", "KHR_materials_volume"]);
    let mut pos = Vec::new();
    for k in 0..8 {
        pos.extend([k & 1, (k >> 1) & 1, (k >> 2) & 1].map(|b| b as f32 * 2.0 - 1.0));
    }
    // Outward-facing, counter-clockwise seen from outside.
    let faces: [u32; 36] = [
        0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6,
        1, 3, 5, 3, 7, 5,
    ];
    let thick = doc.mesh(&pos, &faces, None, Some(0));
    let thin = doc.mesh(&pos, &faces, None, Some(1));
    let a = doc.node(json!({"name": "thick", "mesh": thick}));
    let b = doc.node(json!({"name": "thin", "mesh": thin, "translation": [4.0, 0.0, 0.0]}));
    let cam = camera_node(&mut doc, "cam", 8.0, 0.5);
    for n in [a, b, cam] {
        doc.root(n);
    }
    let path = dir.join("volume.glb");
    doc.write_glb(&path);
    let desc = load(&path);
    assert!(
        !desc
            .warnings
            .iter()
            .any(|w| w.contains("KHR_materials_volume")),
        "{:?}",
        desc.warnings
    );
    // σa = −ln(colour) / distance, the extension's Beer–Lambert law.
    let medium = &desc.media.media["thick (volume)"];
    let want = [0.5f32, 0.25, 1.0].map(|c| -c.ln() / 2.0);
    for (got, want) in medium.sigma_a.iter().zip(want) {
        assert!((got - want).abs() < 1e-6, "{:?}", medium.sigma_a);
    }
    assert_eq!(medium.sigma_s, [0.0; 3]);
    assert_eq!(desc.media.interiors.len(), 1);
    assert_eq!(
        desc.objects[desc.media.interiors[0].object].name.as_deref(),
        Some("thick")
    );
    // The thick glass keeps its base colour's √ on the interface (as Blender, at each
    // crossing); the thin one is tinted by the attenuation colour instead of holding a
    // medium.
    let openpbr = |name: &str| match &desc.materials[name].kind {
        MaterialKind::OpenPbr(p) => **p,
        other => panic!("{name}: {other:?}"),
    };
    assert_eq!(openpbr("thick").transmission_depth, 0.0);
    assert!(
        (openpbr("thick").transmission_color - Vec3A::new(0.9, 1.0, 0.9).powf(0.5))
            .abs()
            .max_element()
            < 1e-6
    );
    assert_eq!(
        openpbr("thin").transmission_color,
        Vec3A::new(0.5, 0.25, 1.0)
    );
    let scene = Scene::build(&desc, &aov::assemble(aov::standard())).unwrap();
    assert_eq!(scene.volumes.len(), 1);
    assert!(
        scene
            .objects
            .iter()
            .filter(|o| o.interior.is_some())
            .count()
            == 1
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn alpha_mask_cuts_out_for_camera_and_shadow_rays() {
    // A card filling the frame whose base colour texture is opaque on its left half and
    // transparent on its right (alpha 255 | 0, bilinear, clamped), alphaMode MASK with
    // cutoff 0.5; behind it a grey floor, lit by a sun along −Z (the view direction), so
    // the floor seen through the cut-out is lit through it. Left: the card (alpha 1,
    // black). Right: no card (the floor, whose alpha is 1 too, lit at 0.5/π; 0 if the
    // shadow ray stopped at the card's missing half).
    let dir = temp_dir("mask");
    let mut doc = Doc::new().with_cameras();
    let mut img = image::RgbaImage::new(2, 1);
    img.put_pixel(0, 0, image::Rgba([0, 0, 0, 255]));
    img.put_pixel(1, 0, image::Rgba([0, 0, 0, 0]));
    let mut png = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    let view = doc.view(&png);
    doc.json["images"] = json!([{"bufferView": view, "mimeType": "image/png"}]);
    doc.json["samplers"] = json!([{"wrapS": 33071, "wrapT": 33071}]);
    doc.json["textures"] = json!([{"source": 0, "sampler": 0}]);
    doc.json["materials"] = json!([
        {"alphaMode": "MASK", "alphaCutoff": 0.5, "pbrMetallicRoughness":
            {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0},
         "extensions": {"KHR_materials_specular": {"specularFactor": 0.0}}},
        {"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1.0],
            "metallicFactor": 0.0},
         "extensions": {"KHR_materials_specular": {"specularFactor": 0.0}}},
    ]);
    let sq = doc.square(1.0, 1.0, Some(0));
    let card = doc.node(json!({"name": "card", "mesh": sq}));
    let big = doc.square(10.0, 1.0, Some(1));
    let floor = doc.node(json!({"name": "floor", "mesh": big, "translation": [0.0, 0.0, -1.0]}));
    let cam = camera_node(&mut doc, "cam", 1.0 / 0.25f32.tan(), 0.5);
    let s = doc.light(json!({"type": "directional", "intensity": 683.0}));
    let sun = doc.node(json!({"name": "sun", "extensions": {"KHR_lights_punctual": {"light": s}}}));
    for n in [card, floor, cam, sun] {
        doc.root(n);
    }
    let path = dir.join("mask.glb");
    doc.write_glb(&path);
    let desc = load(&path);
    let (_, film) = render_desc(&desc, 40, 4, vec![]);
    let lit = 0.5 / std::f32::consts::PI;
    // Columns well inside each half (u < 0.2, u > 0.8: the texture's clamped texels).
    for y in [5, 20, 35] {
        for x in [2, 6] {
            let b = film.pixel(0, x, y).x;
            assert!(b.abs() < 1e-6, "card at ({x}, {y}): {b}");
        }
        for x in [34, 38] {
            let b = film.pixel(0, x, y).x;
            assert!(
                (b - lit).abs() < 1e-3 * lit,
                "floor at ({x}, {y}): {b} vs {lit}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A square of anisotropic metal (KHR_materials_anisotropy strength 0.9, roughness 0.5)
/// facing the camera under a point light off to the side along +x; `rotation` radians,
/// with or without a TANGENT attribute along +y (else the tangent is ∂p/∂u, +x).
fn anisotropic_card(tag: &str, rotation: f32, tangent_y: bool) -> Film {
    let dir = temp_dir(tag);
    let mut doc = Doc::new().with_cameras();
    doc.json["materials"] = json!([{"pbrMetallicRoughness":
        {"baseColorFactor": [0.9, 0.9, 0.9, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.5},
        "extensions": {"KHR_materials_anisotropy":
            {"anisotropyStrength": 0.9, "anisotropyRotation": rotation}}}]);
    let sq = doc.square(1.0, 1.0, Some(0));
    if tangent_y {
        let t = doc.floats(&[0.0, 1.0, 0.0, 1.0].repeat(4), 4);
        let n = doc.floats(&[0.0, 0.0, 1.0].repeat(4), 3);
        doc.json["meshes"][sq]["primitives"][0]["attributes"]["TANGENT"] = json!(t);
        doc.json["meshes"][sq]["primitives"][0]["attributes"]["NORMAL"] = json!(n);
    }
    let card = doc.node(json!({"name": "card", "mesh": sq}));
    let cam = camera_node(&mut doc, "cam", 1.0 / 0.25f32.tan(), 0.5);
    let l = doc.light(json!({"type": "point", "intensity": 683.0 * 4.0}));
    let lamp = doc.node(json!({"name": "lamp", "translation": [2.0, 0.3, 1.5],
                               "extensions": {"KHR_lights_punctual": {"light": l}}}));
    for n in [card, cam, lamp] {
        doc.root(n);
    }
    let path = dir.join("aniso.glb");
    doc.write_glb(&path);
    let desc = load(&path);
    let (_, film) = render_desc(&desc, 24, 4, vec![]);
    let _ = std::fs::remove_dir_all(&dir);
    film
}

#[test]
fn anisotropy_rotation_turns_the_tangent_as_a_turned_tangent_does() {
    // Rotating the anisotropy by 90° (from the tangent +x towards the bitangent +y) is
    // the same surface as a mesh whose tangent is +y: the same image, sample for sample
    // up to rounding. And it is not the unrotated one: the highlight of a light off along
    // x stretches differently (more than a tenth of the image's mean, pixel by pixel
    // summed, where rounding differs by under 1e-4 of it).
    let plain = anisotropic_card("aniso0", 0.0, false);
    let turned = anisotropic_card("aniso90", std::f32::consts::FRAC_PI_2, false);
    let tangent = anisotropic_card("anisot", 0.0, true);
    let sum = |f: &Film| f.channel(0, 0).iter().map(|&v| v as f64).sum::<f64>();
    let diff = |a: &Film, b: &Film| {
        a.channel(0, 0)
            .iter()
            .zip(b.channel(0, 0))
            .map(|(x, y)| (*x as f64 - y as f64).abs())
            .sum::<f64>()
    };
    let total = sum(&turned);
    assert!(total > 0.0);
    assert!(
        diff(&turned, &tangent) < 1e-4 * total,
        "rotation 90° vs tangent +y: {} of {total}",
        diff(&turned, &tangent)
    );
    assert!(
        diff(&turned, &plain) > 0.1 * total,
        "rotation 90° vs none: {} of {total}",
        diff(&turned, &plain)
    );
}
