//! Limits checked before anything large is allocated or started: a scene, an EXR or a
//! command line that asks for more than these gets an error naming the limit and how to
//! raise it, never an out-of-memory abort or a render that would run for years.
//!
//! Each limit has a default and an environment variable that replaces it
//! (`LIGHTPATH_MAX_MEMORY=64G lightpath render …`); `docs/performance.md` lists them.

use crate::error::{LimitError, ReadError};
use std::sync::OnceLock;

/// The limits in force.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// Bytes a render's film (every AOV's accumulators), or an EXR being read, may take.
    /// Default: half the address-space limit (`ulimit -v`) when there is one, else half
    /// the physical memory, else 16 GiB.
    pub memory: u64,
    /// Pixels of a film (width × height).
    pub pixels: u64,
    /// Camera samples of one render (pixels × spp).
    pub samples: u64,
    /// AOVs of one render (light-group parts included).
    pub aovs: u64,
    /// Segments of a disk (object or light).
    pub segments: u64,
    /// Bytes of a scene file, OBJ file or other input read whole.
    pub file_bytes: u64,
}

/// One limit: its field, environment variable and what it counts (for messages).
struct Knob {
    env: &'static str,
    what: &'static str,
}

const MEMORY: Knob = Knob {
    env: "LIGHTPATH_MAX_MEMORY",
    what: "bytes of memory",
};
const PIXELS: Knob = Knob {
    env: "LIGHTPATH_MAX_PIXELS",
    what: "pixels",
};
const SAMPLES: Knob = Knob {
    env: "LIGHTPATH_MAX_SAMPLES",
    what: "camera samples per render",
};
const AOVS: Knob = Knob {
    env: "LIGHTPATH_MAX_AOVS",
    what: "AOVs",
};
const SEGMENTS: Knob = Knob {
    env: "LIGHTPATH_MAX_SEGMENTS",
    what: "disk segments",
};
const FILE_BYTES: Knob = Knob {
    env: "LIGHTPATH_MAX_FILE_SIZE",
    what: "bytes of an input file",
};

impl Default for Limits {
    fn default() -> Limits {
        Limits {
            memory: default_memory(),
            // 32768 × 32768: the largest film the command line accepts.
            pixels: 1 << 30,
            // 2^40 ≈ 1.1e12 samples: days of rendering on one machine.
            samples: 1 << 40,
            aovs: 4096,
            segments: 1 << 20,
            // Parsing holds the text and what it becomes: a quarter of the memory budget.
            file_bytes: (default_memory() / 4).min(4 << 30),
        }
    }
}

impl Limits {
    /// The defaults, each replaced by its environment variable when that is set.
    pub fn from_env() -> Result<Limits, LimitError> {
        let d = Limits::default();
        Ok(Limits {
            memory: read_env(&MEMORY, d.memory)?,
            pixels: read_env(&PIXELS, d.pixels)?,
            samples: read_env(&SAMPLES, d.samples)?,
            aovs: read_env(&AOVS, d.aovs)?,
            segments: read_env(&SEGMENTS, d.segments)?,
            file_bytes: read_env(&FILE_BYTES, d.file_bytes)?,
        })
    }

    /// The process's limits, read from the environment once. A malformed variable is
    /// reported by [`Limits::from_env`] (the binary calls it first); here it falls back
    /// to the defaults.
    pub fn current() -> Limits {
        static LIMITS: OnceLock<Limits> = OnceLock::new();
        *LIMITS.get_or_init(|| Limits::from_env().unwrap_or_default())
    }

    pub fn check_memory(&self, bytes: u64, for_what: &str) -> Result<(), LimitError> {
        exceeds(&MEMORY, bytes, self.memory, for_what)
    }
    pub fn check_pixels(&self, pixels: u64, for_what: &str) -> Result<(), LimitError> {
        exceeds(&PIXELS, pixels, self.pixels, for_what)
    }
    pub fn check_samples(&self, samples: u64, for_what: &str) -> Result<(), LimitError> {
        exceeds(&SAMPLES, samples, self.samples, for_what)
    }
    pub fn check_aovs(&self, aovs: u64, for_what: &str) -> Result<(), LimitError> {
        exceeds(&AOVS, aovs, self.aovs, for_what)
    }
    pub fn check_segments(&self, segments: u64, for_what: &str) -> Result<(), LimitError> {
        exceeds(&SEGMENTS, segments, self.segments, for_what)
    }
    pub fn check_file_bytes(&self, bytes: u64, for_what: &str) -> Result<(), LimitError> {
        exceeds(&FILE_BYTES, bytes, self.file_bytes, for_what)
    }
}

/// Reads an input file whole, within `file_bytes`: a device or a FIFO (`/dev/zero` named
/// as an OBJ) is refused before reading, and a file that grows past the limit while being
/// read is cut off with an error. Every file a render reads comes through here, and is
/// noted in the render's identity (`identity.rs`).
pub fn read_input(path: &std::path::Path) -> Result<Vec<u8>, ReadError> {
    use std::io::Read;
    let limits = Limits::current();
    let file = std::fs::File::open(path).map_err(ReadError::Open)?;
    let meta = file.metadata().map_err(ReadError::Read)?;
    if !meta.is_file() {
        return Err(ReadError::NotRegular);
    }
    limits.check_file_bytes(meta.len(), "reading this file")?;
    let mut bytes = Vec::new();
    file.take(limits.file_bytes.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(ReadError::Read)?;
    limits.check_file_bytes(bytes.len() as u64, "reading this file")?;
    crate::identity::note_read(path, &bytes);
    Ok(bytes)
}

fn exceeds(knob: &Knob, value: u64, limit: u64, for_what: &str) -> Result<(), LimitError> {
    if value <= limit {
        return Ok(());
    }
    Err(LimitError::Exceeded {
        for_what: for_what.to_string(),
        value,
        what: knob.what,
        limit,
        env: knob.env,
    })
}

fn read_env(knob: &Knob, default: u64) -> Result<u64, LimitError> {
    match std::env::var(knob.env) {
        Err(std::env::VarError::NotPresent) => Ok(default),
        Err(std::env::VarError::NotUnicode(_)) => Err(LimitError::EnvNotUnicode(knob.env)),
        Ok(v) => parse_size(&v).ok_or(LimitError::EnvMalformed {
            env: knob.env,
            value: v,
        }),
    }
}

/// `123`, `64K`, `8M`, `16G`, `1T` (binary multiples).
pub fn parse_size(s: &str) -> Option<u64> {
    let s = s.trim();
    let (digits, shift) = match s.chars().last()? {
        'k' | 'K' => (&s[..s.len() - 1], 10),
        'm' | 'M' => (&s[..s.len() - 1], 20),
        'g' | 'G' => (&s[..s.len() - 1], 30),
        't' | 'T' => (&s[..s.len() - 1], 40),
        _ => (s, 0),
    };
    let n: u64 = digits.trim().parse().ok()?;
    n.checked_mul(1u64 << shift)
}

/// Half of what the process can address: `ulimit -v` if set, else physical memory.
fn default_memory() -> u64 {
    let fallback = 16u64 << 30;
    let address_space = address_space_limit();
    let physical = physical_memory();
    let cap = match (address_space, physical) {
        (Some(a), Some(p)) => a.min(p),
        (Some(a), None) => a,
        (None, Some(p)) => p,
        (None, None) => return fallback,
    };
    cap / 2
}

#[cfg(unix)]
// `rlim_t` is u64 here but not on every platform.
#[allow(clippy::unnecessary_cast)]
fn address_space_limit() -> Option<u64> {
    let mut rl = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit writes into the struct we own; no other memory is touched.
    let ok = unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut rl) } == 0;
    (ok && rl.rlim_cur != libc::RLIM_INFINITY).then_some(rl.rlim_cur as u64)
}

#[cfg(not(unix))]
fn address_space_limit() -> Option<u64> {
    None
}

fn physical_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_take_binary_suffixes_and_reject_garbage() {
        assert_eq!(parse_size("123"), Some(123));
        assert_eq!(parse_size("64K"), Some(64 << 10));
        assert_eq!(parse_size(" 16g "), Some(16 << 30));
        assert_eq!(parse_size("2T"), Some(2 << 40));
        assert_eq!(parse_size("G"), None);
        assert_eq!(parse_size("-1"), None);
        assert_eq!(parse_size("99999999999T"), None);
    }

    #[test]
    fn an_exceeded_limit_names_itself_and_its_variable() {
        let l = Limits {
            pixels: 100,
            ..Limits::default()
        };
        assert!(l.check_pixels(100, "x").is_ok());
        let e = l.check_pixels(101, "a 101x1 film").unwrap_err();
        assert!(matches!(
            e,
            LimitError::Exceeded {
                value: 101,
                limit: 100,
                ..
            }
        ));
        let e = e.to_string();
        assert!(e.contains("a 101x1 film needs 101 pixels"), "{e}");
        assert!(
            e.contains("limit of 100") && e.contains("LIGHTPATH_MAX_PIXELS"),
            "{e}"
        );
    }
}
