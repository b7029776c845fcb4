//! What several integration test modules share.

use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Scratch folders of one test binary are told apart by a counter: every module runs in
/// the same process, so the process id alone no longer makes a folder's name unique.
static SCRATCH_COUNT: AtomicUsize = AtomicUsize::new(0);

/// A scratch folder for one test, removed when the test ends, passing or not.
pub struct Scratch(pub PathBuf);

impl Scratch {
    pub fn new(tag: &str) -> Scratch {
        let n = SCRATCH_COUNT.fetch_add(1, Ordering::Relaxed);
        let pid = std::process::id();
        let dir = std::env::temp_dir().join(format!("lightpath-{tag}-{pid}-{n}"));
        std::fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }

    pub fn join(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The position of AOV `name` in a built scene's AOV list (panics naming it if absent).
pub fn index(scene: &lightpath::Scene, name: &str) -> usize {
    scene
        .aovs
        .iter()
        .position(|a| a.name == name)
        .unwrap_or_else(|| panic!("no AOV {name}"))
}
