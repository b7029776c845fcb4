//! Production output and the farm: self-describing headers, Cryptomatte decoded by an
//! independent reader, safe merges of sample ranges and tiles, and the farm scripts.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common;
use common::Scratch;

fn lightpath() -> Command {
    Command::new(env!("CARGO_BIN_EXE_lightpath"))
}

fn succeed(cmd: &mut Command) -> String {
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

fn refuse(cmd: &mut Command) -> String {
    let out = cmd.output().unwrap();
    assert!(!out.status.success(), "should have failed");
    String::from_utf8(out.stderr).unwrap()
}

fn render(scene: &str, out: &Path, args: &[&str]) {
    succeed(
        lightpath()
            .args(["render", scene, "--quiet"])
            .args(args)
            .arg("-o")
            .arg(out),
    );
}

/// An EXR as the `exr` crate reads it, without Lightpath's reader: header and channels.
struct Raw {
    header: exr::meta::header::Header,
    channels: BTreeMap<String, Vec<f32>>,
}

impl Raw {
    fn read(path: &Path) -> Raw {
        use exr::prelude::*;
        let meta = exr::meta::MetaData::read_from_file(path, false).unwrap();
        let image = read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .first_valid_layer()
            .all_attributes()
            .from_file(path)
            .unwrap();
        let channels = image
            .layer_data
            .channel_data
            .list
            .iter()
            .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
            .collect();
        Raw {
            header: meta.headers[0].clone(),
            channels,
        }
    }

    fn text(&self, key: &str) -> Option<String> {
        match self
            .header
            .own_attributes
            .other
            .get(&exr::meta::attribute::Text::from(key))
        {
            Some(exr::meta::attribute::AttributeValue::Text(t)) => Some(t.to_string()),
            _ => None,
        }
    }

    fn channel(&self, name: &str) -> &[f32] {
        self.channels
            .get(name)
            .unwrap_or_else(|| panic!("no channel {name}: {:?}", self.channels.keys()))
    }
}

#[test]
fn identical_renders_are_identical_files_and_the_header_explains_them() {
    let dir = Scratch::new("farm-meta");
    let args = ["--spp", "2", "--resolution", "8x6", "--cryptomatte"];
    render("cornell", &dir.join("a.exr"), &args);
    render("cornell", &dir.join("b.exr"), &args);
    let a = std::fs::read(dir.join("a.exr")).unwrap();
    assert_eq!(a, std::fs::read(dir.join("b.exr")).unwrap());

    let raw = Raw::read(&dir.join("a.exr"));
    let own = &raw.header.own_attributes;
    assert!(own
        .software_name
        .as_ref()
        .is_some_and(|s| s.to_string().starts_with("Lightpath ")));
    let c = raw.header.shared_attributes.chromaticities.unwrap();
    assert_eq!((c.red.x(), c.red.y()), (0.64, 0.33));
    assert_eq!((c.white.x(), c.white.y()), (0.3127, 0.3290));
    assert!(own.world_to_camera.is_some() && own.world_to_normalized_device.is_some());
    assert!(own.capture_date.is_none(), "no date unless --timestamp");
    // The built-in Cornell camera at (0, 0, 3.9) looking at the origin: the origin is
    // 3.9 in front of it and projects to the frame's centre.
    let w2c = own.world_to_camera.unwrap();
    assert!((w2c[14] - 3.9).abs() < 1e-5, "{w2c:?}");
    let n = own.world_to_normalized_device.unwrap();
    let (x, y, w) = (n[12], n[13], n[15]);
    assert!((x / w - 0.5).abs() < 1e-6 && (y / w - 0.5).abs() < 1e-6);
    // pLinear is the same (0) on every channel.
    assert!(raw
        .header
        .channels
        .list
        .iter()
        .all(|c| !c.quantize_linearly));
    // What the user wrote and what was compiled.
    assert_eq!(raw.text("lightpath/aov/albedo").unwrap(), "lpe:albedo");
    let expanded = raw.text("lightpath/expression/albedo").unwrap();
    assert!(
        expanded.contains("U2") && expanded != "lpe:albedo",
        "{expanded}"
    );
    for (k, v) in [
        ("lightpath/spp", "2"),
        ("lightpath/samples", "0-2"),
        ("lightpath/crop", "0,0,8,6"),
        ("lightpath/setting/max_depth", "8"),
        ("lightpath/setting/sampler", "sobol"),
        ("lightpath/setting/resolution", "8x6"),
        ("lightpath/setting/clamp_direct", "0"),
        ("lightpath/seed", "0"),
    ] {
        assert_eq!(raw.text(k).as_deref(), Some(v), "{k}");
    }
    assert_eq!(
        raw.text("lightpath/setting/camera").as_deref(),
        Some("default")
    );
    assert_eq!(raw.text("lightpath/identity").unwrap().len(), 16);
    // The manifest: the built-in scene is the one input, with its hash.
    let inputs = raw.text("lightpath/inputs").unwrap();
    let (hash, path) = inputs.trim_end().split_once(' ').unwrap();
    assert_eq!((hash.len(), path), (16, "builtin:cornell"), "{inputs}");
    // Cryptomatte ids are float32 even when the rest is half.
    render(
        "cornell",
        &dir.join("h.exr"),
        &[&args[..], &["--half", "--timestamp"]].concat(),
    );
    let h = Raw::read(&dir.join("h.exr"));
    for c in &h.header.channels.list {
        let is_id = c.name.to_string().starts_with("Crypto");
        let f32 = c.sample_type == exr::meta::attribute::SampleType::F32;
        assert_eq!(is_id, f32, "{}", c.name);
    }
    let date = h
        .header
        .own_attributes
        .capture_date
        .as_ref()
        .unwrap()
        .to_string();
    assert_eq!(date.len(), 19, "{date}");
}

/// MurmurHash3_x86_32 and the spec's uint32_to_float32, written again from the
/// specification (not the renderer's code).
fn spec_id(name: &str) -> f32 {
    let data = name.as_bytes();
    let (c1, c2) = (0xcc9e2d51u32, 0x1b873593u32);
    let mut h: u32 = 0;
    let n = data.len() / 4;
    for i in 0..n {
        let mut k = u32::from_le_bytes(data[4 * i..4 * i + 4].try_into().unwrap());
        k = k.wrapping_mul(c1);
        k = k.rotate_left(15);
        k = k.wrapping_mul(c2);
        h ^= k;
        h = h.rotate_left(13);
        h = h.wrapping_mul(5).wrapping_add(0xe6546b64);
    }
    let tail = &data[4 * n..];
    let mut k1: u32 = 0;
    if tail.len() >= 3 {
        k1 ^= (tail[2] as u32) << 16;
    }
    if tail.len() >= 2 {
        k1 ^= (tail[1] as u32) << 8;
    }
    if !tail.is_empty() {
        k1 ^= tail[0] as u32;
        k1 = k1.wrapping_mul(c1).rotate_left(15).wrapping_mul(c2);
        h ^= k1;
    }
    h ^= data.len() as u32;
    h ^= h >> 16;
    h = h.wrapping_mul(0x85ebca6b);
    h ^= h >> 13;
    h = h.wrapping_mul(0xc2b2ae35);
    h ^= h >> 16;
    let exp = h >> 23 & 255;
    if exp == 0 || exp == 255 {
        h ^= 1 << 23;
    }
    f32::from_bits(h)
}

/// A Cryptomatte layer decoded as the spec describes, from the header alone: find the
/// layer by its `name` attribute, check hash and conversion, read the manifest, and
/// sum the coverage of every rank whose id is the name's.
fn decode_matte(raw: &Raw, layer: &str, name: &str) -> Vec<f32> {
    let keys: Vec<String> = raw
        .header
        .own_attributes
        .other
        .keys()
        .map(|k| k.to_string())
        .filter(|k| k.starts_with("cryptomatte/") && k.ends_with("/name"))
        .collect();
    let key = keys
        .iter()
        .find(|k| raw.text(k).as_deref() == Some(layer))
        .unwrap_or_else(|| panic!("no layer {layer} in {keys:?}"));
    let prefix = key.trim_end_matches("name");
    assert_eq!(
        raw.text(&format!("{prefix}hash")).unwrap(),
        "MurmurHash3_32"
    );
    assert_eq!(
        raw.text(&format!("{prefix}conversion")).unwrap(),
        "uint32_to_float32"
    );
    let manifest: BTreeMap<String, String> =
        serde_json::from_str(&raw.text(&format!("{prefix}manifest")).unwrap()).unwrap();
    let id = spec_id(name);
    assert_eq!(
        manifest
            .get(name)
            .map(|h| u32::from_str_radix(h, 16).unwrap()),
        Some(id.to_bits()),
        "{name} in the manifest of {layer}"
    );
    let len = raw.channel("A").len();
    let mut matte = vec![0.0f32; len];
    for rank_group in 0.. {
        let ch = |c: &str| format!("{layer}{rank_group:02}.{c}");
        if !raw.channels.contains_key(&ch("R")) {
            assert!(rank_group >= 3, "6 ranks: three RGBA groups");
            break;
        }
        for (idc, covc) in [("R", "G"), ("B", "A")] {
            let (ids, cov) = (raw.channel(&ch(idc)), raw.channel(&ch(covc)));
            for p in 0..len {
                if ids[p] == id {
                    matte[p] += cov[p];
                }
            }
        }
    }
    matte
}

/// Everything glows white and nothing else lights the scene, so the per-object LPE
/// `C<O'name'>` is that object's coverage of each pixel.
const MATTE_SCENE: &str = r#"
[film]
resolution = [20, 14]
filter = "gaussian"
filter_stddev = 0.6

[render]
spp = 16
max_depth = 1

[camera]
position = [0, 0, 5]
look_at = [0, 0, 0]
fov = 40

[materials.red]
type = "diffuse"
albedo = [0.8, 0.1, 0.1]

[materials.blue]
type = "diffuse"
albedo = [0.1, 0.1, 0.8]

[[objects]]
name = "ball"
shape = "sphere"
radius = 0.6
center = [-0.5, 0.2, 0]
material = "red"
emission = [1, 1, 1]
asset = "props"

[[objects]]
name = "box"
shape = "cube"
scale = 0.4
translate = [0.6, -0.3, 0.5]
rotate = [20, 30, 0]
material = "blue"
emission = [1, 1, 1]
asset = "props"

[[objects]]
name = "card"
shape = "rectangle"
scale = [3, 3, 1]
translate = [0, -0.2, -1]
material = "red"
emission = [1, 1, 1]

[[objects]]
name = "matte"
shape = "sphere"
radius = 0.3
center = [0.9, 0.8, 0.5]
holdout = true
emission = [1, 1, 1]

[[objects]]
name = "ghost"
shape = "sphere"
radius = 0.5
center = [-1.2, -0.6, 0.8]
material = "blue"
visible_camera = false
emission = [1, 1, 1]
"#;

const OBJECTS: [&str; 3] = ["ball", "box", "card"];

fn render_matte_scene(dir: &Scratch, out: &str, extra: &[&str]) -> Raw {
    let scene = dir.join("mattes.toml");
    std::fs::write(&scene, MATTE_SCENE).unwrap();
    let mut args = vec!["--aovs", "none", "--cryptomatte"];
    let masks: Vec<String> = OBJECTS.iter().map(|o| format!("m_{o}=C<O'{o}'>")).collect();
    for m in &masks {
        args.extend(["--aov", m]);
    }
    args.extend(extra);
    render(scene.to_str().unwrap(), &dir.join(out), &args);
    Raw::read(&dir.join(out))
}

#[test]
fn cryptomatte_decoded_independently_matches_per_object_lpe_masks() {
    let dir = Scratch::new("farm-crypto");
    let raw = render_matte_scene(&dir, "m.exr", &[]);
    let alpha = raw.channel("A");
    let tol = 1e-6;
    let mut sum = vec![0.0f32; alpha.len()];
    for o in OBJECTS {
        let matte = decode_matte(&raw, "CryptoObject", o);
        let mask = raw.channel(&format!("m_{o}.R"));
        assert!(matte.iter().any(|&m| m > 0.0) && matte.iter().any(|&m| m > 0.0 && m < 1.0));
        for (p, (m, k)) in matte.iter().zip(mask).enumerate() {
            assert!(
                (m - k).abs() <= tol,
                "{o} pixel {p}: matte {m}, LPE mask {k}"
            );
        }
        for (s, m) in sum.iter_mut().zip(&matte) {
            *s += m;
        }
    }
    // Coverage sums to alpha: 1 where the camera sees only geometry, less at the holdout
    // and at the frame's open edges.
    for (p, (s, a)) in sum.iter().zip(alpha).enumerate() {
        assert!((s - a).abs() <= tol, "pixel {p}: coverage {s}, alpha {a}");
    }
    assert!(alpha.iter().filter(|&&a| a == 1.0).count() > alpha.len() / 2);
    assert!(alpha.iter().any(|&a| a < 1.0), "the holdout shows");
    // The hidden object has an id but covers nothing; the holdout has no id at all.
    assert!(decode_matte(&raw, "CryptoObject", "ghost")
        .iter()
        .all(|&m| m == 0.0));
    let key = "cryptomatte/3ae39a5/manifest";
    assert!(!raw.text(key).unwrap().contains("\"matte\""));
    // Materials and assets: the sums of their objects' masks.
    let mask = |o: &str| raw.channel(&format!("m_{o}.R")).to_vec();
    let add = |a: Vec<f32>, b: Vec<f32>| a.iter().zip(&b).map(|(x, y)| x + y).collect::<Vec<_>>();
    for (layer, name, expected) in [
        ("CryptoMaterial", "red", add(mask("ball"), mask("card"))),
        ("CryptoMaterial", "blue", mask("box")),
        ("CryptoAsset", "props", add(mask("ball"), mask("box"))),
        ("CryptoAsset", "card", mask("card")),
    ] {
        let matte = decode_matte(&raw, layer, name);
        for (p, (m, e)) in matte.iter().zip(&expected).enumerate() {
            assert!(
                (m - e).abs() <= 2.0 * tol,
                "{layer} {name} pixel {p}: {m} vs {e}"
            );
        }
    }
}

#[test]
fn tiles_and_sample_ranges_merge_into_the_whole_frame() {
    let dir = Scratch::new("farm-tiles");
    let whole = render_matte_scene(&dir, "whole.exr", &[]);
    // Tiles of different shapes: exactly the whole frame, mattes included.
    let tiles = ["0,0,7,5", "7,0,20,5", "0,5,20,14"];
    let mut parts = Vec::new();
    for (i, t) in tiles.iter().enumerate() {
        let name = format!("tile{i}.exr");
        let tile = render_matte_scene(&dir, &name, &["--crop", t]);
        let own = &tile.header.own_attributes;
        let display = tile.header.shared_attributes.display_window;
        assert_eq!((display.size.width(), display.size.height()), (20, 14));
        assert_eq!(
            format!(
                "{},{},{},{}",
                own.layer_position.x(),
                own.layer_position.y(),
                own.layer_position.x() + tile.header.layer_size.width() as i32,
                own.layer_position.y() + tile.header.layer_size.height() as i32
            ),
            *t
        );
        parts.push(dir.join(&name));
    }
    succeed(
        lightpath()
            .arg("merge")
            .args(&parts)
            .arg("-o")
            .arg(dir.join("tiled.exr")),
    );
    let tiled = Raw::read(&dir.join("tiled.exr"));
    assert_eq!(
        tiled.channels.keys().collect::<Vec<_>>(),
        whole.channels.keys().collect::<Vec<_>>()
    );
    for (name, values) in &whole.channels {
        let t = tiled.channel(name);
        assert!(
            values
                .iter()
                .zip(t)
                .all(|(a, b)| a.to_bits() == b.to_bits()),
            "{name} differs"
        );
    }
    assert_eq!(tiled.text("lightpath/crop").unwrap(), "0,0,20,14");

    // Sample ranges 0-5 and 5-16: to float rounding, mattes included.
    for (name, range) in [
        ("r0.exr", ["--first-sample", "0", "--spp", "5"]),
        ("r1.exr", ["--first-sample", "5", "--spp", "11"]),
    ] {
        render_matte_scene(&dir, name, &range);
    }
    let out = succeed(
        lightpath()
            .arg("merge")
            .args([dir.join("r1.exr"), dir.join("r0.exr")])
            .arg("-o")
            .arg(dir.join("ranges.exr")),
    );
    assert!(out.contains("16 samples per pixel"), "{out}");
    let merged = Raw::read(&dir.join("ranges.exr"));
    assert_eq!(merged.text("lightpath/samples").unwrap(), "0-5 5-16");
    for o in OBJECTS {
        let (a, b) = (
            decode_matte(&whole, "CryptoObject", o),
            decode_matte(&merged, "CryptoObject", o),
        );
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() <= 1e-6, "{o}: {x} vs {y}");
        }
    }
    for (name, values) in &whole.channels {
        if name.starts_with("Crypto") {
            continue;
        }
        for (a, b) in values.iter().zip(merged.channel(name)) {
            assert!(
                (a - b).abs() <= 1e-6 * a.abs().max(1.0),
                "{name}: {a} vs {b}"
            );
        }
    }
}

#[test]
fn merges_that_should_fail_fail_naming_the_reason() {
    let dir = Scratch::new("farm-refuse");
    let base = ["--spp", "2", "--resolution", "8x8", "--aovs", "none"];
    let part = |name: &str, extra: &[&str]| {
        render("cornell", &dir.join(name), &[&base[..], extra].concat());
        dir.join(name)
    };
    let a = part("a.exr", &["--first-sample", "0"]);
    let b = part("b.exr", &["--first-sample", "1"]);
    let c = part("c.exr", &["--first-sample", "2"]);
    let seed = part("seed.exr", &["--first-sample", "4", "--seed", "7"]);
    let depth = part("depth.exr", &["--first-sample", "4", "--max-depth", "3"]);
    let aov = part("aov.exr", &["--first-sample", "4", "--aov", "x=C<RD>L"]);
    let other = {
        let scene = dir.join("other.toml");
        let text = include_str!("../../../../scenes/cornell.toml").replace("0.8", "0.7");
        std::fs::write(&scene, text).unwrap();
        render(
            scene.to_str().unwrap(),
            &dir.join("other.exr"),
            &[&base[..], &["--first-sample", "4"]].concat(),
        );
        dir.join("other.exr")
    };
    let merge = |inputs: &[&PathBuf], out: &str| {
        let mut cmd = lightpath();
        cmd.arg("merge").args(inputs).arg("-o").arg(dir.join(out));
        cmd
    };
    let why = refuse(&mut merge(&[&a, &b], "x.exr"));
    assert!(
        why.contains("overlap") && why.contains("0-2") && why.contains("1-3"),
        "{why}"
    );
    let why = refuse(&mut merge(&[&a, &a], "x.exr"));
    assert!(why.contains("overlap"), "{why}");
    let why = refuse(&mut merge(&[&a, &seed], "x.exr"));
    assert!(why.contains("lightpath/seed"), "{why}");
    let why = refuse(&mut merge(&[&a, &depth], "x.exr"));
    assert!(why.contains("lightpath/setting/max_depth"), "{why}");
    let why = refuse(&mut merge(&[&a, &aov], "x.exr"));
    assert!(why.contains("channels") && why.contains("x.R"), "{why}");
    let why = refuse(&mut merge(&[&a, &other], "x.exr"));
    assert!(
        why.contains("different scenes") && why.contains("other.toml is read now"),
        "{why}"
    );
    // A merged file records its ranges: merging it again with a part double-counts.
    succeed(&mut merge(&[&a, &c], "ac.exr"));
    let why = refuse(&mut merge(&[&dir.join("ac.exr"), &c], "x.exr"));
    assert!(why.contains("overlap"), "{why}");
    // Tiles: overlapping, leaving a hole, or with different samples.
    let t = |name: &str, crop: &str, first: &str| {
        part(name, &["--crop", crop, "--first-sample", first])
    };
    let (t0, t1, t2, t3) = (
        t("t0.exr", "0,0,8,4", "0"),
        t("t1.exr", "0,3,8,8", "0"),
        t("t2.exr", "0,5,8,8", "0"),
        t("t3.exr", "0,4,8,8", "2"),
    );
    let why = refuse(&mut merge(&[&t0, &t1], "x.exr"));
    assert!(why.contains("may not overlap"), "{why}");
    let why = refuse(&mut merge(&[&t0, &t2], "x.exr"));
    assert!(why.contains("uncovered"), "{why}");
    let why = refuse(&mut merge(&[&t0, &t3], "x.exr"));
    assert!(why.contains("same samples"), "{why}");
    // A crop outside the frame is refused before rendering.
    let why = refuse(
        lightpath()
            .args([
                "render",
                "cornell",
                "--quiet",
                "--resolution",
                "8x8",
                "--crop",
                "4,4,9,8",
                "-o",
            ])
            .arg(dir.join("x.exr")),
    );
    assert!(why.contains("crop 4,4,9,8"), "{why}");
}

/// A stand-in `sbatch` in `dir/bin` that runs each submitted script at once, as every
/// array task, checking the merge's dependency names the array (the number it prints
/// counts up from 100 in `$SBATCH_STATE`). Returns the `PATH` to run a script with.
pub(crate) fn fake_sbatch(dir: &Scratch) -> String {
    let bin = dir.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    let fake = r#"#!/usr/bin/env bash
set -eu
array=""; dep=""
for a in "$@"; do
  case "$a" in
    --array=*) array="${a#--array=}" ;;
    --dependency=*) dep="${a#--dependency=afterok:}" ;;
  esac
done
script=$(cat)
n=$(cat "$SBATCH_STATE" 2>/dev/null || echo 100)
if [ -n "$dep" ] && [ "$dep" != "$((n - 1))" ]; then echo "bad dependency $dep" >&2; exit 1; fi
if [ -n "$array" ]; then
  for i in $(seq "${array%-*}" "${array#*-}"); do SLURM_ARRAY_TASK_ID=$i bash -c "$script" >&2; done
else
  bash -c "$script" >&2
fi
echo $((n + 1)) > "$SBATCH_STATE"
echo "$n"
"#;
    let sbatch = bin.join("sbatch");
    std::fs::write(&sbatch, fake).unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&sbatch, std::fs::Permissions::from_mode(0o755)).unwrap();
    format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    )
}

#[test]
fn the_slurm_script_runs_the_parts_and_the_merge_through_sbatch() {
    // A stand-in `sbatch` that runs each submitted script at once, as every array task,
    // checking the merge's dependency names the array: the script's own logic is tested,
    // the real Slurm run is benches/farm/slurm-local.sh.
    let dir = Scratch::new("farm-slurm");
    let path = fake_sbatch(&dir);
    for by in ["samples", "tiles"] {
        let out = dir.join(&format!("{by}.exr"));
        let script = succeed(
            lightpath()
                .args(["farm", "slurm", "cornell", "--tasks", "3", "--by", by, "-o"])
                .arg(&out)
                .args(["--spp", "4", "--resolution", "9x7", "--aovs", "none"]),
        );
        assert!(
            script.contains("--array=0-2") && script.contains("afterok"),
            "{script}"
        );
        std::fs::write(dir.join("submit.sh"), &script).unwrap();
        let said = succeed(
            Command::new("bash")
                .arg(dir.join("submit.sh"))
                .env("PATH", &path)
                .env("SBATCH_STATE", dir.join(&format!("{by}.state"))),
        );
        assert!(said.contains("merge: job 101"), "{said}");
        render(
            "cornell",
            &dir.join("single.exr"),
            &["--spp", "4", "--resolution", "9x7", "--aovs", "none"],
        );
        let (farm, single) = (Raw::read(&out), Raw::read(&dir.join("single.exr")));
        for (name, values) in &single.channels {
            for (a, b) in values.iter().zip(farm.channel(name)) {
                let ok = if by == "tiles" {
                    a.to_bits() == b.to_bits()
                } else {
                    (a - b).abs() <= 1e-6 * a.abs().max(1.0)
                };
                assert!(ok, "{by} {name}: {a} vs {b}");
            }
        }
    }
    // The farm chooses each part's range and window.
    let why = refuse(lightpath().args([
        "farm", "slurm", "cornell", "--tasks", "2", "-o", "x.exr", "--crop", "0,0,2,2",
    ]));
    assert!(why.contains("--crop"), "{why}");
}
