//! Loaders: each scene format becomes a neutral `SceneDesc`. `Source` is a scene file's
//! text with its name, and maps byte offsets to the lines and columns of `Origin`s.

pub mod builtin;
pub mod gltf;
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
        // A glTF file is read (text or binary) by its own loader when parsed.
        if gltf::is_gltf(path) {
            return Ok(Source {
                name: path.display().to_string(),
                text: String::new(),
                dir: path.parent().map(Path::to_path_buf).unwrap_or_default(),
            });
        }
        let text = std::fs::read_to_string(path).map_err(|e| {
            Origin::file(path.display().to_string())
                .error(format!("cannot read the scene file: {e}"))
        })?;
        Ok(Source {
            name: path.display().to_string(),
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

    /// The scene description: glTF (`.gltf`, `.glb`) or TOML.
    pub fn parse(&self) -> Result<SceneDesc, SceneError> {
        let path = Path::new(&self.name);
        if gltf::is_gltf(path) {
            return gltf::load(path);
        }
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
