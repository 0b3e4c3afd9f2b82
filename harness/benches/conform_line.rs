//! `gcl conform` at the speed of the line (issue 21, P1).
//!
//! Run with `cargo bench -p gcl-harness --bench conform_line`. For seed and bh8-262, at 9600
//! and 38400 baud: `gcl sim --pty --baud B` (real time, its defaults otherwise) and `gcl
//! conform --target serial:PTY?baud=B` over the whole suite, and the run's own figures from
//! `report.json`: wall time, the wire-time lower bound, their ratio (aim: at most 1.05).
//!
//! The lower bound ([`gcl_harness::conform`]'s, in `report.json`) counts, per case, its
//! pauses and step after step the larger of the bytes received and the model's motion time
//! (GCL is command-then-answer; the line is full duplex and the hand echoes as it reads), the
//! model carrying the hand's state from one passing case to the next, and what the run puts on
//! the line before its first case (the pre-flight, the motion-time probe: `probes_ms`), since
//! the wall time is the whole run. The bench also prints the cases' own time (the sum of their
//! durations) against the cases' part of the bound, and the run's time outside every case
//! against the probes' part: the first is what load affects least.
//!
//! `GCL_BENCH_BIN=PATH` measures another `gcl` binary (an older build, for a before/after).
//! Without `--bench` (as under `cargo test --all-targets`) it runs the framing cases of seed at
//! 38400 as a smoke test. A word after `--` picks the runs whose name holds it (`seed@9600`).

use std::io::BufRead;
use std::process::{Command, Stdio};

fn main() {
    let bench = std::env::args().any(|a| a == "--bench");
    let filter: Option<String> = std::env::args().skip(1).find(|a| !a.starts_with('-'));
    let bin = std::env::var("GCL_BENCH_BIN").unwrap_or_else(|_| env!("CARGO_BIN_EXE_gcl").to_string());
    println!("gcl conform over gcl sim --pty (real time), {bin}");
    let runs: &[(&str, u32)] = if bench {
        &[("seed", 9600), ("seed", 38400), ("bh8-262", 9600), ("bh8-262", 38400)]
    } else {
        &[("seed", 38400)]
    };
    for (profile, baud) in runs {
        let name = format!("{profile}@{baud}");
        if filter.as_ref().is_some_and(|f| !name.contains(f.as_str())) {
            continue;
        }
        let only: &[&str] = if bench { &[] } else { &["--only", "framing-*"] };
        figure(&bin, profile, *baud, only);
    }
}

fn figure(bin: &str, profile: &str, baud: u32, only: &[&str]) {
    let mut sim = Command::new(bin)
        .args(["sim", "--pty", "--profile", profile, "--baud", &baud.to_string()])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("starting gcl sim --pty");
    let mut pty = String::new();
    if let Some(out) = sim.stdout.take() {
        std::io::BufReader::new(out).read_line(&mut pty).expect("reading the pty path");
    }
    let dir = tempfile::tempdir().unwrap();
    let target = format!("serial:{}?baud={baud}", pty.trim());
    let out = Command::new(bin)
        .args(["conform", "--target", &target, "--profile", profile, "--quiet", "--report"])
        .arg(dir.path())
        .args(only)
        .output()
        .expect("running gcl conform");
    let _ = sim.kill();
    let _ = sim.wait();
    let report: serde_json::Value = match std::fs::read(dir.path().join("report.json")) {
        Ok(b) => serde_json::from_slice(&b).unwrap(),
        Err(e) => panic!("no report ({e}): {}", String::from_utf8_lossy(&out.stdout)),
    };
    let w = &report["wire"];
    let actual = w["actual_ms"].as_f64().unwrap_or(0.0);
    let bound = w["lower_bound_ms"].as_f64().unwrap_or(0.0);
    let probes = w["probes_ms"].as_f64().unwrap_or(0.0);
    let cases_ms: f64 = report["cases"]
        .as_array()
        .into_iter()
        .flatten()
        .filter(|c| matches!(c["verdict"].as_str(), Some("PASS" | "FAIL" | "XFAIL" | "XPASS")))
        .filter_map(|c| c["duration_ms"].as_f64())
        .sum();
    let not_pass: Vec<String> = report["cases"]
        .as_array()
        .into_iter()
        .flatten()
        .filter(|c| c["verdict"] != "PASS")
        .map(|c| format!("{} {}", c["id"].as_str().unwrap_or(""), c["verdict"].as_str().unwrap_or("")))
        .collect();
    println!(
        "{profile:>8} @ {baud:>5}: {} cases, wall {:.1} s, lower bound {:.1} s, ratio {:.3}; the cases alone {:.1} s \
         for {:.1} s of the bound, ratio {:.3}; outside the cases {:.2} s for {:.2} s of the bound{}",
        w["counted_cases"],
        actual / 1000.0,
        bound / 1000.0,
        if bound > 0.0 { actual / bound } else { 0.0 },
        cases_ms / 1000.0,
        (bound - probes) / 1000.0,
        if bound > probes { cases_ms / (bound - probes) } else { 0.0 },
        (actual - cases_ms) / 1000.0,
        probes / 1000.0,
        if not_pass.is_empty() { String::new() } else { format!("; not PASS: {}", not_pass.join(", ")) }
    );
}
