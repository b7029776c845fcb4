//! Every `lightpath …` command line in README.md and docs/*.md runs: the docs are the first
//! thing a newcomer copies (issue 25). Each ```sh block runs in its own scratch directory, in
//! order, so later lines find the files earlier ones wrote; renders are shrunk (resolution and
//! crops ÷10, sample counts ÷16) so the whole test stays short.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::Scratch;

/// Lines not run, each with why.
fn skip_reason(line: &str) -> Option<&'static str> {
    let words: Vec<&str> = line.split_whitespace().collect();
    if words.get(1) == Some(&"view") {
        return Some("`view` is a server that runs until stopped (tests/it/view.rs covers it)");
    }
    if words.contains(&"--preview") {
        return Some("`--preview` serves a page until the render ends and opens a browser");
    }
    let denoises = words.get(1) == Some(&"denoise") || words.contains(&"--denoise");
    if denoises && !cfg!(feature = "denoise") {
        return Some("built without the `denoise` feature");
    }
    None
}

/// `line` without its trailing shell comment (two or more spaces, then `#`).
fn strip_comment(line: &str) -> &str {
    match line.find("  #") {
        Some(i) => line[..i].trim_end(),
        None => line.trim_end(),
    }
}

fn scale(value: &str, by: u32, min: u32) -> String {
    value
        .split([',', 'x'])
        .map(|n| {
            n.parse::<u32>()
                .map(|n| (n / by).max(min).to_string())
                .unwrap_or(n.to_string())
        })
        .collect::<Vec<_>>()
        .join(if value.contains(',') { "," } else { "x" })
}

/// The command shrunk: resolutions and crops ÷10 (the built-in scenes are 320² by default),
/// sample counts and first samples ÷16, so that splits by samples or tiles still tile.
fn shrink(line: &str) -> String {
    let words: Vec<&str> = line.split(' ').collect();
    let render = words.get(1) == Some(&"render") || words.get(1) == Some(&"farm");
    if !render {
        return line.to_string();
    }
    let mut out = Vec::new();
    let mut has_resolution = false;
    let mut i = 0;
    while i < words.len() {
        let w = words[i];
        out.push(w.to_string());
        let next = words.get(i + 1);
        match (w, next) {
            ("--resolution", Some(v)) | ("--crop", Some(v)) => {
                has_resolution |= w == "--resolution";
                // A crop's corners may be 0; a resolution may not.
                out.push(scale(v, 10, has_resolution as u32));
                i += 1;
            }
            ("--spp", Some(v)) | ("--first-sample", Some(v)) | ("--min-spp", Some(v)) => {
                let n: u32 = v.parse().unwrap_or(16);
                out.push(
                    if w == "--first-sample" {
                        n / 16
                    } else {
                        (n / 16).max(1)
                    }
                    .to_string(),
                );
                i += 1;
            }
            _ => {}
        }
        i += 1;
    }
    if words[1] == "render" {
        if !has_resolution {
            out.insert(2, "--resolution 32x32".into());
        }
        if !words.contains(&"--spp") {
            out.insert(2, "--spp 2".into());
        }
        out.insert(2, "--quiet".into());
    }
    out.join(" ")
}

/// The ```sh blocks of `file`, each a list of lines.
fn sh_blocks(file: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(file).unwrap();
    let mut blocks = Vec::new();
    let mut current: Option<Vec<String>> = None;
    for line in text.lines() {
        let t = line.trim();
        match (&mut current, t) {
            (None, "```sh") => current = Some(Vec::new()),
            (Some(_), "```") => blocks.push(current.take().unwrap()),
            (Some(b), _) => b.push(t.to_string()),
            _ => {}
        }
    }
    blocks
}

#[test]
fn every_command_in_the_docs_runs() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let bin = PathBuf::from(env!("CARGO_BIN_EXE_lightpath"));
    let path = format!(
        "{}:{}",
        bin.parent().unwrap().display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let mut files = vec![root.join("README.md")];
    let mut docs: Vec<PathBuf> = std::fs::read_dir(root.join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    files.extend(docs);
    let (mut ran, mut failures, mut skipped) = (0, Vec::new(), Vec::new());
    for file in &files {
        for block in sh_blocks(file) {
            let dir = Scratch::new("docs");
            for tree in ["scenes", "crates"] {
                std::os::unix::fs::symlink(root.join(tree), dir.join(tree)).unwrap();
            }
            let mut after_skip = None;
            for line in &block {
                let line = strip_comment(line);
                // The docs' own shell lines that make inputs (`sed … > x.toml`) run as well.
                let makes_input = line.starts_with("sed ") || line.starts_with("cat ");
                if !line.starts_with("lightpath ") && !makes_input {
                    continue;
                }
                // A skipped line's outputs are missing for the lines after it in its block.
                if let Some(why) = skip_reason(line).or(after_skip) {
                    skipped.push(format!("{line}: {why}"));
                    after_skip = Some("follows a skipped line in its block");
                    continue;
                }
                let cmd = shrink(line);
                let out = Command::new("sh")
                    .arg("-c")
                    .arg(&cmd)
                    .current_dir(&dir.0)
                    .env("PATH", &path)
                    .output()
                    .unwrap();
                ran += 1;
                if !out.status.success() {
                    failures.push(format!(
                        "{}: {cmd}\n{}",
                        file.display(),
                        String::from_utf8_lossy(&out.stderr)
                    ));
                }
            }
        }
    }
    eprintln!("ran {ran} docs lines; skipped:\n{}", skipped.join("\n"));
    assert!(ran > 30, "only {ran} docs lines found");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
