//! `gcl` run as the adversarial tests run it: under a memory limit (`prlimit --data`) and a
//! wall-clock bound, what it printed kept (up to 1 MiB of each stream).

#![allow(dead_code)] // each test file uses a part

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const GCL: &str = env!("CARGO_BIN_EXE_gcl");

/// What a bounded run of `gcl` gave.
pub struct Run {
    pub code: Option<i32>,
    pub stdout: String,
    pub stderr: String,
}

/// The memory a `gcl` of these tests may take (private writable mappings, heap included):
/// a flood read whole, an include bomb or a `/dev/zero` read whole goes past it at once.
pub const MEMORY: &str = "--data=402653184";

/// Runs `gcl ARGS` in `cwd` under [`MEMORY`], killing it if it has not ended within `limit`.
pub fn gcl_bounded(cwd: Option<&Path>, args: &[&str], limit: Duration) -> Run {
    gcl_bounded_closing(cwd, args, limit, None)
}

/// One of `gcl`'s output streams, given as a pipe whose reading end is closed before `gcl`
/// starts (`gcl ... | true` where `true` has already ended): every write to it fails with
/// EPIPE.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Closed {
    Stdout,
    Stderr,
}

/// A pipe nobody reads: its writing end, for a child.
fn closed_pipe() -> Stdio {
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    Stdio::from(writer)
}

/// As [`gcl_bounded`], with the `closed` stream (if any) a pipe nobody reads; what `gcl`
/// printed on it is "" in the [`Run`].
pub fn gcl_bounded_closing(cwd: Option<&Path>, args: &[&str], limit: Duration, closed: Option<Closed>) -> Run {
    let mut cmd = Command::new("prlimit");
    cmd.arg(MEMORY).arg("--").arg(GCL).args(args);
    // Few malloc arenas, so the limit measures what the program keeps, not address space.
    cmd.env("MALLOC_ARENA_MAX", "2").stdin(Stdio::null());
    cmd.stdout(if closed == Some(Closed::Stdout) { closed_pipe() } else { Stdio::piped() });
    cmd.stderr(if closed == Some(Closed::Stderr) { closed_pipe() } else { Stdio::piped() });
    if let Some(d) = cwd {
        cmd.current_dir(d);
    }
    let mut child = cmd.spawn().expect("prlimit (util-linux) runs gcl");
    let out_pipe: Box<dyn std::io::Read + Send> = match child.stdout.take() {
        Some(p) => Box::new(p),
        None => Box::new(std::io::empty()),
    };
    let err_pipe: Box<dyn std::io::Read + Send> = match child.stderr.take() {
        Some(p) => Box::new(p),
        None => Box::new(std::io::empty()),
    };
    let read = |mut p: Box<dyn std::io::Read + Send>| {
        std::thread::spawn(move || {
            // Keep at most 1 MiB of what gcl prints: a flood echoed into a message is a finding,
            // not a reason for the test itself to run out of memory.
            let mut kept = Vec::new();
            let mut buf = [0u8; 65536];
            loop {
                match p.read(&mut buf) {
                    Ok(0) | Err(_) => break,
                    Ok(n) => {
                        if kept.len() < 1 << 20 {
                            kept.extend_from_slice(&buf[..n]);
                        }
                    }
                }
            }
            String::from_utf8_lossy(&kept).into_owned()
        })
    };
    let out = read(out_pipe);
    let err = read(err_pipe);
    let end = Instant::now() + limit;
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if Instant::now() > end {
            let _ = child.kill();
            let _ = child.wait();
            panic!("gcl {args:?} did not end within {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    Run { code: status.code(), stdout: out.join().unwrap(), stderr: err.join().unwrap() }
}

/// Kills process `pid` (a child the test spawned) unless disarmed within `limit`: the
/// wall-clock bound of a test that talks to its child as it runs.
pub struct Watchdog(Option<std::sync::mpsc::Sender<()>>);

impl Watchdog {
    /// The child ended in time.
    pub fn disarm(mut self) {
        if let Some(tx) = self.0.take() {
            let _ = tx.send(());
        }
    }
}

/// A [`Watchdog`] for `pid`.
pub fn kill_after(pid: u32, limit: Duration) -> Watchdog {
    let (tx, rx) = std::sync::mpsc::channel::<()>();
    std::thread::spawn(move || {
        if rx.recv_timeout(limit) == Err(std::sync::mpsc::RecvTimeoutError::Timeout) {
            let _ = Command::new("kill").arg("-KILL").arg(pid.to_string()).status();
        }
    });
    Watchdog(Some(tx))
}
