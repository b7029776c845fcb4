//! The render settings through the binary: every option of the settings table refuses
//! what a scene file refuses, with the same message (the library's
//! `settings::tests` check valid values and defaults both ways).

use crate::common::Scratch;
use lightpath::settings::{Range, SETTINGS};
use std::process::Command;

fn lightpath() -> Command {
    Command::new(env!("CARGO_BIN_EXE_lightpath"))
}

/// Runs a render that must fail; returns its stderr.
fn refused(args: &[&str], scratch: &Scratch) -> String {
    let out = lightpath()
        .arg("render")
        .args(args)
        .arg("-o")
        .arg(scratch.join("out.exr"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(!out.status.success(), "{args:?} rendered: {stderr}");
    assert!(!scratch.join("out.exr").exists(), "{args:?} wrote an image");
    stderr
}

/// A value outside a setting's range, as a flag and as TOML write it: from the range
/// itself, so a new setting is walked without editing this test.
fn out_of_range(value_name: &str, range: Range) -> (String, String) {
    let n = match range {
        Range::Between(_, hi) => hi + 1.0,
        Range::AtLeast(lo) => lo - 1.0,
        Range::Above(lo) => lo,
        // Any number of its type: a negative one is not of an unsigned type.
        Range::Any => -1.0,
    };
    match value_name {
        "WxH" => (format!("{n}x{n}"), format!("[{n}, {n}]")),
        "NAME" => ("none-such".into(), "\"none-such\"".into()),
        _ => (n.to_string(), n.to_string()),
    }
}

#[test]
fn every_flag_refuses_what_the_scene_file_refuses_with_the_same_message() {
    let scratch = Scratch::new("settings-refused");
    for s in SETTINGS {
        let (flag_value, toml_value) = out_of_range(s.value_name, s.range);
        let flag = format!("--{}", s.flag);
        let from_flag = refused(&[&flag, &flag_value], &scratch);
        // clap: "invalid value 'V' for '--flag <N>': MESSAGE".
        let message = from_flag
            .lines()
            .next()
            .and_then(|l| l.split_once(">': "))
            .map(|(_, m)| m.to_string())
            .unwrap_or_else(|| panic!("{flag} {flag_value}: {from_flag}"));
        assert!(message.contains(s.key), "{message}");
        let scene = scratch.join("scene.toml");
        let text = format!("[{}]\n{} = {toml_value}\n", s.section.name(), s.key);
        std::fs::write(&scene, text).unwrap();
        let from_toml = refused(&[scene.to_str().unwrap()], &scratch);
        assert!(
            from_toml.contains(":2:") && from_toml.contains(&message),
            "{} = {toml_value}: '{from_toml}' does not say '{message}'",
            s.key
        );
    }
}

#[test]
fn regularize_5_and_max_depth_0_are_errors() {
    let scratch = Scratch::new("settings-issue");
    let e = refused(&["--regularize", "5"], &scratch);
    assert!(
        e.contains("regularize must be between 0 and 1, got 5"),
        "{e}"
    );
    let e = refused(&["--max-depth", "0"], &scratch);
    assert!(e.contains("max_depth must be at least 1, got 0"), "{e}");
    let e = refused(&["--clamp-indirect", "-1"], &scratch);
    assert!(
        e.contains("clamp_indirect must be at least 0, got -1"),
        "{e}"
    );
}

#[test]
fn min_spp_above_spp_is_refused_from_flags_and_from_the_scene() {
    let scratch = Scratch::new("settings-pilot");
    let e = refused(&["--spp", "8", "--min-spp", "16"], &scratch);
    assert!(e.contains("min_spp (16) is above spp (8)"), "{e}");
    // The scene's spp with the command line's pilot.
    let scene = scratch.join("scene.toml");
    std::fs::write(&scene, "[render]\nspp = 4\n").unwrap();
    let e = refused(&[scene.to_str().unwrap(), "--min-spp", "5"], &scratch);
    assert!(e.contains("min_spp (5) is above spp (4)"), "{e}");
    std::fs::write(&scene, "[render]\nspp = 4\nmin_spp = 5\n").unwrap();
    let e = refused(&[scene.to_str().unwrap()], &scratch);
    assert!(e.contains("min_spp (5) is above spp (4)"), "{e}");
}

#[test]
fn the_default_pilot_fits_any_spp() {
    let scratch = Scratch::new("settings-default-pilot");
    let out = scratch.join("small.exr");
    let status = lightpath()
        .args([
            "render",
            "--spp",
            "2",
            "--noise-threshold",
            "0.1",
            "--resolution",
            "4x4",
        ])
        .arg("-q")
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
}
