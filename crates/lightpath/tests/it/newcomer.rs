//! What a newcomer trips on, as the binary answers it: frame-numbered previews, AOV
//! definitions checked, the renderer's own standard names, typos answered with a guess.

use std::process::Command;

use crate::common::Scratch;

fn lightpath() -> Command {
    Command::new(env!("CARGO_BIN_EXE_lightpath"))
}

/// A tiny render of the built-in Cornell box with `extra` arguments, output `out`.
fn render(out: &std::path::Path, extra: &[&str]) -> std::process::Output {
    lightpath()
        .args([
            "render",
            "cornell",
            "--quiet",
            "--spp",
            "2",
            "--resolution",
            "12x8",
        ])
        .args(extra)
        .arg("-o")
        .arg(out)
        .output()
        .unwrap()
}

fn stderr(out: &std::process::Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn frame_numbered_outputs_keep_their_own_previews() {
    let dir = Scratch::new("frames");
    for frame in ["shot.0001.exr", "shot.0002.exr"] {
        let out = render(&dir.join(frame), &["--aovs", "none"]);
        assert!(out.status.success(), "{}", stderr(&out));
    }
    for png in ["shot.0001.png", "shot.0002.png"] {
        assert!(dir.join(png).exists(), "{png} is missing");
    }
    assert!(!dir.join("shot.png").exists());
    // comp names its preview the same way.
    let comp = lightpath()
        .arg("comp")
        .arg(dir.join("shot.0001.exr"))
        .arg("-o")
        .arg(dir.join("relit.0001.exr"))
        .output()
        .unwrap();
    assert!(comp.status.success(), "{}", stderr(&comp));
    assert!(dir.join("relit.0001.png").exists());
}

#[test]
fn two_aovs_of_one_name_are_refused() {
    let dir = Scratch::new("duplicate-aov");
    let out = render(
        &dir.join("d.exr"),
        &["--aov", "key=C<RD>L", "--aov", "key=C<RS>L"],
    );
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("--aov key is given twice"),
        "{}",
        stderr(&out)
    );
    assert!(!dir.join("d.exr").exists());
}

#[test]
fn a_redefined_standard_name_is_the_users_and_leaves_the_standard_partition() {
    let dir = Scratch::new("redefined-aov");
    let exr = dir.join("r.exr");
    let out = render(&exr, &["--aov", "directDiffuse=C<RD>L"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let file = lightpath::output::read_exr(&exr).unwrap();
    let attribute = |k: &str| {
        file.attributes
            .iter()
            .find(|(n, _)| n == k)
            .map(|(_, v)| v.clone())
    };
    assert_eq!(
        attribute("lightpath/aov/directDiffuse").as_deref(),
        Some("C<RD>L")
    );
    assert_eq!(attribute("lightpath/partition/directDiffuse"), None);
    assert_eq!(attribute("lightpath/partition/indirectDiffuse"), None);
    // The header claims only partitions that hold, so the checker passes.
    let aovs = lightpath().arg("aovs").arg(&exr).output().unwrap();
    assert!(
        aovs.status.success(),
        "{}",
        String::from_utf8_lossy(&aovs.stdout)
    );
    // With the standard definitions the standard partition is declared and holds.
    let plain = dir.join("p.exr");
    assert!(render(&plain, &[]).status.success());
    let file = lightpath::output::read_exr(&plain).unwrap();
    assert!(file
        .attributes
        .iter()
        .any(|(k, v)| k == "lightpath/partition/directDiffuse" && v == "standard"));
}

#[test]
fn the_renderers_own_standard_names_are_definitions_too() {
    let dir = Scratch::new("data-names");
    let exr = dir.join("n.exr");
    let out = render(
        &exr,
        &[
            "--aovs",
            "none",
            "--aov",
            "n=lpe:normal",
            "--aov",
            "z=lpe:depth",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let file = lightpath::output::read_exr(&exr).unwrap();
    let n = file.channel("n.G").unwrap();
    let z = file.channel("z.R").unwrap();
    assert!(n.iter().all(|v| (-1.0..=1.0).contains(v)) && n.iter().any(|v| *v != 0.0));
    assert!(z.iter().all(|v| *v >= 0.0) && z.iter().any(|v| *v > 0.0));
    let check = lightpath()
        .args(["lpe", "check", "lpe:normal", "lpe:depth"])
        .output()
        .unwrap();
    assert!(check.status.success(), "{}", stderr(&check));
}

#[test]
fn typos_are_answered_with_a_guess() {
    let out = lightpath()
        .args(["render", "cornel", "--quiet"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("did you mean 'cornell'?"),
        "{}",
        stderr(&out)
    );
    let dir = Scratch::new("typos");
    let out = render(&dir.join("t.exr"), &["--variance", "directDifuse"]);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("did you mean 'directDiffuse'?"),
        "{}",
        stderr(&out)
    );
    let exr = dir.join("g.exr");
    assert!(render(&exr, &["--light-groups"]).status.success());
    for spelling in ["__default", "_default"] {
        let comp = lightpath()
            .arg("comp")
            .arg(&exr)
            .args(["--gain", &format!("{spelling}=0.5"), "-o"])
            .arg(dir.join(&format!("c{spelling}.exr")))
            .output()
            .unwrap();
        assert!(comp.status.success(), "{spelling}: {}", stderr(&comp));
    }
}

#[test]
fn no_output_replaces_a_file_the_scene_reads() {
    let dir = Scratch::new("inputs-kept");
    let texture = dir.join("wood.png");
    let texels = [vec![0.5f32; 4], vec![0.3; 4], vec![0.1; 4]];
    lightpath::output::write_png_rgb(&texture, 2, 2, &texels, 0.0).unwrap();
    let before = std::fs::read(&texture).unwrap();
    let scene = include_str!("../../../../scenes/cornell-classic.toml").replacen(
        "[materials.white]\ntype = \"diffuse\"",
        "[materials.white]\ntype = \"diffuse\"\ncolor_texture = \"wood.png\"",
        1,
    );
    assert!(scene.contains("wood.png"));
    std::fs::write(dir.join("scene.toml"), scene).unwrap();
    // -o wood.exr would write its preview over the texture wood.png.
    let out = lightpath()
        .arg("render")
        .arg(dir.join("scene.toml"))
        .args(["--quiet", "--spp", "1", "--resolution", "8x8", "-o"])
        .arg(dir.join("wood.exr"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(stderr(&out).contains("wood.png"), "{}", stderr(&out));
    assert_eq!(std::fs::read(&texture).unwrap(), before);
    assert!(!dir.join("wood.exr").exists());
    // Any other name renders, reading the texture.
    let out = lightpath()
        .arg("render")
        .arg(dir.join("scene.toml"))
        .args(["--quiet", "--spp", "1", "--resolution", "8x8", "-o"])
        .arg(dir.join("shot.exr"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
}
