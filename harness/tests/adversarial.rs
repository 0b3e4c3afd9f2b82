//! Issue 20, the second adversarial round, as the attacker wrote it: certificates that would
//! lie, runs that would never end, floods that would eat memory, files that would be
//! overwritten or left half-written. Every `gcl` here runs under a memory limit (`prlimit
//! --data`) and a wall-clock bound, on loopback only; hands and hosts are small scripts.

mod sim_support;

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use sim_support::GCL;

/// What a bounded run of `gcl` gave.
struct Run {
    code: Option<i32>,
    stdout: String,
    stderr: String,
}

/// The memory a `gcl` of these tests may take (private writable mappings, heap included):
/// a flood read whole, an include bomb or a `/dev/zero` read whole goes past it at once.
const MEMORY: &str = "--data=402653184";

/// Runs `gcl ARGS` in `cwd` under [`MEMORY`], killing it if it has not ended within `limit`.
fn gcl_bounded(cwd: Option<&Path>, args: &[&str], limit: Duration) -> Run {
    let mut cmd = Command::new("prlimit");
    cmd.arg(MEMORY).arg("--").arg(GCL).args(args);
    // Few malloc arenas, so the limit measures what the program keeps, not address space.
    cmd.env("MALLOC_ARENA_MAX", "2").stdin(Stdio::null()).stdout(Stdio::piped()).stderr(Stdio::piped());
    if let Some(d) = cwd {
        cmd.current_dir(d);
    }
    let mut child = cmd.spawn().expect("prlimit (util-linux) runs gcl");
    let out_pipe = child.stdout.take().unwrap();
    let err_pipe = child.stderr.take().unwrap();
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
    let out = read(Box::new(out_pipe));
    let err = read(Box::new(err_pipe));
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

fn gcl(args: &[&str]) -> Run {
    gcl_bounded(None, args, Duration::from_secs(120))
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Item 9: every duration argument is bounded; an absurd one is a usage error at once, not a
/// run that spins for ever.
#[test]
fn absurd_durations_are_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let script = dir.path().join("s.gcls");
    std::fs::write(&script, "HI\n").unwrap();
    for args in [
        vec!["record", "--target", "sim", "--quiet", "1000000000000000", "--script", s(&script)],
        vec!["record", "--target", "sim", "--timeout", "1000000000000000", "--script", s(&script)],
        vec!["replay", "--timeout", "1000000000000000", "x.gcl"],
        vec!["conform", "--target", "sim:seed", "--margin", "1000000000000000"],
        vec!["fuzz", "device", "--target", "sim:seed", "--duration", "100000000years"],
    ] {
        let r = gcl_bounded(None, &args, Duration::from_secs(30));
        assert_eq!(r.code, Some(2), "{args:?}: {}", r.stderr);
        assert!(r.stderr.contains("limit"), "{args:?}: {}", r.stderr);
    }
}

/// Item 18: an exit code outside 0..=255 cannot be one a host exits with.
#[test]
fn ok_exit_codes_are_exit_codes() {
    for bad in ["256", "999", "-1"] {
        let r = gcl_bounded(None, &["fuzz", "host", "--runs", "1", "--ok-exit-codes", bad, "--", "true"], Duration::from_secs(30));
        assert_eq!(r.code, Some(2), "{bad}: {}", r.stderr);
        assert!(r.stderr.contains(bad), "{bad}: {}", r.stderr);
    }
}
