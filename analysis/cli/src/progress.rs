//! Progress on a terminal: an indicatif bar that appears once a job has run for two seconds
//! (short runs print nothing), never when stderr is not a terminal or with `--quiet`; and the
//! interrupt flag the jobs poll.

use std::sync::Mutex;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};
use twv_analysis::api::{CancelFlag, Progress};

/// Runs shorter than this show no bar.
const DELAY: Duration = Duration::from_secs(2);

#[derive(Default)]
struct State {
    total: u64,
    done: u64,
    what: String,
    started: Option<Instant>,
    bar: Option<ProgressBar>,
}

/// A [`Progress`] for the terminal.
pub struct Bar {
    visible: bool,
    cancel: &'static CancelFlag,
    state: Mutex<State>,
}

impl Bar {
    /// A bar that draws when `visible` and reads `cancel`.
    pub fn new(visible: bool, cancel: &'static CancelFlag) -> Self {
        Self {
            visible,
            cancel,
            state: Mutex::new(State::default()),
        }
    }
}

impl Progress for Bar {
    fn start(&self, total: u64, what: &str) {
        let Ok(mut s) = self.state.lock() else { return };
        if let Some(bar) = s.bar.take() {
            bar.finish_and_clear();
        }
        *s = State {
            total,
            what: what.to_string(),
            started: Some(Instant::now()),
            ..State::default()
        };
    }

    fn advance(&self, n: u64) {
        if !self.visible {
            return;
        }
        let Ok(mut s) = self.state.lock() else { return };
        s.done += n;
        if let Some(bar) = &s.bar {
            bar.set_position(s.done);
            return;
        }
        if s.started.is_some_and(|t| t.elapsed() >= DELAY) {
            let bar = ProgressBar::new(s.total);
            let template = format!(
                "{{bar:40}} {{pos}}/{{len}} {}, {{elapsed}} (eta {{eta}})",
                s.what
            );
            if let Ok(style) = ProgressStyle::with_template(&template) {
                bar.set_style(style);
            }
            bar.set_position(s.done);
            s.bar = Some(bar);
        }
    }

    fn cancelled(&self) -> bool {
        self.cancel.is_raised()
    }

    fn finish(&self) {
        if let Ok(mut s) = self.state.lock() {
            if let Some(bar) = s.bar.take() {
                bar.finish_and_clear();
            }
        }
    }
}
