//! Checkpoints of a render in progress: the film's exact accumulators and which rows are
//! finished, beside the output (`shot.exr` → `shot.exr.checkpoint`). `render … --resume`
//! loads one and renders only the rows still missing; every sample is seeded by (seed,
//! pixel, sample index) and a row's sums start from zero, so the finished image is
//! bit for bit the uninterrupted render's.
//!
//! An adaptive render (`integrator/adaptive.rs`) also needs its pass, each pixel's sample
//! count and the pilot pass's luminance moments, from which its second pass's targets
//! are computed: a resumed render computes the same targets and continues each pixel
//! from the same sums.
//!
//! A checkpoint is resumed only by the render that wrote it: the same scene (its
//! identity, `identity.rs`: every file read and the identity settings) and the same job
//! (the job's fingerprint: sample range, window, AOVs). When the scene changed, the error
//! names the file or setting that did, and the job may start over instead
//! (`--restart-if-changed`).
//!
//! The format (little-endian): `LPCKPT03`, the identity's hash and the job's fingerprint
//! (u64 each), the identity as text (its length as u32, then UTF-8: `Identity::to_text`),
//! width, height, planes, spp (u32 each), the pass (u8: 0 not adaptive, 1 the pilot, 2
//! the second pass), one byte per row (1: finished in that pass), every plane's
//! `width × height` f32 sums; if adaptive, each pixel's sample count (u32) and then its
//! pilot's sum and sum of squares (f64 each); then an FNV-1a checksum (u64) of all that
//! precedes it. Earlier versions (`LPCKPT01`, `02`: no identity) are refused with a
//! message.

use crate::film::Film;
use crate::identity::{Fnv64, Identity};
use crate::integrator::adaptive::Pilot;
use crate::integrator::Snapshot;
use crate::output::atomic;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 8] = b"LPCKPT04";

/// What every version's magic starts with.
const MAGIC_FAMILY: &[u8; 6] = b"LPCKPT";

/// A film with the rows it holds finished.
#[derive(Debug)]
pub struct Checkpoint {
    pub film: Film,
    /// One entry per row: is it complete (in the current pass, if adaptive)?
    pub rows_done: Vec<bool>,
    /// An adaptive render's pilot pass.
    pub pilot: Option<Pilot>,
    /// Light tracing's splat sums, which `film` does not hold (film/splats.rs).
    pub splats: Option<Vec<i64>>,
}

/// The pass byte of a checkpoint.
fn pass_byte(pilot: Option<&Pilot>) -> u8 {
    match pilot {
        None => 0,
        Some(p) if !p.complete => 1,
        Some(_) => 2,
    }
}

/// Where the checkpoint of a render writing `exr` lives.
pub fn path_for(exr: &Path) -> PathBuf {
    let mut name = exr.as_os_str().to_os_string();
    name.push(".checkpoint");
    PathBuf::from(name)
}

/// The job's fingerprint: a hash of byte strings, each delimited by its length.
pub fn fingerprint(parts: &[&[u8]]) -> u64 {
    let mut h = Fnv64::default();
    for p in parts {
        h.write_field(p);
    }
    h.finish()
}

/// Which render a checkpoint belongs to.
#[derive(Clone, Copy, Debug)]
pub struct Stamp<'a> {
    /// What the render read and the settings that decide its pixels.
    pub identity: &'a Identity,
    /// The rest of the job: sample range, window, AOVs (`job.rs`).
    pub fingerprint: u64,
}

/// Why a checkpoint cannot be resumed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CheckpointError {
    /// It was written by a render of the scene before an edit: what changed, one phrase
    /// per file or setting.
    SceneChanged { path: PathBuf, changes: Vec<String> },
    /// Another job, another version, damage: the message says which.
    Unusable(String),
}

impl std::fmt::Display for CheckpointError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CheckpointError::SceneChanged { path, changes } => {
                let what = match changes.is_empty() {
                    true => "its identity differs (written by another version?)".to_string(),
                    false => changes.join("; "),
                };
                write!(
                    f,
                    "checkpoint {}: the scene changed since it was written: {what}; render \
                     without --resume to start over (or add --restart-if-changed to start \
                     over whenever the scene changed)",
                    path.display()
                )
            }
            CheckpointError::Unusable(why) => f.write_str(why),
        }
    }
}

/// Writes the checkpoint of `snapshot` atomically (synced before it replaces the previous
/// one).
pub fn write(
    path: &Path,
    stamp: Stamp,
    snapshot: &Snapshot,
) -> Result<(), crate::error::OutputError> {
    let Snapshot {
        film,
        rows_done,
        pilot,
        splats,
    } = *snapshot;
    atomic::atomically(path, |file| {
        let mut out = Summed {
            out: BufWriter::with_capacity(1 << 20, file),
            sum: Fnv64::default(),
        };
        let io = (|| -> std::io::Result<()> {
            out.put(MAGIC)?;
            out.put(&stamp.identity.hash.to_le_bytes())?;
            out.put(&stamp.fingerprint.to_le_bytes())?;
            let identity = stamp.identity.to_text();
            out.put(&(identity.len() as u32).to_le_bytes())?;
            out.put(identity.as_bytes())?;
            for v in [film.width, film.height, film.planes.len() as u32, film.spp] {
                out.put(&v.to_le_bytes())?;
            }
            out.put(&[pass_byte(pilot)])?;
            let rows: Vec<u8> = rows_done.iter().map(|&d| d as u8).collect();
            out.put(&rows)?;
            let row = film.width.max(1) as usize;
            let mut chunk = Vec::with_capacity(16 * row);
            for plane in &film.planes {
                for values in plane.chunks(row) {
                    chunk.clear();
                    chunk.extend(values.iter().flat_map(|v| v.to_le_bytes()));
                    out.put(&chunk)?;
                }
            }
            if let Some(pilot) = pilot {
                let pixels = film.width as usize * film.height as usize;
                for i in 0..pixels {
                    out.put(&film.samples_at(i).to_le_bytes())?;
                }
                for sums in pilot.sums.chunks(row) {
                    chunk.clear();
                    chunk.extend(sums.iter().flatten().flat_map(|v| v.to_le_bytes()));
                    out.put(&chunk)?;
                }
            }
            // Light tracing's splats: a count (0 without), then the sums.
            let units = splats.map(|s| s.units()).unwrap_or_default();
            out.put(&(units.len() as u64).to_le_bytes())?;
            for values in units.chunks(4 * row) {
                chunk.clear();
                chunk.extend(values.iter().flat_map(|v| v.to_le_bytes()));
                out.put(&chunk)?;
            }
            let total = out.sum.finish();
            out.out.write_all(&total.to_le_bytes())?;
            out.out.flush()
        })();
        io.map_err(|source| crate::error::OutputError::Checkpoint {
            path: path.to_path_buf(),
            source,
        })
    })
}

/// A writer that checksums what goes through it.
struct Summed<W: Write> {
    out: W,
    sum: Fnv64,
}

impl<W: Write> Summed<W> {
    fn put(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.sum.write(bytes);
        self.out.write_all(bytes)
    }
}

/// The film a checkpoint must hold: its size, AOV count, spp, the AOVs whose squared
/// samples it sums (`--variance`), and whether the render is adaptive.
#[derive(Clone, Debug)]
pub struct FilmShape {
    pub width: u32,
    pub height: u32,
    pub aovs: usize,
    pub spp: u32,
    pub squared: Vec<u32>,
    pub adaptive: bool,
}

/// Reads a checkpoint for a render whose film is `shape`, stamped `stamp`; anything else
/// is an error naming the difference (for another scene, each file or setting that
/// changed).
pub fn read(path: &Path, stamp: Stamp, shape: FilmShape) -> Result<Checkpoint, CheckpointError> {
    let bad =
        |what: &str| CheckpointError::Unusable(format!("checkpoint {}: {what}", path.display()));
    let bytes = crate::limits::read_input(path).map_err(|e| bad(&e.to_string()))?;
    if bytes.len() >= 8 && bytes[..6] == MAGIC_FAMILY[..] && bytes[..8] != MAGIC[..] {
        return Err(bad(&format!(
            "it was written by another version of Lightpath (format {}; this one reads {}): \
             render again without --resume",
            String::from_utf8_lossy(&bytes[..8]),
            String::from_utf8_lossy(MAGIC)
        )));
    }
    if bytes.len() < IDENTITY_TEXT + 8 || &bytes[..8] != MAGIC {
        return Err(bad("not a Lightpath checkpoint"));
    }
    // The checksum first: nothing below reads a damaged file.
    let (body, stored) = bytes.split_at(bytes.len() - 8);
    let mut sum = Fnv64::default();
    sum.write(body);
    if u64_at(stored, 0) != sum.finish() {
        return Err(bad("its checksum does not match: the file is damaged"));
    }
    let text_end = IDENTITY_TEXT
        .checked_add(u32_at(body, IDENTITY_TEXT - 4) as usize)
        .filter(|&end| end <= body.len())
        .ok_or_else(|| bad("its identity overruns the file"))?;
    let identity = u64_at(body, 8);
    if identity != stamp.identity.hash {
        let earlier = std::str::from_utf8(&body[IDENTITY_TEXT..text_end])
            .ok()
            .and_then(|text| Identity::from_text(identity, text));
        return Err(CheckpointError::SceneChanged {
            path: path.to_path_buf(),
            changes: earlier.map_or_else(Vec::new, |e| stamp.identity.changes_since(&e)),
        });
    }
    if u64_at(body, 16) != stamp.fingerprint {
        return Err(bad(
            "it was made by a different render of this scene (another spp, sample range, crop \
             or AOV set): run the command that was interrupted, with --resume",
        ));
    }
    film_of(&body[text_end..], shape).ok_or_else(|| {
        bad("its size does not match this render (truncated or from another version)")
    })
}

/// Where the identity's text starts: after the magic, the identity's hash, the job's
/// fingerprint and the text's length.
const IDENTITY_TEXT: usize = 8 + 8 + 8 + 4;

fn u32_at(bytes: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]])
}

fn u64_at(bytes: &[u8], at: usize) -> u64 {
    let mut v = [0u8; 8];
    v.copy_from_slice(&bytes[at..at + 8]);
    u64::from_le_bytes(v)
}

/// The film, rows and pilot a checkpoint's data holds (after its identity, before its
/// checksum); `None` if they are not of `shape`.
fn film_of(data: &[u8], shape: FilmShape) -> Option<Checkpoint> {
    let FilmShape {
        width,
        height,
        aovs,
        spp,
        squared,
        adaptive,
    } = shape;
    let planes = Film::stride_with(aovs, squared.len());
    let pixels = width as usize * height as usize;
    let header = 16 + 1;
    let adaptive_bytes = if adaptive { pixels * (4 + 16) } else { 0 };
    let before_splats = header + height as usize + planes * pixels * 4 + adaptive_bytes;
    if data.len() < before_splats + 8 {
        return None;
    }
    let splat_count = u64_at(data, before_splats);
    let splat_bytes = usize::try_from(splat_count).ok()?.checked_mul(8)?;
    if data.len() != before_splats + 8 + splat_bytes {
        return None;
    }
    let splats = (splat_count > 0).then(|| {
        data[before_splats + 8..]
            .chunks_exact(8)
            .map(|b| u64_at(b, 0) as i64)
            .collect()
    });
    let data = &data[..before_splats];
    let found = (
        u32_at(data, 0),
        u32_at(data, 4),
        u32_at(data, 8) as usize,
        u32_at(data, 12),
    );
    let pass = data[16];
    if found != (width, height, planes, spp) || (pass != 0) != adaptive || pass > 2 {
        return None;
    }
    let rows_done = data[header..header + height as usize]
        .iter()
        .map(|&b| b == 1)
        .collect();
    let mut film = Film::with_squares(width, height, aovs, spp, squared);
    let values = &data[header + height as usize..];
    let (values, adaptive_values) = values.split_at(planes * pixels * 4);
    for (plane, bytes) in film.planes.iter_mut().zip(values.chunks_exact(pixels * 4)) {
        for (v, b) in plane.iter_mut().zip(bytes.chunks_exact(4)) {
            *v = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
        }
    }
    let pilot = adaptive.then(|| {
        let (counts, sums) = adaptive_values.split_at(pixels * 4);
        film.sample_counts = Some(counts.chunks_exact(4).map(|b| u32_at(b, 0)).collect());
        let f64_at = |b: &[u8]| f64::from_bits(u64_at(b, 0));
        Pilot {
            complete: pass == 2,
            sums: sums
                .chunks_exact(16)
                .map(|b| [f64_at(&b[..8]), f64_at(&b[8..])])
                .collect(),
        }
    });
    Some(Checkpoint {
        film,
        rows_done,
        pilot,
        splats,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stamp(identity: &Identity, fingerprint: u64) -> Stamp<'_> {
        Stamp {
            identity,
            fingerprint,
        }
    }

    /// A scene of two files, the second with `texture` as its bytes.
    fn identity(texture: &[u8]) -> Identity {
        use crate::identity::{hash, FileRead};
        let reads = [
            FileRead {
                path: "shot/a.gltf".into(),
                hash: hash(b"{}"),
            },
            FileRead {
                path: "shot/wood.png".into(),
                hash: hash(texture),
            },
        ];
        Identity::new(Path::new("shot"), &reads, vec![("seed".into(), "0".into())])
    }

    fn snapshot<'s>(
        film: &'s Film,
        rows_done: &'s [bool],
        pilot: Option<&'s Pilot>,
    ) -> Snapshot<'s> {
        Snapshot {
            film,
            rows_done,
            pilot,
            splats: None,
        }
    }

    /// Light tracing's splat sums (film/splats.rs) come back as they were written.
    #[test]
    fn a_checkpoint_keeps_light_tracings_splats() {
        let dir = std::env::temp_dir().join(format!("lightpath-ckpt-s-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.exr.checkpoint");
        let id = identity(b"png");
        let film = Film::with_squares(3, 2, 1, 4, vec![0]);
        let splats =
            crate::film::splats::Splats::new(crate::film::PixelWindow::full(3, 2), 1, &[0]);
        splats.add(2, 1, 0, glam::Vec3A::new(0.25, -3.0, 1e-9));
        let with_splats = Snapshot {
            splats: Some(&splats),
            ..snapshot(&film, &[true, false], None)
        };
        write(&path, stamp(&id, 42), &with_splats).unwrap();
        let shape = FilmShape {
            width: 3,
            height: 2,
            aovs: 1,
            spp: 4,
            squared: vec![0],
            adaptive: false,
        };
        let back = read(&path, stamp(&id, 42), shape).unwrap();
        assert_eq!(back.splats, Some(splats.units()));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_checkpoint_reads_back_bit_for_bit_and_refuses_another_job_or_damage() {
        let dir = std::env::temp_dir().join(format!("lightpath-ckpt-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.exr.checkpoint");
        let id = identity(b"png");
        let shape = |aovs: usize, squared: Vec<u32>| FilmShape {
            width: 3,
            height: 2,
            aovs,
            spp: 4,
            squared,
            adaptive: false,
        };
        let mut film = Film::with_squares(3, 2, 1, 4, vec![0]);
        for (i, plane) in film.planes.iter_mut().enumerate() {
            for (j, v) in plane.iter_mut().enumerate() {
                *v = (i * 10 + j) as f32 * 0.1 + f32::EPSILON;
            }
        }
        write(
            &path,
            stamp(&id, 42),
            &snapshot(&film, &[true, false], None),
        )
        .unwrap();
        let back = read(&path, stamp(&id, 42), shape(1, vec![0])).unwrap();
        assert_eq!(back.rows_done, vec![true, false]);
        for (a, b) in back.film.planes.iter().zip(&film.planes) {
            assert!(a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits()));
        }
        assert_eq!(back.splats, None);
        assert!(read(&path, stamp(&id, 43), shape(1, vec![0]))
            .unwrap_err()
            .to_string()
            .contains("different render"));
        // The same job after the texture was edited: the error names the file.
        let edited = identity(b"png, edited");
        match read(&path, stamp(&edited, 42), shape(1, vec![0])).unwrap_err() {
            CheckpointError::SceneChanged { changes, .. } => {
                assert_eq!(changes.len(), 1, "{changes:?}");
                assert!(changes[0].starts_with("wood.png changed"), "{changes:?}");
            }
            other => panic!("{other}"),
        }
        assert_eq!(back.film.squared, vec![0]);
        assert!(read(&path, stamp(&id, 42), shape(2, vec![0]))
            .unwrap_err()
            .to_string()
            .contains("size"));
        // The same film without the variance planes is another film.
        assert!(read(&path, stamp(&id, 42), shape(1, vec![]))
            .unwrap_err()
            .to_string()
            .contains("size"));
        let mut bytes = std::fs::read(&path).unwrap();
        let n = bytes.len();
        bytes[n - 20] ^= 1;
        std::fs::write(&path, &bytes).unwrap();
        assert!(read(&path, stamp(&id, 42), shape(1, vec![0]))
            .unwrap_err()
            .to_string()
            .contains("damaged"));
        std::fs::write(&path, &bytes[..n / 2]).unwrap();
        assert!(read(&path, stamp(&id, 42), shape(1, vec![0])).is_err());
        bytes[..8].copy_from_slice(b"LPCKPT01");
        std::fs::write(&path, &bytes).unwrap();
        let old = read(&path, stamp(&id, 42), shape(1, vec![0]))
            .unwrap_err()
            .to_string();
        assert!(
            old.contains("another version") && old.contains("without --resume"),
            "{old}"
        );

        // An adaptive render's: its pass, counts and pilot moments, bit for bit.
        film.sample_counts = Some(vec![16, 24, 1024, 0, 16, 40]);
        let pilot = Pilot {
            complete: true,
            sums: (0..6)
                .map(|i| [i as f64 / 3.0, f64::MIN_POSITIVE * i as f64])
                .collect(),
        };
        write(
            &path,
            stamp(&id, 42),
            &snapshot(&film, &[false, true], Some(&pilot)),
        )
        .unwrap();
        let adaptive = FilmShape {
            adaptive: true,
            ..shape(1, vec![0])
        };
        let back = read(&path, stamp(&id, 42), adaptive.clone()).unwrap();
        assert_eq!(back.rows_done, vec![false, true]);
        assert_eq!(back.film.sample_counts, film.sample_counts);
        assert_eq!(back.pilot.as_ref(), Some(&pilot));
        assert!(
            read(&path, stamp(&id, 42), shape(1, vec![0])).is_err(),
            "not an adaptive render's"
        );
        let pilot = Pilot {
            complete: false,
            ..pilot
        };
        write(
            &path,
            stamp(&id, 42),
            &snapshot(&film, &[true, false], Some(&pilot)),
        )
        .unwrap();
        assert_eq!(
            read(&path, stamp(&id, 42), adaptive).unwrap().pilot,
            Some(pilot)
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
