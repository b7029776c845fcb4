//! Checks on an output path made before the work that fills it: a wrong extension, an
//! input about to be overwritten, a symlink or device that would be replaced by a plain
//! file, a directory that is missing or read-only.

use crate::error::OutputError;
use std::path::{Path, PathBuf};

/// An EXR output must be named `.exr`: `-o x.png` wrote an EXR under a PNG's name, and
/// `comp -o x.png` then wrote its PNG preview over it.
pub fn check_exr_name(exr: &Path, preview: Option<&Path>) -> Result<(), OutputError> {
    let is_exr = exr
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if is_exr {
        return Ok(());
    }
    Err(OutputError::NotExr {
        path: exr.to_path_buf(),
        preview: preview.map(Path::to_path_buf),
    })
}

/// `path` can be written: it is none of `inputs`, it is a regular file or nothing, and
/// its directory exists and takes new files.
pub fn check(path: &Path, inputs: &[&Path]) -> Result<(), OutputError> {
    if let Some(input) = inputs.iter().find(|i| same_file(path, i)) {
        return Err(OutputError::IsInput {
            path: path.to_path_buf(),
            input: input.to_path_buf(),
        });
    }
    replaceable(path)?;
    writable_dir(path)
}

/// Whether two paths name the same existing file (through links and `..`).
pub fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
}

/// An output may replace a regular file or nothing: a symlink, a device or a directory
/// under that name would be replaced by a plain file (or fail only after the work).
pub fn replaceable(path: &Path) -> Result<(), OutputError> {
    match std::fs::symlink_metadata(path) {
        Err(_) => Ok(()),
        Ok(m) if m.file_type().is_file() => Ok(()),
        Ok(m) => {
            let kind = if m.file_type().is_symlink() {
                "a symbolic link"
            } else if m.is_dir() {
                "a directory"
            } else {
                "a device, pipe or socket"
            };
            Err(OutputError::NotRegular {
                path: path.to_path_buf(),
                kind,
            })
        }
    }
}

/// The directory `path` goes in exists and a file can be created in it.
pub fn writable_dir(path: &Path) -> Result<(), OutputError> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !dir.is_dir() {
        return Err(OutputError::NoDirectory {
            path: path.to_path_buf(),
            dir,
        });
    }
    let probe = dir.join(format!(".lightpath-probe-{}", std::process::id()));
    match std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
    {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(source) => Err(OutputError::DirectoryNotWritable {
            path: path.to_path_buf(),
            dir,
            source,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_inputs_links_and_missing_directories_are_refused() {
        let dir = std::env::temp_dir().join(format!("lightpath-target-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let input = dir.join("scene.toml");
        std::fs::write(&input, "x").unwrap();
        assert!(check_exr_name(Path::new("a.EXR"), None).is_ok());
        let e = check_exr_name(Path::new("a.png"), Some(Path::new("a.png"))).unwrap_err();
        assert!(matches!(e, OutputError::NotExr { .. }), "{e}");
        assert!(e.to_string().contains("must end in .exr"), "{e}");
        assert!(check(&dir.join("out.exr"), &[&input]).is_ok());
        let e = check(&dir.join("./scene.toml"), &[&input]).unwrap_err();
        assert!(
            matches!(&e, OutputError::IsInput { input: i, .. } if *i == input),
            "{e}"
        );
        #[cfg(unix)]
        {
            let link = dir.join("link.exr");
            let _ = std::fs::remove_file(&link);
            std::os::unix::fs::symlink(&input, &link).unwrap();
            let e = check(&link, &[]).unwrap_err();
            assert!(e.to_string().contains("symbolic link"), "{e}");
            let e = check(Path::new("/dev/null"), &[]).unwrap_err();
            assert!(e.to_string().contains("device"), "{e}");
        }
        let e = check(&dir.join("missing/out.exr"), &[]).unwrap_err();
        assert!(
            matches!(&e, OutputError::NoDirectory { dir: d, .. } if *d == dir.join("missing")),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
