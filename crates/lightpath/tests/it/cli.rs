//! The `lightpath` binary as scripts and conformance suites use it.

use serde_json::Value;
use std::io::Write;
use std::process::{Command, Stdio};

use crate::common;
use common::Scratch;

fn lightpath() -> Command {
    Command::new(env!("CARGO_BIN_EXE_lightpath"))
}

/// Runs the command, asserts it succeeded (showing its stderr if not), returns its output.
fn succeed(cmd: &mut Command) -> std::process::Output {
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Runs the command, asserts it failed, returns its stderr.
fn refuse(cmd: &mut Command) -> String {
    let out = cmd.output().unwrap();
    assert!(!out.status.success());
    String::from_utf8(out.stderr).unwrap()
}

#[test]
fn every_conformance_vector_passes_through_lpe_match_jsonl() {
    let vectors = include_str!("../../../lpe/tests/vectors/conformance.jsonl");
    let mut child = lightpath()
        .args(["lpe", "match", "--jsonl"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    let input = vectors.to_string();
    let writer = std::thread::spawn(move || stdin.write_all(input.as_bytes()));
    let out = child.wait_with_output().unwrap();
    writer.join().unwrap().unwrap();
    assert!(out.status.success());
    let answers: Vec<Value> = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let cases: Vec<Value> = vectors
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(answers.len(), cases.len());
    let mut failures = Vec::new();
    for (case, answer) in cases.iter().zip(&answers) {
        if case.get("error").is_some() {
            if answer.get("span") != case.get("span") || !answer["error"].is_string() {
                failures.push(format!("{case} -> {answer}"));
            }
        } else if answer.get("match") != case.get("match") {
            failures.push(format!("{case} -> {answer}"));
        }
    }
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

#[test]
fn jsonl_reports_bad_paths_and_bad_json_without_stopping() {
    let mut child = lightpath()
        .args(["lpe", "match", "--jsonl"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(b"{\"expr\": \"CL\", \"path\": \"C<RD\"}\nnot json\n{\"expr\": \"C<RD>L\", \"path\": \"C<RD>L\"}\n")
        .unwrap();
    let out = child.wait_with_output().unwrap();
    let lines: Vec<Value> = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert!(lines[0]["path_error"].is_string());
    assert!(lines[1]["input_error"].is_string());
    assert_eq!(lines[2]["match"], Value::Bool(true));
}

#[test]
fn check_exits_nonzero_and_points_at_the_error() {
    let ok = lightpath()
        .args([
            "lpe",
            "check",
            "C<RD>[<L.>O]",
            "lpe:unoccluded;directDiffuse",
        ])
        .output()
        .unwrap();
    assert!(ok.status.success());
    let bad = lightpath()
        .args(["lpe", "check", "unocluded;C<RD>L"])
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(1));
    let err = String::from_utf8(bad.stderr).unwrap();
    assert!(err.contains("unocluded;C<RD>L\n  | ^^^^^^^^^\n"), "{err}");
    assert!(err.contains("did you mean 'unoccluded'?"), "{err}");
    let warn = lightpath()
        .args(["lpe", "check", "C<B>L"])
        .output()
        .unwrap();
    assert!(warn.status.success());
    assert!(String::from_utf8(warn.stderr)
        .unwrap()
        .contains("never emits"));
}

#[test]
fn match_prints_one_line_per_definition() {
    let out = lightpath()
        .args([
            "lpe",
            "match",
            "C<RD>[<L.>O]",
            "C<RS>L",
            "--path",
            "C<RD'floor'><L'key'>",
        ])
        .output()
        .unwrap();
    assert!(out.status.success());
    assert_eq!(String::from_utf8(out.stdout).unwrap(), "match\nno match\n");
    let bad = lightpath()
        .args(["lpe", "match", "C<RD", "--path", "CL"])
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(1));
}

#[test]
fn explain_and_names_describe_the_language() {
    let out = lightpath()
        .args(["lpe", "explain", "C<RD>[<L.>O]", "lpe:albedo"])
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("the camera") && text.contains("DFA states before minimisation"),
        "{text}"
    );
    assert!(text.contains("nothruput"), "{text}");
    let names =
        String::from_utf8(lightpath().args(["lpe", "names"]).output().unwrap().stdout).unwrap();
    assert!(names.contains("directDiffuse") && names.contains("C<RD>[<L.>O]"));
}

#[test]
fn render_writes_exr_and_png_and_reports_speed() {
    let dir = Scratch::new("cli");
    let out = succeed(
        lightpath()
            .args([
                "render",
                "cornell",
                "--quiet",
                "--spp",
                "2",
                "--resolution",
                "24x16",
                "-o",
            ])
            .arg(dir.join("shot.exr")),
    );
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("samples/s") && text.contains("rays/s"),
        "{text}"
    );
    let exr = lightpath::output::read_exr(&dir.join("shot.exr")).unwrap();
    assert_eq!((exr.width, exr.height), (24, 16));
    assert!(exr.channel("directDiffuse.R").is_some() && exr.channel("A").is_some());
    assert!(dir.join("shot.png").exists());
    let bad = refuse(lightpath().args(["render", "no/such/scene.toml", "--quiet"]));
    assert!(bad.contains("no/such/scene.toml"));
}

/// Same scene, same options: the same bytes, whatever the thread count (a farm compares
/// outputs by checksum).
#[test]
fn renders_are_byte_identical() {
    let dir = Scratch::new("bytes");
    let files: Vec<Vec<u8>> = ["1", "2", "2"]
        .iter()
        .enumerate()
        .map(|(i, threads)| {
            let path = dir.join(&format!("shot{i}.exr"));
            succeed(
                lightpath()
                    .args(["render", "cornell", "--quiet", "--spp", "2"])
                    .args([
                        "--resolution",
                        "20x12",
                        "--light-groups",
                        "--threads",
                        threads,
                    ])
                    .arg("-o")
                    .arg(&path),
            );
            std::fs::read(&path).unwrap()
        })
        .collect();
    assert!(files[0] == files[1] && files[1] == files[2]);
    // The rewritten header still reads back, definitions and all.
    let exr = lightpath::output::read_exr(&dir.join("shot0.exr")).unwrap();
    assert!(exr.aovs().len() > 10);
    assert!(exr.channel("beauty_key.R").is_some());
}

#[test]
fn aovs_checks_partitions_and_comp_relights() {
    let dir = Scratch::new("comp");
    let exr = dir.join("c.exr");
    succeed(
        lightpath()
            .args([
                "render",
                "cornell",
                "--quiet",
                "--spp",
                "2",
                "--resolution",
                "16x16",
                "--light-groups",
                "--bounces",
                "2",
                "-o",
            ])
            .arg(&exr),
    );
    let report = lightpath().arg("aovs").arg(&exr).output().unwrap();
    let text = String::from_utf8(report.stdout).unwrap();
    assert!(report.status.success(), "{text}");
    assert!(
        text.contains("directDiffuse") && text.contains("lpe:directDiffuse"),
        "{text}"
    );
    assert_eq!(
        text.matches("ok   beauty =").count(),
        3,
        "standard set, light groups, bounces:\n{text}"
    );

    // comp: gains over the light-group split equal the explicit sum.
    let by_gain = dir.join("g.exr");
    let by_sum = dir.join("s.exr");
    let relit = lightpath()
        .arg("comp")
        .arg(&exr)
        .args(["--gain", "key=2", "-o"])
        .arg(&by_gain)
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&relit.stderr);
    assert!(relit.status.success(), "{said}");
    // The built-in cornell clamps indirect light and picks lights by the tree: comp says
    // that relighting it is not a re-render.
    assert!(
        said.contains("note:") && said.contains("clamp_indirect") && said.contains("tree"),
        "{said}"
    );
    assert!(lightpath()
        .arg("comp")
        .arg(&exr)
        .args(["beauty + beauty_key", "-o"])
        .arg(&by_sum)
        .status()
        .unwrap()
        .success());
    let (g, s) = (
        lightpath::output::read_exr(&by_gain).unwrap(),
        lightpath::output::read_exr(&by_sum).unwrap(),
    );
    assert_eq!(g.channel("R").unwrap(), s.channel("R").unwrap());
    assert!(dir.join("g.png").exists());

    // A file whose parts do not add up fails the check.
    let src = lightpath::output::read_exr(&exr).unwrap();
    let mut channels = src.channels.clone();
    for (name, values) in &mut channels {
        if name == "directDiffuse.R" {
            values.iter_mut().for_each(|v| *v *= 2.0);
        }
    }
    let bad = dir.join("bad.exr");
    lightpath::output::write_channels(
        &bad,
        src.width,
        src.height,
        channels,
        &src.attributes,
        lightpath::output::ExrOptions {
            half: false,
            compression: lightpath::output::ExrCompression::Piz,
        },
    )
    .unwrap();
    let report = lightpath().arg("aovs").arg(&bad).output().unwrap();
    assert_eq!(report.status.code(), Some(1));
    assert!(String::from_utf8(report.stdout)
        .unwrap()
        .contains("FAIL beauty = emission + directDiffuse"));

    let missing = refuse(
        lightpath()
            .arg("comp")
            .arg(&exr)
            .args(["beauty + nothere", "-o"])
            .arg(dir.join("x.exr")),
    );
    assert!(missing.contains("no AOV 'nothere'"));
}

#[test]
fn sample_ranges_rendered_apart_merge_into_the_whole_frame() {
    let dir = Scratch::new("merge");
    let render = |first: u32, spp: u32, name: &str| {
        succeed(
            lightpath()
                .args([
                    "render",
                    "cornell",
                    "--quiet",
                    "--resolution",
                    "12x10",
                    "--spp",
                    &spp.to_string(),
                    "--first-sample",
                    &first.to_string(),
                    "-o",
                ])
                .arg(dir.join(name)),
        );
    };
    render(0, 4, "whole.exr");
    render(0, 1, "a.exr");
    render(1, 3, "b.exr");
    let merged = dir.join("merged.exr");
    succeed(
        lightpath()
            .arg("merge")
            .arg(dir.join("a.exr"))
            .arg(dir.join("b.exr"))
            .arg("-o")
            .arg(&merged),
    );
    let (whole, merged) = (
        lightpath::output::read_exr(&dir.join("whole.exr")).unwrap(),
        lightpath::output::read_exr(&merged).unwrap(),
    );
    for (name, values) in &whole.channels {
        let m = merged.channel(name).unwrap();
        for (a, b) in values.iter().zip(m) {
            assert!(
                (a - b).abs() <= 1e-5 * a.abs().max(1.0),
                "{name}: {a} vs {b}"
            );
        }
    }
    assert!(merged
        .attributes
        .contains(&("lightpath/spp".to_string(), "4".to_string())));
    // The same range twice would count its samples twice.
    refuse(
        lightpath()
            .arg("merge")
            .arg(dir.join("a.exr"))
            .arg(dir.join("a.exr"))
            .arg("-o")
            .arg(dir.join("x.exr")),
    );
}

#[test]
fn a_scene_can_ask_for_light_group_splits() {
    let dir = Scratch::new("lg");
    let scene = format!(
        "light_groups = true\nlight_group_aovs = [\"directDiffuse\"]\n{}",
        include_str!("../../../../scenes/cornell.toml")
    );
    std::fs::write(dir.join("s.toml"), scene).unwrap();
    succeed(
        lightpath()
            .arg("render")
            .arg(dir.join("s.toml"))
            .args(["--quiet", "--spp", "1", "--resolution", "8x8", "-o"])
            .arg(dir.join("s.exr")),
    );
    let exr = lightpath::output::read_exr(&dir.join("s.exr")).unwrap();
    for name in [
        "beauty_key.R",
        "beauty_fill.R",
        "beauty__default.R",
        "directDiffuse_key.R",
        "directDiffuse__default.R",
    ] {
        assert!(exr.channel(name).is_some(), "missing {name}");
    }
}

#[test]
fn comp_and_aovs_read_parts_from_structured_attributes_not_prose() {
    let dir = Scratch::new("prose");
    let exr = dir.join("c.exr");
    succeed(
        lightpath()
            .args([
                "render",
                "cornell",
                "--quiet",
                "--spp",
                "2",
                "--resolution",
                "8x8",
                "--light-groups",
                "--bounces",
                "2",
                "-o",
            ])
            .arg(&exr),
    );
    // Every definition becomes prose that names no group and no partition.
    let src = lightpath::output::read_exr(&exr).unwrap();
    let attributes: Vec<(String, String)> = src
        .attributes
        .iter()
        .map(
            |(k, v)| match k.strip_prefix(lightpath::output::AOV_ATTRIBUTE_PREFIX) {
                Some(_) => (k.clone(), "some words a user wrote".to_string()),
                None => (k.clone(), v.clone()),
            },
        )
        .collect();
    assert!(attributes
        .iter()
        .any(|(k, v)| k == "lightpath/lightgroup/beauty_key" && v == "key"));
    let prose = dir.join("prose.exr");
    lightpath::output::write_channels(
        &prose,
        src.width,
        src.height,
        src.channels.clone(),
        &attributes,
        Default::default(),
    )
    .unwrap();
    let report = succeed(lightpath().arg("aovs").arg(&prose));
    let text = String::from_utf8(report.stdout).unwrap();
    assert_eq!(text.matches("ok   beauty =").count(), 3, "{text}");
    assert!(
        text.contains("beauty = beauty_fill + beauty_key + beauty__default"),
        "{text}"
    );

    let (by_gain, by_sum) = (dir.join("g.exr"), dir.join("s.exr"));
    succeed(
        lightpath()
            .arg("comp")
            .arg(&prose)
            .args(["--gain", "key=2", "--gain", "_default=0.5", "-o"])
            .arg(&by_gain),
    );
    succeed(
        lightpath()
            .arg("comp")
            .arg(&prose)
            .args(["beauty + beauty_key - 0.5*beauty__default", "-o"])
            .arg(&by_sum),
    );
    let (g, s) = (
        lightpath::output::read_exr(&by_gain).unwrap(),
        lightpath::output::read_exr(&by_sum).unwrap(),
    );
    assert_eq!(g.channel("G").unwrap(), s.channel("G").unwrap());

    // Without the structured attributes, a gain has no part to find.
    let bare: Vec<(String, String)> = attributes
        .into_iter()
        .filter(|(k, _)| !k.starts_with("lightpath/part/"))
        .collect();
    let stripped = dir.join("stripped.exr");
    lightpath::output::write_channels(
        &stripped,
        src.width,
        src.height,
        src.channels,
        &bare,
        Default::default(),
    )
    .unwrap();
    let refused = refuse(
        lightpath()
            .arg("comp")
            .arg(&stripped)
            .args(["--gain", "key=2", "-o"])
            .arg(dir.join("x.exr")),
    );
    assert!(
        refused.contains("no light-group part of 'beauty'"),
        "{refused}"
    );
}

#[cfg(not(feature = "denoise"))]
#[test]
fn a_build_without_denoising_says_how_to_get_it() {
    let dir = Scratch::new("nodenoise");
    let err = refuse(
        lightpath()
            .args(["denoise", "in.exr", "-o"])
            .arg(dir.join("o.exr")),
    );
    assert!(err.contains("--features denoise"), "{err}");
    assert!(
        err.contains("pip install --no-deps pyoidn==2.5.1.0"),
        "{err}"
    );
    assert!(err.contains("OIDN_DIR"), "{err}");
    // `render --denoise` refuses before rendering: nothing is written.
    let out = dir.join("r.exr");
    let err = refuse(
        lightpath()
            .args([
                "render",
                "cornell-classic",
                "--spp",
                "1",
                "--resolution",
                "8x8",
            ])
            .args(["--denoise", "-q", "-o"])
            .arg(&out),
    );
    assert!(err.contains("--features denoise"), "{err}");
    assert!(!out.exists());
}

#[cfg(feature = "denoise")]
#[test]
fn render_denoise_in_one_step_keeps_partitions_and_relighting() {
    let dir = Scratch::new("denoise");
    let out = dir.join("d.exr");
    let stdout = succeed(
        lightpath()
            .args([
                "render",
                "cornell-classic",
                "--spp",
                "4",
                "--resolution",
                "32x32",
            ])
            .args([
                "--light-groups",
                "--bounces",
                "2",
                "--denoise",
                "--keep-noisy",
                "-q",
            ])
            .arg("-o")
            .arg(&out),
    )
    .stdout;
    let stdout = String::from_utf8(stdout).unwrap();
    assert!(stdout.contains("denoised"), "{stdout}");
    let aovs = succeed(lightpath().arg("aovs").arg(&out)).stdout;
    let aovs = String::from_utf8(aovs).unwrap();
    assert_eq!(aovs.matches("ok  ").count(), 3, "{aovs}");
    assert!(aovs.contains("beauty_noisy"), "{aovs}");
    // Rebuilding the beauty from the denoised light groups in comp gives the denoised
    // beauty (to float rounding).
    let relit = dir.join("relit.exr");
    succeed(
        lightpath()
            .arg("comp")
            .arg(&out)
            .args(["beauty_light + beauty__default", "-o"])
            .arg(&relit),
    );
    let (a, b) = (
        lightpath::output::read_exr(&out).unwrap(),
        lightpath::output::read_exr(&relit).unwrap(),
    );
    for (x, y) in a.channel("G").unwrap().iter().zip(b.channel("G").unwrap()) {
        assert!((x - y).abs() <= 1e-5 * x.abs().max(1e-3), "{x} vs {y}");
    }
    // A denoised file is not denoised again.
    let err = refuse(
        lightpath()
            .arg("denoise")
            .arg(&out)
            .arg("-o")
            .arg(dir.join("again.exr")),
    );
    assert!(err.contains("already denoised"), "{err}");
}
