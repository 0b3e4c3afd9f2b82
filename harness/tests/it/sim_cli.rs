//! `gcl sim` as a user meets it: start-up errors, the EEPROM file, the trace, the pty link,
//! scenarios, faults, signals.

use crate::sim_support;

use std::process::{Command, Stdio};
use std::time::Duration;

use gcl_host::Link;
use gcl_host::client::ClientError;
use gcl_host::links::{ExecLink, StderrMode};
use sim_support::{GCL, SimProcess, Transport, stdio_argv, stdio_hand};

/// Runs `gcl sim ARGS` to its end; returns (exit code, stderr).
fn run(args: &[&str]) -> (Option<i32>, String) {
    let out = Command::new(GCL)
        .arg("sim")
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .output()
        .unwrap();
    (out.status.code(), String::from_utf8_lossy(&out.stderr).into_owned())
}

#[test]
fn start_up_errors_are_one_line_and_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let busy = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let busy_addr = busy.local_addr().unwrap().to_string();
    let bad_scenario = dir.path().join("bad.toml");
    std::fs::write(&bad_scenario, "tempreature = 1\n").unwrap();
    let bad_eeprom = dir.path().join("garbage.json");
    std::fs::write(&bad_eeprom, "not json").unwrap();
    let plain_file = dir.path().join("taken");
    std::fs::write(&plain_file, "").unwrap();
    let cases: Vec<(Vec<String>, &str)> = vec![
        (vec!["--stdio".into(), "--profile".into(), "nonesuch".into()], "unknown profile"),
        (vec!["--tcp".into(), busy_addr.clone()], "cannot listen"),
        (vec!["--tcp".into(), "0.0.0.0:0".into()], "--allow-remote"),
        (vec!["--stdio".into(), "--eeprom".into(), "/nonexistent-dir/hand.json".into()], "EEPROM"),
        (vec!["--stdio".into(), "--eeprom".into(), bad_eeprom.display().to_string()], "EEPROM"),
        (vec!["--stdio".into(), "--scenario".into(), bad_scenario.display().to_string()], "tempreature"),
        (vec!["--stdio".into(), "--scenario".into(), "/nonexistent-dir/s.toml".into()], "scenario"),
        (vec!["--pty".into(), "--link".into(), plain_file.display().to_string()], "not a symbolic link"),
        (vec!["--stdio".into(), "--fault".into(), "nonesuch".into()], "unknown fault"),
    ];
    for (args, needle) in cases {
        let a: Vec<&str> = args.iter().map(String::as_str).collect();
        let (code, err) = run(&a);
        assert_eq!(code, Some(2), "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
        if needle != "unknown fault" {
            // (clap's own usage errors add a usage hint; ours are one line)
            assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        }
    }
    drop(busy);
}

#[test]
fn help_lists_faults_and_a_scenario_example() {
    let out = Command::new(GCL).args(["sim", "--help"]).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    for needle in ["lfap-little-endian", "no-echo", "objects = {", "--time", "--clock wire", "socket://"] {
        assert!(text.contains(needle), "missing {needle}");
    }
}

#[test]
fn the_eeprom_survives_a_kill_and_a_restart() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("hand.json");
    let f = file.display().to_string();
    {
        let mut hand = stdio_hand("seed", &["--eeprom", &f]);
        hand.resync().unwrap();
        hand.set("1", "DP", 4321).unwrap();
        hand.command("FSAVE").unwrap();
        // Dropping the hand kills the child: no chance to save at exit.
    }
    let saved = std::fs::read_to_string(&file).unwrap();
    assert!(saved.contains("4321"), "{saved}");
    let mut hand = stdio_hand("seed", &["--eeprom", &f]);
    hand.resync().unwrap();
    assert_eq!(hand.get("1", "DP").unwrap(), vec![4321]);
    // No temporary files left behind.
    let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(names.len(), 1, "{names:?}");
}

#[test]
fn the_trace_logs_both_directions_escaped() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("hand.trace");
    let mut link =
        ExecLink::spawn(&stdio_argv(&["--profile", "seed", "--trace", &file.display().to_string()]), StderrMode::Null)
            .unwrap();
    link.send(b"FGET DP\r\x03").unwrap();
    let mut buf = Vec::new();
    assert!(link.recv_until(&mut buf, Duration::from_secs(10), &|b| b.ends_with(b"150\n\r=> \n\r=> ")).unwrap());
    link.close_input();
    assert_eq!(link.wait_exit(Duration::from_secs(10)), Some(0));
    let trace = std::fs::read_to_string(&file).unwrap();
    assert!(trace.contains("> FGET DP\\r\\x03"), "{trace}");
    assert!(trace.contains("< FGET DP\\n\\r1000 1000 1000 150\\n\\r=> "), "{trace}");
    assert!(trace.contains("< \\n\\rBarrettHand Firmware"), "{trace}");
}

#[test]
fn the_pty_link_comes_and_goes_and_sigterm_exits_0() {
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("hand");
    let l = link.display().to_string();
    let mut sim = SimProcess::start(Transport::Pty, &["--profile", "seed", "--link", &l]);
    assert_eq!(std::fs::read_link(&link).unwrap().display().to_string(), sim.address);
    {
        let opts = gcl_host::target::OpenOptions { profile: Some("seed".into()), ..Default::default() };
        let mut hand = gcl_host::client::Hand::open(&format!("serial:{l}").parse().unwrap(), &opts).unwrap();
        hand.resync().unwrap();
        assert_eq!(hand.get("4", "DP").unwrap(), vec![150]);
    }
    // A second simulator may not take over the live simulator's link.
    let (code, err) = run(&["--pty", "--profile", "seed", "--link", &l]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("a pty in use"), "{err}");
    assert_eq!(std::fs::read_link(&link).unwrap().display().to_string(), sim.address);
    let status = sim.terminate();
    assert_eq!(status.code(), Some(0));
    assert!(std::fs::symlink_metadata(&link).is_err(), "the link must be removed");
    // A link left by a simulator that is gone (its pty no longer exists) is replaced.
    std::os::unix::fs::symlink("/dev/pts/999999", &link).unwrap();
    let sim = SimProcess::start(Transport::Pty, &["--profile", "seed", "--link", &l]);
    assert_eq!(std::fs::read_link(&link).unwrap().display().to_string(), sim.address);
}

#[test]
fn scenario_objects_stop_the_fingers() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("world.toml");
    std::fs::write(&file, "objects = { 1 = 6000 }\nstrain_noise = 0\n").unwrap();
    let mut hand = stdio_hand("seed", &["--scenario", &file.display().to_string()]);
    hand.resync().unwrap();
    hand.command("HI").unwrap();
    let _ = hand.close("12");
    let p = hand.get("12", "P").unwrap();
    assert!(p[0] < 9000 && p[1] > 15_000, "{p:?}");
}

#[test]
fn faults_reach_the_hand() {
    let mut hand = stdio_hand("seed", &["--fault", "no-echo"]);
    hand.resync().unwrap();
    assert!(matches!(
        hand.command("FGET DP"),
        Err(ClientError::Violation { violation: gcl_host::client::core::Violation::EchoMismatch { .. }, .. })
    ));
}

#[test]
fn stdio_exits_0_at_end_of_input() {
    let mut link = ExecLink::spawn(&stdio_argv(&["--profile", "seed"]), StderrMode::Null).unwrap();
    link.send(b"HI\r").unwrap();
    link.close_input();
    assert_eq!(link.wait_exit(Duration::from_secs(10)), Some(0));
}

/// The start line says how the hand paces its bytes in words that read: "paced at the hand's
/// BAUD", "paced at 38400 baud", or "unpaced" (never "paced at unpaced").
#[test]
fn the_start_line_says_how_the_hand_is_paced() {
    let dir = tempfile::tempdir().unwrap();
    for (args, want) in [
        (&["--unpaced"][..], "(time real, unpaced)"),
        (&["--time", "fast"][..], "(time fast, unpaced)"),
        (&[][..], "(time real, paced at the hand's BAUD)"),
        (&["--baud", "38400"][..], "(time real, paced at 38400 baud)"),
    ] {
        let log = dir.path().join("stderr");
        let mut sim = SimProcess::start_logged(Transport::Tcp, args, std::fs::File::create(&log).unwrap());
        let start = std::time::Instant::now();
        let line = loop {
            let text = std::fs::read_to_string(&log).unwrap();
            // A whole line: stderr is unbuffered, so the line may still be on its way.
            if let Some(l) = text.split_inclusive('\n').find(|l| l.starts_with("gcl sim: profile") && l.ends_with('\n'))
            {
                break l.trim_end().to_string();
            }
            assert!(start.elapsed() < Duration::from_secs(30), "{args:?}: no start line in {text:?}");
            std::thread::sleep(Duration::from_millis(20));
        };
        assert!(line.contains(want), "{args:?}: {line}");
        assert!(!line.contains("paced at unpaced"), "{line}");
        assert_eq!(sim.terminate().code(), Some(0));
    }
}
