//! Progress for every long command (conform, certify, fuzz device, fuzz host, check-host), one
//! way. On a terminal: a bar with done/total, failures and an ETA. Elsewhere (a CI log): a
//! plain line when the command starts, then one at most every [`INTERVAL`] and at least every
//! 30 s (a ticker thread prints even while one case or run takes long), and one when it ends:
//! `gcl conform: 120/351 cases, 3 failing, 42 s elapsed, ETA 80 s`. Plain lines begin with
//! the first unit done (or after the first interval, whichever comes first).
//!
//! Lines other than progress (a failing case, a finding) go through [`Progress::println`], so
//! they never tear the bar.

use super::stdio::errln;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Plain progress lines come this far apart (the bounds: at most every 10 s, at
/// least every 30 s).
pub const INTERVAL: Duration = Duration::from_secs(10);

/// Whether the next plain line is due at `now`, the last one having come at `last`.
fn due(last: Instant, now: Instant) -> bool {
    now.saturating_duration_since(last) >= INTERVAL
}

/// What the total counts.
#[derive(Debug, Clone, Copy)]
pub enum Total {
    /// This many units (cases, runs).
    Units(u64),
    /// A time budget: the ETA is what is left of it.
    Time(Duration),
}

struct State {
    what: String,
    unit: &'static str,
    failing_word: &'static str,
    total: Mutex<Total>,
    done: AtomicU64,
    failures: AtomicU64,
    started: Instant,
    last_line: Mutex<Instant>,
    finished: AtomicBool,
    started_line: AtomicBool,
}

impl State {
    fn line(&self) -> String {
        let done = self.done.load(Ordering::Relaxed);
        let failures = self.failures.load(Ordering::Relaxed);
        let elapsed = self.started.elapsed();
        let total = *self.total.lock().unwrap_or_else(|e| e.into_inner());
        let (count, eta) = match total {
            Total::Units(n) => {
                // No ETA before its basis: the first units carry the start (the pre-flight,
                // the probes), and one of them said `ETA 79 s` for a run of 0.9 s.
                let eta = (done >= eta_basis(n) && n > done)
                    .then(|| elapsed.mul_f64((n - done) as f64 / done as f64))
                    .map(|d| format!(", ETA {}", secs(d)));
                (format!("{done}/{n} {}", self.unit), eta.unwrap_or_default())
            }
            Total::Time(t) => (format!("{done} {}", self.unit), format!(", ETA {}", secs(t.saturating_sub(elapsed)))),
        };
        format!("{}: {count}, {failures} {}, {} elapsed{eta}", self.what, self.failing_word, secs(elapsed))
    }
}

/// How many of `n` units must be done before the rest is estimated from them: a twentieth,
/// and at least 3.
fn eta_basis(n: u64) -> u64 {
    (n / 20).max(3)
}

fn secs(d: Duration) -> String {
    let s = d.as_secs();
    if s >= 120 { format!("{}m{:02}s", s / 60, s % 60) } else { format!("{s} s") }
}

/// A command's progress.
pub struct Progress {
    state: Arc<State>,
    bar: Option<indicatif::ProgressBar>,
    plain: bool,
}

impl Progress {
    /// Progress of `what` (`gcl conform`), counting `unit`s (`cases`) and failures called
    /// `failing_word` (`failing`, `findings`). `quiet`: only the bar or lines that end it are
    /// left out, never a failure line the caller prints.
    pub fn new(what: &str, unit: &'static str, failing_word: &'static str, total: Total, quiet: bool) -> Progress {
        let tty = super::stdio::stderr_is_terminal();
        let state = Arc::new(State {
            what: what.to_string(),
            unit,
            failing_word,
            total: Mutex::new(total),
            done: AtomicU64::new(0),
            failures: AtomicU64::new(0),
            started: Instant::now(),
            last_line: Mutex::new(Instant::now()),
            finished: AtomicBool::new(false),
            started_line: AtomicBool::new(false),
        });
        let bar = (tty && !quiet).then(|| {
            let len = match total {
                Total::Units(n) => n,
                _ => 0,
            };
            let b = indicatif::ProgressBar::new(len);
            let template = match total {
                Total::Units(_) => "{spinner} [{bar:30}] {pos}/{len} {msg} ({elapsed}, ETA {eta})",
                _ => "{spinner} {pos} {msg} ({elapsed})",
            };
            b.set_style(
                indicatif::ProgressStyle::with_template(template)
                    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
                    .progress_chars("=> "),
            );
            super::without_stop_signals(|| b.enable_steady_tick(Duration::from_millis(200)));
            b
        });
        let plain = !tty && !quiet;
        let p = Progress { state, bar, plain };
        if p.plain {
            // The first line comes with the first unit done (so a line the command prints
            // before it starts, such as the pre-flight, leads), then one every INTERVAL.
            let st = p.state.clone();
            // A signal that stops the command is never this thread's to take.
            super::without_stop_signals(|| {
                std::thread::spawn(move || {
                    while !st.finished.load(Ordering::Relaxed) {
                        std::thread::sleep(Duration::from_millis(250));
                        let mut last = st.last_line.lock().unwrap_or_else(|e| e.into_inner());
                        if !st.finished.load(Ordering::Relaxed) && due(*last, Instant::now()) {
                            *last = Instant::now();
                            errln!("{}", st.line());
                        }
                    }
                })
            });
        }
        p
    }

    /// Sets the total (once the runner knows it).
    pub fn set_total(&self, total: u64) {
        *self.state.total.lock().unwrap_or_else(|e| e.into_inner()) = Total::Units(total);
        if let Some(b) = &self.bar {
            b.set_length(total);
        }
    }

    /// `done` units finished, `failures` of them failing so far; `msg` shown on the bar.
    pub fn update(&self, done: u64, failures: u64, msg: &str) {
        self.state.done.store(done, Ordering::Relaxed);
        self.state.failures.store(failures, Ordering::Relaxed);
        if let Some(b) = &self.bar {
            b.set_position(done);
            b.set_message(gcl_model::escape::printable(msg).into_owned());
        }
        if self.plain && !self.state.started_line.swap(true, Ordering::Relaxed) {
            *self.state.last_line.lock().unwrap_or_else(|e| e.into_inner()) = Instant::now();
            errln!("{}", self.state.line());
        }
    }

    /// A line that is not progress (a failure, a finding), above the bar; what a hand, a host
    /// or a file put in it is shown escaped ([`gcl_model::escape::printable`]).
    pub fn println(&self, line: &str) {
        let line = &*gcl_model::escape::printable(line);
        match &self.bar {
            Some(b) => b.println(line),
            None => errln!("{line}"),
        }
    }

    /// Ends the progress: clears the bar, or prints the last plain line.
    pub fn finish(&self) {
        if self.state.finished.swap(true, Ordering::Relaxed) {
            return;
        }
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
        if self.plain {
            errln!("{} (done)", self.state.line());
        }
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.state.finished.store(true, Ordering::Relaxed);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// README: in a CI log, "one every 10 s" between the first line and the last (those two
    /// are `readme_promises.rs`'s); the ticker wakes every 250 ms and prints when this says.
    #[test]
    fn a_plain_line_is_due_every_10_s() {
        let last = Instant::now();
        assert!(!due(last, last));
        assert!(!due(last, last + Duration::from_millis(9_999)));
        assert!(due(last, last + Duration::from_secs(10)));
        assert!(due(last, last + Duration::from_secs(29)));
    }

    fn state(done: u64, total: u64) -> State {
        State {
            what: "gcl conform".into(),
            unit: "cases",
            failing_word: "failing",
            total: Mutex::new(Total::Units(total)),
            done: AtomicU64::new(done),
            failures: AtomicU64::new(0),
            started: Instant::now(),
            last_line: Mutex::new(Instant::now()),
            finished: AtomicBool::new(false),
            started_line: AtomicBool::new(false),
        }
    }

    /// Issue 40: the first line of a run (one case done, which carried the pre-flight) gives
    /// no ETA; once a twentieth of the cases are done, it does.
    #[test]
    fn no_eta_before_a_twentieth_of_the_units_are_done() {
        for done in [1, 2, 16] {
            assert!(!state(done, 356).line().contains("ETA"), "{}", state(done, 356).line());
        }
        assert!(state(17, 356).line().contains("ETA"), "{}", state(17, 356).line());
        assert!(!state(2, 10).line().contains("ETA"));
        assert!(state(3, 10).line().contains("ETA"));
    }
}
