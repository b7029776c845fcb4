//! Checkpoints of a render in progress: the film's exact accumulators and which rows are
//! finished, beside the output (`shot.exr` → `shot.exr.checkpoint`). `render … --resume`
//! loads one and renders only the rows still missing; every sample is seeded by (seed,
//! pixel, sample index) and a row's sums start from zero, so the finished image is
//! bit for bit the uninterrupted render's.
//!
//! The format (little-endian): `LPCKPT01`, the job's fingerprint (u64), width, height,
//! planes, spp (u32 each), one byte per row (1: finished), every plane's
//! `width × height` f32 sums, then an FNV-1a checksum (u64) of all that precedes it.

use crate::film::Film;
use crate::output::atomic;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 8] = b"LPCKPT01";

/// A film with the rows it holds finished.
#[derive(Debug)]
pub struct Checkpoint {
    pub film: Film,
    /// One entry per row: is it complete?
    pub rows_done: Vec<bool>,
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

/// Writes the checkpoint atomically (synced before it replaces the previous one).
pub fn write(path: &Path, fingerprint: u64, film: &Film, rows_done: &[bool]) -> Result<(), String> {
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
            let rows: Vec<u8> = rows_done.iter().map(|&d| d as u8).collect();
            out.put(&rows)?;
            let mut chunk = Vec::with_capacity(4 * film.width as usize);
            for plane in &film.planes {
                for row in plane.chunks(film.width.max(1) as usize) {
                    chunk.clear();
                    chunk.extend(row.iter().flat_map(|v| v.to_le_bytes()));
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

/// The film a checkpoint must hold: its size, AOV count, spp, and the AOVs whose squared
/// samples it sums (`--variance`).
#[derive(Clone, Debug)]
pub struct FilmShape {
    pub width: u32,
    pub height: u32,
    pub aovs: usize,
    pub spp: u32,
    pub squared: Vec<u32>,
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
    } = shape;
    let bad = |what: &str| format!("checkpoint {}: {what}", path.display());
    let bytes = crate::limits::read_input(path).map_err(|e| bad(&e))?;
    let planes = Film::stride_with(aovs, squared.len());
    let pixels = width as usize * height as usize;
    let header = 8 + 8 + 16;
    let expected = header + height as usize + planes * pixels * 4 + 8;
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
    if found != (width, height, planes, spp) || bytes.len() != expected {
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
    for (plane, bytes) in film.planes.iter_mut().zip(values.chunks_exact(pixels * 4)) {
        for (v, b) in plane.iter_mut().zip(bytes.chunks_exact(4)) {
            *v = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
        }
    }
    Ok(Checkpoint { film, rows_done })
}

#[cfg(test)]
mod tests {
    use super::*;

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
        };
        let mut film = Film::with_squares(3, 2, 1, 4, vec![0]);
        for (i, plane) in film.planes.iter_mut().enumerate() {
            for (j, v) in plane.iter_mut().enumerate() {
                *v = (i * 10 + j) as f32 * 0.1 + f32::EPSILON;
            }
        }
        write(&path, 42, &film, &[true, false]).unwrap();
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
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
