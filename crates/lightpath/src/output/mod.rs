//! Writing renders: one single-part EXR with every AOV (beauty as R, G, B, A and each AOV
//! as `<name>.R/.G/.B`, the expressions in the header) and a PNG preview of the beauty.
//! Both are written to a temporary file beside the target, then renamed into place, so a
//! crash never leaves a half-written image under the real name.

mod exr;
pub mod naming;
mod png;

pub use self::exr::{
    derived_aovs, read_exr, shadow_matte, software, write_channels, write_exr, write_film,
    write_image, DerivedAov, ExrCompression, ExrContents, ExrHeader, ExrOptions,
};
pub use self::png::{write_png, write_png_rgb};
pub use crate::aov::naming::{channel_names, AOV_ATTRIBUTE_PREFIX};
use std::path::{Path, PathBuf};

fn temp_path(path: &Path) -> PathBuf {
    let mut name = path
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(format!(".tmp-{}", std::process::id()));
    path.with_file_name(name)
}

/// Runs `write` on a temporary path, then renames it to `path`.
pub(crate) fn atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> std::result::Result<(), String>,
) -> std::result::Result<(), String> {
    let tmp = temp_path(path);
    match write(&tmp) {
        Ok(()) => std::fs::rename(&tmp, path).map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            format!("cannot move {} into place: {e}", path.display())
        }),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(e)
        }
    }
}
