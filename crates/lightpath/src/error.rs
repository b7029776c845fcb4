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
#[derive(Debug)]
pub enum Error {
    /// A scene that cannot be read, parsed or built; AOV expressions included (their
    /// message shows the expression and where in it).
    Scene(SceneError),
    /// An AOV plan that cannot be made (a malformed `--aov`, a split of an unknown AOV).
    Plan(String),
    /// An output that cannot be written; the message names the file and the OS reason.
    Output(String),
    /// A render setting that cannot be honoured (`spp = 0`, a sample range past 2^32) or
    /// a request above one of the `limits`; checked before rendering.
    Setting(String),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Scene(e) => e.fmt(f),
            Error::Plan(m) | Error::Output(m) | Error::Setting(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::Scene(e) => Some(e),
            Error::Plan(_) | Error::Output(_) | Error::Setting(_) => None,
        }
    }
}

impl From<SceneError> for Error {
    fn from(e: SceneError) -> Error {
        Error::Scene(e)
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
