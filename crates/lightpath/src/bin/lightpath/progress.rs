//! How a render reports progress: a bar in a terminal, lines in a log, or nothing.

use lightpath::progress::{PeriodicLines, Progress, Silent, Task};

/// How a render reports progress.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ProgressChoice {
    /// An `indicatif` bar: stderr is a terminal.
    Bar,
    /// A plain line every 10 s: stderr is a log (a farm's), where a bar shows nothing.
    Lines,
    /// `--quiet`.
    Silent,
}

/// The reporter for `--quiet` and whether stderr is a terminal (a pure function: tested).
pub(crate) fn choose_progress(quiet: bool, stderr_is_terminal: bool) -> ProgressChoice {
    match (quiet, stderr_is_terminal) {
        (true, _) => ProgressChoice::Silent,
        (false, true) => ProgressChoice::Bar,
        (false, false) => ProgressChoice::Lines,
    }
}

pub(crate) fn progress_reporter(choice: ProgressChoice) -> Box<dyn Progress> {
    match choice {
        ProgressChoice::Bar => {
            let bar = indicatif::ProgressBar::hidden();
            bar.set_prefix(Task::RENDER.doing);
            Box::new(Bar(bar))
        }
        ProgressChoice::Lines => Box::new(PeriodicLines::new(std::time::Duration::from_secs(10))),
        ProgressChoice::Silent => Box::new(Silent),
    }
}

/// `Progress` as an `indicatif` bar; hidden until `start` knows the total.
pub(crate) struct Bar(indicatif::ProgressBar);

impl Progress for Bar {
    fn start(&self, total: u64, _samples: u64) {
        // A bar may count a second task after the first (a render, then its denoise).
        self.0.reset();
        self.0.set_length(total);
        self.0.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} {prefix} [{bar:40}] {pos}/{len} {elapsed_precise} (eta {eta})",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
            .progress_chars("=> "),
        );
        self.0
            .set_draw_target(indicatif::ProgressDrawTarget::stderr());
    }
    fn advance(&self, units: u64, _samples: u64) {
        self.0.inc(units);
    }
    fn task(&self, task: Task) {
        self.0.set_prefix(task.doing);
    }
    fn finish(&self) {
        self.0.finish_and_clear();
    }
}
