//! The library's error type. Every scene error carries where it was written
//! (`file:line:col`, or just the file), and prints as `file:line:col: message`.

use crate::film::PixelWindow;
use crate::scene::desc::Origin;
use std::fmt;
use std::path::PathBuf;

/// A scene error: which file, where in it, and what was expected.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SceneError {
    pub file: String,
    pub line: usize,
    pub column: usize,
    pub message: String,
}

impl SceneError {
    pub fn origin(&self) -> Origin {
        Origin {
            file: self.file.clone(),
            line: self.line,
            col: self.column,
        }
    }
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.origin(), self.message)
    }
}

impl std::error::Error for SceneError {}

impl Origin {
    pub fn error(&self, message: impl Into<String>) -> SceneError {
        SceneError {
            file: self.file.clone(),
            line: self.line,
            column: self.col,
            message: message.into(),
        }
    }
}

/// Any error of the library.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scene that cannot be read, parsed or built; AOV expressions included (their
    /// message shows the expression and where in it).
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// An AOV plan that cannot be made (a malformed `--aov`, a split of an unknown AOV).
    #[error("{0}")]
    Plan(String),
    /// An output that cannot be written; the message names the file and the OS reason.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// A render setting that cannot be honoured (`spp = 0`, a sample range past 2^32) or
    /// a request above one of the `limits`; checked before rendering.
    #[error("{0}")]
    Setting(String),
    /// A request above one of the `limits`, or a malformed `LIGHTPATH_MAX_*` variable.
    #[error(transparent)]
    Limit(#[from] LimitError),
    /// A file that cannot be read within the limits.
    #[error(transparent)]
    Read(#[from] ReadError),
    /// The accelerator cannot trace as asked (`--accel embree`).
    #[error(transparent)]
    Accel(#[from] AccelError),
    /// An EXR that cannot be read (renders, merges, denoise, the viewer), or post-render
    /// work (merge, diff, comp, denoise) that cannot be done: the message says which file
    /// and why.
    #[error(transparent)]
    Post(#[from] PostError),
    /// A command-line value that does not parse (`--crop`, `--accel`, `--aov`, …).
    #[error(transparent)]
    Value(#[from] InvalidValue),
    /// SIGINT and SIGTERM cannot be caught.
    #[error("cannot catch interrupts ({0})")]
    Interrupts(String),
}

/// A request above one of the limits of `limits.rs`, or a malformed limit variable.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum LimitError {
    #[error("{for_what} needs {value} {what}, above the limit of {limit} (set {env} to raise it)")]
    Exceeded {
        for_what: String,
        value: u64,
        what: &'static str,
        limit: u64,
        env: &'static str,
    },
    #[error("{0} is not valid UTF-8")]
    EnvNotUnicode(&'static str),
    #[error("{env}='{value}': expected a whole number, optionally with a K, M, G or T suffix")]
    EnvMalformed { env: &'static str, value: String },
}

/// An input file that cannot be read whole within the limits (`limits::read_input`).
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    #[error("cannot open: {0}")]
    Open(std::io::Error),
    #[error("cannot read: {0}")]
    Read(std::io::Error),
    #[error("not a regular file (a directory, device or pipe)")]
    NotRegular,
    #[error(transparent)]
    Limit(#[from] LimitError),
}

/// Why the accelerator cannot trace with the backend asked for.
#[derive(Debug, Clone, thiserror::Error)]
pub enum AccelError {
    /// `--accel embree` in a build without the `embree` feature.
    #[error("{}", crate::geometry::Backend::EMBREE_UNAVAILABLE)]
    EmbreeUnavailable,
    /// Embree could not make a device or build the scene; the message is Embree's.
    #[error("{0}")]
    Embree(String),
}

/// A command-line or scene value that does not parse; the message names the option and
/// what was expected.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct InvalidValue(pub String);

/// An output that cannot be written, or an output path that must not be written to.
/// Each names the file; the OS reason is its `source`.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// Creating, writing or syncing the file failed.
    #[error("cannot write {}: {source}", path.display())]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    /// Writing a render's checkpoint failed.
    #[error("cannot write the checkpoint {}: {source}", path.display())]
    Checkpoint {
        path: PathBuf,
        source: std::io::Error,
    },
    /// The encoder (EXR, PNG) failed; `reason` is its message.
    #[error("cannot write {}: {reason}", path.display())]
    Encode { path: PathBuf, reason: String },
    /// The written file could not be renamed over its target.
    #[error("cannot move {} into place: {source}", path.display())]
    Move {
        path: PathBuf,
        source: std::io::Error,
    },
    /// The file an output replaces could not be removed.
    #[error("cannot remove {what} {}: {source}", path.display())]
    Remove {
        what: &'static str,
        path: PathBuf,
        source: std::io::Error,
    },
    /// An EXR output named otherwise than `.exr` (`-o x.png` wrote an EXR under a PNG's
    /// name, and the PNG preview then over it).
    #[error(
        "output {}: the output is OpenEXR, so its name must end in .exr{}",
        path.display(),
        preview.as_ref().map_or(String::new(), |p| format!(
            " (the PNG preview is written beside it, as {})",
            p.display()
        ))
    )]
    NotExr {
        path: PathBuf,
        preview: Option<PathBuf>,
    },
    /// The output is one of the job's inputs.
    #[error("output {} is the input {}: writing would destroy it", path.display(), input.display())]
    IsInput { path: PathBuf, input: PathBuf },
    /// A symlink, directory or device under the output's name.
    #[error("output {} is {kind}: outputs replace regular files only; name a file", path.display())]
    NotRegular { path: PathBuf, kind: &'static str },
    /// The output's directory does not exist.
    #[error("cannot write {}: the directory {} does not exist", path.display(), dir.display())]
    NoDirectory { path: PathBuf, dir: PathBuf },
    /// The output's directory takes no new files.
    #[error("cannot write {}: cannot create files in {}: {source}", path.display(), dir.display())]
    DirectoryNotWritable {
        path: PathBuf,
        dir: PathBuf,
        source: std::io::Error,
    },
}

/// A render setting whose value cannot be taken: which setting (its TOML key; the
/// command line says the same of its flag), what was written and what was expected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SettingError {
    /// A name that is none of the setting's choices.
    #[error("unknown {key} '{written}': expected {}{suggestion}", choices.join(" or "))]
    UnknownChoice {
        key: &'static str,
        written: String,
        choices: &'static [&'static str],
        /// `did_you_mean`'s hint, or empty.
        suggestion: String,
    },
    /// A value not of the setting's type; `range` describes the values it takes (empty
    /// for any).
    #[error(
        "{key} must be {expected}{}, got '{written}'",
        if range.is_empty() { String::new() } else { format!(" {range}") }
    )]
    NotOfType {
        key: &'static str,
        expected: &'static str,
        range: String,
        written: String,
    },
    #[error("{key} must be a finite number, got {value}")]
    NotFinite { key: &'static str, value: String },
    #[error("{key} must be {range}, got {value}")]
    OutOfRange {
        key: &'static str,
        range: String,
        value: String,
    },
    #[error(
        "min_spp ({min_spp}) is above spp ({spp}): adaptive sampling's pilot pass takes \
         min_spp of a pixel's spp samples (--min-spp and --spp, [render] min_spp and spp)"
    )]
    MinSppAboveSpp { min_spp: u32, spp: u32 },
    #[error(
        "--first-sample {first_sample} with {spp} spp runs past sample index {}: expected \
         first sample + spp ≤ 2^32 - 1",
        u32::MAX
    )]
    PastLastSample { first_sample: u32, spp: u32 },
    /// The film or its samples above one of the `limits`.
    #[error(transparent)]
    Limit(#[from] LimitError),
}

/// An EXR that cannot be read: which file, and why.
#[derive(Debug, thiserror::Error)]
#[error("cannot read {}: {fault}", path.display())]
pub struct ExrReadError {
    pub path: PathBuf,
    pub fault: ExrFault,
}

/// Why an EXR (a file, or bytes a scene read) cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum ExrFault {
    #[error("{0}")]
    Open(std::io::Error),
    #[error("not a regular file (a directory, device or pipe)")]
    NotRegular,
    #[error(transparent)]
    Limit(#[from] LimitError),
    /// The `exr` crate's message: not an EXR, truncated, unsupported.
    #[error("{0}")]
    Decode(String),
    #[error("no image in the file")]
    NoImage,
    /// A render's data window must lie in its display window.
    #[error(
        "the data window ({data_origin:?} + {data_size:?}) does not lie inside the display \
         window ({display_origin:?} + {display_size:?})"
    )]
    DataWindow {
        data_origin: [i64; 2],
        data_size: [usize; 2],
        display_origin: [i64; 2],
        display_size: [usize; 2],
    },
    /// An image read as a texture must have R, G and B.
    #[error("the image has no {0} channel")]
    MissingChannel(&'static str),
}

impl ExrFault {
    /// This fault, of the file at `path`.
    pub fn of(self, path: &std::path::Path) -> ExrReadError {
        ExrReadError {
            path: path.to_path_buf(),
            fault: self,
        }
    }
}

// Modules still reporting errors as text (the scene loaders and materials, rewritten in
// issue 26) take these through `?` and `format!` unchanged.
impl From<LimitError> for String {
    fn from(e: LimitError) -> String {
        e.to_string()
    }
}
impl From<ReadError> for String {
    fn from(e: ReadError) -> String {
        e.to_string()
    }
}
impl From<InvalidValue> for String {
    fn from(e: InvalidValue) -> String {
        e.0
    }
}
/// Post-render work (merge, diff, comp, denoise, the partition report) that cannot be
/// done: which files, and why.
#[derive(Debug, thiserror::Error)]
pub enum PostError {
    #[error(transparent)]
    Read(#[from] ExrReadError),
    #[error(transparent)]
    Write(#[from] OutputError),
    #[error("give the EXRs to merge")]
    NothingToMerge,
    #[error("{} is an interrupted render (some rows are empty): finish it with --resume first", path.display())]
    Interrupted { path: PathBuf },
    #[error("{} has no {attribute} header: not a Lightpath render", path.display())]
    NotARender {
        path: PathBuf,
        attribute: &'static str,
    },
    /// A header attribute of a part that does not say what it must (`expected`).
    #[error("{}: {attribute} is '{value}': expected {expected}", path.display())]
    BadAttribute {
        path: PathBuf,
        attribute: &'static str,
        value: String,
        expected: &'static str,
    },
    #[error(
        "{} is a {}x{} frame but {} is {}x{}",
        path.display(), size[0], size[1], other.display(), other_size[0], other_size[1]
    )]
    FrameSize {
        path: PathBuf,
        size: [u32; 2],
        other: PathBuf,
        other_size: [u32; 2],
    },
    #[error(
        "{} and {} have different channels (only in the first: {only_first:?}; only in the \
         second: {only_second:?})",
        first.display(), second.display()
    )]
    Channels {
        first: PathBuf,
        second: PathBuf,
        only_first: Vec<String>,
        only_second: Vec<String>,
    },
    /// Parts whose manifests of inputs differ: each change names the file.
    #[error(
        "{} and {} are renders of different scenes: {} (from the first to the second; \
         render every part from the same files)",
        first.display(), second.display(), changes.join("; ")
    )]
    InputsChanged {
        first: PathBuf,
        second: PathBuf,
        changes: Vec<String>,
    },
    /// A header attribute that must agree between the parts of a frame (boxed: the
    /// largest of these errors).
    #[error(transparent)]
    NotOneFrame(Box<FrameMismatch>),
    #[error(
        "{} holds samples {}-{} and {} holds {}-{}: they overlap, so those samples would \
         count twice",
        first.display(), first_range.0, first_range.1,
        second.display(), second_range.0, second_range.1
    )]
    SamplesOverlap {
        first: PathBuf,
        first_range: (u64, u64),
        second: PathBuf,
        second_range: (u64, u64),
    },
    #[error(
        "{} covers pixels {first_window} and {} covers {second_window}: tiles may not overlap",
        first.display(), second.display()
    )]
    TilesOverlap {
        first: PathBuf,
        first_window: PixelWindow,
        second: PathBuf,
        second_window: PixelWindow,
    },
    #[error(
        "tile {first_window} holds samples {first_samples} but tile {second_window} holds \
         {second_samples}: tiles of one frame need the same samples"
    )]
    TileSamples {
        first_window: PixelWindow,
        first_samples: String,
        second_window: PixelWindow,
        second_samples: String,
    },
    #[error("the tiles leave {uncovered} of the {area} pixels of window {window} uncovered")]
    Uncovered {
        uncovered: u64,
        area: u64,
        window: PixelWindow,
    },
    /// Two files `diff` cannot compare pixel by pixel: (frame, origin, size) of each.
    #[error(
        "{} and {} cover different pixels (frame {:?} at {:?} + {}x{} against {:?} at {:?} + {}x{})",
        first.display(), second.display(),
        first_window.0, first_window.1, first_window.2[0], first_window.2[1],
        second_window.0, second_window.1, second_window.2[0], second_window.2[1]
    )]
    DifferentPixels {
        first: PathBuf,
        second: PathBuf,
        first_window: ([u32; 2], [u32; 2], [usize; 2]),
        second_window: ([u32; 2], [u32; 2], [usize; 2]),
    },
    #[error("{} and {} have different channels", first.display(), second.display())]
    DifferentChannels { first: PathBuf, second: PathBuf },
    /// A compositing expression that does not parse: where (a byte offset) and what was
    /// expected there.
    #[error("in the expression {expression:?}: at {at}: expected {expected}")]
    Expression {
        expression: String,
        at: usize,
        expected: &'static str,
    },
    /// `--gain GROUP=GAIN` written otherwise.
    #[error("--gain '{written}': expected {expected}")]
    Gain {
        written: String,
        expected: &'static str,
    },
    #[error(
        "the EXR has no AOV '{aov}' (channel {channel}){suggestion}; it has {}",
        known.join(", ")
    )]
    NoAov {
        aov: String,
        channel: String,
        known: Vec<String>,
        suggestion: String,
    },
    #[error(
        "the EXR has no light-group part of '{base}' for group '{group}'{suggestion} (its \
         light groups of '{base}': {})",
        known.join(", ")
    )]
    NoLightGroup {
        base: String,
        group: String,
        known: Vec<String>,
        suggestion: String,
    },
    /// A build without the `denoise` feature asked to denoise.
    #[error("{}", crate::post::denoise::UNAVAILABLE)]
    DenoiseUnavailable,
    #[error("cannot denoise {}: {fault}", path.display())]
    Denoise { path: PathBuf, fault: DenoiseFault },
}

/// A header attribute that differs between two parts of one frame; `flag` is the
/// command-line option of the setting it records, if it records one.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "{} and {} are not parts of one frame: {attribute}{} is {} in the first and {} in the \
     second",
    first.display(),
    second.display(),
    flag.map_or(String::new(), |f| format!(" (--{f})")),
    shown(in_first.as_deref()),
    shown(in_second.as_deref())
)]
pub struct FrameMismatch {
    pub first: PathBuf,
    pub second: PathBuf,
    pub attribute: String,
    pub flag: Option<&'static str>,
    pub in_first: Option<String>,
    pub in_second: Option<String>,
}

/// A header value as `merge` quotes it: at most 80 characters.
fn shown(v: Option<&str>) -> String {
    match v {
        Some(v) if v.chars().count() > 80 => {
            format!("'{}…'", v.chars().take(80).collect::<String>())
        }
        Some(v) => format!("'{v}'"),
        None => "nothing".to_string(),
    }
}

/// Why one file cannot be denoised.
#[derive(Debug, thiserror::Error)]
pub enum DenoiseFault {
    #[error(
        "it is already denoised (it has a lightpath/denoised attribute): denoise the noisy \
         render instead"
    )]
    AlreadyDenoised,
    #[error("--keep-noisy would name the noisy '{aov}' '{name}', which the file already has")]
    NoisyNameTaken { aov: String, name: String },
    #[error("filtering AOV '{aov}': {source}")]
    Filtering { aov: String, source: OidnError },
    /// Prefiltering an auxiliary image (`albedo`, `normal`).
    #[error("prefiltering the {aux}: {source}")]
    Prefiltering {
        aux: &'static str,
        source: OidnError,
    },
    #[error(transparent)]
    Oidn(#[from] OidnError),
    #[error(transparent)]
    Limit(#[from] LimitError),
}

/// Open Image Denoise's own message.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("Open Image Denoise: {0}")]
pub struct OidnError(pub String);

/// The viewer cannot show a file or cannot serve.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    #[error(transparent)]
    Read(#[from] ExrReadError),
    #[error("cannot listen on 127.0.0.1:{port}: {source}")]
    Listen { port: u16, source: std::io::Error },
}

// The binary reports errors as text (`anyhow`-style): each converts through `?`.
macro_rules! as_text {
    ($($t:ty),*) => {$(
        impl From<$t> for String {
            fn from(e: $t) -> String {
                e.to_string()
            }
        }
    )*};
}
as_text!(
    OutputError,
    ExrReadError,
    SettingError,
    PostError,
    ViewError
);

impl From<ExrFault> for String {
    fn from(e: ExrFault) -> String {
        e.to_string()
    }
}
impl From<Error> for String {
    fn from(e: Error) -> String {
        e.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_print_file_line_column_or_just_the_file() {
        let at = Origin {
            file: "a.toml".into(),
            line: 3,
            col: 7,
        };
        assert_eq!(at.error("bad").to_string(), "a.toml:3:7: bad");
        let whole = Origin::file("a.toml").error("bad");
        assert_eq!(Error::from(whole).to_string(), "a.toml: bad");
    }
}
