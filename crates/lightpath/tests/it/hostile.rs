//! Reproducers of hostile input (`tests/hostile/`): every one must end in a clear error, a
//! warning or a right result — never a panic, an abort or a hang — with the address space
//! capped at 4 GB, as the issue's "done when" asks.
//!
//! Each `*.toml` there is a scene whose first line says what to expect (`# expect error:
//! TEXT`, `# expect warning: TEXT`, `# expect stdout: TEXT`, `# expect ok`); `cases.txt`
//! holds command lines with their expectations.

use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn hostile_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/hostile")
}

/// A scratch copy of `tests/hostile`, removed at the end.
struct Scratch(PathBuf);

impl Scratch {
    fn new(tag: &str) -> Scratch {
        let dir =
            std::env::temp_dir().join(format!("lightpath-hostile-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        for e in std::fs::read_dir(hostile_dir()).unwrap() {
            let e = e.unwrap();
            std::fs::copy(e.path(), dir.join(e.file_name())).unwrap();
        }
        Scratch(dir)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The binary with its address space capped at 4 GB.
fn lightpath() -> Command {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_lightpath"));
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::process::CommandExt;
        // SAFETY: setrlimit is async-signal-safe and touches only the child's limits.
        unsafe {
            cmd.pre_exec(|| {
                let cap = libc::rlimit {
                    rlim_cur: 4 << 30,
                    rlim_max: 4 << 30,
                };
                libc::setrlimit(libc::RLIMIT_AS, &cap);
                Ok(())
            });
        }
    }
    cmd
}

struct Outcome {
    code: Option<i32>,
    stdout: String,
    stderr: String,
}

/// Runs with a time limit: a hang is a failure, not a stuck test.
fn run(mut cmd: Command, what: &str) -> Outcome {
    let mut child = cmd
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            break;
        }
        if start.elapsed() > Duration::from_secs(120) {
            let _ = child.kill();
            panic!("{what}: still running after 120 s");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().unwrap();
    Outcome {
        code: out.status.code(),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

/// Checks an outcome against `error: TEXT`, `warning: TEXT`, `stdout: TEXT` or `ok`.
fn check(expect: &str, out: &Outcome, what: &str) {
    let shown = format!(
        "{what}: expected {expect}\nexit {:?}\nstdout: {}\nstderr: {}",
        out.code, out.stdout, out.stderr
    );
    // Exit 0, 1 or 2 (a usage error): never a panic (101), an abort or a signal (None).
    assert!(matches!(out.code, Some(0..=2)), "{shown}");
    assert!(!out.stderr.contains("panicked"), "{shown}");
    let (kind, text) = expect.split_once(':').unwrap_or((expect, ""));
    let text = text.trim();
    match kind.trim() {
        "error" => {
            assert!(matches!(out.code, Some(1 | 2)), "{shown}");
            assert!(
                out.stderr.contains("error") && out.stderr.contains(text),
                "{shown}"
            );
        }
        "warning" => {
            assert_eq!(out.code, Some(0), "{shown}");
            assert!(
                out.stderr.contains("warning: ") && out.stderr.contains(text),
                "{shown}"
            );
        }
        "stdout" => {
            assert_eq!(out.code, Some(0), "{shown}");
            assert!(out.stdout.contains(text), "{shown}");
        }
        "ok" => assert_eq!(out.code, Some(0), "{shown}"),
        other => panic!("{what}: unknown expectation '{other}'"),
    }
}

#[test]
fn every_hostile_scene_errors_warns_or_renders() {
    let scratch = Scratch::new("scenes");
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(&scratch.0)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    scenes.sort();
    assert!(scenes.len() >= 20, "{} scenes", scenes.len());
    for scene in &scenes {
        let text = std::fs::read(scene).unwrap();
        let first =
            String::from_utf8_lossy(text.split(|&b| b == b'\n').next().unwrap()).into_owned();
        let expect = first
            .strip_prefix("# expect")
            .unwrap_or_else(|| panic!("{}: first line must say '# expect …'", scene.display()))
            .trim();
        let mut cmd = lightpath();
        cmd.arg("render")
            .arg(scene)
            .arg("-o")
            .arg(scratch.0.join("out.exr"))
            .args(["--resolution", "8x8", "-q"]);
        // The scenes that set their own resolution and spp are the ones testing them.
        if first.contains("LIGHTPATH_MAX_PIXELS") || first.contains("LIGHTPATH_MAX_SAMPLES") {
            cmd = lightpath();
            cmd.arg("render")
                .arg(scene)
                .arg("-o")
                .arg(scratch.0.join("out.exr"))
                .arg("-q");
        }
        let out = run(cmd, &scene.display().to_string());
        check(expect, &out, &scene.display().to_string());
        if expect.starts_with("error") {
            // The error names the scene file (or the file it refers to).
            assert!(
                out.stderr.contains(".toml") || out.stderr.contains(".obj"),
                "{}",
                out.stderr
            );
        }
    }
}

#[test]
fn every_hostile_command_line_errors_or_runs() {
    let scratch = Scratch::new("cases");
    std::fs::create_dir_all(scratch.0.join("adir.exr")).unwrap();
    let deep = format!("C{}L{}", "(".repeat(9000), ")".repeat(9000));
    let cases = std::fs::read_to_string(hostile_dir().join("cases.txt")).unwrap();
    let mut n = 0;
    for line in cases
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
    {
        let fields: Vec<&str> = line.split(" | ").collect();
        let (expect, env, args) = match fields.as_slice() {
            [e, a] => (*e, None, *a),
            [e, env, a] => (*e, env.strip_prefix("env "), *a),
            _ => panic!("bad case line: {line}"),
        };
        let mut cmd = lightpath();
        if let Some((k, v)) = env.and_then(|e| e.split_once('=')) {
            cmd.env(k, v);
        }
        for a in args.split_whitespace() {
            cmd.arg(
                a.replace("{dir}", &scratch.0.display().to_string())
                    .replace("{deep}", &deep),
            );
        }
        let out = run(cmd, line);
        check(expect, &out, line);
        n += 1;
    }
    assert!(n >= 15);
}

#[test]
#[cfg(unix)]
fn a_symlink_or_a_pipe_as_output_is_refused_and_left_alone() {
    let scratch = Scratch::new("links");
    let target = scratch.0.join("precious.txt");
    std::fs::write(&target, "keep me").unwrap();
    let link = scratch.0.join("link.exr");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    let fifo = scratch.0.join("fifo.exr");
    let name = std::ffi::CString::new(fifo.display().to_string()).unwrap();
    // SAFETY: a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(name.as_ptr(), 0o644) }, 0);
    for out in [link.as_path(), fifo.as_path()] {
        let mut cmd = lightpath();
        cmd.args([
            "render",
            "cornell",
            "--spp",
            "1",
            "--resolution",
            "4x4",
            "-q",
            "-o",
        ])
        .arg(out);
        let o = run(cmd, &out.display().to_string());
        check(
            "error: outputs replace regular files only",
            &o,
            "symlink/device output",
        );
    }
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "keep me");
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
}

/// An EXR of one AOV with the header of a Lightpath render.
fn write_exr(path: &Path, value: f32, spp: &str) {
    let channels = ["R", "G", "B"]
        .map(|c| (c.to_string(), vec![value; 4]))
        .to_vec();
    let attributes = vec![
        ("lightpath/aov/beauty".to_string(), "lpe:beauty".to_string()),
        ("lightpath/spp".to_string(), spp.to_string()),
    ];
    lightpath::output::write_channels(path, 2, 2, channels, &attributes, Default::default())
        .unwrap();
}

#[test]
fn merging_zero_or_overflowing_sample_counts_is_an_error_not_nan() {
    let scratch = Scratch::new("merge");
    let (a, b) = (scratch.0.join("a.exr"), scratch.0.join("b.exr"));
    for (spp, expect) in [
        ("0", "expected a sample count"),
        ("18446744073709551616", "expected a sample count"),
        ("-3", "expected a sample count"),
    ] {
        write_exr(&a, 1.0, "4");
        write_exr(&b, 1.0, spp);
        let mut cmd = lightpath();
        cmd.arg("merge")
            .arg(&a)
            .arg(&b)
            .arg("-o")
            .arg(scratch.0.join("m.exr"));
        let out = run(cmd, spp);
        check(&format!("error: {expect}"), &out, spp);
    }
    let mut cmd = lightpath();
    cmd.arg("merge").arg(&a).arg(&a).arg("-o").arg(&a);
    check(
        "error: is the input",
        &run(cmd, "merge onto an input"),
        "merge onto an input",
    );
}

#[test]
fn aovs_fails_a_file_with_nan_or_inf_pixels() {
    let scratch = Scratch::new("aovs");
    for (value, ok) in [(0.5f32, true), (f32::NAN, false), (f32::INFINITY, false)] {
        let path = scratch.0.join("x.exr");
        write_exr(&path, value, "1");
        let mut cmd = lightpath();
        cmd.arg("aovs").arg(&path);
        let out = run(cmd, "aovs");
        assert_eq!(
            out.code,
            Some(if ok { 0 } else { 1 }),
            "{value}: {}",
            out.stdout
        );
        assert_eq!(
            out.stdout.contains("NaN or infinite"),
            !ok,
            "{}",
            out.stdout
        );
    }
}

#[test]
fn comp_warns_when_gains_join_an_expression_and_refuses_a_png_output() {
    let scratch = Scratch::new("comp");
    let exr = scratch.0.join("r.exr");
    let mut cmd = lightpath();
    cmd.args([
        "render",
        "cornell",
        "--spp",
        "1",
        "--resolution",
        "8x8",
        "--light-groups",
        "-q",
        "-o",
    ])
    .arg(&exr);
    check("ok", &run(cmd, "render"), "render");
    let mut cmd = lightpath();
    cmd.arg("comp")
        .arg(&exr)
        .args(["beauty", "--gain", "key=0.5", "-o"])
        .arg(scratch.0.join("c.exr"));
    check(
        "warning: --gain with an expression",
        &run(cmd, "comp"),
        "comp",
    );
    let mut cmd = lightpath();
    cmd.arg("comp")
        .arg(&exr)
        .arg("-o")
        .arg(scratch.0.join("d.png"));
    check(
        "error: must end in .exr",
        &run(cmd, "comp -o png"),
        "comp -o png",
    );
    assert!(!scratch.0.join("d.png").exists());
}

#[test]
fn lpe_match_jsonl_answers_each_line_before_the_next_arrives() {
    let mut child = lightpath()
        .args(["lpe", "match", "--jsonl"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    let mut stdout = BufReader::new(child.stdout.take().unwrap());
    let mut answers = Vec::new();
    for case in [
        r#"{"expr":"C<RD>L","path":"C<RD>L"}"#,
        &format!(
            r#"{{"expr":"C{}L{}","path":"CL"}}"#,
            "(".repeat(9000),
            ")".repeat(9000)
        ),
    ] {
        writeln!(stdin, "{case}").unwrap();
        stdin.flush().unwrap();
        // Read the answer while stdin is still open: it must have been flushed.
        let mut line = String::new();
        stdout.read_line(&mut line).unwrap();
        answers.push(line);
    }
    drop(stdin);
    assert!(child.wait().unwrap().success());
    assert!(answers[0].contains("\"match\""), "{}", answers[0]);
    assert!(answers[1].contains("nested more than"), "{}", answers[1]);
}

#[test]
fn a_named_light_is_its_own_light_group() {
    let src = lightpath::Source {
        name: "named.toml".into(),
        text: "[[lights]]\ntype = \"point\"\nname = \"key\"\nposition = [0, 1, 0]\nintensity = [1, 1, 1]\n\
               [[lights]]\ntype = \"point\"\nname = \"rim\"\ngroups = [\"back\"]\nposition = [0, 1, 0]\nintensity = [1, 1, 1]\n"
            .into(),
        dir: Default::default(),
    };
    let desc = src.parse().unwrap();
    assert_eq!(desc.lights[0].groups, vec!["key".to_string()]);
    assert_eq!(desc.lights[1].groups, vec!["back".to_string()]);
}

#[test]
fn a_cancelled_render_resumed_from_its_checkpoint_equals_the_uninterrupted_one_bit_for_bit() {
    use lightpath::{render_resumable, RenderOptions, Resumable};
    use std::sync::atomic::{AtomicBool, Ordering};
    let mut desc = lightpath::load_scene("cornell").unwrap();
    desc.render.resolution = [24, 40];
    let specs = lightpath::aov::plan::AovPlan::build(&lightpath::aov::plan::PlanRequest {
        standard: true,
        ..Default::default()
    })
    .unwrap()
    .specs;
    let scene = lightpath::Scene::build(&desc, &specs).unwrap();
    let options = RenderOptions {
        spp: 4,
        first_sample: 0,
    };
    let silent = lightpath::progress::Silent;
    let request = lightpath::integrator::FrameRequest::whole(&scene);
    let whole = render_resumable(&scene, &options, &request, &silent, Resumable::default());
    // Stop after the first band of 8 rows.
    let cancel = AtomicBool::new(false);
    let mut stop = |_: &lightpath::integrator::Snapshot| cancel.store(true, Ordering::SeqCst);
    let part = render_resumable(
        &scene,
        &options,
        &request,
        &silent,
        Resumable {
            cancel: Some(&cancel),
            after_band: Some(&mut stop),
            max_band_rows: Some(8),
            ..Resumable::default()
        },
    );
    let done = part.rows_done.iter().filter(|d| **d).count();
    assert_eq!(done, 8, "{:?}", part.rows_done);
    // Through the checkpoint file, as `--resume` reads it.
    let dir = std::env::temp_dir().join(format!("lightpath-resume-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("a.exr.checkpoint");
    let snapshot = lightpath::integrator::Snapshot {
        film: &part.film,
        rows_done: &part.rows_done,
        pilot: None,
        splats: None,
    };
    // A checkpoint of some scene: its identity does not matter here.
    let identity = lightpath::identity::Identity::new(std::path::Path::new(""), &[], Vec::new());
    let stamp = lightpath::checkpoint::Stamp {
        identity: &identity,
        fingerprint: 7,
    };
    lightpath::checkpoint::write(&path, stamp, &snapshot).unwrap();
    let shape = lightpath::checkpoint::FilmShape {
        width: 24,
        height: 40,
        aovs: scene.aovs.len(),
        spp: 4,
        squared: Vec::new(),
        adaptive: false,
    };
    let back = lightpath::checkpoint::read(&path, stamp, shape).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    let resumed = render_resumable(
        &scene,
        &options,
        &request,
        &silent,
        Resumable {
            film: Some(back.film),
            rows_done: back.rows_done,
            ..Resumable::default()
        },
    );
    assert!(resumed.rows_done.iter().all(|d| *d));
    for (a, b) in resumed.film.planes.iter().zip(&whole.film.planes) {
        assert!(a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits()));
    }
    assert_eq!(
        resumed.stats.samples + part.stats.samples,
        whole.stats.samples
    );
}

/// Waits until `path` exists (the render is under way, its signal handler installed).
fn wait_for(path: &Path, child: &mut std::process::Child) {
    let start = Instant::now();
    while !path.exists() {
        assert!(
            child.try_wait().unwrap().is_none(),
            "the render ended before its first checkpoint"
        );
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "no checkpoint after 120 s"
        );
        std::thread::sleep(Duration::from_millis(1));
    }
}

/// `lightpath render cornell` at 32², quiet, checkpointing at every chance, with
/// `sampling` flags and output `out`.
#[cfg(unix)]
fn signal_test_args(sampling: &[&str], out: &Path) -> Vec<String> {
    ["render", "cornell", "--resolution", "32x32"]
        .iter()
        .chain(sampling)
        .chain(&["-q", "--checkpoint-every", "0.001", "-o"])
        .map(|s| s.to_string())
        .chain([out.display().to_string()])
        .collect()
}

/// Starts a render with `args`, sends it SIGINT once `checkpoint` exists, and returns
/// what it printed after checking it exited with 130.
#[cfg(unix)]
fn render_then_sigint(args: Vec<String>, checkpoint: &Path) -> String {
    let mut child = lightpath()
        .args(args)
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    wait_for(checkpoint, &mut child);
    // SAFETY: signalling our own child by its id.
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    let status = child.wait_with_output().unwrap();
    let said = String::from_utf8_lossy(&status.stdout).into_owned();
    assert_eq!(status.status.code(), Some(130), "{said}");
    said
}

#[cfg(unix)]
#[test]
fn sigint_then_resume_gives_the_uninterrupted_render_and_kill_9_leaves_the_old_output() {
    let scratch = Scratch::new("signals");
    let args = |out: &Path| signal_test_args(&["--spp", "256"], out);
    let reference = scratch.0.join("ref.exr");
    check(
        "ok",
        &run(
            {
                let mut c = lightpath();
                c.args(args(&reference));
                c
            },
            "reference",
        ),
        "reference",
    );

    // SIGINT during a re-render: the rows done go beside the output, as int.partial.exr
    // and .png, with a checkpoint; the finished pair already there is left as it was.
    // Then --resume finishes it and removes the partial pair.
    let out = scratch.0.join("int.exr");
    let checkpoint = scratch.0.join("int.exr.checkpoint");
    let (partial_exr, partial_png) = (
        scratch.0.join("int.partial.exr"),
        scratch.0.join("int.partial.png"),
    );
    std::fs::write(&out, b"finished exr").unwrap();
    std::fs::write(scratch.0.join("int.png"), b"finished png").unwrap();
    render_then_sigint(args(&out), &checkpoint);
    assert!(partial_exr.exists() && partial_png.exists() && checkpoint.exists());
    assert_eq!(std::fs::read(&out).unwrap(), b"finished exr");
    assert_eq!(
        std::fs::read(scratch.0.join("int.png")).unwrap(),
        b"finished png"
    );
    let partial = lightpath::output::read_exr(&partial_exr).unwrap();
    assert!(partial
        .attributes
        .iter()
        .any(|(k, v)| k == "lightpath/interrupted" && v.contains("rows rendered")));
    let mut resume = lightpath();
    resume.args(args(&out)).arg("--resume");
    check("ok", &run(resume, "resume"), "resume");
    assert_eq!(
        std::fs::read(&out).unwrap(),
        std::fs::read(&reference).unwrap()
    );
    assert!(
        !checkpoint.exists(),
        "a finished render removes its checkpoint"
    );
    assert!(
        !partial_exr.exists() && !partial_png.exists(),
        "a finished render removes the partial image"
    );

    // kill -9: the previous pair intact, no temporary file; --resume still finishes.
    let out = scratch.0.join("kill.exr");
    let checkpoint = scratch.0.join("kill.exr.checkpoint");
    std::fs::write(&out, b"previous exr").unwrap();
    std::fs::write(scratch.0.join("kill.png"), b"previous png").unwrap();
    let mut child = lightpath().args(args(&out)).spawn().unwrap();
    wait_for(&checkpoint, &mut child);
    child.kill().unwrap();
    child.wait().unwrap();
    assert_eq!(std::fs::read(&out).unwrap(), b"previous exr");
    assert_eq!(
        std::fs::read(scratch.0.join("kill.png")).unwrap(),
        b"previous png"
    );
    let temporary: Vec<String> = std::fs::read_dir(&scratch.0)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".tmp"))
        .collect();
    assert!(temporary.is_empty(), "{temporary:?}");
    let mut resume = lightpath();
    resume.args(args(&out)).arg("--resume");
    check(
        "ok",
        &run(resume, "resume after kill -9"),
        "resume after kill -9",
    );
    assert_eq!(
        std::fs::read(&out).unwrap(),
        std::fs::read(&reference).unwrap()
    );
}

/// The same for an adaptive render (two passes; the checkpoint holds the pass, the
/// per-pixel counts and the pilot's moments): SIGINT, then `--resume` gives the
/// uninterrupted render's EXR byte for byte.
#[cfg(unix)]
#[test]
fn sigint_then_resume_an_adaptive_render_gives_the_uninterrupted_one() {
    let scratch = Scratch::new("adaptive-signals");
    let sampling = [
        "--spp",
        "512",
        "--min-spp",
        "16",
        "--noise-threshold",
        "0.02",
    ];
    let args = |out: &Path| signal_test_args(&sampling, out);
    let reference = scratch.0.join("ref.exr");
    let mut c = lightpath();
    c.args(args(&reference));
    check("ok", &run(c, "reference"), "reference");
    let out = scratch.0.join("int.exr");
    let checkpoint = scratch.0.join("int.exr.checkpoint");
    let said = render_then_sigint(args(&out), &checkpoint);
    assert!(said.contains(" pass"), "the message names the pass: {said}");
    let mut resume = lightpath();
    resume.args(args(&out)).arg("--resume");
    check("ok", &run(resume, "resume"), "resume");
    assert_eq!(
        std::fs::read(&out).unwrap(),
        std::fs::read(&reference).unwrap()
    );
    assert!(!checkpoint.exists());
}
