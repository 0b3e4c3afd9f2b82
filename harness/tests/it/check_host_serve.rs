//! `gcl check-host --serve`: a graded hand for whoever connects, stopped by closing its stdin
//! (as the pytest fixture does) or by a signal, then graded as `gcl check-host` grades a host.

use std::io::{BufRead, BufReader, Read, Write};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

/// Starts a served hand; returns it and its port (read from its first lines).
fn serve(extra: &[&str]) -> (Child, String, Vec<String>) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_gcl"))
        .args(["check-host", "--serve", "--stop-on-eof", "--profile", "seed"])
        .args(extra)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut header = Vec::new();
    loop {
        let mut line = String::new();
        assert!(out.read_line(&mut line).unwrap() > 0, "the served hand ended before it was ready");
        let line = line.trim_end().to_string();
        if line == "ready" {
            break;
        }
        header.push(line);
    }
    let port = header.iter().find_map(|l| l.strip_prefix("port ")).unwrap().to_string();
    // Keep the rest of stdout for the verdict.
    child.stdout = Some(out.into_inner());
    (child, port, header)
}

/// Talks to the pty: ^C, then each line, waiting for the prompt after each.
fn talk(port: &str, lines: &[&[u8]]) {
    let mut f = std::fs::OpenOptions::new().read(true).write(true).open(port).unwrap();
    let wait_prompt = |f: &mut std::fs::File| {
        let mut seen = Vec::new();
        let mut b = [0u8; 256];
        while !seen.ends_with(b"=> ") && !seen.ends_with(b"=> \n") {
            let n = f.read(&mut b).unwrap();
            assert!(n > 0);
            seen.extend_from_slice(&b[..n]);
        }
    };
    f.write_all(b"\x03").unwrap();
    wait_prompt(&mut f);
    for l in lines {
        f.write_all(l).unwrap();
        wait_prompt(&mut f);
    }
}

fn stop(mut child: Child) -> (i32, String) {
    drop(child.stdin.take());
    let mut out = String::new();
    child.stdout.take().unwrap().read_to_string(&mut out).unwrap();
    let status = child.wait().unwrap();
    (status.code().unwrap(), out)
}

#[test]
fn a_served_hand_grades_whoever_connected() {
    let dir = tempfile::tempdir().unwrap();
    let (child, port, _) = serve(&["--report", dir.path().to_str().unwrap(), "--name", "good host"]);
    // Two connections make one session, as on a serial line.
    talk(&port, &[b"FGET DP\r"]);
    talk(&port, &[b"FGET DP\r"]);
    let (code, out) = stop(child);
    assert_eq!(code, 0, "{out}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("report.json")).unwrap()).unwrap();
    assert_eq!(report["target"], "host: good host");
    // Every clause passes, but RealTime's two (the host never entered it) and how the host
    // exits (there is no host process): those are not exercised.
    let cases = report["cases"].as_array().unwrap();
    let idle = |c: &serde_json::Value| {
        c["id"] == "host-realtime-blocks" || c["id"] == "host-leaves-cleanly" || c["id"] == "host-exits-cleanly"
    };
    assert!(cases.iter().all(|c| c["verdict"] == if idle(c) { "SKIP" } else { "PASS" }), "{cases:?}");

    let (child, port, _) = serve(&[]);
    talk(&port, &[b"FGET DP\r\n"]);
    std::thread::sleep(Duration::from_millis(50));
    let (code, out) = stop(child);
    assert_eq!(code, 1, "{out}");
    assert!(out.lines().any(|l| l.starts_with("FAIL") && l.contains("host-line-ending")), "{out}");
}

#[test]
fn a_served_hand_plays_a_schedule_of_the_fuzzer() {
    let (child, port, header) = serve(&["--misbehave", "3:1", "--ops", "err-bits"]);
    assert!(header.iter().any(|l| l.starts_with("planned err-bits at answer")), "{header:?}");
    let lines: Vec<&[u8]> = (0..12).map(|_| b"FGET NOPE\r" as &[u8]).collect();
    talk(&port, &lines);
    let (_, out) = stop(child);
    assert!(out.lines().any(|l| l.starts_with("fired err-bits at answer")), "{out}");
    // A command line without --serve still needs its host command.
    let o = Command::new(env!("CARGO_BIN_EXE_gcl")).args(["check-host", "--profile", "seed"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
}

/// Issue 29 item 1: a session nobody opened, or opened without sending a byte, judged
/// nothing: an ERROR that says so and exit 2 (it was "PASS" on every clause and exit 0).
#[test]
fn a_served_hand_nobody_talks_to_judges_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let (child, _, _) = serve(&["--report", dir.path().to_str().unwrap()]);
    let (code, out) = stop(child);
    assert_eq!(code, 2, "{out}");
    assert!(out.lines().any(|l| l.starts_with("ERROR") && l.contains("host-session")), "{out}");
    assert!(out.contains("nobody opened the port before the hand was stopped"), "{out}");
    assert!(!out.lines().any(|l| l.starts_with("PASS")), "{out}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("report.json")).unwrap()).unwrap();
    assert_eq!(report["summary"]["ERROR"], 1, "{report}");
    assert_eq!(report["summary"]["PASS"], 0, "{report}");

    let (child, port, _) = serve(&[]);
    drop(std::fs::OpenOptions::new().read(true).write(true).open(&port).unwrap());
    let (code, out) = stop(child);
    assert_eq!(code, 2, "{out}");
    assert!(out.contains("the port was opened, but nothing was sent to the hand"), "{out}");
}

/// Issue 39 item 4: a served session has no host process, so nothing is known of how it
/// exits: `host-exits-cleanly` is not exercised (it was PASS, from an exit code 0 the session
/// made up), and a client that sent only ^C exercised nothing: an ERROR, exit 2 (it was exit
/// 0 on that one PASS).
#[test]
fn a_served_session_invents_no_exit() {
    let dir = tempfile::tempdir().unwrap();
    let (child, port, _) = serve(&["--report", dir.path().to_str().unwrap()]);
    talk(&port, &[]);
    let (code, out) = stop(child);
    assert_eq!(code, 2, "{out}");
    assert!(!out.lines().any(|l| l.starts_with("PASS")), "{out}");
    assert!(out.lines().any(|l| l.starts_with("ERROR") && l.contains("host-session")), "{out}");
    assert!(out.contains("nothing judged: the host exercised no clause"), "{out}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("report.json")).unwrap()).unwrap();
    let exits = report["cases"].as_array().unwrap().iter().find(|c| c["id"] == "host-exits-cleanly").unwrap();
    assert_eq!(exits["verdict"], "SKIP", "{exits}");
    assert!(exits["message"].as_str().unwrap().contains("no host process"), "{exits}");
    assert_eq!(report["summary"]["PASS"], 0, "{report}");
}
