//! Whether two renders are of the same scene, the question `merge` and `--resume` ask.
//! A render's identity is one hash of everything that decides its pixels:
//!
//! - every file it read, as it read it: the scene file, included files, OBJ and MTL, PLY,
//!   glTF with its buffers and images, textures and dome maps. Loaders read input files
//!   through one function, [`crate::limits::read_input`], which notes each file in the
//!   [`Recording`] the render job holds open while it loads and builds the scene; a new
//!   loader (USD layers, VDB grids) that reads through it is covered with no more code.
//! - the settings that decide what a pixel converges to, or which samples a part holds
//!   ([`settings`]); not the sample count, the first sample or the crop, in which the
//!   parts of one frame differ by design.
//!
//! The EXR header carries the hash (`lightpath/identity`) and the manifest of inputs
//! (`lightpath/inputs`: each file's path relative to the scene's folder and its own
//! hash), and a checkpoint carries both with the settings, so a refusal names the file or
//! the setting that changed (docs/farm.md).

use crate::scene::desc::SceneDesc;
use std::cell::RefCell;
use std::path::{Component, Path, PathBuf};

/// FNV-1a, 64 bits: the crate's one content hash (identities, checkpoint checksums).
/// It is stable across machines, builds and versions, unlike `std`'s hasher, and needs
/// no dependency; it hashes about a gigabyte a second, far below what decoding the same
/// images and meshes takes.
#[derive(Clone, Copy, Debug)]
pub struct Fnv64(u64);

impl Default for Fnv64 {
    fn default() -> Self {
        Fnv64(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv64 {
    pub fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= b as u64;
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }

    /// A field of a record: its bytes, then its length, so that `("ab", "c")` and
    /// `("a", "bc")` hash differently.
    pub fn write_field(&mut self, bytes: &[u8]) {
        self.write(bytes);
        self.write(&(bytes.len() as u64).to_le_bytes());
    }

    pub fn finish(&self) -> u64 {
        self.0
    }
}

/// The hash of one byte string.
pub fn hash(bytes: &[u8]) -> u64 {
    let mut h = Fnv64::default();
    h.write(bytes);
    h.finish()
}

/// A file read while a [`Recording`] was open: where, and the hash of what was read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FileRead {
    pub path: PathBuf,
    pub hash: u64,
}

thread_local! {
    /// The recordings open on this thread, innermost last. Scenes are loaded and built
    /// on the thread that asked for them (the parallel parts of a build trace no files).
    static OPEN: RefCell<Vec<Vec<FileRead>>> = const { RefCell::new(Vec::new()) };
}

/// The files this thread reads from [`Recording::start`] until [`Recording::finish`]
/// (or until it is dropped, on an early return).
#[must_use = "a recording collects the files read until it is finished"]
pub struct Recording {
    depth: usize,
    /// Recordings are per thread: a recording may not move to another one.
    _thread: std::marker::PhantomData<*const ()>,
}

impl Recording {
    pub fn start() -> Recording {
        let depth = OPEN.with(|open| {
            let mut open = open.borrow_mut();
            open.push(Vec::new());
            open.len()
        });
        Recording {
            depth,
            _thread: std::marker::PhantomData,
        }
    }

    /// The files read since the start, in the order they were read.
    pub fn finish(self) -> Vec<FileRead> {
        let reads = OPEN.with(|open| {
            let mut open = open.borrow_mut();
            let reads = open.get_mut(self.depth - 1).map(std::mem::take);
            open.truncate(self.depth - 1);
            reads
        });
        std::mem::forget(self);
        reads.unwrap_or_default()
    }
}

impl Drop for Recording {
    fn drop(&mut self) {
        // Drop can run while the thread's storage is being torn down: then there is
        // nothing left to close.
        let _ = OPEN.try_with(|open| open.borrow_mut().truncate(self.depth - 1));
    }
}

/// Notes that `path` was read and held `bytes`, in every recording open on this thread
/// (nothing is hashed when none is).
pub fn note_read(path: &Path, bytes: &[u8]) {
    OPEN.with(|open| {
        let mut open = open.borrow_mut();
        if open.is_empty() {
            return;
        }
        let read = FileRead {
            path: path.to_path_buf(),
            hash: hash(bytes),
        };
        for recording in open.iter_mut() {
            recording.push(read.clone());
        }
    });
}

/// One input of a render: its path relative to the scene's folder (`/`-separated) and
/// the hash of its bytes.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct Input {
    pub path: String,
    pub hash: u64,
}

/// What decides a render's pixels, and its hash.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Identity {
    pub hash: u64,
    /// Sorted by path, each path once.
    pub inputs: Vec<Input>,
    /// `(name, value)` of each identity setting, in [`settings`]' order.
    pub settings: Vec<(String, String)>,
}

impl Identity {
    /// The identity of a render of the scene in `scene_dir` that read `reads` (paths are
    /// kept relative to the scene's folder, so the parts of a frame agree wherever the
    /// scene lies on each machine).
    pub fn new(scene_dir: &Path, reads: &[FileRead], settings: Vec<(String, String)>) -> Self {
        let mut inputs: Vec<Input> = reads
            .iter()
            .map(|r| Input {
                path: relative_path(scene_dir, &r.path),
                hash: r.hash,
            })
            .collect();
        inputs.sort();
        // A file read twice (an image two materials share) counts once, as first read.
        inputs.dedup_by(|b, a| a.path == b.path);
        let mut h = Fnv64::default();
        for i in &inputs {
            h.write_field(i.path.as_bytes());
            h.write(&i.hash.to_le_bytes());
        }
        for (name, value) in &settings {
            h.write_field(name.as_bytes());
            h.write_field(value.as_bytes());
        }
        Identity {
            hash: h.finish(),
            inputs,
            settings,
        }
    }

    /// The hash as the header writes it: 16 hex digits.
    pub fn hash_text(&self) -> String {
        format!("{:016x}", self.hash)
    }

    /// The manifest of inputs: one line per file, `<hash> <path>`, by path.
    pub fn manifest(&self) -> String {
        format_manifest(&self.inputs)
    }

    /// The whole identity as text (a checkpoint stores it): the manifest's lines, then
    /// one `setting <name>=<value>` line per setting.
    pub fn to_text(&self) -> String {
        let mut text = self.manifest();
        for (name, value) in &self.settings {
            text.push_str(&format!("setting {name}={value}\n"));
        }
        text
    }

    /// An identity written by [`Identity::to_text`] with its hash; `None` if the text is
    /// not one.
    pub fn from_text(hash: u64, text: &str) -> Option<Identity> {
        let mut inputs = Vec::new();
        let mut settings = Vec::new();
        for line in text.lines() {
            match line.strip_prefix("setting ") {
                Some(s) => {
                    let (name, value) = s.split_once('=')?;
                    settings.push((name.to_string(), value.to_string()));
                }
                None => inputs.push(parse_manifest_line(line)?),
            }
        }
        Some(Identity {
            hash,
            inputs,
            settings,
        })
    }

    /// What differs from an `earlier` render's identity: each input that changed, is new
    /// or is no longer read, then each setting that differs. Empty if only the hashes
    /// differ (an identity from another version of Lightpath).
    pub fn changes_since(&self, earlier: &Identity) -> Vec<String> {
        let mut out = input_changes(&earlier.inputs, &self.inputs);
        for (name, value) in &self.settings {
            match earlier.settings.iter().find(|(n, _)| n == name) {
                Some((_, was)) if was != value => {
                    out.push(format!("the setting {name} was {was} and is now {value}"))
                }
                None => out.push(format!("the setting {name} is new ({value})")),
                _ => {}
            }
        }
        out
    }
}

/// `<hash> <path>` lines, one per input.
fn format_manifest(inputs: &[Input]) -> String {
    inputs
        .iter()
        .map(|i| format!("{:016x} {}\n", i.hash, i.path))
        .collect()
}

fn parse_manifest_line(line: &str) -> Option<Input> {
    let (hash, path) = line.split_once(' ')?;
    Some(Input {
        path: path.to_string(),
        hash: u64::from_str_radix(hash, 16).ok()?,
    })
}

/// A manifest as the header's `lightpath/inputs` holds it; `None` if it is not one.
pub fn parse_manifest(text: &str) -> Option<Vec<Input>> {
    text.lines().map(parse_manifest_line).collect()
}

/// How the inputs `now` differ from those read `earlier`, one phrase per file, naming it.
pub fn input_changes(earlier: &[Input], now: &[Input]) -> Vec<String> {
    let mut out = Vec::new();
    for i in now {
        match earlier.iter().find(|e| e.path == i.path) {
            Some(e) if e.hash != i.hash => out.push(format!(
                "{} changed (its content hashed {:016x}, now {:016x})",
                i.path, e.hash, i.hash
            )),
            None => out.push(format!("{} is read now but was not before", i.path)),
            _ => {}
        }
    }
    for e in earlier {
        if !now.iter().any(|i| i.path == e.path) {
            out.push(format!("{} was read before but is not now", e.path));
        }
    }
    out
}

/// `path` relative to `dir` when it lies under it (as the loaders join them), with `/`
/// separators and no `.` components; otherwise as it is.
fn relative_path(dir: &Path, path: &Path) -> String {
    let rel = match dir.as_os_str().is_empty() {
        true => path,
        false => path.strip_prefix(dir).unwrap_or(path),
    };
    let mut parts: Vec<String> = Vec::new();
    for c in rel.components() {
        match c {
            Component::CurDir => {}
            Component::RootDir => parts.push(String::new()),
            Component::Prefix(p) => parts.push(p.as_os_str().to_string_lossy().into_owned()),
            Component::ParentDir => parts.push("..".into()),
            Component::Normal(s) => parts.push(s.to_string_lossy().into_owned()),
        }
    }
    match parts.as_slice() {
        [root] if root.is_empty() => "/".into(),
        _ => parts.join("/"),
    }
}

/// The render settings that are part of a render's identity, as `(name, value)`, from
/// the scene description after the command line's overrides and the camera chosen
/// (`--camera`). Two kinds:
///
/// - what a pixel converges to: the depth limits, the clamps, path regularisation, the
///   pixel filter, the resolution and the camera;
/// - which numbers each sample index gets and how samples are spent: the seed, the
///   sampler, light selection, Russian roulette's depth and adaptive sampling. These
///   change only the noise, but the parts of a frame must share them: a part's sample
///   range means those sample indices of this sequence, so parts made with another
///   seed would merge into an image no single render makes (and a resumed render would
///   mix two), where the split is meant to be exact (docs/farm.md).
///
/// Not the sample count, the first sample or the crop (parts differ in them by design),
/// nor the ray tracing backend (`--accel`: the same rays, the same hits).
pub fn settings(desc: &SceneDesc, camera: Option<&str>) -> Vec<(String, String)> {
    use crate::settings::{Role, SETTINGS};
    // The camera a file names that the render looks through (its first, unless told),
    // or the scene's only camera.
    let camera = camera
        .or(desc.cameras.first().map(|c| c.name.as_str()))
        .unwrap_or("default");
    let mut out = vec![("camera".to_string(), camera.to_string())];
    out.extend(
        SETTINGS
            .iter()
            .filter(|s| s.role != Role::PerPart)
            .map(|s| (s.key.to_string(), (s.show)(&desc.render))),
    );
    out.sort();
    out
}

/// The header attribute of an identity setting: `lightpath/setting/<name>`, except the
/// seed's, `lightpath/seed`, as renders have always written it.
pub fn setting_attribute(name: &str) -> String {
    use crate::aov::naming;
    match name {
        "seed" => naming::SEED_ATTRIBUTE.to_string(),
        _ => naming::setting_attribute(name),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fnv_matches_its_reference_values() {
        assert_eq!(hash(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(hash(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(hash(b"foobar"), 0x8594_4171_f739_67e8);
        let field = |parts: &[&[u8]]| {
            let mut h = Fnv64::default();
            parts.iter().for_each(|p| h.write_field(p));
            h.finish()
        };
        assert_ne!(field(&[b"ab", b"c"]), field(&[b"a", b"bc"]));
    }

    #[test]
    fn a_recording_notes_the_files_read_on_its_thread_until_it_ends() {
        note_read(Path::new("before.obj"), b"x");
        let outer = Recording::start();
        note_read(Path::new("scenes/a.toml"), b"a");
        {
            let inner = Recording::start();
            note_read(Path::new("scenes/tex/b.png"), b"b");
            // Another thread's reads are its own.
            std::thread::spawn(|| note_read(Path::new("elsewhere"), b"c"))
                .join()
                .unwrap();
            let reads = inner.finish();
            assert_eq!(reads.len(), 1);
            assert_eq!(reads[0].hash, hash(b"b"));
        }
        // A recording dropped on an early return closes.
        drop(Recording::start());
        note_read(Path::new("scenes/./tex/b.png"), b"b");
        let reads = outer.finish();
        let paths: Vec<&Path> = reads.iter().map(|r| r.path.as_path()).collect();
        assert_eq!(
            paths,
            [
                Path::new("scenes/a.toml"),
                Path::new("scenes/tex/b.png"),
                Path::new("scenes/./tex/b.png")
            ]
        );
        let id = Identity::new(
            Path::new("scenes"),
            &reads,
            vec![("seed".into(), "0".into())],
        );
        let paths: Vec<&str> = id.inputs.iter().map(|i| i.path.as_str()).collect();
        assert_eq!(paths, ["a.toml", "tex/b.png"]);
        assert_eq!(
            Identity::from_text(id.hash, &id.to_text()),
            Some(id.clone())
        );
        assert_eq!(parse_manifest(&id.manifest()), Some(id.inputs.clone()));
    }

    #[test]
    fn the_identity_moves_with_each_file_and_setting_and_names_what_changed() {
        let read = |path: &str, bytes: &[u8]| FileRead {
            path: PathBuf::from(path),
            hash: hash(bytes),
        };
        let settings = |depth: &str| vec![("max_depth".to_string(), depth.to_string())];
        let base = [read("/a/s.gltf", b"{}"), read("/a/s.bin", b"\0")];
        let id = Identity::new(Path::new("/a"), &base, settings("8"));
        // The same scene in another folder is the same scene.
        let moved = [read("/b/s.gltf", b"{}"), read("/b/s.bin", b"\0")];
        assert_eq!(Identity::new(Path::new("/b"), &moved, settings("8")), id);
        let edited = [read("/a/s.gltf", b"{ }"), read("/a/s.bin", b"\0")];
        let e = Identity::new(Path::new("/a"), &edited, settings("8"));
        assert_ne!(e.hash, id.hash);
        let changes = e.changes_since(&id);
        assert_eq!(changes.len(), 1);
        assert!(changes[0].starts_with("s.gltf changed"), "{changes:?}");
        let deeper = Identity::new(Path::new("/a"), &base, settings("3"));
        assert_ne!(deeper.hash, id.hash);
        assert_eq!(
            deeper.changes_since(&id),
            ["the setting max_depth was 8 and is now 3"]
        );
        let fewer = Identity::new(Path::new("/a"), &base[..1], settings("8"));
        assert_eq!(
            fewer.changes_since(&id),
            ["s.bin was read before but is not now"]
        );
        assert_eq!(
            relative_path(Path::new("s"), Path::new("s/../t/x.png")),
            "../t/x.png"
        );
        assert_eq!(
            relative_path(Path::new("s"), Path::new("/abs/x.png")),
            "/abs/x.png"
        );
        assert_eq!(relative_path(Path::new(""), Path::new("x.toml")), "x.toml");
    }
}
