//! Figures of `gcl fuzz device` (issue 11).
//!
//! Run with `cargo bench -p gcl-harness --bench fuzz_device`. Figures:
//! - cases per second against the in-process sim (bh8-262, no fault, findings not minimized);
//! - cases per second over `exec:gcl sim --stdio` (one child reused, `--no abort-timing`,
//!   since the stdio sim's motion completes at once);
//! - for every fault of the sim, the wall time to the first finding with seed 1 (in-process,
//!   up to 3000 cases), and the share found under 10 s. Aim: at least 90 %.
//!
//! Not measured here (see the report of the branch): bytes per second over a pty at 38400
//! against the line rate, and the side-by-side with boofuzz.
//!
//! Without `--bench` (as under `cargo test --all-targets`) it runs a few cases of each as a
//! smoke test.

use std::time::Duration;

use gcl_harness::fuzz::device::{Budget, FuzzOptions, run};
use gcl_host::target::Target;
use gcl_model::{Fault, Profile};

fn main() {
    let bench = std::env::args().any(|a| a == "--bench");
    let p = Profile::builtin("bh8-262").unwrap();
    let n = |full: u64, smoke: u64| if bench { full } else { smoke };

    let mut o = FuzzOptions::new(Target::Sim { profile: None }, p.clone());
    o.budget = Budget::Runs(n(3000, 20));
    o.minimize = false;
    let s = run(&o, &|_| {}).unwrap();
    println!(
        "in-process sim: {} cases in {:.2} s = {:.0} cases/s ({} dropped by the model)",
        s.runs,
        s.elapsed.as_secs_f64(),
        s.cases_per_second(),
        s.dropped
    );

    let exec: Target = format!("exec:{} sim --stdio", env!("CARGO_BIN_EXE_gcl")).parse().unwrap();
    let mut o = FuzzOptions::new(exec, p.clone());
    o.budget = Budget::Runs(n(300, 5));
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
