//! Loaders: each scene format becomes a neutral `SceneDesc`. `Source` is a scene file's
//! text with its name, and maps byte offsets to the lines and columns of `Origin`s.

pub mod builtin;
pub mod defaults;
pub mod gltf;
pub mod include;
pub mod obj;
pub mod ply;
mod text;
pub mod toml;
pub mod usd;
pub mod vdb;

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

/// Scene file formats, told by the file's extension (anything else is TOML).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Toml,
    Obj,
    Ply,
    Gltf,
    Usd,
}

impl Format {
    pub fn of(path: &Path) -> Format {
        let ext = path.extension().map(|e| e.to_ascii_lowercase());
        match ext.as_ref().and_then(|e| e.to_str()) {
            Some("obj") => Format::Obj,
            Some("ply") => Format::Ply,
            Some("gltf" | "glb") => Format::Gltf,
            Some("usd" | "usda" | "usdc" | "usdz") => Format::Usd,
            _ => Format::Toml,
        }
    }
}

/// A scene file of a format other than TOML as its `SceneDesc`, without defaults: what
/// `[[include]]` merges and what `lightpath render model.obj` completes. `at` is where
/// the file was named (an error opening it points there).
pub fn load_file(path: &Path, at: &Origin) -> Result<SceneDesc, SceneError> {
    load_file_with(path, at, &usd::UsdOptions::default())
}

/// [`load_file`], with what the command line tells the USD loader.
pub fn load_file_with(
    path: &Path,
    at: &Origin,
    usd_options: &usd::UsdOptions,
) -> Result<SceneDesc, SceneError> {
    match Format::of(path) {
        Format::Usd => usd::load_scene(path, at, usd_options),
        Format::Obj => obj::load_scene(path, at),
        Format::Ply => ply::load_scene(path, at),
        Format::Gltf => gltf::load_scene(path, at),
        Format::Toml => Err(at.error(format!(
            "{}: only OBJ, PLY, glTF and USD files can be included (.obj, .ply, .gltf, .glb, \
             .usd, .usda, .usdc, .usdz)",
            path.display()
        ))),
    }
}

impl Source {
    /// A scene file; OBJ, PLY and glTF files are read by their loader when parsed (their
    /// `text` stays empty).
    pub fn from_file(path: &Path) -> Result<Source, SceneError> {
        if Format::of(path) != Format::Toml {
            return Ok(Source {
                name: path.display().to_string(),
                text: String::new(),
                dir: path.parent().map(Path::to_path_buf).unwrap_or_default(),
            });
        }
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

    /// The scene description: TOML, or a model file completed with a default camera
    /// and light where it has none (with warnings in `SceneDesc::warnings`).
    pub fn parse(&self) -> Result<SceneDesc, SceneError> {
        self.parse_with(&usd::UsdOptions::default())
    }

    /// [`Source::parse`], with what the command line tells the USD loader (`--frame`,
    /// `--render-settings`).
    pub fn parse_with(&self, usd_options: &usd::UsdOptions) -> Result<SceneDesc, SceneError> {
        let path = Path::new(&self.name);
        match Format::of(path) {
            Format::Toml => toml::load(self),
            _ => {
                let mut desc = load_file_with(path, &Origin::file(&self.name), usd_options)?;
                defaults::complete(&mut desc);
                Ok(desc)
            }
        }
    }
}

/// A built-in scene by name, or else a scene file by path.
pub fn source(name_or_path: &str) -> Result<Source, SceneError> {
    match builtin::source(name_or_path) {
        Some(src) => Ok(src),
        None if !Path::new(name_or_path).exists() => {
            let names = builtin::BUILTIN.map(|(n, _)| n);
            Err(Origin::file(name_or_path).error(format!(
                "no such file, and no built-in scene of that name{} (the built-in scenes: {})",
                crate::suggest::did_you_mean(name_or_path, names),
                names.join(", ")
            )))
        }
        None => Source::from_file(Path::new(name_or_path)),
    }
}
