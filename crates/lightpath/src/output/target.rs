//! Checks on an output path made before the work that fills it: a wrong extension, an
//! input about to be overwritten, a symlink or device that would be replaced by a plain
//! file, a directory that is missing or read-only.

use std::path::{Path, PathBuf};

/// An EXR output must be named `.exr`: `-o x.png` wrote an EXR under a PNG's name, and
/// `comp -o x.png` then wrote its PNG preview over it.
pub fn check_exr_name(exr: &Path, preview: Option<&Path>) -> Result<(), String> {
    let is_exr = exr
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if is_exr {
        return Ok(());
    }
    let beside = preview.map_or(String::new(), |p| {
        format!(
            " (the PNG preview is written beside it, as {})",
            p.display()
        )
    });
    Err(format!(
        "output {}: the output is OpenEXR, so its name must end in .exr{beside}",
        exr.display(),
    ))
}

/// `path` can be written: it is none of `inputs`, it is a regular file or nothing, and
/// its directory exists and takes new files.
pub fn check(path: &Path, inputs: &[&Path]) -> Result<(), String> {
    if let Some(input) = inputs.iter().find(|i| same_file(path, i)) {
        return Err(format!(
            "output {} is the input {}: writing would destroy it",
            path.display(),
            input.display()
        ));
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
pub fn replaceable(path: &Path) -> Result<(), String> {
    match std::fs::symlink_metadata(path) {
        Err(_) => Ok(()),
        Ok(m) if m.file_type().is_file() => Ok(()),
        Ok(m) => {
            let what = if m.file_type().is_symlink() {
                "a symbolic link"
            } else if m.is_dir() {
                "a directory"
            } else {
                "a device, pipe or socket"
            };
            Err(format!(
                "output {} is {what}: outputs replace regular files only; name a file",
                path.display()
            ))
        }
    }
}

/// The directory `path` goes in exists and a file can be created in it.
pub fn writable_dir(path: &Path) -> Result<(), String> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !dir.is_dir() {
        return Err(format!(
            "cannot write {}: the directory {} does not exist",
            path.display(),
            dir.display()
        ));
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
        Err(e) => Err(format!(
            "cannot write {}: cannot create files in {}: {e}",
            path.display(),
            dir.display()
        )),
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
        assert!(e.contains("must end in .exr"), "{e}");
        assert!(check(&dir.join("out.exr"), &[&input]).is_ok());
        let e = check(&dir.join("./scene.toml"), &[&input]).unwrap_err();
        assert!(e.contains("is the input"), "{e}");
        #[cfg(unix)]
        {
            let link = dir.join("link.exr");
            let _ = std::fs::remove_file(&link);
            std::os::unix::fs::symlink(&input, &link).unwrap();
            let e = check(&link, &[]).unwrap_err();
            assert!(e.contains("symbolic link"), "{e}");
            let e = check(Path::new("/dev/null"), &[]).unwrap_err();
            assert!(e.contains("device"), "{e}");
        }
        let e = check(&dir.join("missing/out.exr"), &[]).unwrap_err();
        assert!(e.contains("does not exist"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
