//! How a render reports how far it is. The library only calls this trait; the binary
//! chooses an `indicatif` bar in a terminal and [`PeriodicLines`] when stderr is a log
//! (a farm's), where a bar would print nothing useful.

use crate::film::Film;
use std::io::Write;
use std::ops::Range;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Receives a render's progress. Called from worker threads, hence `Sync`.
pub trait Progress: Sync {
    /// Work is about to start: `total` units (rows × passes), `samples` camera samples.
    fn start(&self, total: u64, samples: u64);
    /// `units` more units are done.
    fn advance(&self, units: u64);
    /// The render is over (also after an early stop).
    fn finish(&self);
    /// Rows `rows` of `film` hold their final sums (the render loop stores a band of rows
    /// at a time): a live preview copies them; other reporters ignore it.
    fn rows_done(&self, _film: &Film, _rows: Range<usize>) {}
    /// The most rows a band should have, for a reporter that wants rows sooner (a live
    /// preview). The render's pixels do not depend on the band size.
    fn band_rows(&self) -> Option<usize> {
        None
    }
}

/// Reports nothing.
pub struct Silent;

impl Progress for Silent {
    fn start(&self, _: u64, _: u64) {}
    fn advance(&self, _: u64) {}
    fn finish(&self) {}
}

/// Plain lines on stderr every `every` (and at the end): percent, samples/s and ETA.
pub struct PeriodicLines {
    every: Duration,
    state: Mutex<LinesState>,
}

struct LinesState {
    started: Instant,
    last: Instant,
    total: u64,
    samples: u64,
    done: u64,
}

impl PeriodicLines {
    pub fn new(every: Duration) -> PeriodicLines {
        let now = Instant::now();
        PeriodicLines {
            every,
            state: Mutex::new(LinesState {
                started: now,
                last: now,
                total: 0,
                samples: 0,
                done: 0,
            }),
        }
    }
}

/// One progress line: `rendering 42.0 % 1.23 M samples/s, eta 0:00:12`.
pub fn progress_line(done: u64, total: u64, samples: u64, elapsed: Duration) -> String {
    let fraction = if total == 0 {
        1.0
    } else {
        done as f64 / total as f64
    };
    let secs = elapsed.as_secs_f64();
    let rate = if secs > 0.0 {
        fraction * samples as f64 / secs
    } else {
        0.0
    };
    let eta = if fraction > 0.0 {
        secs * (1.0 - fraction) / fraction
    } else {
        0.0
    };
    let eta = eta.round() as u64;
    format!(
        "rendering {:5.1} % {:.2} M samples/s, eta {}:{:02}:{:02}",
        100.0 * fraction,
        rate / 1e6,
        eta / 3600,
        eta / 60 % 60,
        eta % 60
    )
}

impl Progress for PeriodicLines {
    fn start(&self, total: u64, samples: u64) {
        let mut s = self.state.lock().unwrap_or_else(|e| e.into_inner());
        let now = Instant::now();
        *s = LinesState {
            started: now,
            last: now,
            total,
            samples,
            done: 0,
        };
    }

    fn advance(&self, units: u64) {
        let mut s = self.state.lock().unwrap_or_else(|e| e.into_inner());
        s.done += units;
        let now = Instant::now();
        if now.duration_since(s.last) >= self.every {
            s.last = now;
            let line = progress_line(s.done, s.total, s.samples, now - s.started);
            let _ = writeln!(std::io::stderr(), "{line}");
        }
    }

    fn finish(&self) {
        let s = self.state.lock().unwrap_or_else(|e| e.into_inner());
        let line = progress_line(s.done, s.total, s.samples, s.started.elapsed());
        let _ = writeln!(std::io::stderr(), "{line}");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_has_percent_rate_and_eta() {
        // Half of 2 M samples in 1 s: 1 M samples/s, 1 s to go.
        let line = progress_line(50, 100, 2_000_000, Duration::from_secs(1));
        assert_eq!(line, "rendering  50.0 % 1.00 M samples/s, eta 0:00:01");
        assert!(progress_line(0, 0, 0, Duration::ZERO).contains("100.0 %"));
    }
}
