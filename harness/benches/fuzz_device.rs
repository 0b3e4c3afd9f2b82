//! Figures of `gcl fuzz device` (issue 11).
//!
//! Run with `cargo bench -p gcl-harness --bench fuzz_device`. Figures:
//! - cases per second against the in-process sim (bh8-262, no fault, findings not minimized),
//!   and beside it cases per CPU-second of this process (which a busy machine moves less),
//!   at 2,000 and at 20,000 cases (the corpus grows as a campaign goes on, and with it the
//!   cases drawn from it: a later fall shows at the larger figure; issue 31);
//! - cases per second over `exec:gcl sim --stdio` (one child reused, `--no abort-timing`,
//!   since the stdio sim's motion completes at once);
//! - for every fault of the sim, the wall time to the first finding with seed 1 (in-process,
//!   up to 3000 cases), and the share found under 10 s. Aim: at least 90 %.
//!
//! - over a pty at 38400 (`gcl sim --pty --time fast --baud 38400`, fuzzed as
//!   `serial:PATH?baud=38400`, `--no abort-timing` since fast time ends motion at once, 20 s):
//!   cases per second and wire bytes per second (both directions) ÷ the line rate (3840 bytes/s
//!   at 8N1). Aim: at least 0.9.
//!
//! The side-by-side with boofuzz is `harness/benches/boofuzz/compare.sh` (it installs boofuzz
//! into a venv under `target/`).
//!
//! Without `--bench` (as under `cargo test --all-targets`) it runs a few cases of each as a
//! smoke test. A word after `--` picks the figures whose name holds it (`in-process`, `exec`,
//! `pty`, `faults`), e.g. `cargo bench -p gcl-harness --bench fuzz_device -- pty`.

use std::io::BufRead;
use std::process::{Command, Stdio};
use std::time::Duration;

use gcl_harness::deadline::predict;
use gcl_harness::fuzz::device::action::HostAction;
use gcl_harness::fuzz::device::case::build_case;
use gcl_harness::fuzz::device::{Budget, FuzzOptions, run};
use gcl_harness::suite::Case;
use gcl_host::target::Target;
use gcl_model::{Fault, Profile};

// (the allocator the `gcl` binary runs with, so that these figures are the binary's)
#[global_allocator]
static ALLOC: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() {
    let bench = std::env::args().any(|a| a == "--bench");
    let filter: Option<String> = std::env::args().skip(1).find(|a| !a.starts_with('-'));
    let wanted = |name: &str| filter.as_ref().is_none_or(|f| name.contains(f.as_str()));
    let p = Profile::builtin("bh8-262").unwrap();
    let n = |full: u64, smoke: u64| if bench { full } else { smoke };

    if wanted("in-process") {
        // (the suite's cases, the corpus every campaign starts from, are made once per process;
        // `gcl fuzz device` counts that in its figure, these do not)
        let t = std::time::Instant::now();
        let seeds = gcl_harness::fuzz::device::suite_seeds(&p).len();
        println!(
            "the suite's {seeds} cases as the corpus's start: {:.2} s, once per process",
            t.elapsed().as_secs_f64()
        );
        for runs in [n(2000, 20), n(20000, 40)] {
            in_process(&p, runs);
        }
    }
    if wanted("exec") {
        exec(&p, n(300, 5));
    }
    if wanted("pty") {
        pty_figure(&p, n(20, 1));
    }
    if wanted("faults") {
        faults(&p, bench);
    }
}

/// Cases per second against the in-process sim (seed 1, as `gcl fuzz device --target sim
/// --seed 1 --runs N --no-minimize`).
fn in_process(p: &std::sync::Arc<Profile>, runs: u64) {
    let mut o = FuzzOptions::new(Target::Sim { profile: None }, p.clone());
    o.budget = Budget::Runs(runs);
    o.seed = 1;
    o.minimize = false;
    let cpu = cpu_seconds();
    let s = run(&o, &|_| {}).unwrap();
    let per_cpu = match (cpu, cpu_seconds()) {
        (Some(a), Some(b)) if b > a => format!("{:.0} per CPU-second", s.runs as f64 / (b - a)),
        _ => "CPU time unknown".to_string(),
    };
    println!(
        "in-process sim, {runs} cases: {} cases in {:.2} s = {:.0} cases/s, {per_cpu} ({} dropped by the model)",
        s.runs,
        s.elapsed.as_secs_f64(),
        s.cases_per_second(),
        s.dropped
    );
}

/// The CPU time this process has used (user and system, every thread, those ended too), from
/// `/proc/self/stat` in clock ticks of 1/100 s (Linux's `USER_HZ`); `None` elsewhere. Beside a
/// wall-clock figure it tells a slower program from a busier machine.
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // (the fields after the command's name, which is in parentheses and may hold spaces)
    let rest = &stat[stat.rfind(')')? + 1..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |i: usize| fields.get(i).and_then(|f| f.parse::<u64>().ok());
    // (utime and stime are fields 14 and 15 of the line, 12 and 13 after the name)
    Some((ticks(11)? + ticks(12)?) as f64 / 100.0)
}

/// Cases per second over `exec:gcl sim --stdio`.
fn exec(p: &std::sync::Arc<Profile>, runs: u64) {
    let exec: Target = format!("exec:{} sim --stdio", env!("CARGO_BIN_EXE_gcl")).parse().unwrap();
    let mut o = FuzzOptions::new(exec, p.clone());
    o.budget = Budget::Runs(runs);
    o.minimize = false;
    o.allowed.abort_timing = false;
    let s = run(&o, &|_| {}).unwrap();
    println!(
        "exec:gcl sim --stdio: {} cases in {:.2} s = {:.1} cases/s, {} findings (expected 0)",
        s.runs,
        s.elapsed.as_secs_f64(),
        s.cases_per_second(),
        s.findings.len()
    );
}

/// Time to the first finding of every fault, in-process.
fn faults(p: &std::sync::Arc<Profile>, bench: bool) {
    let n = |full: u64, smoke: u64| if bench { full } else { smoke };
    let faults: &[Fault] = if bench { Fault::ALL } else { &Fault::ALL[..2] };
    let mut under = 0;
    for f in faults {
        let mut o = FuzzOptions::new(Target::Sim { profile: None }, p.clone());
        o.open.faults = vec![*f];
        o.seed = 1;
        o.budget = Budget::Runs(n(3000, 50));
        o.max_findings = Some(1);
        o.minimize = false;
        let s = run(&o, &|_| {}).unwrap();
        match s.findings.first() {
            Some(x) => {
                if x.found_after < Duration::from_secs(10) {
                    under += 1;
                }
                println!(
                    "  {:<24} first finding after {:>7.3} s (case {:>4}): {}",
                    f.name(),
                    x.found_after.as_secs_f64(),
                    x.run,
                    x.signature
                );
            }
            None => println!("  {:<24} not found in {} cases ({:.1} s)", f.name(), s.runs, s.elapsed.as_secs_f64()),
        }
    }
    println!(
        "faults found in-process under 10 s: {under} of {} = {:.0} % (aim: at least 90 %)",
        faults.len(),
        100.0 * under as f64 / faults.len() as f64
    );
}

/// Bytes per second over a pty at 38400 against the line rate.
fn pty_figure(p: &std::sync::Arc<Profile>, seconds: u64) {
    const BAUD: u32 = 38400;
    let mut sim = Command::new(env!("CARGO_BIN_EXE_gcl"))
        .args(["sim", "--pty", "--time", "fast", "--baud", &BAUD.to_string()])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("starting gcl sim --pty");
    let mut path = String::new();
    if let Some(out) = sim.stdout.take() {
        std::io::BufReader::new(out).read_line(&mut path).expect("reading the pty path");
    }
    let target: Target = format!("serial:{}?baud={BAUD}", path.trim()).parse().expect("a serial target");
    let mut o = FuzzOptions::new(target, p.clone());
    o.budget = Budget::Time(Duration::from_secs(seconds));
    o.minimize = false;
    o.allowed.abort_timing = false;
    let s = run(&o, &|_| {});
    let _ = sim.kill();
    let _ = sim.wait();
    let s = s.expect("fuzzing the pty");
    let busy = s.elapsed.saturating_sub(s.minimizing).as_secs_f64().max(1e-3);
    let line_rate = f64::from(BAUD) / 10.0;
    println!(
        "pty at {BAUD}: {} cases in {:.1} s = {:.1} cases/s, {:.0} wire bytes/s = {:.2} of the line rate \
         ({line_rate:.0} bytes/s; aim: at least 0.9), {} findings (expected 0)",
        s.runs,
        s.elapsed.as_secs_f64(),
        s.cases_per_second(),
        s.wire_bytes as f64 / busy,
        s.wire_bytes as f64 / busy / line_rate,
        s.findings.len()
    );
    println!(
        "  each way: {:.0} bytes/s sent = {:.2}, {:.0} received = {:.2} of the line; per case {:.0} bytes sent, {:.0} received",
        s.per_second(s.bytes_sent),
        s.per_second(s.bytes_sent) / line_rate,
        s.per_second(s.wire_bytes - s.bytes_sent),
        s.per_second(s.wire_bytes - s.bytes_sent) / line_rate,
        s.bytes_sent as f64 / s.runs.max(1) as f64,
        (s.wire_bytes - s.bytes_sent) as f64 / s.runs.max(1) as f64,
    );
    // Where a case's bytes go: the preamble every case starts with (a case of one ^C, less
    // the ^C's own step), as the model answers it.
    let built = build_case(p, &[HostAction::Abort], "preamble", "preamble", true, true).expect("a case of one ^C");
    let case = Case { profile: p.id.clone(), transcript: built.transcript };
    let pred = predict(&case, p).expect("the model passes its own case");
    let pre = &pred[..pred.len() - 1];
    let sent: usize = pre.iter().map(|s| s.wire_bytes - s.answer_len).sum();
    let back: usize = pre.iter().map(|s| s.answer_len).sum();
    println!("  the preamble of every case: {} steps, {sent} bytes sent, {back} received", pre.len());
}
