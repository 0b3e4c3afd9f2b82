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
//!   so this is far lower; it depends on the host's timeouts, here 200 ms), with a fixed hang
//!   timeout and as `gcl fuzz host` runs by default, calibrated (the host's give-up time
//!   measured first, the calibration runs counted in the campaign's time).
//! - the per-run overhead of pty + hand + process: runs/s and ms/run with `/bin/true` as the
//!   host (it opens nothing and exits at once).
//! - how much guidance helps: for each Python host mutant (`tests/host_mutants/`, needs
//!   python3 with pyserial), the runs to its first finding of the expected kind with guidance
//!   and without (`guided: false`, every schedule fresh), over several seeds, and the mean.
//!
//! Without `--bench` (as under `cargo test --all-targets`) it makes a few runs of each and
//! prints the same lines.

use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use gcl_harness::fuzz::host::{Event, FindingKind, FuzzOptions, HostRun, Transport, Weights, fuzz, run_once};
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
        link: None,
        coverage: Default::default(),
        env: Vec::new(),
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

/// Python mutants: file, the operators fuzzed, the kind of finding and what its signature names
/// (as in `tests/it/fuzz_host.rs`).
const MUTANTS: [(&str, &str, FindingKind, &str); 6] = [
    ("py_prompt_forever.py", "no-prompt,truncate,bad-prompt,silence", FindingKind::Hang, "awaiting the answer"),
    ("py_err_table.py", "err-bits,garbage", FindingKind::Crash, "python KeyError"),
    ("py_parse_values.py", "crlf,garbage,restart", FindingKind::Crash, "python ValueError"),
    ("py_rt_length.py", "rt-block-length,rt-err", FindingKind::Crash, "python IndexError"),
    ("py_banner_version.py", "banner-variant,restart", FindingKind::Crash, "python ValueError"),
    ("py_sends_lf.py", "truncate", FindingKind::Violation, "line-ending"),
];

/// Runs (1-based) until the first finding of `kind` naming `needle`, or `None` within `cap`.
fn runs_to_first(
    command: Vec<String>,
    ops: &str,
    kind: FindingKind,
    needle: &str,
    seed: u64,
    guided: bool,
    cap: u64,
) -> Option<u64> {
    let mut run = spec(command);
    run.timeout_hang = Duration::from_millis(2500);
    let opts = FuzzOptions {
        run,
        seed,
        runs: Some(cap),
        duration: None,
        ok_exit_codes: vec![0, 1],
        jobs: 1,
        weights: Weights::parse(ops).expect("ops"),
        max_planned: 3,
        minimize: false,
        guided,
        calibrate: false,
        shard: None,
    };
    let stop = AtomicBool::new(false);
    let first = Mutex::new(None);
    fuzz(&opts, &stop, &|e| {
        if let Event::Found(f) = e
            && f.verdict.kind == kind
            && f.verdict.signature.contains(needle)
        {
            first.lock().unwrap().get_or_insert(f.run + 1);
            stop.store(true, Ordering::Relaxed);
        }
    })
    .expect("campaign");
    first.into_inner().unwrap()
}

fn guidance(bench: bool) {
    let ok =
        std::process::Command::new("python3").args(["-c", "import serial"]).output().is_ok_and(|o| o.status.success());
    if !ok {
        println!("guidance: skipped (python3 with pyserial is not available)");
        return;
    }
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/host_mutants");
    let (seeds, cap, mutants) = if bench { (1..=5u64, 60, &MUTANTS[..]) } else { (1..=1u64, 10, &MUTANTS[..1]) };
    let mut totals = [(0u64, 0u64, 0u64); 2];
    for (file, ops, kind, needle) in mutants {
        let command = vec!["python3".to_string(), dir.join(file).display().to_string()];
        let mut line = format!("guidance, {file}:");
        for (g, guided) in [true, false].into_iter().enumerate() {
            let found: Vec<Option<u64>> =
                seeds.clone().map(|s| runs_to_first(command.clone(), ops, *kind, needle, s, guided, cap)).collect();
            let hit: Vec<u64> = found.iter().flatten().copied().collect();
            totals[g].0 += hit.iter().sum::<u64>();
            totals[g].1 += hit.len() as u64;
            totals[g].2 += (found.len() - hit.len()) as u64;
            let shown: Vec<String> = found.iter().map(|f| f.map_or(format!(">{cap}"), |n| n.to_string())).collect();
            line += &format!(" {} [{}]", if guided { "guided" } else { "unguided" }, shown.join(" "));
        }
        println!("{line}");
    }
    for (g, name) in [(0, "guided"), (1, "unguided")] {
        let (sum, n, missed) = totals[g];
        println!(
            "guidance, {name}: mean {:.1} runs to the first finding over {n} campaigns, {missed} without one in {cap} runs",
            sum as f64 / n.max(1) as f64
        );
    }
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
        guided: true,
        calibrate: false,
        shard: None,
    };
    let c = fuzz(&opts, &AtomicBool::new(false), &|_| {}).expect("campaign");
    let secs = c.elapsed_ms as f64 / 1000.0;
    println!(
        "fuzzing campaign, 2 jobs: {} runs in {secs:.2} s: {:.1} runs/s, {} finding(s)",
        c.runs,
        c.runs as f64 / secs,
        c.findings.len()
    );
    // The same campaign as `gcl fuzz host` runs it by default: the host's give-up time
    // measured first (its time counted in the campaign's).
    let c = fuzz(&FuzzOptions { calibrate: true, ..opts }, &AtomicBool::new(false), &|_| {}).expect("campaign");
    let secs = c.elapsed_ms as f64 / 1000.0;
    let cal = c.calibration.clone().unwrap_or_default();
    println!(
        "fuzzing campaign, 2 jobs, calibrated: {} runs (+{} to calibrate) in {secs:.2} s: {:.1} runs/s, {} finding(s); host timeout {:?} ms, hang timeout {} ms",
        c.runs,
        cal.runs,
        c.runs as f64 / secs,
        c.findings.len(),
        cal.host_timeout_ms,
        cal.timeout_hang_ms
    );
    guidance(bench);
    std::process::ExitCode::SUCCESS
}
