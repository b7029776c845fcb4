//! Thousands of mutated scene files, OBJ files and EXRs through the loaders and the scene
//! build: each must load, or fail with an error that names the file, and never panic.
//! The mutations are deterministic (a fixed seed), so a failure names a reproducible case.

use lightpath::scene::desc::SceneDesc;
use lightpath::scene::Scene;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;

/// xorshift64*: a deterministic stream of mutations.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Tokens a hostile user (or a typo) puts in scene files.
const TOKENS: &[&str] = &[
    "nan",
    "inf",
    "-inf",
    "1e300",
    "-1e300",
    "1e-45",
    "0",
    "-1",
    "4294967295",
    "4294967296",
    "18446744073709551615",
    "-0.0",
    "\"\"",
    "[]",
    "[0]",
    "[1, 2]",
    "[[0,0,0]]",
    "{}",
    "=",
    "[",
    "]",
    "\"",
    "'",
    "\n",
    "\n[[objects]]\nshape = \"sphere\"\n",
    "\n[[lights]]\ntype = \"dome\"\n",
    "\n[render]\n",
    "\n[aovs]\nx = \"C((((D))))\"\n",
    "segments = 100000",
    "radius = 0",
    "shape = \"obj\"",
    "file = \"/dev/zero\"",
    "type = \"spot\"",
    "\u{feff}",
    "\u{0}",
    "é",
    "resolution = [1, 1]",
    "resolution = [0, 5]",
    "spp = 0",
    "matrix = [0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0]",
];

fn mutate(rng: &mut Rng, text: &str) -> String {
    let mut bytes = text.as_bytes().to_vec();
    for _ in 0..1 + rng.below(3) {
        let at = rng.below(bytes.len() + 1);
        match rng.below(6) {
            0 => {
                let end = (at + 1 + rng.below(40)).min(bytes.len());
                bytes.drain(at.min(end)..end);
            }
            1 => {
                let t = TOKENS[rng.below(TOKENS.len())];
                bytes.splice(at..at, t.bytes());
            }
            2 => {
                // Replace a number-looking run with a token.
                let start = at.min(bytes.len());
                let end = bytes[start..]
                    .iter()
                    .position(|b| !(b.is_ascii_digit() || *b == b'.' || *b == b'-'))
                    .map_or(bytes.len(), |p| start + p);
                let t = TOKENS[rng.below(12)];
                bytes.splice(start..end, t.bytes());
            }
            3 if !bytes.is_empty() => {
                let i = at.min(bytes.len() - 1);
                bytes[i] ^= 1 << rng.below(8);
            }
            4 => {
                let start = at.min(bytes.len());
                let end = (start + rng.below(200)).min(bytes.len());
                let copy = bytes[start..end].to_vec();
                let to = rng.below(bytes.len() + 1);
                bytes.splice(to..to, copy);
            }
            _ => {
                let end = bytes.len().min(at);
                bytes.truncate(end);
            }
        }
    }
    String::from_utf8_lossy(&bytes).into_owned()
}

fn scene_text(name: &str) -> String {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name);
    std::fs::read_to_string(path).unwrap()
}

/// Loads and builds a scene text (beauty only, to keep each case fast).
fn load_and_build(text: &str, dir: &std::path::Path) -> Result<(), String> {
    let source = lightpath::Source {
        name: "mutant.toml".into(),
        text: text.to_string(),
        dir: dir.to_path_buf(),
    };
    let mut desc: SceneDesc = source.parse().map_err(|e| e.to_string())?;
    // The film is never allocated here; keep a mutant's resolution from mattering.
    desc.render.resolution = [
        desc.render.resolution[0].clamp(1, 64),
        desc.render.resolution[1].clamp(1, 64),
    ];
    let specs = vec![lightpath::aov::AovSpec::new("beauty", "lpe:beauty")];
    let specs: Vec<_> = specs
        .into_iter()
        .chain(
            desc.aovs
                .iter()
                .map(|(n, d)| lightpath::aov::AovSpec::new(n.clone(), d.definition.clone())),
        )
        .collect();
    Scene::build(&desc, &specs)
        .map(|_| ())
        .map_err(|e| e.to_string())
}

#[test]
fn mutated_scene_files_load_or_fail_with_a_located_error_and_never_panic() {
    let dir = std::env::temp_dir().join(format!("lightpath-mutation-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("mesh.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let mut cases = 0;
    let mut loaded = 0;
    for name in ["cornell.toml", "cornell-classic.toml", "two-rooms.toml"] {
        let original = scene_text(name);
        for _ in 0..1000 {
            let text = mutate(&mut rng, &original);
            let result = catch_unwind(AssertUnwindSafe(|| load_and_build(&text, &dir)));
            match result {
                Ok(Ok(())) => loaded += 1,
                Ok(Err(e)) => assert!(
                    e.starts_with("mutant.toml"),
                    "an error that does not name the file: {e}\n--- scene ---\n{text}"
                ),
                Err(_) => panic!("panicked on this mutant of {name}:\n{text}"),
            }
            cases += 1;
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
    // The mutations must not all be rejected outright (then nothing would be tested past
    // the parser).
    assert!(loaded > cases / 10, "{loaded} of {cases} mutants loaded");
}

#[test]
fn mutated_obj_files_load_or_fail_and_never_panic() {
    let dir = std::env::temp_dir().join(format!("lightpath-mutation-obj-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let original = "# a quad and a triangle\no quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
                    vn 0 0 1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1/1 2/2/1 3/3/1 4/4/1\n\
                    o tri\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf -3 -2 -1\n";
    let scene = "[[objects]]\nshape = \"obj\"\nfile = \"m.obj\"\n[[lights]]\ntype = \"point\"\n\
                 position = [0, 0, 3]\nintensity = [1, 1, 1]\n";
    let mut rng = Rng(7);
    for _ in 0..1500 {
        let obj = mutate(&mut rng, original);
        std::fs::write(dir.join("m.obj"), &obj).unwrap();
        let result = catch_unwind(AssertUnwindSafe(|| load_and_build(scene, &dir)));
        match result {
            Ok(Ok(())) => {}
            Ok(Err(e)) => assert!(e.contains("m.obj") || e.starts_with("mutant.toml"), "{e}"),
            Err(_) => panic!("panicked on this OBJ:\n{obj}"),
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn mutated_exr_files_are_read_or_refused_and_never_panic() {
    let dir = std::env::temp_dir().join(format!("lightpath-mutation-exr-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("a.exr");
    let channels = vec![
        ("R".to_string(), vec![0.5f32; 16]),
        ("G".to_string(), vec![0.25f32; 16]),
        ("B".to_string(), vec![1.0f32; 16]),
    ];
    let attributes = vec![("lightpath/aov/beauty".to_string(), "lpe:beauty".to_string())];
    let mut originals = Vec::new();
    for compression in ["none", "rle", "zips", "piz"] {
        let options = lightpath::output::ExrOptions {
            half: false,
            compression: lightpath::output::ExrCompression::parse(compression).unwrap(),
        };
        lightpath::output::write_channels(&path, 4, 4, channels.clone(), &attributes, options)
            .unwrap();
        originals.push(std::fs::read(&path).unwrap());
    }
    let mut rng = Rng(99);
    for i in 0..800 {
        let original = &originals[i % originals.len()];
        let mut bytes = original.clone();
        for _ in 0..1 + rng.below(4) {
            let at = rng.below(bytes.len());
            match rng.below(3) {
                0 => bytes[at] ^= 1 << rng.below(8),
                1 => bytes[at] = [0x00, 0xff, 0x7f, 0x80][rng.below(4)],
                _ => bytes.truncate(at.max(1)),
            }
        }
        std::fs::write(&path, &bytes).unwrap();
        let result = catch_unwind(AssertUnwindSafe(|| lightpath::output::read_exr(&path)));
        assert!(result.is_ok(), "panicked on mutant {i} of an EXR");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Loads a scene file of any format (by extension) and builds it.
fn load_file_and_build(path: &std::path::Path) -> Result<(), String> {
    let desc = lightpath::load_scene(path.to_str().unwrap_or("")).map_err(|e| e.to_string())?;
    let specs = vec![lightpath::aov::AovSpec::new("beauty", "lpe:beauty")];
    Scene::build(&desc, &specs)
        .map(|_| ())
        .map_err(|e| e.to_string())
}

/// A small glTF with a camera, a point light, a material and one triangle (its buffer a
/// data URI, so the file stands alone).
const GLTF: &str = r#"{
  "asset": {"version": "2.0"},
  "extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {"KHR_lights_punctual": {"lights": [
    {"type": "point", "color": [1, 1, 1], "intensity": 10, "name": "key"}]}},
  "scene": 0,
  "scenes": [{"nodes": [0, 1, 2]}],
  "nodes": [
    {"name": "tri", "mesh": 0, "translation": [0, 0, -2], "extras": {"lpegroup": "props"}},
    {"name": "cam", "camera": 0},
    {"name": "lamp", "extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0, 1, 0]}
  ],
  "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.01}}],
  "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.5, 0.2, 1], "metallicFactor": 0.5, "roughnessFactor": 0.3}}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
    {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}
  ],
  "bufferViews": [
    {"buffer": 0, "byteOffset": 0, "byteLength": 36},
    {"buffer": 0, "byteOffset": 36, "byteLength": 6}
  ],
  "buffers": [{"byteLength": 44, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAIAAAA="}]
}"#;

#[test]
fn mutated_gltf_files_load_or_fail_naming_the_file_and_never_panic() {
    let dir = std::env::temp_dir().join(format!("lightpath-mutation-gltf-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("m.gltf");
    std::fs::write(&path, GLTF).unwrap();
    load_file_and_build(&path).expect("the unmutated file loads");
    let mut rng = Rng(0x5eed);
    let mut loaded = 0;
    for i in 0..1200 {
        let text = if i % 2 == 0 {
            mutate(&mut rng, GLTF)
        } else {
            // Numbers in the JSON replaced by hostile ones (keeps the syntax valid more often).
            let mut t = GLTF.to_string();
            for _ in 0..1 + rng.below(3) {
                let digits: Vec<usize> = t
                    .char_indices()
                    .filter(|(_, c)| c.is_ascii_digit())
                    .map(|(k, _)| k)
                    .collect();
                let at = digits[rng.below(digits.len())];
                let token = ["-1", "1e300", "4294967295", "0", "65535", "-0", "3"][rng.below(7)];
                t.replace_range(at..at + 1, token);
            }
            t
        };
        std::fs::write(&path, &text).unwrap();
        match catch_unwind(AssertUnwindSafe(|| load_file_and_build(&path))) {
            Ok(Ok(())) => loaded += 1,
            Ok(Err(e)) => assert!(
                e.contains("m.gltf"),
                "an error that does not name the file: {e}"
            ),
            Err(_) => panic!("panicked on this glTF:\n{text}"),
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(loaded > 50, "only {loaded} mutants loaded");
}

#[test]
fn mutated_ply_files_load_or_fail_naming_the_file_and_never_panic() {
    let dir = std::env::temp_dir().join(format!("lightpath-mutation-ply-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let original = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
                    property float z\nproperty float nx\nproperty float ny\nproperty float nz\n\
                    property uchar red\nproperty uchar green\nproperty uchar blue\n\
                    element face 2\nproperty list uchar int vertex_indices\nend_header\n\
                    0 0 0 0 0 1 255 0 0\n1 0 0 0 0 1 0 255 0\n1 1 0 0 0 1 0 0 255\n\
                    0 1 0 0 0 1 255 255 255\n3 0 1 2\n4 0 1 2 3\n";
    let path = dir.join("m.ply");
    std::fs::write(&path, original).unwrap();
    load_file_and_build(&path).expect("the unmutated file loads");
    let mut rng = Rng(0x91a);
    for _ in 0..1200 {
        let text = mutate(&mut rng, original);
        std::fs::write(&path, &text).unwrap();
        match catch_unwind(AssertUnwindSafe(|| load_file_and_build(&path))) {
            Ok(Ok(())) => {}
            Ok(Err(e)) => assert!(
                e.contains("m.ply"),
                "an error that does not name the file: {e}"
            ),
            Err(_) => panic!("panicked on this PLY:\n{text}"),
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
