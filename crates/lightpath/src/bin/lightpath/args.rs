//! The command line: every subcommand and option, as clap parses them.

use clap::{Parser, Subcommand};
use lightpath::output;
use lightpath::settings::{SettingOverrides, SETTINGS};
use std::path::PathBuf;

#[derive(Parser)]
#[command(
    name = "lightpath",
    version,
    about = "A CPU path tracer whose every AOV is a Light Path Expression"
)]
pub(crate) struct Cli {
    #[command(subcommand)]
    pub(crate) command: Command,
}

#[derive(Subcommand)]
pub(crate) enum Command {
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
        /// Open Image Denoise quality of every AOV but beauty (always filtered at high) and
        /// of the albedo and normal prefilters: high, balanced or fast (2–4× less CPU
        /// than high).
        #[arg(long, default_value = "fast", value_parser = lightpath::post::denoise::Quality::parse)]
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
pub(crate) struct ServeArgs {
    /// Port on 127.0.0.1 (default: a free one).
    #[arg(long, default_value_t = 0)]
    pub(crate) port: u16,
    /// Print the URL without opening a browser.
    #[arg(long)]
    pub(crate) no_open: bool,
}

#[derive(Subcommand)]
pub(crate) enum FarmCommand {
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
pub(crate) struct FarmArgs {
    /// A scene file (TOML) or the name of a built-in scene.
    pub(crate) scene: String,
    /// Number of parts.
    #[arg(long)]
    pub(crate) tasks: u32,
    /// Split by sample ranges or by tiles (strips of rows).
    #[arg(long, default_value = "samples", value_parser = lightpath::farm::SplitBy::parse)]
    pub(crate) by: lightpath::farm::SplitBy,
    /// The merged EXR; the parts and logs go in <OUT stem>.parts/ beside it. A directory
    /// (existing, or ending in /) for a USD stage of several render products: each
    /// product's merged file in it.
    #[arg(short, long)]
    pub(crate) output: PathBuf,
}

/// `lightpath render`'s options alone, to check a farm's shared render options.
#[derive(Parser)]
#[command(name = "lightpath render")]
pub(crate) struct RenderOnly {
    #[command(flatten)]
    pub(crate) args: RenderArgs,
}

#[derive(clap::Args)]
pub(crate) struct CompArgs {
    /// The EXR holding the AOVs.
    pub(crate) exr: PathBuf,
    /// A sum of scaled AOVs, e.g. "beauty + 0.5*beauty_key - caustics + (1,0.4,0.4)*caustics".
    /// Default: the --base AOV. One that starts with '-' goes after `--`:
    /// `comp in.exr -o out.exr -- "-0.5*caustics + beauty"`.
    pub(crate) expression: Option<String>,
    /// Output EXR (beauty as R, G, B, A); a PNG preview is written beside it.
    #[arg(short, long)]
    pub(crate) output: PathBuf,
    /// Rebalance a light group of the split --base AOV: GROUP=GAIN or GROUP=R,G,B
    /// (repeatable; `__default` for lights without a group).
    #[arg(long = "gain")]
    pub(crate) gains: Vec<String>,
    /// The light-group-split AOV that --gain applies to.
    #[arg(long, default_value = "beauty")]
    pub(crate) base: String,
    #[arg(long, default_value_t = 0.0)]
    pub(crate) exposure: f32,
}

#[derive(clap::Args)]
pub(crate) struct RenderArgs {
    /// A scene file (TOML, glTF .gltf/.glb) or the name of a built-in scene.
    #[arg(default_value = "cornell")]
    pub(crate) scene: String,
    /// Output EXR; the PNG preview goes beside it. Default: <scene>.exr (a USD stage's
    /// render products) in this directory. A directory (existing, or ending in /): the
    /// default names in it. A file, for a stage of several products: all in that file.
    #[arg(short, long)]
    pub(crate) output: Option<PathBuf>,
    #[command(flatten)]
    pub(crate) settings: SettingArgs,
    /// An extra AOV, NAME=DEFINITION (repeatable).
    #[arg(long = "aov")]
    pub(crate) aovs: Vec<String>,
    /// Which standard AOVs to add: standard (the table of docs/lpe.md#standard-aovs) or none
    /// [default: standard, except for a USD stage with render settings, whose RenderVars
    /// are the AOVs].
    #[arg(long = "aovs", value_parser = ["standard", "none"])]
    pub(crate) aov_set: Option<String>,
    /// Split beauty per light group: beauty_<group>, and beauty__default for lights
    /// without a group.
    #[arg(long)]
    pub(crate) light_groups: bool,
    /// Also split these AOVs per light group (comma-separated names).
    #[arg(long, value_delimiter = ',')]
    pub(crate) light_group_aovs: Vec<String>,
    /// Also write the per-pixel variance of these AOVs (comma-separated names) as
    /// <aov>_var: the estimated variance of the pixel mean (RenderMan's `mse`).
    #[arg(long, value_delimiter = ',')]
    pub(crate) variance: Vec<String>,
    /// Add bounce AOVs bounce0 … bounce<K-1> and bounce<K>plus (they sum to beauty).
    #[arg(long)]
    pub(crate) bounces: Option<u32>,
    /// Worker threads (1 to 1024; default: one per core).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_THREADS))]
    pub(crate) threads: Option<u32>,
    /// Write half-float channels instead of float32.
    #[arg(long)]
    pub(crate) half: bool,
    /// Index of the first sample: a farm splits a frame into sample ranges (`--first-sample
    /// 0 --spp 64`, `--first-sample 64 --spp 64`, …) and `lightpath merge` joins them.
    #[arg(long, default_value_t = 0)]
    pub(crate) first_sample: u32,
    /// EXR compression: none, rle, zips (ZIP by scan line, default), zip (16 lines) or piz.
    #[arg(long, default_value = "zips", value_parser = output::ExrCompression::parse)]
    pub(crate) compression: output::ExrCompression,
    /// Exposure of the PNG preview, in stops.
    #[arg(long, default_value_t = 0.0)]
    pub(crate) exposure: f32,
    /// Render through this camera of a glTF scene (default: its first).
    #[arg(long)]
    pub(crate) camera: Option<String>,
    /// No progress bar.
    #[arg(short, long)]
    pub(crate) quiet: bool,
    /// Serve the viewer's page during the render (refreshed as rows arrive), then the
    /// written EXR until Ctrl-C.
    #[arg(long)]
    pub(crate) preview: bool,
    #[command(flatten)]
    pub(crate) serve: ServeArgs,
    /// Render only the window X0,Y0,X1,Y1 of the frame (pixels, end exclusive), with
    /// the frame's own sample numbers: the EXR's data window, inside the whole frame's
    /// display window. `lightpath merge` stitches tiles into the frame.
    #[arg(long, value_parser = lightpath::film::PixelWindow::parse)]
    pub(crate) crop: Option<lightpath::film::PixelWindow>,
    /// Write Cryptomatte layers CryptoObject, CryptoMaterial and CryptoAsset.
    #[arg(long)]
    pub(crate) cryptomatte: bool,
    /// Ranks (id/coverage pairs) per Cryptomatte layer.
    #[arg(long, default_value_t = 6, value_parser = clap::value_parser!(u32).range(1..=16))]
    pub(crate) cryptomatte_ranks: u32,
    /// Record the render's date in the header (capDate); without it identical renders are
    /// identical files.
    #[arg(long)]
    pub(crate) timestamp: bool,
    /// Continue an interrupted render from the checkpoint beside its output: the same
    /// command plus --resume. The finished image equals an uninterrupted render's.
    #[arg(long)]
    pub(crate) resume: bool,
    /// With --resume: if the scene changed since the checkpoint was written (a file it
    /// read, or a setting that decides its pixels), start over instead of refusing.
    #[arg(long, requires = "resume")]
    pub(crate) restart_if_changed: bool,
    /// Also write a checkpoint every SECONDS while rendering (a render killed outright
    /// then loses at most that much).
    #[arg(long, value_name = "SECONDS", value_parser = parse_seconds)]
    pub(crate) checkpoint_every: Option<f64>,
    /// Denoise the EXR after rendering (as `lightpath denoise`; needs a build with the
    /// `denoise` feature).
    #[arg(long)]
    pub(crate) denoise: bool,
    /// With --denoise: keep each filtered AOV's input as <aov>_noisy.
    #[arg(long, requires = "denoise")]
    pub(crate) keep_noisy: bool,
    /// With --denoise: Open Image Denoise quality of every AOV but beauty (always filtered
    /// at high) and of the albedo and normal prefilters: high, balanced or fast (2–4× less
    /// CPU than high).
    #[arg(long, default_value = "fast", value_parser = lightpath::post::denoise::Quality::parse)]
    pub(crate) denoise_quality: lightpath::post::denoise::Quality,
    /// What traces the rays: bvh (Lightpath's own, the default) or embree (Intel Embree 3;
    /// needs a build with the `embree` feature). Same hits up to float rounding.
    #[arg(long, default_value = "bvh", value_parser = lightpath::geometry::Backend::parse)]
    pub(crate) accel: lightpath::geometry::Backend,
}

/// The render settings' options, one per entry of the settings table (`--spp`,
/// `--max-depth`, …): each value is read and checked by its entry, so the command line
/// accepts exactly what a scene file accepts.
#[derive(Clone, Debug, Default)]
pub(crate) struct SettingArgs(pub(crate) SettingOverrides);

impl clap::FromArgMatches for SettingArgs {
    fn from_arg_matches(matches: &clap::ArgMatches) -> Result<Self, clap::Error> {
        let mut args = SettingArgs::default();
        args.update_from_arg_matches(matches)?;
        Ok(args)
    }

    fn update_from_arg_matches(&mut self, matches: &clap::ArgMatches) -> Result<(), clap::Error> {
        for setting in SETTINGS {
            if let Some(text) = matches.get_one::<String>(setting.key) {
                (setting.read_flag)(text, &mut self.0)
                    .map_err(|e| clap::Error::raw(clap::error::ErrorKind::ValueValidation, e))?;
            }
        }
        Ok(())
    }
}

impl clap::Args for SettingArgs {
    fn augment_args(cmd: clap::Command) -> clap::Command {
        SETTINGS.iter().fold(cmd, |cmd, setting| {
            // The value is checked while parsing, so clap reports it as it reports any
            // invalid value; `update_from_arg_matches` then reads it again.
            let check = move |text: &str| -> Result<String, String> {
                (setting.read_flag)(text, &mut SettingOverrides::default())?;
                Ok(text.to_string())
            };
            cmd.arg(
                clap::Arg::new(setting.key)
                    .long(setting.flag)
                    .value_name(setting.value_name)
                    // `--clamp-direct -1` is a value to refuse with the setting's message,
                    // not an unknown option.
                    .allow_negative_numbers(true)
                    .help(setting.help_line())
                    .value_parser(check),
            )
        })
    }

    fn augment_args_for_update(cmd: clap::Command) -> clap::Command {
        Self::augment_args(cmd)
    }
}

pub(crate) fn parse_seconds(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v > 0.0 && v.is_finite() && v < 1e9 => Ok(v),
        _ => Err(format!("expected a positive number of seconds, got '{s}'")),
    }
}

/// A `comp` expression starting with '-' (`-0.5*beauty + …`) reads as an option unless it
/// follows `--`; clap's own tip names only its first characters, so say it whole.
pub(crate) fn hyphen_expression_hint(args: impl Iterator<Item = String>) -> Option<String> {
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
pub(crate) const MAX_THREADS: i64 = 1024;

#[derive(Subcommand)]
pub(crate) enum LpeCommand {
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
