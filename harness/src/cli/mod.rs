//! The `gcl` subcommands. Each module owns one subcommand: its clap arguments and its `run`.
//! `run` returns the process exit code: 0 success, 1 conformance failures, 2 usage or
//! infrastructure errors (errors returned as `Err` become 2 in `main`).

pub mod certify;
pub mod check_host;
pub mod check_host_serve;
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
pub mod suite;
pub mod vectors;

use std::sync::Arc;

use gcl_model::Profile;

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

/// SIGINT, SIGTERM and SIGHUP (a CI job's time limit) end a campaign (`gcl fuzz host`, `gcl
/// fuzz device`): the returned flag is set, the work in flight is called off, and the findings
/// and reports are still written; a second signal exits at once (exit 2). `what` names the
/// command in the message printed at the first signal.
pub fn stop_on_signals(what: &'static str) -> anyhow::Result<std::sync::Arc<std::sync::atomic::AtomicBool>> {
    use anyhow::Context;
    use nix::sys::signal::{SigSet, SigmaskHow, Signal, pthread_sigmask};
    use std::sync::atomic::{AtomicBool, Ordering};
    let mut mask = SigSet::empty();
    for s in [Signal::SIGINT, Signal::SIGTERM, Signal::SIGHUP] {
        mask.add(s);
    }
    // Threads started from here on inherit the mask; child processes do not (std resets it).
    pthread_sigmask(SigmaskHow::SIG_BLOCK, Some(&mask), None).context("blocking signals")?;
    let signals = nix::sys::signalfd::SignalFd::new(&mask).context("signalfd")?;
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    std::thread::spawn(move || {
        while let Ok(Some(_)) = signals.read_signal() {
            if flag.swap(true, Ordering::Relaxed) {
                std::process::exit(i32::from(EXIT_ERROR));
            }
            eprintln!("gcl {what}: stopping: the work in flight is called off (again to exit now)");
        }
    });
    Ok(stop)
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
