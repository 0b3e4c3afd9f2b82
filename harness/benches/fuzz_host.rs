//! Figures of `gcl fuzz host`: runs per second and the per-run overhead.
//!
//! Run with `cargo bench -p gcl-harness --bench fuzz_host`. Each run is what the fuzzer does
//! per run: a fresh simulated hand (profile seed, fast time, unpaced) on a fresh pty, a host
//! process started, its scenario run to the end, the host's traffic checked. The host is this
//! very executable started again with `--as-host`: the host library (`Hand` over
//! the `serial:` link) running ten supervisory commands, as a compiled host library would.
//!
//! Figures:
//! - runs/s for the ten-command scenario, without misbehaviour, one job and two jobs.
//!   Aim: at least 20 runs/s.
//! - runs/s with a random schedule of misbehaviours (most runs then wait out a host timeout,
//!   so this is far lower; it depends on the host's timeouts, here 200 ms).
//! - the per-run overhead of pty + hand + process: runs/s and ms/run with `/bin/true` as the
//!   host (it opens nothing and exits at once).
//!
//! Without `--bench` (as under `cargo test --all-targets`) it makes a few runs of each and
//! prints the same lines.

use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use gcl_harness::fuzz::host::{FuzzOptions, HostRun, Transport, Weights, fuzz, run_once};
use gcl_harness::sim::misbehave::Schedule;
use gcl_harness::sim::{Pace, TimeMode};
use gcl_host::client::{Hand, Timeouts};
use gcl_host::target::{OpenOptions, Target};

const SCENARIO: [&str; 10] =
    ["FGET DP", "HI", "1M 5000", "1FGET P", "C", "FGET P", "O", "2M 1000", "123FGET P", "FGET DP"];

/// The host side: ten commands over the port named by GCL_PORT.
fn host() -> std::process::ExitCode {
    let port = std::env::var("GCL_PORT").unwrap_or_default();
    let target: Target = match format!("serial:{port}").parse() {
        Ok(t) => t,
        Err(_) => return std::process::ExitCode::from(2),
    };
    let opts = OpenOptions { profile: Some("seed".into()), ..Default::default() };
    let result = Hand::open(&target, &opts).and_then(|mut hand| {
        let t = Duration::from_millis(200);
        hand.set_timeouts(Timeouts { reply: t, motion: t, block: t, sync: t });
        for line in SCENARIO {
            hand.command(line)?;
        }
        Ok(())
    });
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("bench host: {e}");
            std::process::ExitCode::from(1)
        }
    }
}

fn spec(command: Vec<String>) -> HostRun {
    HostRun {
        command,
        transport: Transport::Pty,
        profile: gcl_model::Profile::builtin("seed").unwrap(),
        time: TimeMode::Fast,
        pace: Pace::Unpaced,
        hand_seed: 0,
        timeout_hang: Duration::from_secs(3),
        budget: Duration::from_secs(30),
    }
}

fn clean_runs(label: &str, run: &HostRun, n: usize, jobs: usize) {
    let t0 = Instant::now();
    std::thread::scope(|s| {
        for j in 0..jobs {
            s.spawn(move || {
                for _ in (j..n).step_by(jobs) {
                    let r = run_once(run, &Schedule::default()).expect("run");
                    assert!(r.violations.is_empty(), "{:?}", r.violations);
                }
            });
        }
    });
    let secs = t0.elapsed().as_secs_f64();
    println!(
        "{label}, {jobs} job(s): {n} runs in {secs:.2} s: {:.1} runs/s, {:.1} ms/run",
        n as f64 / secs,
        secs * 1000.0 / n as f64
    );
}

fn main() -> std::process::ExitCode {
    if std::env::args().nth(1).as_deref() == Some("--as-host") {
        return host();
    }
    let bench = std::env::args().any(|a| a == "--bench");
    let me = std::env::current_exe().expect("own path").display().to_string();
    let scenario = spec(vec![me, "--as-host".into()]);
    let n = if bench { 200 } else { 5 };
    clean_runs("ten-command scenario, no misbehaviour", &scenario, n, 1);
    clean_runs("ten-command scenario, no misbehaviour", &scenario, n, 2);
    clean_runs("overhead (pty + hand + /bin/true)", &spec(vec!["/bin/true".into()]), n, 1);
    let opts = FuzzOptions {
        run: scenario,
        seed: 1,
        runs: Some(if bench { 100 } else { 5 }),
        duration: None,
        ok_exit_codes: vec![0, 1],
        jobs: 2,
        weights: Weights::default(),
        max_planned: 3,
        minimize: false,
    };
    let c = fuzz(&opts, &AtomicBool::new(false), &|_| {}).expect("campaign");
    let secs = c.elapsed_ms as f64 / 1000.0;
    println!(
        "fuzzing campaign, 2 jobs: {} runs in {secs:.2} s: {:.1} runs/s, {} finding(s)",
        c.runs,
        c.runs as f64 / secs,
        c.findings.len()
    );
    std::process::ExitCode::SUCCESS
}
