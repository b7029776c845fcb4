//! # Lightpath
//!
//! A CPU path tracer whose every AOV is a Light Path Expression. The data flow is the
//! module list: `scene` (description → built scene with LPE-classified events) →
//! `integrator` (paths, one automaton step per vertex) → `film` → `output`.

pub mod aov;
pub mod camera;
pub mod checkpoint;
pub mod error;
pub mod events;
pub mod farm;
pub mod film;
pub mod geometry;
pub mod guiding;
pub mod identity;
pub mod integrator;
pub mod interrupt;
pub mod job;
pub mod light;
pub mod limits;
pub mod lpe_tools;
pub mod material;
pub mod media;
pub mod output;
pub mod post;
pub mod progress;
pub mod sampler;
pub mod sampling;
pub mod scene;
pub mod settings;
pub mod suggest;
pub mod view;

pub use error::Error;
pub use integrator::{
    render, render_resumable, render_with_progress, RenderOptions, RenderStats, Rendered, Resumable,
};
pub use job::RenderJob;
pub use scene::{Scene, SceneError, Source};

/// Loads a built-in scene by name or a scene file by path.
pub fn load_source(scene: &str) -> Result<Source, SceneError> {
    scene::load::source(scene)
}

/// Loads and parses a built-in scene by name or a scene file by path.
pub fn load_scene(name_or_path: &str) -> Result<scene::desc::SceneDesc, Error> {
    Ok(load_source(name_or_path)?.parse()?)
}
