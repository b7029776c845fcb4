//! The library's error type. Every scene error carries where it was written
//! (`file:line:col`, or just the file), and prints as `file:line:col: message`.

use crate::scene::desc::Origin;
use std::fmt;

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
    #[error("{0}")]
    Output(String),
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
    #[error("{0}")]
    Post(String),
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
