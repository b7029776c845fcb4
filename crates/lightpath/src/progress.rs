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
    /// `units` more units are done, with `samples` camera samples really taken for them (an
    /// adaptive render takes fewer than `start`'s count; resumed units took none this run).
    fn advance(&self, units: u64, samples: u64);
    /// The render is over (also after an early stop).
    fn finish(&self);
    /// What the next `start` counts, for the words a reporter shows: a render (the
    /// default) or other work, such as a denoise's filter runs.
    fn task(&self, _task: Task) {}
    /// Rows `rows` of `film` hold their final sums (the render loop stores a band of rows
    /// at a time): a live preview copies them; other reporters ignore it.
    fn rows_done(&self, _film: &Film, _rows: Range<usize>) {}
    /// The most rows a band should have, for a reporter that wants rows sooner (a live
    /// preview). The render's pixels do not depend on the band size.
    fn band_rows(&self) -> Option<usize> {
        None
    }
}

/// What a reporter's line says: the work (`rendering`) and what its rate counts
/// (`samples`, the `samples` of `advance`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Task {
    pub doing: &'static str,
    pub counting: &'static str,
}

impl Task {
    pub const RENDER: Task = Task {
        doing: "rendering",
        counting: "samples",
    };
    /// A denoise: units are filter runs, `samples` the pixels each filtered.
    pub const DENOISE: Task = Task {
        doing: "denoising",
        counting: "pixels",
    };
}

/// Reports nothing.
pub struct Silent;

impl Progress for Silent {
    fn start(&self, _: u64, _: u64) {}
    fn advance(&self, _: u64, _: u64) {}
    fn finish(&self) {}
}

/// Plain lines on stderr every `every` (and at the end): percent, samples/s and ETA.
pub struct PeriodicLines {
    every: Duration,
    task: Mutex<Task>,
    state: Mutex<LinesState>,
}

struct LinesState {
    started: Instant,
    last: Instant,
    total: u64,
    done: u64,
    /// Units and samples this run did itself (not those a resumed render already held).
    done_now: u64,
    taken: u64,
}

impl PeriodicLines {
    pub fn new(every: Duration) -> PeriodicLines {
        let now = Instant::now();
        PeriodicLines {
            every,
            task: Mutex::new(Task::RENDER),
            state: Mutex::new(LinesState {
                started: now,
                last: now,
                total: 0,
                done: 0,
                done_now: 0,
                taken: 0,
            }),
        }
    }
}

/// Where a render is: `done` of `total` units, of which `done_now` this run did, taking
/// `taken` camera samples in `elapsed`.
#[derive(Clone, Copy, Debug)]
pub struct Status {
    pub done: u64,
    pub total: u64,
    pub done_now: u64,
    pub taken: u64,
    pub elapsed: Duration,
}

/// One progress line: `rendering 42.0 % 1.23 M samples/s, eta 0:00:12`. The rate counts the
/// samples really taken (an adaptive render's cheap rows would otherwise count as full), and
/// the ETA extrapolates this run's pace over the units left (resumed units took no time).
pub fn progress_line(s: Status) -> String {
    task_line(Task::RENDER, s)
}

/// [`progress_line`] for any task: `denoising 42.0 % 1.23 M pixels/s, eta 0:00:12`.
pub fn task_line(task: Task, s: Status) -> String {
    let fraction = if s.total == 0 {
        1.0
    } else {
        s.done as f64 / s.total as f64
    };
    let secs = s.elapsed.as_secs_f64();
    let rate = if secs > 0.0 {
        s.taken as f64 / secs
    } else {
        0.0
    };
    let left = s.total.saturating_sub(s.done);
    let eta = if s.done_now > 0 {
        secs * left as f64 / s.done_now as f64
    } else {
        0.0
    };
    let eta = eta.round() as u64;
    format!(
        "{} {:5.1} % {:.2} M {}/s, eta {}:{:02}:{:02}",
        task.doing,
        100.0 * fraction,
        rate / 1e6,
        task.counting,
        eta / 3600,
        eta / 60 % 60,
        eta % 60
    )
}

impl PeriodicLines {
    fn current_task(&self) -> Task {
        *self.task.lock().unwrap_or_else(|e| e.into_inner())
    }
}

impl LinesState {
    fn status(&self, now: Instant) -> Status {
        Status {
            done: self.done,
            total: self.total,
            done_now: self.done_now,
            taken: self.taken,
            elapsed: now - self.started,
        }
    }
}

impl Progress for PeriodicLines {
    fn start(&self, total: u64, _samples: u64) {
        let mut s = self.state.lock().unwrap_or_else(|e| e.into_inner());
        let now = Instant::now();
        *s = LinesState {
            started: now,
            last: now,
            total,
            done: 0,
            done_now: 0,
            taken: 0,
        };
    }

    fn advance(&self, units: u64, samples: u64) {
        let mut s = self.state.lock().unwrap_or_else(|e| e.into_inner());
        s.done += units;
        // Units that took no samples were resumed, not done by this run.
        if samples > 0 {
            s.done_now += units;
        }
        s.taken += samples;
        let now = Instant::now();
        if now.duration_since(s.last) >= self.every {
            s.last = now;
            let line = task_line(self.current_task(), s.status(now));
            let _ = writeln!(std::io::stderr(), "{line}");
        }
    }

    fn task(&self, task: Task) {
        *self.task.lock().unwrap_or_else(|e| e.into_inner()) = task;
    }

    fn finish(&self) {
        let s = self.state.lock().unwrap_or_else(|e| e.into_inner());
        let line = task_line(self.current_task(), s.status(Instant::now()));
        let _ = writeln!(std::io::stderr(), "{line}");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_has_percent_rate_and_eta() {
        // Half of 100 rows, 1 M samples taken in 1 s: 1 M samples/s, 1 s to go.
        let line = progress_line(Status {
            done: 50,
            total: 100,
            done_now: 50,
            taken: 1_000_000,
            elapsed: Duration::from_secs(1),
        });
        assert_eq!(line, "rendering  50.0 % 1.00 M samples/s, eta 0:00:01");
        let none = Status {
            done: 0,
            total: 0,
            done_now: 0,
            taken: 0,
            elapsed: Duration::ZERO,
        };
        assert!(progress_line(none).contains("100.0 %"));
    }

    #[test]
    fn the_rate_counts_samples_taken_not_planned() {
        // An adaptive render planned for 64 spp whose rows took 8 spp: the rate is the
        // samples advance() was given, whatever start() planned.
        let p = PeriodicLines::new(Duration::from_secs(3600));
        p.start(10, 10 * 100 * 64);
        for _ in 0..10 {
            p.advance(1, 100 * 8);
        }
        let s = p.state.lock().unwrap();
        assert_eq!(s.taken, 10 * 100 * 8);
        let line = progress_line(Status {
            elapsed: Duration::from_secs(1),
            ..s.status(s.started)
        });
        assert!(line.contains(" 0.01 M samples/s"), "{line}");
    }

    #[test]
    fn resumed_units_do_not_shorten_the_eta() {
        // 40 of 100 rows resumed, 10 rendered in 1 s: 50 left at 10 rows/s is 5 s.
        let p = PeriodicLines::new(Duration::from_secs(3600));
        p.start(100, 0);
        p.advance(40, 0);
        for _ in 0..10 {
            p.advance(1, 1000);
        }
        let s = p.state.lock().unwrap();
        let line = progress_line(Status {
            elapsed: Duration::from_secs(1),
            ..s.status(s.started)
        });
        assert!(line.ends_with("eta 0:00:05"), "{line}");
    }
}
