//! Files replaced whole or not at all. A file is first written, unnamed, in its target's
//! directory (Linux `O_TMPFILE`: if the process is killed, even by `kill -9`, the
//! kernel frees it and no temporary file is left), flushed to disk (`fsync`), and only
//! then linked under a temporary name and renamed over the target in one step. Where
//! unnamed files are not supported, a named temporary file (`.<name>.tmp-<pid>`) is used;
//! it is registered so that every exit path, an immediate exit on a second Ctrl-C
//! included, removes it ([`remove_temporary_files`]).

use crate::error::OutputError;
use std::fs::File;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Named temporary files in existence, for [`remove_temporary_files`].
static TEMPORARY: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn register(path: &Path) {
    if let Ok(mut t) = TEMPORARY.lock() {
        t.push(path.to_path_buf());
    }
}

fn unregister(path: &Path) {
    if let Ok(mut t) = TEMPORARY.lock() {
        t.retain(|p| p != path);
    }
}

/// Removes every named temporary file this process has not yet renamed into place: for
/// a process about to exit without unwinding (a second interrupt).
pub fn remove_temporary_files() {
    if let Ok(mut t) = TEMPORARY.lock() {
        for p in t.drain(..) {
            let _ = std::fs::remove_file(p);
        }
    }
}

/// A file completely written and synced beside its target, not yet under the target's
/// name. Dropping it without [`Staged::commit`] discards it.
pub struct Staged {
    file: Option<File>,
    target: PathBuf,
    /// The temporary name, when the file has one.
    named: Option<PathBuf>,
}

fn temporary_name(path: &Path) -> PathBuf {
    let mut name = std::ffi::OsString::from(".");
    name.push(path.file_name().unwrap_or_default());
    name.push(format!(".tmp-{}", std::process::id()));
    path.with_file_name(name)
}

fn directory_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// An unnamed file in `dir`, where the system has them.
#[cfg(target_os = "linux")]
fn unnamed_file(dir: &Path) -> Option<File> {
    use std::os::unix::fs::OpenOptionsExt;
    std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .custom_flags(libc::O_TMPFILE)
        .open(dir)
        .ok()
}

#[cfg(not(target_os = "linux"))]
fn unnamed_file(_dir: &Path) -> Option<File> {
    None
}

/// Gives an unnamed file the name `to` (which must not exist).
#[cfg(target_os = "linux")]
fn link_unnamed(file: &File, to: &Path) -> std::io::Result<()> {
    use std::ffi::CString;
    use std::os::unix::ffi::OsStrExt;
    use std::os::unix::io::AsRawFd;
    let from = CString::new(format!("/proc/self/fd/{}", file.as_raw_fd()))?;
    let to = CString::new(to.as_os_str().as_bytes())?;
    // SAFETY: both are valid NUL-terminated strings that outlive the call.
    let r = unsafe {
        libc::linkat(
            libc::AT_FDCWD,
            from.as_ptr(),
            libc::AT_FDCWD,
            to.as_ptr(),
            libc::AT_SYMLINK_FOLLOW,
        )
    };
    if r == 0 {
        Ok(())
    } else {
        Err(std::io::Error::last_os_error())
    }
}

#[cfg(not(target_os = "linux"))]
fn link_unnamed(_file: &File, _to: &Path) -> std::io::Result<()> {
    Err(std::io::Error::other(
        "unnamed files are not supported here",
    ))
}

/// Writes a file for `path` through `write` and syncs it; nothing is visible under
/// `path` until [`Staged::commit`].
pub fn stage(
    path: &Path,
    write: impl FnOnce(&mut File) -> Result<(), OutputError>,
) -> Result<Staged, OutputError> {
    let cannot = |source| OutputError::Write {
        path: path.to_path_buf(),
        source,
    };
    let mut staged = match unnamed_file(&directory_of(path)) {
        Some(file) => Staged {
            file: Some(file),
            target: path.to_path_buf(),
            named: None,
        },
        None => {
            let tmp = temporary_name(path);
            register(&tmp);
            // Registered before it exists: on an error below, dropping `staged` removes
            // whatever was created.
            let mut staged = Staged {
                file: None,
                target: path.to_path_buf(),
                named: Some(tmp.clone()),
            };
            let file = std::fs::OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(true)
                .open(&tmp)
                .map_err(cannot)?;
            staged.file = Some(file);
            staged
        }
    };
    // Set in both arms above.
    let Some(file) = staged.file.as_mut() else {
        return Err(cannot(std::io::Error::other("no file")));
    };
    write(file)?;
    file.sync_all().map_err(cannot)?;
    Ok(staged)
}

impl Staged {
    /// Moves the file under its target's name, replacing what was there in one step.
    pub fn commit(mut self) -> Result<(), OutputError> {
        let target = self.target.clone();
        let cannot = |source| OutputError::Move {
            path: target.clone(),
            source,
        };
        let Some(file) = self.file.take() else {
            return Err(cannot(std::io::Error::other("no file")));
        };
        let tmp = match self.named.clone() {
            Some(tmp) => tmp,
            None => {
                let tmp = temporary_name(&self.target);
                let _ = std::fs::remove_file(&tmp);
                register(&tmp);
                self.named = Some(tmp.clone());
                link_unnamed(&file, &tmp).map_err(cannot)?;
                tmp
            }
        };
        drop(file);
        std::fs::rename(&tmp, &self.target).map_err(cannot)?;
        unregister(&tmp);
        self.named = None;
        // The rename itself reaches the disk with the directory.
        if let Ok(dir) = File::open(directory_of(&self.target)) {
            let _ = dir.sync_all();
        }
        Ok(())
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if let Some(tmp) = self.named.take() {
            let _ = std::fs::remove_file(&tmp);
            unregister(&tmp);
        }
    }
}

/// Writes `path` whole or not at all.
pub fn atomically(
    path: &Path,
    write: impl FnOnce(&mut File) -> Result<(), OutputError>,
) -> Result<(), OutputError> {
    stage(path, write)?.commit()
}

/// Replaces a render's EXR and its PNG preview together: both are written and synced
/// first; then the old preview is removed, the EXR renamed into place, the PNG renamed
/// beside it. Interrupted anywhere, this leaves the old pair, or an EXR without a
/// preview — never an EXR beside the preview of another render.
pub fn commit_pair(exr: Staged, png: Staged) -> Result<(), OutputError> {
    match std::fs::remove_file(&png.target) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(source) => {
            return Err(OutputError::Remove {
                what: "the old preview",
                path: png.target.clone(),
                source,
            })
        }
    }
    exr.commit()?;
    png.commit()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    fn put(f: &mut File, bytes: &[u8], path: &Path) -> Result<(), OutputError> {
        f.write_all(bytes).map_err(|source| OutputError::Write {
            path: path.to_path_buf(),
            source,
        })
    }

    fn scratch(tag: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("lightpath-atomic-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn entries(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn a_staged_file_is_invisible_until_committed_and_leaves_nothing_when_dropped() {
        let dir = scratch("stage");
        let target = dir.join("a.exr");
        std::fs::write(&target, b"old").unwrap();
        let staged = stage(&target, |f| put(f, b"new", &target)).unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"old");
        drop(staged);
        assert_eq!(entries(&dir), vec!["a.exr"]);
        let failed = stage(&target, |_| {
            Err(OutputError::Encode {
                path: target.clone(),
                reason: "no".into(),
            })
        });
        assert!(failed.is_err());
        assert_eq!(entries(&dir), vec!["a.exr"]);
        atomically(&target, |f| put(f, b"new", &target)).unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"new");
        assert_eq!(entries(&dir), vec!["a.exr"]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_pair_is_replaced_together() {
        let dir = scratch("pair");
        let (exr, png) = (dir.join("a.exr"), dir.join("a.png"));
        std::fs::write(&exr, b"old exr").unwrap();
        std::fs::write(&png, b"old png").unwrap();
        let e = stage(&exr, |f| put(f, b"new exr", &exr)).unwrap();
        let p = stage(&png, |f| put(f, b"new png", &png)).unwrap();
        commit_pair(e, p).unwrap();
        assert_eq!(std::fs::read(&exr).unwrap(), b"new exr");
        assert_eq!(std::fs::read(&png).unwrap(), b"new png");
        assert_eq!(entries(&dir), vec!["a.exr", "a.png"]);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
