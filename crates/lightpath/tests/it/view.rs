//! `lightpath view`'s server, spoken to over HTTP with std::net: on a synthetic EXR whose
//! every value is known (light groups, a Cryptomatte layer, a `_noisy` twin), on a live
//! render, and the binary's Ctrl-C.

use ::exr::prelude::f16;
use lightpath::aov::naming::{self, PartInfo};
use lightpath::output::{self, ExrOptions};
use lightpath::view::{self, Viewer};
use serde_json::Value;
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::Path;

use crate::common;
use common::Scratch;

const W: usize = 6;
const H: usize = 4;
const FLOOR: u32 = 0x3f80_1234;
const BALL: u32 = 0x4120_abcd;

/// key(x, y) and fill(x, y): distinct values everywhere; beauty is their sum.
fn key(i: usize, c: usize) -> f32 {
    0.01 * (i as f32 + 1.0) * (c as f32 + 1.0)
}
fn fill(i: usize, c: usize) -> f32 {
    0.5 - 0.003 * i as f32 + 0.1 * c as f32
}

/// Writes the synthetic EXR: beauty split into light groups `key` and the default group,
/// a `beauty_noisy` twin, and a Cryptomatte layer: the left half is the floor, the right
/// half 75 % ball over 25 % floor.
fn synthetic(path: &Path) {
    let n = W * H;
    let plane = |f: &dyn Fn(usize) -> f32| (0..n).map(f).collect::<Vec<f32>>();
    let mut channels = Vec::new();
    let mut attributes = Vec::new();
    for (name, f) in [
        (
            "beauty",
            &(|i, c| key(i, c) + fill(i, c)) as &dyn Fn(usize, usize) -> f32,
        ),
        ("beauty_key", &key),
        ("beauty__default", &fill),
        ("beauty_noisy", &(|i, c| key(i, c) + fill(i, c) + 0.25)),
    ] {
        for (c, ch) in naming::channel_names(name).into_iter().enumerate() {
            channels.push((ch, plane(&|i| f(i, c))));
        }
        attributes.push((naming::aov_attribute(name), format!("definition of {name}")));
    }
    channels.push(("A".into(), plane(&|_| 1.0)));
    attributes.extend(naming::partition_attributes(&[
        PartInfo {
            name: "beauty",
            definition: "lpe:beauty",
            split_of: None,
        },
        PartInfo {
            name: "beauty_key",
            definition: "lpe:beauty",
            split_of: Some("beauty"),
        },
        PartInfo {
            name: "beauty__default",
            definition: "lpe:beauty",
            split_of: Some("beauty"),
        },
    ]));
    let left = |i: usize| i % W < W / 2;
    let id = |v: u32| f32::from_bits(v);
    channels.push((
        "CryptoObject00.R".into(),
        plane(&|i| if left(i) { id(FLOOR) } else { id(BALL) }),
    ));
    channels.push((
        "CryptoObject00.G".into(),
        plane(&|i| if left(i) { 1.0 } else { 0.75 }),
    ));
    channels.push((
        "CryptoObject00.B".into(),
        plane(&|i| if left(i) { 0.0 } else { id(FLOOR) }),
    ));
    channels.push((
        "CryptoObject00.A".into(),
        plane(&|i| if left(i) { 0.0 } else { 0.25 }),
    ));
    attributes.push(("cryptomatte/a1b2c3d/name".into(), "CryptoObject".into()));
    attributes.push((
        "cryptomatte/a1b2c3d/manifest".into(),
        format!(r#"{{"floor": "{FLOOR:08x}", "ball": "{BALL:08x}"}}"#),
    ));
    output::write_channels(path, W, H, channels, &attributes, ExrOptions::default()).unwrap();
}

/// One HTTP/1.1 exchange: status, headers (lower-case names), body.
fn http(addr: SocketAddr, raw: &str, body: &[u8]) -> (u16, Vec<(String, String)>, Vec<u8>) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.write_all(raw.as_bytes()).unwrap();
    s.write_all(body).unwrap();
    let mut reply = Vec::new();
    s.read_to_end(&mut reply).unwrap();
    let split = reply.windows(4).position(|w| w == b"\r\n\r\n").unwrap();
    let head = String::from_utf8(reply[..split].to_vec()).unwrap();
    let mut lines = head.lines();
    let status = lines
        .next()
        .unwrap()
        .split(' ')
        .nth(1)
        .unwrap()
        .parse()
        .unwrap();
    let headers = lines
        .filter_map(|l| l.split_once(':'))
        .map(|(k, v)| (k.trim().to_ascii_lowercase(), v.trim().to_string()))
        .collect();
    (status, headers, reply[split + 4..].to_vec())
}

fn get(addr: SocketAddr, path: &str) -> (u16, Vec<(String, String)>, Vec<u8>) {
    http(
        addr,
        &format!("GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n"),
        b"",
    )
}

fn get_json(addr: SocketAddr, path: &str) -> Value {
    let (status, _, body) = get(addr, path);
    let v: Value = serde_json::from_slice(&body).unwrap();
    assert_eq!(status, 200, "{path}: {v}");
    v
}

fn post_comp(addr: SocketAddr, body: &str, content_type: &str) -> (u16, Value) {
    let raw = format!(
        "POST /api/comp HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\nContent-Type: {content_type}\r\nContent-Length: {}\r\n\r\n",
        body.len()
    );
    let (status, _, reply) = http(addr, &raw, body.as_bytes());
    (status, serde_json::from_slice(&reply).unwrap())
}

/// The half floats of an image reply, and its size.
fn halves(reply: &(u16, Vec<(String, String)>, Vec<u8>)) -> (usize, usize, Vec<f32>) {
    let header = |k: &str| -> usize {
        reply
            .1
            .iter()
            .find(|(n, _)| n == k)
            .unwrap()
            .1
            .parse()
            .unwrap()
    };
    assert_eq!(reply.0, 200);
    let v = reply
        .2
        .chunks_exact(2)
        .map(|b| f16::from_bits(u16::from_le_bytes([b[0], b[1]])).to_f32())
        .collect();
    (header("x-width"), header("x-height"), v)
}

fn serve(path: &Path) -> Viewer {
    Viewer::start(view::open(path).unwrap(), Some(path.to_path_buf()), 0).unwrap()
}

#[test]
fn info_lists_every_aov_with_partitions_mixers_cryptomatte_and_noisy_twins() {
    let dir = Scratch::new("view-info");
    let exr = dir.join("synthetic.exr");
    synthetic(&exr);
    let viewer = serve(&exr);
    // The partition checks are measured on a thread of their own: ask until they are in.
    let mut info = get_json(viewer.addr(), "/api/info");
    for _ in 0..200 {
        if !info["partitions"][0]["max_relative_error"].is_null() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
        info = get_json(viewer.addr(), "/api/info");
    }
    let names: Vec<&str> = info["aovs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a["name"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        ["beauty", "beauty__default", "beauty_key", "beauty_noisy"]
    );
    assert_eq!(info["aovs"][2]["definition"], "definition of beauty_key");
    assert_eq!(info["aovs"][2]["partition"], "lightgroups");
    let partitions = info["partitions"].as_array().unwrap();
    assert_eq!(partitions.len(), 1);
    assert_eq!(partitions[0]["whole"], "beauty");
    assert_eq!(
        partitions[0]["parts"],
        serde_json::json!(["beauty_key", "beauty__default"])
    );
    // beauty is the float sum of its parts: the measured error is a rounding error.
    assert!(partitions[0]["max_relative_error"].as_f64().unwrap() < 1e-6);
    let groups = &info["mixers"][0]["groups"];
    assert_eq!(info["mixers"][0]["base"], "beauty");
    assert_eq!(groups[0]["arg"], "key");
    assert_eq!(groups[1]["arg"], naming::DEFAULT_GROUP);
    assert_eq!(groups[1]["part"], "beauty__default");
    assert_eq!(
        info["noisy"],
        serde_json::json!([{ "aov": "beauty", "noisy": "beauty_noisy" }])
    );
    assert_eq!(info["cryptomatte"][0]["name"], "CryptoObject");
    assert_eq!(info["cryptomatte"][0]["objects"], 2);
    assert_eq!(info["comp"], true);
    viewer.stop();
}

#[test]
fn images_are_the_aovs_as_half_floats_and_thumbnails_their_box_averages() {
    let dir = Scratch::new("view-images");
    let exr = dir.join("synthetic.exr");
    synthetic(&exr);
    let viewer = serve(&exr);
    let (w, h, full) = halves(&get(viewer.addr(), "/api/image?name=beauty_key"));
    assert_eq!((w, h), (W, H));
    for i in 0..W * H {
        for c in 0..3 {
            assert_eq!(full[3 * i + c], f16::from_f32(key(i, c)).to_f32());
        }
    }
    // Width 3: factor 2, each value the mean of a 2×2 box.
    let (w, h, small) = halves(&get(viewer.addr(), "/api/image?name=beauty_key&width=3"));
    assert_eq!((w, h), (3, 2));
    let box_mean = |x: usize, y: usize, c: usize| {
        let at = |dx, dy| key((2 * y + dy) * W + 2 * x + dx, c);
        (at(0, 0) + at(1, 0) + at(0, 1) + at(1, 1)) / 4.0
    };
    for (y, x, c) in [(0, 0, 0), (1, 2, 2), (1, 1, 1)] {
        let got = small[3 * (y * 3 + x) + c];
        assert!(
            (got - box_mean(x, y, c)).abs() <= box_mean(x, y, c) * 1e-3,
            "{got}"
        );
    }
    let (status, _, _) = get(viewer.addr(), "/api/image?name=nothing");
    assert_eq!(status, 404);
    let (status, _, _) = get(viewer.addr(), "/api/image");
    assert_eq!(status, 400);
    viewer.stop();
}

#[test]
fn a_pixel_shows_every_aov_and_the_object_under_it_and_its_matte() {
    let dir = Scratch::new("view-pixel");
    let exr = dir.join("synthetic.exr");
    synthetic(&exr);
    let viewer = serve(&exr);
    let (x, y) = (4, 2);
    let i = y * W + x;
    let p = get_json(viewer.addr(), &format!("/api/pixel?x={x}&y={y}"));
    let values = p["values"].as_array().unwrap();
    assert_eq!(values.len(), 4);
    let fill_rgb: Vec<f64> = (0..3).map(|c| fill(i, c) as f64).collect();
    let got: Vec<f64> = values[1]["rgb"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(values[1]["name"], "beauty__default");
    for (g, f) in got.iter().zip(&fill_rgb) {
        assert!((g - f).abs() < 1e-6);
    }
    assert_eq!(p["alpha"], 1.0);
    // Right half: 75 % ball.
    assert_eq!(p["cryptomatte"][0]["name"], "ball");
    assert_eq!(p["cryptomatte"][0]["id"], format!("{BALL:08x}"));
    let left = get_json(viewer.addr(), "/api/pixel?x=0&y=0");
    assert_eq!(left["cryptomatte"][0]["name"], "floor");
    // The floor's matte: 1 on the left, the 25 % rank on the right.
    let (w, h, matte) = halves(&get(
        viewer.addr(),
        &format!("/api/matte?layer=CryptoObject&id={FLOOR:08x}"),
    ));
    assert_eq!((w, h), (W, H));
    for (i, m) in matte.iter().enumerate() {
        assert_eq!(*m, if i % W < W / 2 { 1.0 } else { 0.25 }, "pixel {i}");
    }
    let (status, _, _) = get(viewer.addr(), "/api/pixel?x=6&y=0");
    assert_eq!(status, 404);
    let (status, _, _) = get(viewer.addr(), "/api/pixel?x=-1&y=0");
    assert_eq!(status, 400);
    let (status, _, _) = get(viewer.addr(), "/api/matte?layer=CryptoObject&id=zz");
    assert_eq!(status, 400);
    viewer.stop();
}

#[test]
fn save_comp_writes_what_its_command_line_writes() {
    let dir = Scratch::new("view-comp");
    let exr = dir.join("synthetic.exr");
    synthetic(&exr);
    let viewer = serve(&exr);
    let (status, reply) = post_comp(
        viewer.addr(),
        r#"{"gains": ["key=2.5", "_default=1,0.5,0.25"], "base": "beauty", "output": "relit.exr"}"#,
        "application/json",
    );
    assert_eq!(status, 200, "{reply}");
    let command = reply["command"].as_str().unwrap();
    let relit = output::read_exr(&dir.join("relit.exr")).unwrap();
    for i in 0..W * H {
        for (c, gain) in [1.0f32, 0.5, 0.25].into_iter().enumerate() {
            let want = key(i, c) + fill(i, c) + 1.5 * key(i, c) + (gain - 1.0) * fill(i, c);
            let got = relit.channel(&naming::channel_names("beauty")[c]).unwrap()[i];
            assert!(
                (got - want).abs() <= 1e-6 * want.abs().max(1.0),
                "{got} {want}"
            );
        }
    }
    // The command line, run with another output, writes the same bytes.
    let words: Vec<String> = command.split(' ').map(String::from).collect();
    assert_eq!(words[..2], ["lightpath", "comp"]);
    let mut args = words[1..].to_vec();
    let o = args.iter().position(|a| a == "-o").unwrap();
    args[o + 1] = dir.join("cli.exr").display().to_string();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_lightpath"))
        .args(&args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        std::fs::read(dir.join("relit.exr")).unwrap(),
        std::fs::read(dir.join("cli.exr")).unwrap()
    );
    viewer.stop();
}

#[test]
fn bad_requests_are_refused_with_a_reason_and_the_server_keeps_answering() {
    let dir = Scratch::new("view-refuse");
    let exr = dir.join("synthetic.exr");
    synthetic(&exr);
    let viewer = serve(&exr);
    let addr = viewer.addr();
    let refuse = |body: &str, kind: &str, status: u16, says: &str| {
        let (s, reply) = post_comp(addr, body, kind);
        assert_eq!(s, status, "{reply}");
        assert!(reply["error"].as_str().unwrap().contains(says), "{reply}");
    };
    let ok_body = r#"{"gains": [], "output": "x.exr"}"#;
    refuse(ok_body, "text/plain", 415, "application/json");
    refuse(
        r#"{"gains": [], "output": "../x.exr"}"#,
        "application/json",
        400,
        "no folder",
    );
    refuse(
        r#"{"gains": [], "output": "x.png"}"#,
        "application/json",
        400,
        "ending in .exr",
    );
    refuse(
        r#"{"gains": [], "output": "synthetic.exr"}"#,
        "application/json",
        400,
        "overwrite",
    );
    refuse(
        r#"{"gains": ["nogroup=2"], "output": "x.exr"}"#,
        "application/json",
        400,
        "nogroup",
    );
    refuse(
        r#"{"gains": "key=2", "output": "x.exr"}"#,
        "application/json",
        400,
        "bad comp request",
    );
    refuse("{", "application/json", 400, "bad comp request");
    // Another Host (a page of another site resolving its name to 127.0.0.1).
    let (s, _, _) = http(
        addr,
        "GET /api/info HTTP/1.1\r\nHost: evil.example:80\r\nConnection: close\r\n\r\n",
        b"",
    );
    assert_eq!(s, 403);
    // Garbage on the socket, then a real request.
    let mut junk = TcpStream::connect(addr).unwrap();
    let _ = junk.write_all(b"\x00\xff NOT HTTP\r\n\r\n");
    drop(junk);
    assert_eq!(get(addr, "/nothing").0, 404);
    assert_eq!(get(addr, "/").0, 200);
    assert!(!dir.join("x.exr").exists());
    viewer.stop();
}

#[test]
fn a_live_preview_ends_with_exactly_the_written_render() {
    let dir = Scratch::new("view-live");
    let mut job = lightpath::RenderJob::new("cornell");
    job.overrides.resolution = Some([20, 36]);
    job.overrides.spp = Some(2);
    job.aovs.light_groups = true;
    job.output = Some(dir.join("live.exr"));
    let prepared = job.prepare().unwrap();
    let data = view::preview::live_data(&prepared.scene, "cornell");
    let viewer = Viewer::start(data, None, 0).unwrap();
    let info = get_json(viewer.addr(), "/api/info");
    assert_eq!(
        (info["live"].as_bool(), info["comp"].as_bool()),
        (Some(true), Some(false))
    );
    let silent = lightpath::progress::Silent;
    let preview = view::preview::LivePreview::new(&silent, viewer.shared().clone(), 36);
    let summary = prepared.run(&preview).unwrap();
    // 36 rows in bands of 2 (36 / 32 rounded up): 18 refreshes.
    let generation = viewer.shared().update(|d| d.generation);
    assert_eq!(generation, 18);
    let written = output::read_exr(&summary.paths.exr).unwrap();
    let live = viewer.shared().update(|d| d.exr.channels.clone());
    for (name, values) in &live {
        assert_eq!(written.channel(name), Some(values.as_slice()), "{name}");
    }
    let (status, _) = post_comp(
        viewer.addr(),
        r#"{"gains": [], "output": "x.exr"}"#,
        "application/json",
    );
    assert_eq!(status, 409);
    viewer.shared().show_file(
        view::open(&summary.paths.exr).unwrap(),
        summary.paths.exr.clone(),
    );
    let info = get_json(viewer.addr(), "/api/info");
    assert_eq!(
        (info["live"].as_bool(), info["comp"].as_bool()),
        (Some(false), Some(true))
    );
    assert!(!info["partitions"].as_array().unwrap().is_empty());
    viewer.stop();
}

#[test]
fn the_view_command_prints_its_url_and_stops_cleanly_on_ctrl_c() {
    let dir = Scratch::new("view-cmd");
    let exr = dir.join("synthetic.exr");
    synthetic(&exr);
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_lightpath"))
        .args(["view", exr.to_str().unwrap(), "--no-open"])
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdout = std::io::BufReader::new(child.stdout.take().unwrap());
    let mut line = String::new();
    std::io::BufRead::read_line(&mut stdout, &mut line).unwrap();
    let url = line
        .split_whitespace()
        .find(|w| w.starts_with("http://127.0.0.1:"))
        .unwrap();
    let addr: SocketAddr = url
        .trim_start_matches("http://")
        .trim_end_matches('/')
        .parse()
        .unwrap();
    assert_ne!(addr.port(), 0);
    assert_eq!(get_json(addr, "/api/info")["width"], W);
    let killed = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let status = child.wait().unwrap();
    assert!(status.success(), "{status:?}");
    let mut rest = String::new();
    stdout.read_to_string(&mut rest).unwrap();
    assert!(rest.contains("stopped"), "{rest}");
    assert!(TcpStream::connect(addr).is_err());
}

#[test]
fn view_refuses_a_file_that_is_not_an_exr() {
    let dir = Scratch::new("view-bad");
    let bad = dir.join("bad.exr");
    std::fs::write(&bad, b"not an exr").unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_lightpath"))
        .args(["view", bad.to_str().unwrap(), "--no-open"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.exr"), "{err}");
}
