//! The `lightpath` command: render scenes and work with Light Path Expressions.

use args::*;
use clap::Parser;
use lightpath::interrupt::EXIT_INTERRUPTED;
use lightpath::job::{AovRequest, DenoiseRequest, RenderJob};
use lightpath::lpe_tools;
use lightpath::output;
use std::io::{BufRead, IsTerminal, Write};
use std::process::ExitCode;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

/// `println!` that ignores a closed stdout (`lightpath … | head` must not panic).
macro_rules! say {
    ($($t:tt)*) => {{
        let _ = writeln!(std::io::stdout(), $($t)*);
    }};
}

/// `eprintln!` that ignores a closed stderr.
macro_rules! tell {
    ($($t:tt)*) => {{
        let _ = writeln!(std::io::stderr(), $($t)*);
    }};
}

/// `eprint!` that ignores a closed stderr.
macro_rules! tell_raw {
    ($($t:tt)*) => {{
        let _ = write!(std::io::stderr(), $($t)*);
    }};
}

mod args;
mod farm;
mod progress;
mod viewer;

use farm::farm_command;
use progress::{choose_progress, progress_reporter};
use viewer::{render_with_preview, view_command};

fn main() -> ExitCode {
    if let Some(hint) = hyphen_expression_hint(std::env::args().skip(1)) {
        tell!("{hint}");
    }
    let cli = Cli::parse();
    if let Err(e) = lightpath::limits::Limits::from_env() {
        tell!("error: {e}");
        return ExitCode::FAILURE;
    }
    match cli.command {
        Command::Render(args) => render(*args),
        Command::Lpe(cmd) => lpe_command(cmd),
        Command::Aovs { exr, tolerance } => aovs_command(&exr, tolerance),
        Command::Comp(args) => comp_command(args),
        Command::Farm(cmd) => match farm_command(cmd) {
            Ok(script) => {
                let _ = write!(std::io::stdout(), "{script}");
                ExitCode::SUCCESS
            }
            Err(e) => {
                tell!("error: {e}");
                ExitCode::FAILURE
            }
        },
        Command::Diff { a, b, tolerance } => match lightpath::post::diff::diff(&a, &b) {
            Ok(d) => {
                say!(
                    "{} channels, {} values differ; largest relative difference {:e}{}",
                    d.channels,
                    d.differing_values,
                    d.worst,
                    if d.differing_values > 0 {
                        format!(" (in {})", d.worst_channel)
                    } else {
                        String::new()
                    }
                );
                if d.worst <= tolerance {
                    ExitCode::SUCCESS
                } else {
                    tell!("error: the difference exceeds {tolerance:e}");
                    ExitCode::FAILURE
                }
            }
            Err(e) => {
                tell!("error: {e}");
                ExitCode::FAILURE
            }
        },
        Command::Merge { inputs, output } => match lightpath::post::merge(&inputs, &output) {
            Ok(m) => {
                say!(
                    "wrote {} ({} samples per pixel: {}; window {} from {} tile{})",
                    output.display(),
                    m.spp,
                    lightpath::aov::naming::format_ranges(&m.ranges),
                    m.window,
                    m.tiles,
                    if m.tiles == 1 { "" } else { "s" }
                );
                ExitCode::SUCCESS
            }
            Err(e) => {
                tell!("error: {e}");
                ExitCode::FAILURE
            }
        },
        Command::View { exr, serve } => view_command(exr, &serve),
        Command::Denoise {
            input,
            output,
            keep_noisy,
            quality,
        } => {
            let job = lightpath::post::denoise::DenoiseJob {
                input,
                output,
                keep_noisy,
                quality,
                preview_exposure: 0.0,
            };
            let progress =
                progress_reporter(choose_progress(false, std::io::stderr().is_terminal()));
            match lightpath::post::denoise::run_with_progress(&job, progress.as_ref()) {
                Ok(summary) => {
                    say!("{}", summary.line());
                    say!(
                        "wrote {} and {}",
                        job.output.display(),
                        lightpath::output::naming::preview_path(&job.output).display()
                    );
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    tell!("error: {e}");
                    ExitCode::FAILURE
                }
            }
        }
    }
}

fn aovs_command(path: &std::path::Path, tolerance: f32) -> ExitCode {
    match lightpath::post::partitions::report(path, tolerance) {
        Ok((text, ok)) => {
            let _ = write!(std::io::stdout(), "{text}");
            if ok {
                ExitCode::SUCCESS
            } else {
                ExitCode::FAILURE
            }
        }
        Err(e) => {
            tell!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn comp_command(args: CompArgs) -> ExitCode {
    let job = lightpath::post::comp::CompJob {
        exr: args.exr.clone(),
        expression: args.expression.clone(),
        gains: args.gains.clone(),
        base: args.base.clone(),
        output: args.output.clone(),
        exposure: args.exposure,
    };
    for w in lightpath::post::comp::warnings(&job) {
        tell!("warning: {w}");
    }
    if !job.gains.is_empty() {
        let header = lightpath::output::read_exr_header(&job.exr);
        if let Some(note) = header
            .ok()
            .and_then(|h| lightpath::post::comp::relight_caveat(&h.attributes))
        {
            tell!("note: {} {note}", job.exr.display());
        }
    }
    let run = || -> Result<(), String> {
        let png = lightpath::post::comp::run(&job)?;
        say!("wrote {} and {}", args.output.display(), png.display());
        Ok(())
    };
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            tell!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn render(args: RenderArgs) -> ExitCode {
    if let Some(n) = args.threads {
        if let Err(e) = rayon::ThreadPoolBuilder::new()
            .num_threads(n as usize)
            .build_global()
        {
            tell!("error: cannot start {n} threads: {e}");
            return ExitCode::FAILURE;
        }
    }
    let job = RenderJob {
        scene: args.scene,
        output: args.output,
        overrides: args.settings.0.clone(),
        aovs: AovRequest {
            standard: args.aov_set.as_deref() != Some("none"),
            standard_asked: args.aov_set.as_deref() == Some("standard"),
            extra: args.aovs,
            bounces: args.bounces,
            light_groups: args.light_groups,
            light_group_aovs: args.light_group_aovs,
            variance: args.variance,
        },
        first_sample: args.first_sample,
        exr: output::ExrOptions {
            half: args.half,
            compression: args.compression,
        },
        preview_exposure: args.exposure,
        camera: args.camera,
        crop: args.crop,
        cryptomatte: args.cryptomatte.then_some(args.cryptomatte_ranks),
        timestamp: args.timestamp,
        resume: args.resume,
        restart_if_changed: args.restart_if_changed,
        checkpoint_every: args
            .checkpoint_every
            .map(std::time::Duration::from_secs_f64),
        cancel: Some(Arc::new(AtomicBool::new(false))),
        denoise: args.denoise.then_some(DenoiseRequest {
            keep_noisy: args.keep_noisy,
            quality: args.denoise_quality,
        }),
        accel: args.accel,
    };
    let prepared = match job.prepare() {
        Ok(p) => p,
        Err(e) => {
            tell!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    for w in &prepared.warnings {
        tell!("warning: {w}");
    }
    if let Some(cancel) = &prepared.job.cancel {
        if let Err(e) = lightpath::interrupt::render_started(cancel.clone()) {
            tell!("warning: {e}: Ctrl-C will lose the render");
        }
    }
    let progress = progress_reporter(choose_progress(args.quiet, std::io::stderr().is_terminal()));
    if args.preview {
        if args.crop.is_some() {
            tell!("error: --preview shows whole frames: leave out --crop");
            return ExitCode::FAILURE;
        }
        return render_with_preview(prepared, progress.as_ref(), &args.serve);
    }
    match prepared.run(progress.as_ref()) {
        Ok(lightpath::job::RenderSummary {
            interrupted: Some(i),
            files,
            ..
        }) => {
            let summary = lightpath::job::RenderSummary::files_line_of(&files);
            say!(
                "interrupted after {}: wrote {} with the rows done, and the checkpoint {}; run the same command with --resume to finish",
                i.rows_line(),
                summary,
                i.checkpoint.display()
            );
            ExitCode::from(EXIT_INTERRUPTED)
        }
        Ok(summary) => {
            say!("{}", summary.line());
            if let Some(d) = &summary.denoised {
                say!("{d}");
            }
            say!("wrote {}", summary.files_line());
            ExitCode::SUCCESS
        }
        Err(e) => {
            tell!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn lpe_command(cmd: LpeCommand) -> ExitCode {
    let report = match cmd {
        LpeCommand::Check { definitions } => lpe_tools::check(&definitions),
        LpeCommand::Match {
            definitions,
            path,
            jsonl,
        } => {
            if jsonl {
                return match_jsonl();
            }
            let Some(path) = path else {
                tell!("error: give --path PATH, or --jsonl to read cases on stdin");
                return ExitCode::FAILURE;
            };
            lpe_tools::match_path(&definitions, &path)
        }
        LpeCommand::Explain { definitions } => lpe_tools::explain(&definitions),
        LpeCommand::Names => lpe_tools::names(),
    };
    let _ = write!(std::io::stdout(), "{}", report.stdout);
    tell_raw!("{}", report.stderr);
    if report.success {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}

/// The conformance interface: one JSON object per input line, in order, each written and
/// flushed as soon as it is made (a harness reading line by line gets every answer, and
/// nothing answered is lost if a later line ends the process).
fn match_jsonl() -> ExitCode {
    let stdin = std::io::stdin();
    let mut out = std::io::stdout().lock();
    for line in stdin.lock().lines() {
        let Ok(line) = line else { break };
        if line.trim().is_empty() {
            continue;
        }
        let answer = lpe_tools::answer_case(&line);
        if writeln!(out, "{answer}")
            .and_then(|()| out.flush())
            .is_err()
        {
            break;
        }
    }
    ExitCode::SUCCESS
}

#[cfg(test)]
mod tests {
    use super::progress::{choose_progress, ProgressChoice};

    #[test]
    fn progress_is_a_bar_in_a_terminal_lines_in_a_log_and_nothing_when_quiet() {
        assert_eq!(choose_progress(false, true), ProgressChoice::Bar);
        assert_eq!(choose_progress(false, false), ProgressChoice::Lines);
        assert_eq!(choose_progress(true, true), ProgressChoice::Silent);
        assert_eq!(choose_progress(true, false), ProgressChoice::Silent);
    }
}
