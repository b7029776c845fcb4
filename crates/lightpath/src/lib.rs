//! # Lightpath
//!
//! A CPU path tracer whose every AOV is a Light Path Expression. The data flow is the
//! module list: `scene` (description → built scene with LPE-classified events) →
//! `integrator` (paths, one automaton step per vertex) → `film` → `output`.

pub mod aov;
pub mod camera;
pub mod comp;
pub mod film;
pub mod geometry;
pub mod integrator;
pub mod light;
pub mod material;
pub mod output;
pub mod progress;
pub mod sampler;
pub mod sampling;
pub mod scene;

pub use integrator::{render, render_with_progress, RenderOptions, RenderStats};
pub use scene::{Scene, SceneError, Source};

/// Loads a built-in scene by name or a scene file by path.
pub fn load_source(scene: &str) -> Result<Source, SceneError> {
    if let Some(text) = scene::builtin::get(scene) {
        return Ok(Source {
            name: format!("builtin:{scene}"),
            text: text.to_string(),
            dir: std::path::PathBuf::new(),
        });
    }
    Source::from_file(std::path::Path::new(scene))
}
