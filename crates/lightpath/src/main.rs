//! The `lightpath` command: render scenes and work with Light Path Expressions.

use clap::{Parser, Subcommand};
use lightpath::job::{AovRequest, DenoiseRequest, RenderJob, SettingOverrides};
use lightpath::light::select::LightSelection;
use lightpath::lpe_tools;
use lightpath::output;
use lightpath::progress::{PeriodicLines, Progress, Silent};
use lightpath::sampler::SamplerKind;
use lightpath::view;
use std::io::{BufRead, IsTerminal, Write};
use std::path::PathBuf;
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

#[derive(Parser)]
#[command(
    name = "lightpath",
    version,
    about = "A CPU path tracer whose every AOV is a Light Path Expression"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene file or a built-in scene (cornell, cornell-classic) to EXR and PNG.
    Render(Box<RenderArgs>),
    /// Check, match and explain Light Path Expressions.
    #[command(subcommand)]
    Lpe(LpeCommand),
    /// List an EXR's AOVs with their expressions and check that its partitions
    /// (standard set, light groups, bounces) add up; exit 1 if one does not.
    Aovs {
        exr: PathBuf,
        /// Largest acceptable relative error of a partition.
        #[arg(long, default_value_t = lightpath::post::partitions::DEFAULT_TOLERANCE)]
        tolerance: f32,
    },
    /// Composite AOVs by addition: relight without re-rendering.
    Comp(CompArgs),
    /// Join the parts of one frame (sample ranges from --first-sample, tiles from --crop)
    /// into one EXR; refuses parts of different scenes or settings, overlapping sample
    /// ranges and overlapping tiles, naming what differs.
    Merge {
        inputs: Vec<PathBuf>,
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Denoise every light AOV of an EXR with Intel Open Image Denoise (albedo and normal
    /// as auxiliary images, diffuse AOVs divided by albedo), keeping its partitions summing
    /// (needs a build with the `denoise` feature).
    Denoise {
        input: PathBuf,
        #[arg(short, long)]
        output: PathBuf,
        /// Keep each filtered AOV's input as <aov>_noisy.
        #[arg(long)]
        keep_noisy: bool,
        /// Open Image Denoise quality: high, balanced or fast.
        #[arg(long, default_value = "high", value_parser = lightpath::post::denoise::Quality::parse)]
        quality: lightpath::post::denoise::Quality,
    },
    /// Compare two EXRs of one frame channel by channel: print the largest relative
    /// difference; exit 1 if it exceeds --tolerance (0: every value's bits must match).
    Diff {
        a: PathBuf,
        b: PathBuf,
        #[arg(long, default_value_t = 0.0)]
        tolerance: f64,
    },
    /// Split a frame over a farm: print a script that renders its parts and merges them.
    #[command(subcommand)]
    Farm(FarmCommand),
    /// Look at an EXR's AOVs in the browser: every AOV with its expression, the
    /// partitions' errors, a pixel inspector, a light-group mixer, "Save comp".
    View {
        exr: PathBuf,
        #[command(flatten)]
        serve: ServeArgs,
    },
}

/// Where and how the viewer's page is served.
#[derive(clap::Args)]
struct ServeArgs {
    /// Port on 127.0.0.1 (default: a free one).
    #[arg(long, default_value_t = 0)]
    port: u16,
    /// Print the URL without opening a browser.
    #[arg(long)]
    no_open: bool,
}

#[derive(Subcommand)]
enum FarmCommand {
    /// Print a script that submits the parts as an sbatch job array and a merge job that
    /// depends on it: `lightpath farm slurm SCENE --tasks N -o OUT.exr [render options] >
    /// submit.sh && bash submit.sh`.
    Slurm {
        #[command(flatten)]
        farm: FarmArgs,
        /// An extra sbatch option for both jobs, e.g. --sbatch=--partition=render
        /// (repeatable).
        #[arg(long = "sbatch")]
        sbatch: Vec<String>,
        /// Render options every part shares (--spp, --aov, --cryptomatte, …), last.
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        render: Vec<String>,
    },
    /// Print a script that renders the parts with GNU parallel on this machine and
    /// merges them.
    Parallel {
        #[command(flatten)]
        farm: FarmArgs,
        /// Parts rendered at once.
        #[arg(long, default_value_t = 2)]
        jobs: u32,
        /// Render options every part shares (--spp, --aov, --cryptomatte, …), last.
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        render: Vec<String>,
    },
}

#[derive(clap::Args)]
struct FarmArgs {
    /// A scene file (TOML) or the name of a built-in scene.
    scene: String,
    /// Number of parts.
    #[arg(long)]
    tasks: u32,
    /// Split by sample ranges or by tiles (strips of rows).
    #[arg(long, default_value = "samples", value_parser = lightpath::farm::SplitBy::parse)]
    by: lightpath::farm::SplitBy,
    /// The merged EXR; the parts and logs go in <OUT stem>.parts/ beside it.
    #[arg(short, long)]
    output: PathBuf,
}

/// `lightpath render`'s options alone, to check a farm's shared render options.
#[derive(Parser)]
#[command(name = "lightpath render")]
struct RenderOnly {
    #[command(flatten)]
    args: RenderArgs,
}

#[derive(clap::Args)]
struct CompArgs {
    /// The EXR holding the AOVs.
    exr: PathBuf,
    /// A sum of scaled AOVs, e.g. "beauty + 0.5*beauty_key - caustics + (1,0.4,0.4)*caustics".
    /// Default: the --base AOV. One that starts with '-' goes after `--`:
    /// `comp in.exr -o out.exr -- "-0.5*caustics + beauty"`.
    expression: Option<String>,
    /// Output EXR (beauty as R, G, B, A); a PNG preview is written beside it.
    #[arg(short, long)]
    output: PathBuf,
    /// Rebalance a light group of the split --base AOV: GROUP=GAIN or GROUP=R,G,B
    /// (repeatable; `_default` for lights without a group).
    #[arg(long = "gain")]
    gains: Vec<String>,
    /// The light-group-split AOV that --gain applies to.
    #[arg(long, default_value = "beauty")]
    base: String,
    #[arg(long, default_value_t = 0.0)]
    exposure: f32,
}

#[derive(clap::Args)]
struct RenderArgs {
    /// A scene file (TOML, glTF .gltf/.glb) or the name of a built-in scene.
    #[arg(default_value = "cornell")]
    scene: String,
    /// Output EXR; the PNG preview goes beside it. Default: <scene>.exr in this directory.
    #[arg(short, long)]
    output: Option<PathBuf>,
    #[arg(long)]
    spp: Option<u32>,
    /// Path segments, as Mitsuba counts them (1: emitters seen directly, 2: + direct light).
    #[arg(long)]
    max_depth: Option<u32>,
    /// WIDTHxHEIGHT
    #[arg(long, value_parser = parse_resolution)]
    resolution: Option<[u32; 2]>,
    /// An extra AOV, NAME=DEFINITION (repeatable).
    #[arg(long = "aov")]
    aovs: Vec<String>,
    /// Which standard AOVs to add: standard (the table of LPE.md §7) or none.
    #[arg(long = "aovs", default_value = "standard", value_parser = ["standard", "none"])]
    aov_set: String,
    /// Split beauty per light group: beauty_<group>, and beauty__default for lights
    /// without a group.
    #[arg(long)]
    light_groups: bool,
    /// Also split these AOVs per light group (comma-separated names).
    #[arg(long, value_delimiter = ',')]
    light_group_aovs: Vec<String>,
    /// Also write the per-pixel variance of these AOVs (comma-separated names) as
    /// <aov>_var: the estimated variance of the pixel mean (RenderMan's `mse`).
    #[arg(long, value_delimiter = ',')]
    variance: Vec<String>,
    /// Add bounce AOVs bounce0 … bounce<K-1> and bounce<K>plus (they sum to beauty).
    #[arg(long)]
    bounces: Option<u32>,
    /// Worker threads (1 to 1024; default: one per core).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_THREADS))]
    threads: Option<u32>,
    #[arg(long)]
    seed: Option<u64>,
    /// Write half-float channels instead of float32.
    #[arg(long)]
    half: bool,
    /// Index of the first sample: a farm splits a frame into sample ranges (`--first-sample
    /// 0 --spp 64`, `--first-sample 64 --spp 64`, …) and `lightpath merge` joins them.
    #[arg(long, default_value_t = 0)]
    first_sample: u32,
    /// EXR compression: none, rle, zips (ZIP by scan line, default), zip (16 lines) or piz.
    #[arg(long, default_value = "zips", value_parser = output::ExrCompression::parse)]
    compression: output::ExrCompression,
    /// Exposure of the PNG preview, in stops.
    #[arg(long, default_value_t = 0.0)]
    exposure: f32,
    /// Render through this camera of a glTF scene (default: its first).
    #[arg(long)]
    camera: Option<String>,
    /// No progress bar.
    #[arg(short, long)]
    quiet: bool,
    /// Serve the viewer's page during the render (refreshed as rows arrive), then the
    /// written EXR until Ctrl-C.
    #[arg(long)]
    preview: bool,
    #[command(flatten)]
    serve: ServeArgs,
    /// Sample numbers: sobol (Owen-scrambled Sobol points, the default) or independent.
    #[arg(long, value_parser = ["sobol", "independent"])]
    sampler: Option<String>,
    /// How lights are chosen for light sampling: tree (power, distance and orientation;
    /// the default), power, or uniform (relighting from AOVs then equals re-rendering
    /// bit for bit).
    #[arg(long, value_parser = ["tree", "power", "uniform"])]
    light_selection: Option<String>,
    /// Adaptive sampling: a pixel stops once the relative standard error of its beauty
    /// is below this (e.g. 0.02); --spp is then the most a pixel takes.
    #[arg(long)]
    noise_threshold: Option<f32>,
    /// Adaptive sampling: samples every pixel takes first.
    #[arg(long)]
    min_spp: Option<u32>,
    /// Largest luminance of one contribution of indirect light (0: off).
    #[arg(long)]
    clamp_indirect: Option<f32>,
    /// Largest luminance of one contribution of direct light (0: off).
    #[arg(long)]
    clamp_direct: Option<f32>,
    /// Path regularisation: after a diffuse bounce, specular lobes are at least this
    /// rough (0 to 1; e.g. 0.3). Tames caustic fireflies at the cost of sharp caustics.
    #[arg(long)]
    regularize: Option<f32>,
    /// Render only the window X0,Y0,X1,Y1 of the frame (pixels, end exclusive), with
    /// the frame's own sample numbers: the EXR's data window, inside the whole frame's
    /// display window. `lightpath merge` stitches tiles into the frame.
    #[arg(long, value_parser = lightpath::film::PixelWindow::parse)]
    crop: Option<lightpath::film::PixelWindow>,
    /// Write Cryptomatte layers CryptoObject, CryptoMaterial and CryptoAsset.
    #[arg(long)]
    cryptomatte: bool,
    /// Ranks (id/coverage pairs) per Cryptomatte layer.
    #[arg(long, default_value_t = 6, value_parser = clap::value_parser!(u32).range(1..=16))]
    cryptomatte_ranks: u32,
    /// Record the render's date in the header (capDate); without it identical renders are
    /// identical files.
    #[arg(long)]
    timestamp: bool,
    /// Continue an interrupted render from the checkpoint beside its output: the same
    /// command plus --resume. The finished image equals an uninterrupted render's.
    #[arg(long)]
    resume: bool,
    /// Also write a checkpoint every SECONDS while rendering (a render killed outright
    /// then loses at most that much).
    #[arg(long, value_name = "SECONDS", value_parser = parse_seconds)]
    checkpoint_every: Option<f64>,
    /// Denoise the EXR after rendering (as `lightpath denoise`; needs a build with the
    /// `denoise` feature).
    #[arg(long)]
    denoise: bool,
    /// With --denoise: keep each filtered AOV's input as <aov>_noisy.
    #[arg(long, requires = "denoise")]
    keep_noisy: bool,
    /// With --denoise: Open Image Denoise quality, high, balanced or fast.
    #[arg(long, default_value = "high", value_parser = lightpath::post::denoise::Quality::parse)]
    denoise_quality: lightpath::post::denoise::Quality,
}

fn parse_seconds(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v > 0.0 && v.is_finite() && v < 1e9 => Ok(v),
        _ => Err(format!("expected a positive number of seconds, got '{s}'")),
    }
}

use lightpath::interrupt::EXIT_INTERRUPTED;

/// A `comp` expression starting with '-' (`-0.5*beauty + …`) reads as an option unless it
/// follows `--`; clap's own tip names only its first characters, so say it whole.
fn hyphen_expression_hint(args: impl Iterator<Item = String>) -> Option<String> {
    let args: Vec<String> = args.take_while(|a| a != "--").collect();
    if args.first().map(String::as_str) != Some("comp") {
        return None;
    }
    let expression = args.iter().skip(1).find(|a| {
        let mut c = a.chars();
        c.next() == Some('-')
            && c.next()
                .is_some_and(|c| c.is_ascii_digit() || c == '.' || c == '(')
    })?;
    Some(format!(
        "note: the expression '{expression}' starts with '-': put it after `--`, as in \
         lightpath comp IN.exr -o OUT.exr -- \"{expression}\""
    ))
}

/// `--threads` above this is refused: a pool of 100000 threads could not start.
const MAX_THREADS: i64 = 1024;

fn parse_resolution(s: &str) -> Result<[u32; 2], String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or("expected WIDTHxHEIGHT, e.g. 640x480")?;
    let w: u32 = w.trim().parse().map_err(|_| format!("bad width '{w}'"))?;
    let h: u32 = h.trim().parse().map_err(|_| format!("bad height '{h}'"))?;
    if w == 0 || h == 0 || w > 32768 || h > 32768 {
        return Err("resolution must be between 1 and 32768 in each direction".into());
    }
    Ok([w, h])
}

#[derive(Subcommand)]
enum LpeCommand {
    /// Exit 0 when every definition is valid; otherwise print diagnostics and exit 1.
    Check { definitions: Vec<String> },
    /// Print `match` or `no match` for each definition against a path; with --jsonl,
    /// read {"expr", "path"} lines on stdin and answer one JSON line each.
    Match {
        definitions: Vec<String>,
        #[arg(long)]
        path: Option<String>,
        #[arg(long)]
        jsonl: bool,
    },
    /// Each rule in plain English, and the automaton's size.
    Explain { definitions: Vec<String> },
    /// The standard names and their expressions.
    Names,
}

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
            };
            match lightpath::post::denoise::run(&job) {
                Ok(summary) => {
                    say!("{}", summary.line());
                    say!("wrote {}", job.output.display());
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

/// Starts the viewer on `data`, prints its URL and opens a browser unless told not to.
fn start_viewer(
    data: view::ViewData,
    exr: Option<PathBuf>,
    serve: &ServeArgs,
) -> Result<view::Viewer, String> {
    let viewer = view::Viewer::start(data, exr, serve.port)?;
    say!("viewing at {}", viewer.url());
    if !serve.no_open && !view::open_browser(&viewer.url()) {
        tell!("no browser opener found (xdg-open, open): open the URL yourself");
    }
    Ok(viewer)
}

/// Blocks until Ctrl-C (SIGINT, or SIGTERM).
fn wait_for_ctrl_c() {
    if let Err(e) = lightpath::interrupt::wait() {
        tell!("warning: {e}; stop with another signal");
        loop {
            std::thread::park();
        }
    }
}

fn view_command(exr: PathBuf, serve: &ServeArgs) -> ExitCode {
    // Before the URL is printed: a Ctrl-C right after it must stop the viewer cleanly.
    if let Err(e) = lightpath::interrupt::catch() {
        tell!("warning: {e}");
    }
    let data = match view::open(&exr) {
        Ok(d) => d,
        Err(e) => {
            tell!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    let viewer = match start_viewer(data, Some(exr), serve) {
        Ok(v) => v,
        Err(e) => {
            tell!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    say!("press Ctrl-C to stop");
    wait_for_ctrl_c();
    viewer.stop();
    say!("stopped");
    ExitCode::SUCCESS
}

/// The farm script: the parts of the frame and the commands rendering and merging them.
fn farm_command(cmd: FarmCommand) -> Result<String, String> {
    use lightpath::farm::{absolute, split, FarmJob};
    type Printer = Box<dyn Fn(&FarmJob) -> String>;
    let (farm, render, script): (FarmArgs, Vec<String>, Printer) = match cmd {
        FarmCommand::Slurm {
            farm,
            sbatch,
            render,
        } => (
            farm,
            render,
            Box::new(move |job: &FarmJob| {
                FarmJob {
                    sbatch_args: sbatch.clone(),
                    ..job.clone()
                }
                .slurm_script()
            }),
        ),
        FarmCommand::Parallel { farm, jobs, render } => (
            farm,
            render,
            Box::new(move |job: &FarmJob| job.parallel_script(jobs.max(1))),
        ),
    };
    // The shared options must be valid render options, and leave the split to the farm.
    let parsed = RenderOnly::try_parse_from(
        ["lightpath render".to_string(), farm.scene.clone()]
            .into_iter()
            .chain(render.iter().cloned()),
    )
    .map_err(|e| format!("in the render options: {e}"))?
    .args;
    if parsed.output.is_some() || parsed.crop.is_some() || parsed.first_sample != 0 {
        return Err(
            "the farm chooses each part's --output, --crop and --first-sample: leave them out of the render options"
                .into(),
        );
    }
    let desc = lightpath::load_scene(&farm.scene).map_err(|e| e.to_string())?;
    let spp = parsed.spp.unwrap_or(desc.render.spp).max(1);
    let resolution = parsed.resolution.unwrap_or(desc.film.resolution);
    let parts = split(farm.by, farm.tasks, spp, resolution)?;
    // Each sample range sets its own --spp; tiles all render the frame's.
    let mut render = lightpath::farm::without_option(&render, "--spp");
    if farm.by == lightpath::farm::SplitBy::Tiles {
        render.extend(["--spp".to_string(), spp.to_string()]);
    }
    // A built-in scene's name stays a name; a file becomes an absolute path.
    let scene = if std::path::Path::new(&farm.scene).exists() {
        absolute(std::path::Path::new(&farm.scene))
            .display()
            .to_string()
    } else {
        farm.scene.clone()
    };
    let job = FarmJob {
        lightpath: std::env::current_exe()
            .map_err(|e| format!("cannot locate the lightpath binary: {e}"))?,
        scene,
        render_args: render,
        parts,
        output: absolute(&farm.output),
        sbatch_args: Vec::new(),
    };
    Ok(script(&job))
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

/// How a render reports progress.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum ProgressChoice {
    /// An `indicatif` bar: stderr is a terminal.
    Bar,
    /// A plain line every 10 s: stderr is a log (a farm's), where a bar shows nothing.
    Lines,
    /// `--quiet`.
    Silent,
}

/// The reporter for `--quiet` and whether stderr is a terminal (a pure function: tested).
fn choose_progress(quiet: bool, stderr_is_terminal: bool) -> ProgressChoice {
    match (quiet, stderr_is_terminal) {
        (true, _) => ProgressChoice::Silent,
        (false, true) => ProgressChoice::Bar,
        (false, false) => ProgressChoice::Lines,
    }
}

fn progress_reporter(choice: ProgressChoice) -> Box<dyn Progress> {
    match choice {
        ProgressChoice::Bar => Box::new(Bar(indicatif::ProgressBar::hidden())),
        ProgressChoice::Lines => Box::new(PeriodicLines::new(std::time::Duration::from_secs(10))),
        ProgressChoice::Silent => Box::new(Silent),
    }
}

/// `Progress` as an `indicatif` bar; hidden until `start` knows the total.
struct Bar(indicatif::ProgressBar);

impl Progress for Bar {
    fn start(&self, total: u64, _samples: u64) {
        self.0.set_length(total);
        self.0.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} rendering [{bar:40}] {pos}/{len} {elapsed_precise} (eta {eta})",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
            .progress_chars("=> "),
        );
        self.0
            .set_draw_target(indicatif::ProgressDrawTarget::stderr());
    }
    fn advance(&self, units: u64) {
        self.0.inc(units);
    }
    fn finish(&self) {
        self.0.finish_and_clear();
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
        overrides: SettingOverrides {
            spp: args.spp,
            max_depth: args.max_depth,
            resolution: args.resolution,
            seed: args.seed,
            sampler: args.sampler.as_deref().and_then(SamplerKind::parse),
            light_selection: args
                .light_selection
                .as_deref()
                .and_then(LightSelection::parse),
            noise_threshold: args.noise_threshold,
            min_spp: args.min_spp,
            clamp_indirect: args.clamp_indirect,
            clamp_direct: args.clamp_direct,
            regularize: args.regularize,
        },
        aovs: AovRequest {
            standard: args.aov_set == "standard",
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
        checkpoint_every: args
            .checkpoint_every
            .map(std::time::Duration::from_secs_f64),
        cancel: Some(Arc::new(AtomicBool::new(false))),
        denoise: args.denoise.then_some(DenoiseRequest {
            keep_noisy: args.keep_noisy,
            quality: args.denoise_quality,
        }),
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
            paths,
            ..
        }) => {
            say!(
                "interrupted after {} of {} rows: wrote {} and {} with the rows done, and the checkpoint {}; run the same command with --resume to finish",
                i.rows_done,
                i.rows,
                paths.exr.display(),
                paths.png.display(),
                i.checkpoint.display()
            );
            ExitCode::from(EXIT_INTERRUPTED)
        }
        Ok(summary) => {
            say!("{}", summary.line());
            if let Some(d) = &summary.denoised {
                say!("{d}");
            }
            say!(
                "wrote {} and {}",
                summary.paths.exr.display(),
                summary.paths.png.display()
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            tell!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// `render --preview`: the viewer fed by the render, then showing the written EXR.
fn render_with_preview(
    prepared: lightpath::job::PreparedRender,
    progress: &dyn Progress,
    serve: &ServeArgs,
) -> ExitCode {
    let data = view::preview::live_data(&prepared.scene, prepared.source.name.clone());
    let height = prepared.scene.camera.height;
    let viewer = match start_viewer(data, None, serve) {
        Ok(v) => v,
        Err(e) => {
            tell!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    let preview = view::preview::LivePreview::new(progress, viewer.shared().clone(), height);
    let summary = prepared.run(&preview);
    // From here a Ctrl-C stops the viewer.
    lightpath::interrupt::render_finished();
    let summary = match summary {
        Ok(s) => s,
        Err(e) => {
            tell!("error: {e}");
            viewer.stop();
            return ExitCode::FAILURE;
        }
    };
    say!("{}", summary.line());
    say!(
        "wrote {} and {}",
        summary.paths.exr.display(),
        summary.paths.png.display()
    );
    match view::open(&summary.paths.exr) {
        Ok(data) => viewer.shared().show_file(data, summary.paths.exr.clone()),
        Err(e) => tell!("warning: cannot show the written EXR: {e}"),
    }
    say!("still viewing at {}; press Ctrl-C to stop", viewer.url());
    wait_for_ctrl_c();
    viewer.stop();
    say!("stopped");
    ExitCode::SUCCESS
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
    use super::*;

    #[test]
    fn progress_is_a_bar_in_a_terminal_lines_in_a_log_and_nothing_when_quiet() {
        assert_eq!(choose_progress(false, true), ProgressChoice::Bar);
        assert_eq!(choose_progress(false, false), ProgressChoice::Lines);
        assert_eq!(choose_progress(true, true), ProgressChoice::Silent);
        assert_eq!(choose_progress(true, false), ProgressChoice::Silent);
    }
}
