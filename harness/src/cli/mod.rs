//! The `gcl` subcommands. Each module owns one subcommand: its clap arguments and its `run`.
//! `run` returns the process exit code: 0 success, 1 conformance failures, 2 usage or
//! infrastructure errors (errors returned as `Err` become 2 in `main`).
//!
//! The `cli` module belongs to the `gcl` binary (`main.rs` declares `mod cli;`), not to the
//! library. Each subcommand module owns its clap arguments (with its own value enums, such as
//! `--level` and `--time`, mapped to the library's types). Only here do `anyhow`, `clap` and
//! `indicatif` appear; the library returns typed errors (`ConformError`, `KnownFailuresError`,
//! `ProfileError`, `KeyError`, `BundleError`, ...).
//!
//! Every command prints through `stdio` (`outln!`, `errln!`, `stdio::out()`): a reader that
//! went away or a full disk never cuts a command short or changes its exit code.
//!
//! Helpers two commands share live here: `find_upward`, `load_profile`; `progress`, the one
//! progress display every long command uses (a bar with an ETA on a terminal; without one a line at
//! the start, every 10 s from a ticker thread, and at the end; its threads start with the stop
//! signals blocked, `without_stop_signals`); and `stop_on_signals`, which turns SIGINT, SIGTERM and
//! SIGHUP into a stop flag for `fuzz host`, `fuzz device` and `check-host` and records which signal
//! (and whether a host under test sent it: `stopped_by`). A second signal kills every live host's
//! process group and removes its run folder (`fuzz::host::session::end_all`) before it exits.

pub mod certify;
pub mod check_host;
pub mod conform;
pub mod explain;
pub mod fuzz;
pub mod fuzz_host;
pub mod fuzz_merge;
pub mod progress;
pub mod record;
pub mod replay;
pub mod sim;
pub mod spec;
pub mod stdio;
pub mod suite;
pub mod vectors;

use std::sync::Arc;

use gcl_model::Profile;
use stdio::errln;

/// Exit code: everything passed.
pub const EXIT_OK: u8 = 0;
/// Exit code: conformance failures (or a mismatch).
pub const EXIT_FAIL: u8 = 1;
/// Exit code: usage or infrastructure error.
pub const EXIT_ERROR: u8 = 2;

/// The one line `main` prints for an error: the error and its causes, outermost first, as
/// anyhow's `{:#}` writes them, but without a cause that an earlier part already says in full
/// (an error whose message embeds its source, as many `thiserror` messages do, would say it
/// twice: `...(os error 2): cannot open ...(os error 2)`).
pub fn error_line(e: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if line.contains(&text) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&text);
    }
    line
}

/// Loads a profile by built-in name or alias (`seed`, `bh8-262-4.3`, `bh8-262-4.4`,
/// `bh8-262`) or from a TOML file ([`gcl_host::profiles::load`]).
pub fn load_profile(name: &str) -> anyhow::Result<Arc<Profile>> {
    Ok(gcl_host::profiles::load(name)?)
}

/// The longest wait a millisecond argument may name (`--timeout`, `--quiet`, `--margin`): one
/// hour. Beyond it a typo (`--quiet 1000000000000000`) would mean a run that never ends.
pub const MAX_WAIT_MS: u64 = 3_600_000;

/// The longest campaign a duration argument may name (`--duration`, `--run-budget`): 7 days.
pub const MAX_DURATION: std::time::Duration = std::time::Duration::from_secs(7 * 24 * 3600);

/// Parses a millisecond argument of at most [`MAX_WAIT_MS`].
pub fn millis(s: &str) -> Result<u64, String> {
    let ms: u64 = s.parse().map_err(|e| format!("`{s}`: {e} (a number of milliseconds)"))?;
    if ms > MAX_WAIT_MS {
        return Err(format!("{ms} ms is more than the limit of {MAX_WAIT_MS} ms (one hour)"));
    }
    Ok(ms)
}

/// Parses a duration argument (`30s`, `500ms`, `5m`) of at most [`MAX_DURATION`].
pub fn duration(s: &str) -> Result<std::time::Duration, String> {
    let d = humantime::parse_duration(s).map_err(|e| format!("`{s}`: {e} (write durations as 30s, 500ms or 5m)"))?;
    if d > MAX_DURATION {
        return Err(format!("`{s}` is more than the limit of {}", humantime::format_duration(MAX_DURATION)));
    }
    Ok(d)
}

/// SIGINT, SIGTERM and SIGHUP (a CI job's time limit) end a campaign or a check (`gcl fuzz
/// host`, `gcl fuzz device`, `gcl check-host`): the returned flag is set, the work in flight
/// is called off (hosts stopped), and the findings and reports are still written, saying
/// that the run was stopped ([`stopped_by`]); a second signal exits at once (exit 2), after
/// killing the hosts in flight and removing their run folders. `what` names the command in
/// the message printed at the first signal.
///
/// Call it before any thread starts (the progress ticker included): a thread started before
/// keeps these signals unblocked, and a signal delivered to it kills the process.
pub fn stop_on_signals(what: &'static str) -> anyhow::Result<std::sync::Arc<std::sync::atomic::AtomicBool>> {
    use anyhow::Context;
    use nix::sys::signal::{SigmaskHow, pthread_sigmask};
    use std::sync::atomic::{AtomicBool, Ordering};
    let mask = stop_signals();
    // Threads started from here on inherit the mask; child processes do not (std resets it).
    pthread_sigmask(SigmaskHow::SIG_BLOCK, Some(&mask), None).context("blocking signals")?;
    let signals = nix::sys::signalfd::SignalFd::new(&mask).context("signalfd")?;
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    std::thread::spawn(move || {
        let mut heard = 0;
        while let Ok(Some(info)) = signals.read_signal() {
            heard += 1;
            if heard > 1 {
                gcl_harness::fuzz::host::session::end_all();
                std::process::exit(i32::from(EXIT_ERROR));
            }
            let name = nix::sys::signal::Signal::try_from(info.ssi_signo as i32).map_or("a signal", |s| s.as_str());
            let pid = info.ssi_pid as i32;
            // A host's group leader has its group's number; another member is looked up.
            let host_group = gcl_harness::fuzz::host::session::is_host_group;
            let from_host = pid > 0
                && (host_group(pid)
                    || nix::unistd::getpgid(Some(nix::unistd::Pid::from_raw(pid)))
                        .is_ok_and(|g| host_group(g.as_raw())));
            let by = if from_host { format!("{name} from the host under test (pid {pid})") } else { name.to_string() };
            *STOPPED_BY.lock().unwrap_or_else(|e| e.into_inner()) = Some(by);
            flag.store(true, Ordering::Relaxed);
            errln!("gcl {what}: stopping: the work in flight is called off (again to exit now)");
        }
    });
    Ok(stop)
}

/// The signals that stop a campaign or a check.
fn stop_signals() -> nix::sys::signal::SigSet {
    use nix::sys::signal::{SigSet, Signal};
    let mut mask = SigSet::empty();
    for s in [Signal::SIGINT, Signal::SIGTERM, Signal::SIGHUP] {
        mask.add(s);
    }
    mask
}

/// Runs `f` with the signals that stop a campaign blocked in this thread, then restores the
/// mask: a thread `f` starts (the progress ticker, a bar's tick) inherits the block from its
/// creation, so it never takes such a signal (one delivered to a thread that does not block
/// it kills the process before the command's handler hears it), whenever it was started.
pub fn without_stop_signals<T>(f: impl FnOnce() -> T) -> T {
    use nix::sys::signal::{SigSet, SigmaskHow, pthread_sigmask};
    let mut old = SigSet::empty();
    let blocked = pthread_sigmask(SigmaskHow::SIG_BLOCK, Some(&stop_signals()), Some(&mut old)).is_ok();
    let out = f();
    if blocked {
        let _ = pthread_sigmask(SigmaskHow::SIG_SETMASK, Some(&old), None);
    }
    out
}

static STOPPED_BY: std::sync::Mutex<Option<String>> = std::sync::Mutex::new(None);

/// The signal that stopped the command (`SIGTERM`, or `SIGTERM from the host under test (pid
/// N)`), once [`stop_on_signals`] heard one.
pub fn stopped_by() -> Option<String> {
    STOPPED_BY.lock().unwrap_or_else(|e| e.into_inner()).clone()
}

/// `rel` (a repository path such as `vectors/suite`) in the current directory or the nearest
/// folder above it that has it, for the commands that only read it.
pub(crate) fn find_upward(rel: &str) -> anyhow::Result<std::path::PathBuf> {
    let cwd = std::env::current_dir()?;
    for d in cwd.ancestors() {
        let candidate = d.join(rel);
        if candidate.is_dir() {
            // Shown relative when it is the current directory's own, as before.
            return Ok(if d == cwd { std::path::PathBuf::from(rel) } else { candidate });
        }
    }
    anyhow::bail!(
        "no {rel} in {} or any folder above it: run gcl inside a checkout of the repository, or give --dir DIR \
(`gcl suite list` shows the cases built into gcl anywhere)",
        cwd.display()
    )
}
#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, thiserror::Error)]
    #[error("opening the target: {0}")]
    struct Outer(#[source] std::io::Error);

    #[test]
    fn an_error_line_says_each_cause_once() {
        let io = || std::io::Error::new(std::io::ErrorKind::NotFound, "No such file or directory (os error 2)");
        // A message that embeds its source: the source is not said again.
        let e = anyhow::Error::new(Outer(io())).context("gcl fuzz device");
        assert_eq!(error_line(&e), "gcl fuzz device: opening the target: No such file or directory (os error 2)");
        // A context over a plain cause keeps both.
        let e = anyhow::Error::new(io()).context("reading corpus/a.json");
        assert_eq!(error_line(&e), "reading corpus/a.json: No such file or directory (os error 2)");
    }
}
