//! Issue 32, items 1 to 3: output that a hostile host, hand or file controls. Whatever bytes
//! they send, every JUnit file parses with a strict XML parser (and with Python's `minidom`
//! and `junitparser`), every console line shows them escaped (no escape sequence reaches the
//! user's terminal), and every command printed to be run again is quoted for a shell: pasted,
//! it runs the same argv, never a command of its own. Hosts and hands are real child
//! processes (a Python host over loopback TCP, `gcl sim --stdio` on a hostile profile behind
//! `exec:`), files are forged as an attacker would; every `gcl` runs under a memory limit and
//! a wall-clock bound.

use crate::bounded;
use crate::deps;

use std::io::{BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

use bounded::{Run, gcl_bounded};
use proptest::prelude::*;

/// What the hostile parties send: an OSC that retitles the window, a screen clear, a NUL, a
/// CR that would overwrite the line, and a C1 control (CSI).
const HOSTILE: &str = "\u{1b}]0;PWNED\u{7}\u{1b}[2J";

/// [`HOSTILE`] as [`gcl_model::escape::printable`] shows it: what a user must see instead.
const SHOWN: &str = "\\x1B]0;PWNED\\x07\\x1B[2J";

fn gcl(args: &[&str]) -> Run {
    gcl_bounded(None, args, Duration::from_secs(180))
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Every character of `text` a terminal would obey: controls but newline and tab, and the
/// bidirectional controls (U+202E reorders what follows it).
fn obeyed(text: &str) -> Vec<char> {
    text.chars()
        .filter(|c| c.is_control() && !matches!(c, '\n' | '\t') || gcl_model::escape::bidi_control(*c))
        .collect()
}

/// `run`'s output has the hostile text, escaped, and nothing a terminal would obey.
#[track_caller]
fn assert_shown_escaped(what: &str, run: &Run) {
    for (name, text) in [("stdout", &run.stdout), ("stderr", &run.stderr)] {
        let bad = obeyed(text);
        assert!(bad.is_empty(), "{what}: {name} has {bad:?}:\n{text}");
    }
    assert!(
        run.stdout.contains(SHOWN) || run.stderr.contains(SHOWN),
        "{what}: the hostile bytes did not reach the output (the test fed nothing):\n{}\n{}",
        run.stdout,
        run.stderr
    );
}

/// A JUnit file reads with a strict XML parser here, and with Python's `minidom` and
/// `junitparser` (the tests' Python, [`deps::python_with`]).
#[track_caller]
fn assert_junit_parses(path: &Path) {
    let xml = std::fs::read_to_string(path).unwrap();
    if let Err(e) = roxmltree::Document::parse(&xml) {
        panic!("{}: {e}\n{xml}", path.display());
    }
    let Some(py) = deps::python_with(&["junitparser"]) else { return };
    let script = "import sys, xml.dom.minidom\nfrom junitparser import JUnitXml\n\
                  xml.dom.minidom.parse(sys.argv[1])\nfor s in JUnitXml.fromfile(sys.argv[1]):\n    list(s)\n";
    let o = Command::new(py).args(["-c", script]).arg(path).output().unwrap();
    assert!(o.status.success(), "{}: {}", path.display(), String::from_utf8_lossy(&o.stderr));
}

/// The argv a POSIX shell makes of `line`: each word as `sh` parses it.
fn argv_in_sh(line: &str) -> Vec<String> {
    let o = Command::new("sh").arg("-c").arg(format!("set -- {line}\nprintf '%s\\0' \"$@\"")).output().unwrap();
    assert!(o.status.success(), "sh refused `{line}`: {}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8(o.stdout).unwrap();
    out.strip_suffix('\0').unwrap_or(&out).split('\0').map(str::to_string).collect()
}

/// A host over loopback TCP, in a file whose name is hostile (a traceback names it): it sends
/// a command word of control bytes, says it believes a value the hand never sent with a
/// hostile WHERE (`gcl-observe`), and raises an exception whose text is hostile.
fn hostile_host(dir: &Path) -> PathBuf {
    let path = dir.join(format!("h{HOSTILE}host.py"));
    std::fs::write(
        &path,
        r#"import os, socket, sys
ESC = b"\x1b]0;PWNED\x07\x1b[2J"
def talk():
    host, port = sys.argv[1].rsplit(":", 1)
    s = socket.create_connection((host, int(port)))
    s.settimeout(1)
    def answer():
        got = b""
        while not got.endswith(b"=> "):
            b = s.recv(256)
            if not b:
                raise ConnectionError("closed")
            got += b
    s.sendall(b"\x03")
    answer()
    s.sendall(b"A\x00" + ESC + b"\r")
    answer()
    os.write(int(os.environ.get("GCL_OBSERVE_FD", "2")), b"gcl-observe: P 1 12345 " + ESC + b"where\n")
    raise ValueError("the hand said " + ESC.decode())
talk()
"#,
    )
    .unwrap();
    path
}

/// Item 1 and 2 for `gcl check-host`: its clause lines show the host's command word escaped,
/// and its JUnit file parses.
#[test]
fn check_host_shows_a_hostile_hosts_bytes_escaped_and_its_junit_parses() {
    let Some(py) = deps::python_with(&[]) else { return };
    let dir = tempfile::tempdir().unwrap();
    let host = hostile_host(dir.path());
    let rep = dir.path().join("r");
    let r = gcl(&["check-host", "--tcp", "--profile", "seed", "--report", s(&rep), "--", &py, s(&host), "{port}"]);
    assert_eq!(r.code, Some(1), "{}\n{}", r.stdout, r.stderr);
    assert_shown_escaped("check-host", &r);
    assert_junit_parses(&rep.join("junit.xml"));
}

/// Item 1 and 2 for `gcl check-host --serve`: a client that sends control bytes as its command
/// word; the graded lines show them escaped, and the JUnit file parses.
#[test]
fn a_served_hand_shows_a_hostile_clients_bytes_escaped_and_its_junit_parses() {
    let dir = tempfile::tempdir().unwrap();
    let rep = dir.path().join("r");
    let mut child = Command::new("prlimit")
        .arg(bounded::MEMORY)
        .arg("--")
        .arg(env!("CARGO_BIN_EXE_gcl"))
        .args(["check-host", "--serve", "--stop-on-eof", "--tcp", "--profile", "seed", "--report", s(&rep)])
        .args(["--name", &format!("served {HOSTILE}")])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let watchdog = bounded::kill_after(child.id(), Duration::from_secs(60));
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut port = None;
    loop {
        let mut line = String::new();
        assert!(out.read_line(&mut line).unwrap() > 0, "the served hand ended before it was ready");
        if let Some(p) = line.trim_end().strip_prefix("port ") {
            port = Some(p.to_string());
        }
        if line.trim_end() == "ready" {
            break;
        }
    }
    let mut sock = std::net::TcpStream::connect(port.unwrap()).unwrap();
    sock.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    sock.write_all(format!("\x03A\0{HOSTILE}\r").as_bytes()).unwrap();
    let mut got = Vec::new();
    let mut buf = [0u8; 256];
    while got.windows(3).filter(|w| w == b"=> ").count() < 2 {
        let n = sock.read(&mut buf).unwrap();
        assert!(n > 0, "the served hand hung up");
        got.extend_from_slice(&buf[..n]);
    }
    drop(sock);
    drop(child.stdin.take());
    let mut stdout = String::new();
    out.read_to_string(&mut stdout).unwrap();
    let mut stderr = String::new();
    child.stderr.take().unwrap().read_to_string(&mut stderr).unwrap();
    let status = child.wait().unwrap();
    watchdog.disarm();
    let r = Run { code: status.code(), stdout, stderr };
    assert_eq!(r.code, Some(1), "{}\n{}", r.stdout, r.stderr);
    assert_shown_escaped("check-host --serve", &r);
    assert_junit_parses(&rep.join("junit.xml"));
}

/// Items 1 to 3 for `gcl fuzz host`: the findings' signatures (a traceback's file name, a
/// `gcl-observe` WHERE) and the protocol states of what fired ("answer to <command word>")
/// show escaped, the JUnit file parses, `--replay` of a forged bundle shows its signature
/// escaped (and a bundle forged to break its reader, the error), and each finding's "run it
/// again" command, run by `sh`, is the argv of the campaign.
#[test]
fn fuzz_host_shows_hostile_signatures_escaped_and_its_replay_commands_run_as_given() {
    let Some(py) = deps::python_with(&[]) else { return };
    let dir = tempfile::tempdir().unwrap();
    let host = hostile_host(dir.path());
    let (rep, out) = (dir.path().join("r"), dir.path().join("b"));
    let command = [py.as_str(), s(&host), "{port}"];
    let mut args = vec!["fuzz", "host", "--tcp", "--profile", "seed", "--runs", "4", "--ops", "extra-bytes"];
    args.extend(["--timeout-hang", "5s", "--report", s(&rep), "--out", s(&out), "--"]);
    args.extend(command);
    let r = gcl(&args);
    assert_eq!(r.code, Some(1), "{}\n{}", r.stdout, r.stderr);
    assert_shown_escaped("fuzz host", &r);
    // What fired at the answer to the hostile command word, by protocol state.
    assert!(r.stderr.contains(&format!("answer to A\\x00{SHOWN}")), "{}", r.stderr);
    assert_junit_parses(&rep.join("junit.xml"));

    // Each finding's command to run it again is the campaign's argv, word for word.
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(rep.join("report.json")).unwrap()).unwrap();
    let findings = report["host"]["findings"].as_array().unwrap();
    assert!(!findings.is_empty());
    for f in findings {
        let line = f["replay"].as_str().unwrap();
        let bundle = f["bundle"].as_str().unwrap();
        let mut want = vec!["gcl", "fuzz", "host", "--replay", bundle, "--"];
        want.extend(command);
        assert_eq!(argv_in_sh(line), want, "{line}");
    }

    // A bundle whose signature was forged: NOT reproduced, shown escaped.
    let bundle = PathBuf::from(findings[0]["bundle"].as_str().unwrap());
    let finding = bundle.join("finding.json");
    let mut info: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&finding).unwrap()).unwrap();
    info["signature"] = format!("crash: forged {HOSTILE}").into();
    std::fs::write(&finding, serde_json::to_vec(&info).unwrap()).unwrap();
    let mut replay = vec!["fuzz", "host", "--replay", s(&bundle), "--"];
    replay.extend(command);
    let r = gcl(&replay);
    assert!(r.stderr.contains("NOT reproduced"), "{}", r.stderr);
    assert_shown_escaped("fuzz host --replay", &r);
    // A bundle forged so that its reader quotes it in the error.
    info["transport"] = HOSTILE.into();
    std::fs::write(&finding, serde_json::to_vec(&info).unwrap()).unwrap();
    let r = gcl(&replay);
    assert_eq!(r.code, Some(2), "{}", r.stderr);
    assert_shown_escaped("fuzz host --replay of a broken bundle", &r);
}

/// Item 3: `-- sh -c 'printf ...; exit 3' {port}`: the replay command printed for its finding,
/// run by `sh`, is that argv, and pasted into a shell (with this `gcl` first on PATH) it
/// reproduces the finding (before, it ran `gcl ... -- sh -c printf ...` and then `exit 3` in
/// the shell). The host sends the hand a line first: one that never does tests nothing.
/// A host in one shell word: it sends the hand a line on the port (`$0`), then fails.
const SEND_AND_FAIL: &str = "printf 'VERS\\r' >\"$0\"; sleep 0.1; exit 3";

#[test]
fn a_printed_replay_command_pasted_into_a_shell_reproduces_its_finding() {
    let dir = tempfile::tempdir().unwrap();
    let (rep, out) = (dir.path().join("r r"), dir.path().join("it's here"));
    let r = gcl(&[
        "fuzz",
        "host",
        "--runs",
        "1",
        "--timeout-hang",
        "5s",
        "--report",
        s(&rep),
        "--out",
        s(&out),
        "--",
        "sh",
        "-c",
        SEND_AND_FAIL,
        "{port}",
    ]);
    assert_eq!(r.code, Some(1), "{}\n{}", r.stdout, r.stderr);
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(rep.join("report.json")).unwrap()).unwrap();
    let f = &report["host"]["findings"][0];
    let line = f["replay"].as_str().unwrap();
    let bundle = f["bundle"].as_str().unwrap();
    assert_eq!(
        argv_in_sh(line),
        ["gcl", "fuzz", "host", "--replay", bundle, "--", "sh", "-c", SEND_AND_FAIL, "{port}"]
    );
    let bin = Path::new(env!("CARGO_BIN_EXE_gcl")).parent().unwrap();
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap_or_default());
    let o = Command::new("sh").arg("-c").arg(line).env("PATH", path).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("gcl fuzz host: reproduced: exit-code"), "{err}");
    assert_eq!(o.status.code(), Some(1), "{err}");
}

/// A profile whose hand is hostile: `seed`'s spec with control bytes in its version text (what
/// the hand answers to VERS), its title (with a right-to-left override too) and the text of
/// ERR 32, in a copy of `spec/` (for its includes).
fn hostile_profile(dir: &Path) -> PathBuf {
    let spec = Path::new(env!("CARGO_MANIFEST_DIR")).join("../spec");
    let to = dir.join("spec");
    std::fs::create_dir_all(to.join("shared")).unwrap();
    let esc = "\\u001b]0;PWNED\\u0007\\u001b[2J";
    for f in std::fs::read_dir(spec.join("shared")).unwrap() {
        let f = f.unwrap().path();
        let text = std::fs::read_to_string(&f).unwrap();
        let text = text.replace("text = \"Unknown command\"", &format!("text = \"Unknown {esc} command\""));
        std::fs::write(to.join("shared").join(f.file_name().unwrap()), text).unwrap();
    }
    let text = std::fs::read_to_string(spec.join("seed.toml"))
        .unwrap()
        .replacen("version = [\"GCL seed profile", &format!("version = [\"GCL {esc} seed profile"), 1)
        .replacen("title = \"GCL as", &format!("title = \"GCL {esc} \\u202Eas"), 1);
    let p = to.join("hostile.toml");
    std::fs::write(&p, text).unwrap();
    p
}

/// Item 2 (and 3) for `gcl certify`: the `firmware:` line shows the hand's VERS text escaped,
/// `--verify` shows a forged certificate's profile and a forged bundle's file names escaped,
/// and the `--verify` command it prints, run by `sh`, names the bundle's folder.
#[test]
fn certify_shows_a_hostile_hands_and_a_forged_bundles_text_escaped() {
    let dir = tempfile::tempdir().unwrap();
    let profile = hostile_profile(dir.path());
    let hand = format!("exec:{} sim --stdio --profile {}", env!("CARGO_BIN_EXE_gcl"), s(&profile));
    let out = dir.path().join("it's a certificate");
    let r = gcl(&[
        "certify",
        "--target",
        &hand,
        "--profile",
        "seed",
        "--partial",
        "--only",
        "framing-echo",
        "--out",
        s(&out),
    ]);
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    assert_shown_escaped("certify", &r);
    let verify = r.stdout.split('`').nth(1).unwrap();
    assert_eq!(argv_in_sh(verify), ["gcl", "certify", "--verify", s(&out), "--allow-unverified"]);

    // Forged: the profile rewritten in the certificate and its report, the manifest redone.
    for name in ["certificate.json", "report.json"] {
        let p = out.join(name);
        let mut v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
        v["profile"] = format!("seed {HOSTILE}").into();
        std::fs::write(&p, serde_json::to_vec_pretty(&v).unwrap()).unwrap();
    }
    let manifest = out.join("MANIFEST.sha256");
    let lines: Vec<String> = std::fs::read_to_string(&manifest)
        .unwrap()
        .lines()
        .map(|l| {
            let (_, name) = l.split_once("  ").unwrap();
            let o = Command::new("sha256sum").arg(out.join(name)).output().unwrap();
            format!("{}  {name}", String::from_utf8_lossy(&o.stdout).split(' ').next().unwrap())
        })
        .collect();
    std::fs::write(&manifest, lines.join("\n") + "\n").unwrap();
    // The report's spec no longer backs the forged name, so the bundle is found tampered; the
    // forged name is still shown, escaped.
    let r = gcl(&["certify", "--verify", s(&out), "--allow-unverified"]);
    assert_eq!(r.code, Some(1), "{}\n{}", r.stdout, r.stderr);
    assert!(r.stdout.contains("TAMPERED") && r.stdout.contains("PWNED"), "{}", r.stdout);
    assert_shown_escaped("certify --verify", &r);
    // A file the manifest does not list, named to clear the screen.
    std::fs::write(out.join(format!("x{HOSTILE}")), "").unwrap();
    let r = gcl(&["certify", "--verify", s(&out)]);
    assert!(r.stdout.contains("TAMPERED"), "{}", r.stdout);
    assert_shown_escaped("certify --verify (tampered)", &r);
}

/// Item 2 for the commands that read a hand or a file: `conform` against the hostile hand (its
/// ERR 32 text) and `replay` of a golden against it, `spec` of its profile.
#[test]
fn hand_and_file_bytes_are_shown_escaped_by_conform_replay_and_spec() {
    let dir = tempfile::tempdir().unwrap();
    let profile = hostile_profile(dir.path());
    let hand = format!("exec:{} sim --stdio --profile {}", env!("CARGO_BIN_EXE_gcl"), s(&profile));
    let r = gcl(&["conform", "--target", &hand, "--profile", "seed", "--only", "cmd-err"]);
    assert_eq!(r.code, Some(1), "{}\n{}", r.stdout, r.stderr);
    assert_shown_escaped("conform", &r);
    let r = gcl(&["spec", "--profile", s(&profile)]);
    assert_shown_escaped("spec", &r);
    // The title's right-to-left override is shown, not obeyed (it was printed raw).
    assert!(r.stdout.contains("\\u{202E}as"), "{}", r.stdout);
    let golden = Path::new(env!("CARGO_MANIFEST_DIR")).join("../vectors/suite/seed/cmd-err.gcl");
    let r = gcl(&["replay", s(&golden), "--target", &hand]);
    assert_eq!(r.code, Some(1), "{}\n{}", r.stdout, r.stderr);
    assert_shown_escaped("replay", &r);
    // A transcript whose file name is hostile (a folder of them from elsewhere, globbed):
    // its verdict line names it escaped (it was printed raw).
    let named = dir.path().join(format!("x{HOSTILE}\u{202E}.gcl"));
    std::fs::copy(&golden, &named).unwrap();
    let r = gcl(&["replay", s(&named), "--target", "sim"]);
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    assert!(
        r.stdout.contains(&format!("PASS {}", s(&dir.path().join(format!("x{SHOWN}\\u{{202E}}.gcl"))))),
        "{}",
        r.stdout
    );
    assert_shown_escaped("replay of a hostile file name", &r);
}

/// Issue 39 item 14: `gcl fuzz merge` names what it leaves behind of a shard, and a shard's
/// file names are a CI artifact's: a bundle's entry and corpus entries named to retitle the
/// window and clear the screen (and with a right-to-left override) are shown escaped (they
/// reached the terminal raw).
#[test]
fn fuzz_merge_shows_a_shards_hostile_file_names_escaped() {
    let dir = tempfile::tempdir().unwrap();
    let hostile = format!("x{HOSTILE}\u{202E}");
    let fifo = |p: &Path| nix::unistd::mkfifo(p, nix::sys::stat::Mode::from_bits_truncate(0o600)).unwrap();
    // A host campaign of one shard, with a FIFO in its finding's bundle.
    let shard = dir.path().join("host");
    let (rep, out) = (shard.join("report"), shard.join("bundles"));
    let r = gcl(&[
        "fuzz",
        "host",
        "--shard",
        "1/1",
        "--runs",
        "1",
        "--timeout-hang",
        "5s",
        "--report",
        s(&rep),
        "--out",
        s(&out),
        "--",
        "sh",
        "-c",
        SEND_AND_FAIL,
        "{port}",
    ]);
    assert_eq!(r.code, Some(1), "{}\n{}", r.stdout, r.stderr);
    let bundle = std::fs::read_dir(&out).unwrap().next().unwrap().unwrap().path();
    fifo(&bundle.join(&hostile));
    let r = gcl(&["fuzz", "merge", s(&shard), "--out", s(&dir.path().join("merged-host"))]);
    assert_eq!(r.code, Some(1), "{}\n{}", r.stdout, r.stderr);
    assert!(r.stderr.contains("a named pipe, not copied"), "{}", r.stderr);
    assert_shown_escaped("fuzz merge (host)", &r);
    // A device campaign of one shard, with a FIFO and a file that is no corpus entry, each
    // named to do harm, in its corpus.
    let shard = dir.path().join("device");
    let (rep, out, corpus) = (shard.join("report"), shard.join("findings"), shard.join("corpus"));
    let r = gcl(&["fuzz", "device", "--target", "sim:seed", "--shard", "1/1", "--runs", "4", "--quiet"]
        .into_iter()
        .chain(["--report", s(&rep), "--out", s(&out), "--corpus", s(&corpus)])
        .collect::<Vec<_>>());
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    fifo(&corpus.join(format!("{hostile}.json")));
    std::fs::write(corpus.join(format!("y{hostile}.json")), format!("[\"{}\"]", "\\u001b]0;PWNED\\u0007")).unwrap();
    let r = gcl(&["fuzz", "merge", s(&shard), "--out", s(&dir.path().join("merged-device"))]);
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    assert!(r.stderr.contains("not a corpus entry, not copied"), "{}", r.stderr);
    assert!(r.stderr.contains(&format!("x{SHOWN}\\u{{202E}}.json: a named pipe")), "{}", r.stderr);
    assert_shown_escaped("fuzz merge (device)", &r);
}

/// A run report with every field a writer reads set, for each kind of report.
fn run_report_json() -> serde_json::Value {
    let case = |id: &str, verdict: &str| {
        serde_json::json!({
            "id": id, "title": "t", "clauses": ["c"], "decisions": ["d"], "level": "MUST", "verdict": verdict,
            "duration_ms": 1.0, "message": "m", "failure": "f", "transcript": "> HI\\r\n",
            "diff": {"step": 1, "offset": 2, "expected": "e", "actual": "a", "before": "b", "golden": "g", "form": "text"}
        })
    };
    let verdicts = ["PASS", "FAIL", "ERROR", "TIMEOUT", "SKIP", "XFAIL", "XPASS"];
    let cases: Vec<serde_json::Value> =
        verdicts.iter().enumerate().map(|(i, v)| case(&format!("case-{i}"), v)).collect();
    serde_json::json!({
        "format": 1, "kind": "conform", "tool": "gcl", "target": "sim", "profile": "seed", "level": "all",
        "started": "2026-01-01T00:00:00Z", "duration_ms": 1.0, "suite_hash": "00",
        "liveness": {"before": true, "after": true},
        "options": {"only": ["o"], "skip": ["s"], "refused": ["r"], "fixtures": ["x"], "faults": ["f"], "seed": 1,
                    "suite_dir": "d", "step_timeout_ms": 1, "known_failures_file": "k"},
        "preflight": "p", "stopped": {"cause": "dead-hand", "case": "c", "message": "m"},
        "groups": [{"command": "c", "kind": "k", "summary": "s", "clause": "c", "representative": "r",
                    "cases": ["a"], "blocked": ["b"]}],
        "summary": {}, "clauses": [],
        "cases": cases,
        "host": {"command": ["h", "a"], "runs": 1, "seed": 0, "ops": ["o"], "facts": [["k", "v"]],
                 "fired_at": {"op": {"answer to X": 1}},
                 "findings": [{"case": "c", "kind": "crash", "signature": "s", "run": 0, "bundle": "b", "replay": "r",
                               "stderr": "e"}]}
    })
}

/// Keys whose values are names of a closed set (a verdict, a kind of report): not free text.
const CLOSED: &[&str] = &["kind", "verdict", "form", "cause", "level", "started"];

/// Every string of `v` (but [`CLOSED`] ones) replaced by one of `texts`, in turn.
fn hostile_strings(v: &mut serde_json::Value, texts: &[String], next: &mut usize) {
    match v {
        serde_json::Value::String(s) => {
            *s = texts[*next % texts.len()].clone();
            *next += 1;
        }
        serde_json::Value::Array(a) => a.iter_mut().for_each(|x| hostile_strings(x, texts, next)),
        serde_json::Value::Object(o) => {
            for (k, x) in o.iter_mut() {
                if !CLOSED.contains(&k.as_str()) {
                    hostile_strings(x, texts, next);
                }
            }
        }
        _ => {}
    }
}

/// A `gcl fuzz device` report with findings: a short campaign on the simulator with a fault.
fn fuzz_device_report() -> &'static serde_json::Value {
    static REPORT: std::sync::OnceLock<serde_json::Value> = std::sync::OnceLock::new();
    REPORT.get_or_init(|| {
        use gcl_harness::fuzz::device::{Budget, FuzzOptions, report, run};
        let mut o = FuzzOptions::new(
            gcl_host::target::Target::Sim { profile: None },
            gcl_model::Profile::builtin("seed").unwrap(),
        );
        o.open.faults = vec![gcl_model::Fault::FgetReversed];
        o.budget = Budget::Runs(300);
        o.seed = 1;
        o.max_findings = Some(1);
        let s = run(&o, &|_| {}).unwrap();
        assert!(!s.findings.is_empty(), "fget-reversed not found");
        let mut r = report::FuzzReport::new(&o, &s);
        r.findings.iter_mut().for_each(|f| f.path = Some("findings/f.gcl".into()));
        serde_json::to_value(&r).unwrap()
    })
}

/// Hostile text: arbitrary bytes (as a host's lossy line) and arbitrary characters (controls,
/// non-characters, `]]>` that ends CDATA).
fn hostile_text() -> impl Strategy<Value = String> {
    let bytes = prop::collection::vec(any::<u8>(), 0..12).prop_map(|b| String::from_utf8_lossy(&b).into_owned());
    let chars = prop::collection::vec(
        prop_oneof![any::<char>(), (0u32..0x20).prop_map(|c| char::from_u32(c).unwrap()), Just('\u{FFFE}'), Just(']')],
        0..8,
    )
    .prop_map(|c| c.into_iter().collect::<String>());
    (bytes, chars, prop_oneof![Just(""), Just("]]>"), Just(HOSTILE)]).prop_map(|(a, b, c)| format!("{a}{c}{b}"))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// Item 1: arbitrary bytes in every string of a report, through every JUnit writer
    /// (conform, certify, check-host and fuzz host's; fuzz device's): a strict XML parser
    /// reads the file, with every test case in it.
    #[test]
    fn every_junit_file_parses_whatever_the_bytes(texts in prop::collection::vec(hostile_text(), 1..8)) {
        for kind in ["conform", "certify", "check-host", "fuzz-host"] {
            let mut v = run_report_json();
            hostile_strings(&mut v, &texts, &mut 0);
            v["kind"] = kind.into();
            let mut r: gcl_harness::report::RunReport = serde_json::from_value(v).unwrap();
            r.tally();
            let xml = gcl_harness::report::to_junit(&r).unwrap();
            let doc = roxmltree::Document::parse(&xml).map_err(|e| TestCaseError::fail(format!("{kind}: {e}\n{xml}")))?;
            prop_assert_eq!(doc.descendants().filter(|n| n.has_tag_name("testcase")).count(), r.cases.len());
        }
        let mut v = fuzz_device_report().clone();
        hostile_strings(&mut v, &texts, &mut 0);
        let r: gcl_harness::fuzz::device::report::FuzzReport = serde_json::from_value(v).unwrap();
        let xml = gcl_harness::fuzz::device::report::to_junit(&r).unwrap();
        let doc = roxmltree::Document::parse(&xml).map_err(|e| TestCaseError::fail(format!("fuzz device: {e}\n{xml}")))?;
        prop_assert_eq!(doc.descendants().filter(|n| n.has_tag_name("testcase")).count(), r.findings.len().max(1));
    }

    /// Item 3: whatever the words, the command printed for them, run by `sh`, is those words.
    #[test]
    fn a_printed_command_is_its_words_in_sh(words in prop::collection::vec("[^\\x00]{0,12}", 1..5)) {
        let line = gcl_harness::report::shell_command(&words);
        prop_assert_eq!(argv_in_sh(&line), words);
    }
}

/// Item 3 on a merged `fuzz device` page: a shard's JSON whose target would inject a command
/// (`'…'; touch X; echo '…'`). The merged report's "run it again" lines, pasted into a shell
/// (with a `gcl` that prints its argv first on PATH), run `gcl replay` with that target as one
/// word, and nothing else.
#[test]
fn a_merged_device_page_never_offers_an_injected_command() {
    let dir = tempfile::tempdir().unwrap();
    let shard = dir.path().join("shard-1");
    let r = gcl(&[
        "fuzz",
        "device",
        "--target",
        "sim:seed",
        "--fault",
        "fget-reversed",
        "--seed",
        "1",
        "--runs",
        "300",
        "--max-findings",
        "1",
        "--report",
        s(&shard.join("report")),
        "--out",
        s(&shard.join("findings")),
    ]);
    assert_eq!(r.code, Some(1), "{}\n{}", r.stdout, r.stderr);
    let touched = dir.path().join("X");
    let target = format!("tcp://127.0.0.1:1'; touch {}; echo '", touched.display());
    let json = shard.join("report/fuzz-device.json");
    let mut v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    v["target"] = target.clone().into();
    // Sealed again, as a forger would (a shard's digest is no signature): the page must hold
    // whatever a sealed shard says.
    v["provenance"]["digest"] =
        gcl_harness::fuzz::shard::report_digest(&serde_json::to_vec(&v).unwrap()).unwrap().into();
    std::fs::write(&json, serde_json::to_vec_pretty(&v).unwrap()).unwrap();
    let merged = dir.path().join("merged");
    let r = gcl(&["fuzz", "merge", s(&shard), "--out", s(&merged)]);
    assert_eq!(r.code, Some(1), "{}\n{}", r.stdout, r.stderr);
    let xml = std::fs::read_to_string(merged.join("report/junit.xml")).unwrap();
    let doc = roxmltree::Document::parse(&xml).unwrap();
    let lines: Vec<String> = doc
        .descendants()
        .filter_map(|n| n.text())
        .flat_map(|t| {
            t.lines().filter_map(|l| l.strip_prefix("run it again: ")).map(str::to_string).collect::<Vec<_>>()
        })
        .collect();
    assert!(!lines.is_empty(), "{xml}");
    let fake = dir.path().join("bin");
    std::fs::create_dir(&fake).unwrap();
    std::fs::write(fake.join("gcl"), "#!/bin/sh\nprintf '%s\\0' \"$@\"\n").unwrap();
    std::fs::set_permissions(fake.join("gcl"), std::os::unix::fs::PermissionsExt::from_mode(0o755)).unwrap();
    for line in lines {
        let path = format!("{}:{}", fake.display(), std::env::var("PATH").unwrap_or_default());
        let o = Command::new("sh").arg("-c").arg(&line).env("PATH", path).current_dir(dir.path()).output().unwrap();
        let argv: Vec<String> =
            String::from_utf8_lossy(&o.stdout).trim_end_matches('\0').split('\0').map(str::to_string).collect();
        assert_eq!(argv[..3], ["replay", "--target", target.as_str()], "{line}");
        assert!(!touched.exists(), "pasting `{line}` ran `touch`");
    }
}
