//! Loaders: each scene format becomes a neutral `SceneDesc`. `Source` is a scene file's
//! text with its name, and maps byte offsets to the lines and columns of `Origin`s.

pub mod builtin;
pub mod obj;
pub mod toml;

use super::desc::{Origin, SceneDesc};
use super::SceneError;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// A scene file's text.
pub struct Source {
    pub name: String,
    pub text: String,
    /// Directory that relative paths in the file are resolved against.
    pub dir: PathBuf,
}

impl Source {
    pub fn from_file(path: &Path) -> Result<Source, SceneError> {
        let name = path.display().to_string();
        let bytes = crate::limits::read_input(path)
            .map_err(|e| Origin::file(&name).error(format!("cannot read the scene file: {e}")))?;
        let text = String::from_utf8(bytes).map_err(|e| {
            let valid = &e.as_bytes()[..e.utf8_error().valid_up_to()];
            let line = valid.iter().filter(|&&b| b == b'\n').count() + 1;
            let line_start = valid.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
            let col = String::from_utf8_lossy(&valid[line_start..])
                .chars()
                .count()
                + 1;
            Origin {
                file: name.clone(),
                line,
                col,
            }
            .error("invalid UTF-8: a scene file is UTF-8 text")
        })?;
        Ok(Source {
            name,
            text,
            dir: path.parent().map(Path::to_path_buf).unwrap_or_default(),
        })
    }

    /// Where a byte span starts (None: the whole file).
    pub fn origin(&self, span: Option<Range<usize>>) -> Origin {
        let (line, col) = match span {
            Some(r) => {
                let at = r.start.min(self.text.len());
                let before = &self.text[..at];
                let line = before.matches('\n').count() + 1;
                let column = before.rfind('\n').map_or(at, |i| at - i - 1) + 1;
                (line, column)
            }
            None => (0, 0),
        };
        Origin {
            file: self.name.clone(),
            line,
            col,
        }
    }

    pub fn error(&self, span: Option<Range<usize>>, message: impl Into<String>) -> SceneError {
        self.origin(span).error(message)
    }

    /// The scene description (TOML).
    pub fn parse(&self) -> Result<SceneDesc, SceneError> {
        toml::load(self)
    }
}

/// A built-in scene by name, or else a scene file by path.
pub fn source(name_or_path: &str) -> Result<Source, SceneError> {
    match builtin::source(name_or_path) {
        Some(src) => Ok(src),
        None => Source::from_file(Path::new(name_or_path)),
    }
}
