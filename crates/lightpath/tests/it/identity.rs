//! Scene identity: two parts of a glTF, or a checkpoint and its resume, are of the same
//! scene only if every file the render read is unchanged (the glTF, its buffer and its
//! texture image); `merge` and `--resume` refuse an edit, naming the file that changed.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use crate::common::Scratch;
use lightpath::progress::Silent;
use lightpath::RenderJob;

/// A textured floor lit by a point light, seen from above: `scene.gltf` with its
/// `scene.bin` and `wood.png`, the material's colour and the light's intensity given.
fn write_scene(dir: &Path, color: f32, intensity: f32) -> PathBuf {
    let mut bin: Vec<u8> = Vec::new();
    let positions = [
        -1.0f32, 0.0, -1.0, 1.0, 0.0, -1.0, 1.0, 0.0, 1.0, -1.0, 0.0, 1.0,
    ];
    let uvs = [0.0f32, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0];
    bin.extend(positions.iter().flat_map(|v| v.to_le_bytes()));
    bin.extend(uvs.iter().flat_map(|v| v.to_le_bytes()));
    bin.extend([0u16, 2, 1, 0, 3, 2].iter().flat_map(|i| i.to_le_bytes()));
    std::fs::write(dir.join("scene.bin"), &bin).unwrap();
    let gltf = format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {{"KHR_lights_punctual": {{"lights": [
    {{"type": "point", "intensity": {intensity}, "color": [1, 1, 1]}}]}}}},
  "scene": 0,
  "scenes": [{{"nodes": [0, 1, 2]}}],
  "nodes": [
    {{"name": "floor", "mesh": 0}},
    {{"name": "lamp", "translation": [0, 1.5, 0],
      "extensions": {{"KHR_lights_punctual": {{"light": 0}}}}}},
    {{"name": "cam", "camera": 0, "translation": [0, 3, 0],
      "rotation": [-0.70710677, 0, 0, 0.70710677]}}
  ],
  "cameras": [{{"type": "perspective",
    "perspective": {{"yfov": 0.9, "znear": 0.01, "aspectRatio": 1.0}}}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "TEXCOORD_0": 1}},
    "indices": 2, "material": 0}}]}}],
  "materials": [{{"name": "wood", "pbrMetallicRoughness": {{
    "baseColorFactor": [{color}, {color}, {color}, 1],
    "baseColorTexture": {{"index": 0}}, "metallicFactor": 0}}}}],
  "textures": [{{"source": 0}}],
  "images": [{{"uri": "wood.png"}}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
      "min": [-1, 0, -1], "max": [1, 0, 1]}},
    {{"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"}},
    {{"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}}
  ],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": 48}},
    {{"buffer": 0, "byteOffset": 48, "byteLength": 32}},
    {{"buffer": 0, "byteOffset": 80, "byteLength": 12}}
  ],
  "buffers": [{{"uri": "scene.bin", "byteLength": {}}}]
}}"#,
        bin.len()
    );
    let path = dir.join("scene.gltf");
    std::fs::write(&path, gltf).unwrap();
    path
}

/// `wood.png`: 2×2 texels of one grey.
fn write_texture(dir: &Path, grey: u8) {
    image::RgbImage::from_pixel(2, 2, image::Rgb([grey, grey, grey]))
        .save(dir.join("wood.png"))
        .unwrap();
}

fn lightpath() -> Command {
    Command::new(env!("CARGO_BIN_EXE_lightpath"))
}

/// Renders one sample per pixel of `scene`, sample `first`, into `out`.
fn render_part(scene: &Path, out: &Path, first: u32) {
    let status = lightpath()
        .arg("render")
        .arg(scene)
        .args([
            "--quiet",
            "--spp",
            "1",
            "--resolution",
            "8x8",
            "--aovs",
            "none",
        ])
        .args(["--first-sample", &first.to_string(), "-o"])
        .arg(out)
        .status()
        .unwrap();
    assert!(status.success());
}

/// `lightpath merge`'s error, or `None` if it merged.
fn merge(a: &Path, b: &Path, out: &Path) -> Option<String> {
    let result = lightpath()
        .arg("merge")
        .args([a, b])
        .arg("-o")
        .arg(out)
        .output()
        .unwrap();
    (!result.status.success()).then(|| String::from_utf8_lossy(&result.stderr).into_owned())
}

/// An edit of the scene: what it changes, the file the refusal must name, and how.
type Edit = (&'static str, &'static str, fn(&Path));

#[test]
fn merge_refuses_parts_across_an_edit_of_the_gltf_its_light_or_its_texture_naming_the_file() {
    let dir = Scratch::new("identity-merge");
    let scene = write_scene(&dir.0, 0.8, 50.0);
    write_texture(&dir.0, 128);
    let first = dir.join("a.exr");
    render_part(&scene, &first, 0);
    // Unchanged: the second part merges.
    render_part(&scene, &dir.join("same.exr"), 1);
    let same = merge(&first, &dir.join("same.exr"), &dir.join("ok.exr"));
    assert_eq!(same, None);

    // Each edit, made between the two parts, then undone.
    let edits: [Edit; 3] = [
        ("material colour", "scene.gltf changed", |d| {
            write_scene(d, 0.5, 50.0);
        }),
        ("light intensity", "scene.gltf changed", |d| {
            write_scene(d, 0.8, 80.0);
        }),
        ("texture image", "wood.png changed", |d| {
            write_texture(d, 129)
        }),
    ];
    for (what, named, edit) in edits {
        edit(&dir.0);
        let part = dir.join("edited.exr");
        render_part(&scene, &part, 1);
        let why = merge(&first, &part, &dir.join("x.exr"))
            .unwrap_or_else(|| panic!("parts across an edit of the {what} merged"));
        assert!(
            why.contains("different scenes") && why.contains(named),
            "{what}: {why}"
        );
        // Only the file that changed is named.
        let others = ["scene.gltf", "scene.bin", "wood.png"];
        for other in others.iter().filter(|o| !named.starts_with(*o)) {
            assert!(!why.contains(&format!("{other} changed")), "{what}: {why}");
        }
        write_scene(&dir.0, 0.8, 50.0);
        write_texture(&dir.0, 128);
    }
}

/// A render of `scene` into `out`, stopped before its first row: it leaves a checkpoint.
fn job(scene: &Path, out: &Path, cancelled: bool) -> RenderJob {
    let mut job = RenderJob::new(scene.to_str().unwrap());
    job.output = Some(out.to_path_buf());
    job.overrides.spp = Some(2);
    job.overrides.resolution = Some([8, 8]);
    job.aovs.standard = false;
    job.cancel = Some(Arc::new(AtomicBool::new(cancelled)));
    job
}

#[test]
fn resume_refuses_a_checkpoint_of_the_gltf_before_an_edit_unless_told_to_start_over() {
    let dir = Scratch::new("identity-resume");
    let scene = write_scene(&dir.0, 0.8, 50.0);
    write_texture(&dir.0, 128);
    let out = dir.join("shot.exr");
    let stopped = job(&scene, &out, true)
        .prepare()
        .unwrap()
        .run(&Silent)
        .unwrap();
    let checkpoint = stopped.interrupted.expect("stopped").checkpoint;
    assert!(checkpoint.exists());

    let resume = |restart: bool| {
        let mut j = job(&scene, &out, false);
        j.resume = true;
        j.restart_if_changed = restart;
        j.prepare()
    };
    write_scene(&dir.0, 0.5, 50.0);
    let why = resume(false)
        .err()
        .expect("resumed an edited scene")
        .to_string();
    assert!(
        why.contains("scene changed") && why.contains("scene.gltf changed"),
        "{why}"
    );
    assert!(why.contains("--restart-if-changed"), "{why}");
    // Told to, it starts over and says why.
    let restarted = resume(true).unwrap();
    assert!(restarted.resume.is_none());
    assert!(
        restarted
            .warnings
            .iter()
            .any(|w| w.contains("scene.gltf changed") && w.contains("starting over")),
        "{:?}",
        restarted.warnings
    );
    drop(restarted);

    // Unedited, the checkpoint resumes, and the result is the uninterrupted render's.
    write_scene(&dir.0, 0.8, 50.0);
    let resumed = resume(false).unwrap();
    assert!(resumed.resume.is_some());
    resumed.run(&Silent).unwrap();
    let whole = dir.join("whole.exr");
    job(&scene, &whole, false)
        .prepare()
        .unwrap()
        .run(&Silent)
        .unwrap();
    let (a, b) = (
        lightpath::output::read_exr(&out).unwrap(),
        lightpath::output::read_exr(&whole).unwrap(),
    );
    assert_eq!(a.channels.len(), b.channels.len());
    for ((name, x), (_, y)) in a.channels.iter().zip(&b.channels) {
        let same = x.iter().zip(y).all(|(p, q)| p.to_bits() == q.to_bits());
        assert!(same, "channel {name} differs after the resume");
    }
    // Restarting is only for a changed scene: another job's checkpoint is still refused.
    job(&scene, &out, true)
        .prepare()
        .unwrap()
        .run(&Silent)
        .unwrap();
    let mut other = job(&scene, &out, false);
    other.overrides.spp = Some(3);
    other.resume = true;
    other.restart_if_changed = true;
    let why = other
        .prepare()
        .err()
        .expect("resumed another job")
        .to_string();
    assert!(why.contains("different render"), "{why}");
}
