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
//! The format (little-endian): `LPCKPT02`, the job's fingerprint (u64), width, height,
//! planes, spp (u32 each), the pass (u8: 0 not adaptive, 1 the pilot, 2 the second pass),
//! one byte per row (1: finished in that pass), every plane's `width × height` f32 sums;
//! if adaptive, each pixel's sample count (u32) and then its pilot's sum and sum of
//! squares (f64 each); then an FNV-1a checksum (u64) of all that precedes it. Version
//! `LPCKPT01` (no pass byte, no adaptive renders) is refused with a message.

use crate::film::Film;
use crate::integrator::adaptive::Pilot;
use crate::integrator::Snapshot;
use crate::output::atomic;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 8] = b"LPCKPT02";

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

/// FNV-1a over byte strings, each followed by its length (stable across builds and
/// machines, unlike `DefaultHasher`).
pub fn fingerprint(parts: &[&[u8]]) -> u64 {
    let mut h = Fnv::default();
    for p in parts {
        h.write(p);
        h.write(&(p.len() as u64).to_le_bytes());
    }
    h.0
}

struct Fnv(u64);

impl Default for Fnv {
    fn default() -> Fnv {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.0 ^= *b as u64;
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
}

/// Writes the checkpoint of `snapshot` atomically (synced before it replaces the previous
/// one).
pub fn write(path: &Path, fingerprint: u64, snapshot: &Snapshot) -> Result<(), String> {
    let Snapshot {
        film,
        rows_done,
        pilot,
    } = *snapshot;
    atomic::atomically(path, |file| {
        let mut out = Summed {
            out: BufWriter::with_capacity(1 << 20, file),
            sum: Fnv::default(),
        };
        let io = (|| -> std::io::Result<()> {
            out.put(MAGIC)?;
            out.put(&fingerprint.to_le_bytes())?;
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
            let total = out.sum.0;
            out.out.write_all(&total.to_le_bytes())?;
            out.out.flush()
        })();
        io.map_err(|e| format!("cannot write the checkpoint {}: {e}", path.display()))
    })
}

/// A writer that checksums what goes through it.
struct Summed<W: Write> {
    out: W,
    sum: Fnv,
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

/// Reads a checkpoint for a render whose film is `shape`, made by a job with this
/// `fingerprint`; anything else is an error naming the difference.
pub fn read(path: &Path, fingerprint: u64, shape: FilmShape) -> Result<Checkpoint, String> {
    let FilmShape {
        width,
        height,
        aovs,
        spp,
        squared,
        adaptive,
    } = shape;
    let bad = |what: &str| format!("checkpoint {}: {what}", path.display());
    let bytes = crate::limits::read_input(path).map_err(|e| bad(&e))?;
    let planes = Film::stride_with(aovs, squared.len());
    let pixels = width as usize * height as usize;
    let header = 8 + 8 + 16 + 1;
    let adaptive_bytes = if adaptive { pixels * (4 + 16) } else { 0 };
    let expected = header + height as usize + planes * pixels * 4 + adaptive_bytes + 8;
    if bytes.len() >= 8 && bytes[..6] == MAGIC_FAMILY[..] && bytes[..8] != MAGIC[..] {
        return Err(bad(&format!(
            "it was written by another version of Lightpath (format {}; this one reads {}): \
             render again without --resume",
            String::from_utf8_lossy(&bytes[..8]),
            String::from_utf8_lossy(MAGIC)
        )));
    }
    if bytes.len() < header || &bytes[..8] != MAGIC {
        return Err(bad("not a Lightpath checkpoint"));
    }
    let u32_at =
        |at: usize| u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    let mut fp = [0u8; 8];
    fp.copy_from_slice(&bytes[8..16]);
    if u64::from_le_bytes(fp) != fingerprint {
        return Err(bad(
            "it was made by a different render (another scene, resolution, spp, seed, sample \
             range or AOV set): run the command that was interrupted, with --resume",
        ));
    }
    let found = (u32_at(16), u32_at(20), u32_at(24) as usize, u32_at(28));
    let pass = bytes[32];
    if found != (width, height, planes, spp)
        || bytes.len() != expected
        || (pass != 0) != adaptive
        || pass > 2
    {
        return Err(bad(
            "its size does not match this render (truncated or from another version)",
        ));
    }
    let body = &bytes[..expected - 8];
    let mut sum = Fnv::default();
    sum.write(body);
    let mut stored = [0u8; 8];
    stored.copy_from_slice(&bytes[expected - 8..]);
    if u64::from_le_bytes(stored) != sum.0 {
        return Err(bad("its checksum does not match: the file is damaged"));
    }
    let rows_done = body[header..header + height as usize]
        .iter()
        .map(|&b| b == 1)
        .collect();
    let mut film = Film::with_squares(width, height, aovs, spp, squared);
    let values = &body[header + height as usize..];
    let (values, adaptive_values) = values.split_at(planes * pixels * 4);
    for (plane, bytes) in film.planes.iter_mut().zip(values.chunks_exact(pixels * 4)) {
        for (v, b) in plane.iter_mut().zip(bytes.chunks_exact(4)) {
            *v = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
        }
    }
    let pilot = adaptive.then(|| {
        let (counts, sums) = adaptive_values.split_at(pixels * 4);
        film.sample_counts = Some(
            counts
                .chunks_exact(4)
                .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect(),
        );
        let f64_at = |b: &[u8]| {
            let mut v = [0u8; 8];
            v.copy_from_slice(b);
            f64::from_le_bytes(v)
        };
        Pilot {
            complete: pass == 2,
            sums: sums
                .chunks_exact(16)
                .map(|b| [f64_at(&b[..8]), f64_at(&b[8..])])
                .collect(),
        }
    });
    Ok(Checkpoint {
        film,
        rows_done,
        pilot,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn snapshot<'s>(
        film: &'s Film,
        rows_done: &'s [bool],
        pilot: Option<&'s Pilot>,
    ) -> Snapshot<'s> {
        Snapshot {
            film,
            rows_done,
            pilot,
        }
    }

    #[test]
    fn a_checkpoint_reads_back_bit_for_bit_and_refuses_another_job_or_damage() {
        let dir = std::env::temp_dir().join(format!("lightpath-ckpt-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.exr.checkpoint");
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
        write(&path, 42, &snapshot(&film, &[true, false], None)).unwrap();
        let back = read(&path, 42, shape(1, vec![0])).unwrap();
        assert_eq!(back.rows_done, vec![true, false]);
        for (a, b) in back.film.planes.iter().zip(&film.planes) {
            assert!(a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits()));
        }
        assert!(read(&path, 43, shape(1, vec![0]))
            .unwrap_err()
            .contains("different render"));
        assert_eq!(back.film.squared, vec![0]);
        assert!(read(&path, 42, shape(2, vec![0]))
            .unwrap_err()
            .contains("size"));
        // The same film without the variance planes is another film.
        assert!(read(&path, 42, shape(1, vec![]))
            .unwrap_err()
            .contains("size"));
        let mut bytes = std::fs::read(&path).unwrap();
        let n = bytes.len();
        bytes[n - 20] ^= 1;
        std::fs::write(&path, &bytes).unwrap();
        assert!(read(&path, 42, shape(1, vec![0]))
            .unwrap_err()
            .contains("damaged"));
        std::fs::write(&path, &bytes[..n / 2]).unwrap();
        assert!(read(&path, 42, shape(1, vec![0])).is_err());
        bytes[..8].copy_from_slice(b"LPCKPT01");
        std::fs::write(&path, &bytes).unwrap();
        let old = read(&path, 42, shape(1, vec![0])).unwrap_err();
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
        write(&path, 42, &snapshot(&film, &[false, true], Some(&pilot))).unwrap();
        let adaptive = FilmShape {
            adaptive: true,
            ..shape(1, vec![0])
        };
        let back = read(&path, 42, adaptive.clone()).unwrap();
        assert_eq!(back.rows_done, vec![false, true]);
        assert_eq!(back.film.sample_counts, film.sample_counts);
        assert_eq!(back.pilot.as_ref(), Some(&pilot));
        assert!(
            read(&path, 42, shape(1, vec![0])).is_err(),
            "not an adaptive render's"
        );
        let pilot = Pilot {
            complete: false,
            ..pilot
        };
        write(&path, 42, &snapshot(&film, &[true, false], Some(&pilot))).unwrap();
        assert_eq!(read(&path, 42, adaptive).unwrap().pilot, Some(pilot));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
