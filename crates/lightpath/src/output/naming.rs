//! Where a render's files go and what its header says about the render: the library's
//! answer, so the binary only passes its arguments through.

use crate::aov::naming::{FIRST_SAMPLE_ATTRIBUTE, SCENE_ATTRIBUTE, SEED_ATTRIBUTE, SPP_ATTRIBUTE};
use std::path::{Path, PathBuf};

/// The files one render writes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OutputPaths {
    pub exr: PathBuf,
    pub png: PathBuf,
}

/// `output` if given, else `<scene file stem>.exr` in the working directory; the PNG
/// preview always sits beside the EXR.
pub fn output_paths(scene: &str, output: Option<&Path>) -> OutputPaths {
    let exr = match output {
        Some(p) => p.to_path_buf(),
        None => PathBuf::from(
            Path::new(scene)
                .file_stem()
                .map(|s| s.to_os_string())
                .unwrap_or_else(|| "render".into()),
        )
        .with_extension("exr"),
    };
    OutputPaths {
        png: preview_path(&exr),
        exr,
    }
}

/// The PNG preview beside a render's EXR: the EXR's name without its last extension, and
/// without one more (`a.b.exr` → `a.png`), as renders always named it.
pub fn preview_path(exr: &Path) -> PathBuf {
    exr.with_extension("").with_extension("png")
}

/// What a render's header records about how it was made.
#[derive(Clone, Debug)]
pub struct RenderMetadata {
    pub scene: String,
    pub spp: u32,
    pub first_sample: u32,
    pub seed: u64,
}

impl RenderMetadata {
    /// The header attributes (`lightpath/scene`, `spp`, `first_sample`, `seed`).
    pub fn attributes(&self) -> Vec<(String, String)> {
        vec![
            (SCENE_ATTRIBUTE.to_string(), self.scene.clone()),
            (SPP_ATTRIBUTE.to_string(), self.spp.to_string()),
            (
                FIRST_SAMPLE_ATTRIBUTE.to_string(),
                self.first_sample.to_string(),
            ),
            (SEED_ATTRIBUTE.to_string(), self.seed.to_string()),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_output_is_the_scene_stem_with_the_png_beside_it() {
        let p = output_paths("scenes/cornell.toml", None);
        assert_eq!(p.exr, PathBuf::from("cornell.exr"));
        assert_eq!(p.png, PathBuf::from("cornell.png"));
        let p = output_paths("x.toml", Some(Path::new("out/a.b.exr")));
        assert_eq!(p.png, PathBuf::from("out/a.png"));
    }
}
