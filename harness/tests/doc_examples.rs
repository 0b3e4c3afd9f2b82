//! Every example command in README.md and in every `--help` runs and exits as its text says
//! (issue 21 item 2): each line is found in the documents (a new or changed example fails this
//! test until it is listed in `PLANS`), then run with `sh` from a fresh temporary directory
//! with the `gcl` under test first on PATH, in the order the documents give them (later lines
//! use what earlier ones wrote: a key, a certificate, findings).
//!
//! Where a line needs what only a user has (a hand on `/dev/ttyUSB0`, a firmware build, a host
//! program) or runs for minutes, the plan says what stands in for it: the in-process model or
//! `gcl sim`, the `host_scenario` example as the host, a few seconds or runs; everything else
//! of the line is kept. Benchmarks and `cargo test` itself are not run, each with its reason.
//! A `--help` example must also fit its line: one that wraps cannot be pasted.

mod deps;

use std::collections::BTreeSet;
use std::io::{BufRead, BufReader, Read};
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const GCL: &str = env!("CARGO_BIN_EXE_gcl");

/// How an example is run.
enum Run {
    /// Through `sh -c` in the temporary directory (`in_repo`: the repository root, for lines
    /// about its files), `as_run` instead of the line when given; it must exit with `code`.
    Sh { as_run: Option<&'static str>, code: i32, in_repo: bool },
    /// A server: it must print its address (or pty) on stdout's first line; then it is stopped.
    Serve { as_run: Option<&'static str> },
    /// Not run, and why.
    Not(&'static str),
}

const fn sh(code: i32) -> Run {
    Run::Sh { as_run: None, code, in_repo: false }
}

const fn sh_as(as_run: &'static str, code: i32) -> Run {
    Run::Sh { as_run: Some(as_run), code, in_repo: false }
}

const fn in_repo(as_run: Option<&'static str>, code: i32) -> Run {
    Run::Sh { as_run, code, in_repo: true }
}

/// A `gcl sim` in the background for the line after it: `with_sim ARGS` sets `$SIM` to what it
/// printed first (a pty path or an address); `stop_sim` ends it. The old `.sim.out` goes first:
/// the background job truncates it only when it starts, so the wait could read the previous
/// example's (dead or reused) pty path, or an empty line.
const PRELUDE: &str = r#"
with_sim() { rm -f .sim.out; gcl sim "$@" > .sim.out 2>/dev/null & sim=$!; n=0; until [ -s .sim.out ] || [ $n -ge 300 ]; do sleep 0.1; n=$((n+1)); done; SIM=$(head -n 1 .sim.out); }
stop_sim() { kill $sim 2>/dev/null; wait $sim 2>/dev/null; }
"#;

/// The host programs of the examples (`python3 my_host.py {port}`, `./host_c --port {port}`)
/// stand for a host author's own: the host library's `host_scenario` example.
const HOST: &str = "{examples}/host_scenario --target 'serial:{port}'";

/// Every example, as the documents write it, and how it is run.
fn plans() -> Vec<(String, Run)> {
    let host = |profile: &str| format!("{HOST} --profile {profile}");
    let leak = |s: String| -> &'static str { Box::leak(s.into_boxed_str()) };
    vec![
        // README.md
        ("cargo run --release -- conform --target sim".into(), sh_as("gcl conform --target sim", 0)),
        ("cargo test --workspace".into(), Run::Not("the run this test is part of")),
        ("cargo run -q -- explain --profile seed HI 'FGET DP'".into(), sh_as("gcl explain --profile seed HI 'FGET DP'", 0)),
        (
            r"cargo run -q -- explain --profile seed HI '12FSET LCV 1 LCVC 1 LCPG 0 LFV 0 LFS 1 LFAP 0 LFDP 1 LFDPC 1' '4FSET LCV 0 LCVC 1 LCPG 0 LFV 0 LFS 0 LFAP 0 LFDP 1 LFDPC 1' 124LOOP 'C\x14\xFB' '\x03'".into(),
            sh_as(
                r"gcl explain --profile seed HI '12FSET LCV 1 LCVC 1 LCPG 0 LFV 0 LFS 1 LFAP 0 LFDP 1 LFDPC 1' '4FSET LCV 0 LCVC 1 LCPG 0 LFV 0 LFS 0 LFAP 0 LFDP 1 LFDPC 1' 124LOOP 'C\x14\xFB' '\x03'",
                0,
            ),
        ),
        // The link goes into the temporary directory: /tmp/bhand may be another user's.
        ("cargo run -q -- sim --pty --link /tmp/bhand".into(), Run::Serve { as_run: Some("gcl sim --pty --link bhand") }),
        (
            "cargo run --example supervisory -- --target sim:seed".into(),
            sh_as("{examples}/supervisory --target sim:seed", 0),
        ),
        ("cargo run --example realtime -- --target sim:seed".into(), sh_as("{examples}/realtime --target sim:seed", 0)),
        (
            "cargo run --release -- conform --target sim:seed --level should --report reports/out".into(),
            sh_as("gcl conform --target sim:seed --level should --report reports/out", 0),
        ),
        (
            "gcl conform --target 'serial:/dev/ttyUSB0?baud=9600' --profile bh8-262-4.3 --known-failures known.toml".into(),
            sh_as("gcl conform --target sim:bh8-262-4.3 --profile bh8-262-4.3 --known-failures known.toml", 0),
        ),
        // A fast simulator stands for the firmware build: ^C cannot land mid-motion on it.
        (
            "gcl conform --target 'exec:./my-firmware --stdio' --profile bh8-262".into(),
            sh_as("gcl conform --target 'exec:gcl sim --stdio' --profile bh8-262 --no abort-timing", 0),
        ),
        (
            "gcl conform --target 'exec:./my-firmware --stdio' --profile seed --skip-decision framing-max-line".into(),
            sh_as(
                "gcl conform --target 'exec:gcl sim --stdio --profile seed' --profile seed --skip-decision framing-max-line --no abort-timing",
                0,
            ),
        ),
        ("gcl sim --pty --baud 38400 &".into(), Run::Serve { as_run: Some("gcl sim --pty --baud 38400") }),
        // The pair: the pty the line above printed; the framing cases keep it to seconds.
        (
            "gcl conform --target 'serial:/dev/pts/N?baud=38400'".into(),
            sh_as(
                r#"with_sim --pty --baud 38400; gcl conform --target "serial:$SIM?baud=38400" --only 'framing-*'; rc=$?; stop_sim; exit $rc"#,
                0,
            ),
        ),
        ("gcl certify --keygen lab-key.pem".into(), sh(0)),
        (
            "gcl certify --target 'serial:/dev/ttyUSB0?baud=9600' --profile bh8-262-4.3 --key lab-key.pem --out cert".into(),
            sh_as("gcl certify --target sim:bh8-262-4.3 --profile bh8-262-4.3 --key lab-key.pem --out cert", 0),
        ),
        ("gcl certify --verify cert --pubkey lab-key.pem.pub".into(), sh(0)),
        ("gcl record --target sim:seed --script my.script --out my.gcl".into(), sh(0)),
        // The hand answers CR LF where the golden has LF CR: a mismatch.
        ("gcl replay my.gcl --target 'exec:gcl sim --stdio --profile seed --fault crlf'".into(), sh(1)),
        ("gcl suite check".into(), in_repo(None, 0)),
        (
            "cd vectors/python && python3 -m gcl_vectors replay --target 'exec:gcl sim --stdio --profile seed' ../suite/seed/cmd-fget.gcl".into(),
            in_repo(
                Some(
                    "cd vectors/python && {python} -m gcl_vectors replay --target 'exec:gcl sim --stdio --profile seed' ../suite/seed/cmd-fget.gcl",
                ),
                0,
            ),
        ),
        (
            "gcl fuzz device --target sim --fault fget-reversed --seed 1 --runs 2000 --out findings --report reports/fuzz".into(),
            sh_as("gcl fuzz device --target sim --fault fget-reversed --seed 1 --runs 100 --out findings --report reports/fuzz", 1),
        ),
        ("gcl replay findings/fuzz-fget-order.gcl --target 'exec:gcl sim --stdio --fault fget-reversed'".into(), sh(1)),
        ("gcl replay findings/fuzz-fget-order.gcl --target sim".into(), sh(0)),
        (
            "gcl fuzz device --target 'exec:./my-firmware --stdio' --duration 5m --jobs 2 --corpus corpus --out findings".into(),
            sh_as(
                "gcl fuzz device --target 'exec:gcl sim --stdio' --no abort-timing --duration 3s --jobs 2 --corpus corpus --out findings-2",
                0,
            ),
        ),
        (
            "gcl fuzz device --target serial:/dev/ttyUSB0?baud=9600 --profile bh8-262-4.3 --no motion --duration 10m".into(),
            sh_as("gcl fuzz device --target sim:bh8-262-4.3 --profile bh8-262-4.3 --no motion --duration 3s", 0),
        ),
        (
            "gcl check-host --profile bh8-262 --report reports/host-check -- python3 ci/host_scenario.py {port}".into(),
            sh_as(leak(format!("gcl check-host --profile bh8-262 --report reports/host-check -- {}", host("bh8-262"))), 0),
        ),
        (
            // (the hang timeout is given so the 3 s run does not spend its time calibrating)
            "gcl fuzz host --profile bh8-262 --duration 5m --jobs 2 --report reports/host-fuzz --out reports/host-fuzz/bundles -- python3 ci/host_scenario.py {port}".into(),
            sh_as(
                leak(format!(
                    "gcl fuzz host --profile bh8-262 --duration 3s --jobs 2 --timeout-hang 3s --report reports/host-fuzz --out reports/host-fuzz/bundles -- {}",
                    host("bh8-262")
                )),
                0,
            ),
        ),
        (
            "gcl check-host --serve --profile seed --report reports/host   # grades whoever connects".into(),
            Run::Not("serves until it is stopped; harness/tests/check_host_serve.rs runs it with hosts that connect"),
        ),
        (
            "gcl fuzz merge shard-1 shard-2 shard-3 shard-4 --out merged".into(),
            Run::Not("needs four shards' folders; harness/tests/fuzz_merge.rs merges real ones"),
        ),
        (
            "pip install target/wheels/gcl_harness-*.whl".into(),
            Run::Not("installs into the Python at hand; .ci/run installs the wheel into a fresh venv and tests it there"),
        ),
        (
            "python3 -m venv target/py-build && target/py-build/bin/pip install 'maturin>=1.5,<2' && target/py-build/bin/maturin build --release --out target/wheels".into(),
            Run::Not("a release build from PyPI's maturin, minutes long; .ci/run builds the wheel exactly so"),
        ),
        ("cargo bench -p gcl-model --bench model".into(), Run::Not(BENCH)),
        ("cargo bench -p gcl-harness --bench transport".into(), Run::Not(BENCH)),
        ("cargo bench -p gcl-transcript --bench parse".into(), Run::Not(BENCH)),
        ("cargo bench -p gcl-harness --bench fuzz_device".into(), Run::Not(BENCH)),
        ("cargo bench -p gcl-harness --bench conform_line".into(), Run::Not(BENCH)),
        ("harness/benches/boofuzz/compare.sh 30".into(), Run::Not("installs boofuzz from PyPI into target/ and runs for minutes")),
        ("cargo bench -p gcl-harness --bench fuzz_host".into(), Run::Not(BENCH)),
        // gcl explain --help
        (
            r"gcl explain --profile seed HI '12FSET LCV 1 LCVC 1 LCPG 0 LFV 0 LFS 1 LFAP 0 LFDP 1 LFDPC 1' '4FSET LCV 0 LCVC 1 LCPG 0 LFV 0 LFS 0 LFAP 0 LFDP 1 LFDPC 1' 124LOOP 'C\x14\xFB' '\x03'".into(),
            sh(0),
        ),
        // gcl sim --help
        (
            "cargo run --example realtime -- --target serial:/dev/pts/7 --profile seed --clock wire".into(),
            sh_as(
                r#"with_sim --pty --time fast --profile seed; {examples}/realtime --target "serial:$SIM" --profile seed --clock wire; rc=$?; stop_sim; exit $rc"#,
                0,
            ),
        ),
        ("gcl sim --pty --link /tmp/hand --profile seed".into(), Run::Serve { as_run: Some("gcl sim --pty --link hand --profile seed") }),
        // Port 5000 may be taken on a shared machine: any free port.
        (
            "gcl sim --tcp 127.0.0.1:5000 --trace hand.trace".into(),
            Run::Serve { as_run: Some("gcl sim --tcp 127.0.0.1:0 --trace hand.trace") },
        ),
        ("gcl sim --pty --time fast --unpaced".into(), Run::Serve { as_run: None }),
        // On stdio the host is stdin: a ^C, then end of input ends it.
        (
            "gcl sim --stdio --eeprom hand.json --fault no-echo".into(),
            sh_as(r"printf '\003' | gcl sim --stdio --eeprom hand.json --fault no-echo", 0),
        ),
        // gcl record --help
        ("gcl record --target sim:seed --script my-case.script --out my-case.gcl".into(), sh(0)),
        // gcl replay --help
        ("gcl replay vectors/suite/seed/framing-echo.gcl --target sim:seed".into(), in_repo(None, 0)),
        // gcl conform --help
        ("gcl conform --target sim".into(), sh(0)),
        ("gcl conform --target sim:seed --level must --report reports/out".into(), sh(0)),
        (
            "gcl conform --target serial:/dev/ttyUSB0 --profile bh8-262-4.3 --known-failures known.toml".into(),
            sh_as("gcl conform --target sim:bh8-262-4.3 --profile bh8-262-4.3 --known-failures known.toml", 0),
        ),
        // gcl certify --help (its keygen and verify lines are the README's, run above)
        (
            "gcl certify --target serial:/dev/ttyUSB0 --profile bh8-262-4.3 --key lab-key.pem --out cert".into(),
            sh_as("rm -rf cert; gcl certify --target sim:bh8-262-4.3 --profile bh8-262-4.3 --key lab-key.pem --out cert", 0),
        ),
        // gcl fuzz device --help
        ("gcl fuzz device --target sim --fault fget-reversed --seed 1 --runs 500 --out findings".into(), sh_as("gcl fuzz device --target sim --fault fget-reversed --seed 1 --runs 100 --out findings-3", 1)),
        (
            "gcl fuzz device --target 'exec:gcl sim --stdio' --no abort-timing --duration 30s --jobs 2".into(),
            sh_as("gcl fuzz device --target 'exec:gcl sim --stdio' --no abort-timing --duration 3s --jobs 2", 0),
        ),
        (
            "gcl fuzz device --target serial:/dev/ttyUSB0 --profile bh8-262-4.3 --no motion --duration 5m".into(),
            sh_as("gcl fuzz device --target sim:bh8-262-4.3 --profile bh8-262-4.3 --no motion --duration 3s", 0),
        ),
        // gcl fuzz host --help
        (
            "gcl fuzz host --duration 5m --report reports/host -- python3 my_host.py {port}".into(),
            // (the hang timeout is given: measuring it would take the 3 s, and a campaign
            // whose budget runs out before its first run tested nothing, exit 2)
            sh_as(leak(format!("gcl fuzz host --duration 3s --timeout-hang 3s --report reports/host -- {}", host("bh8-262"))), 0),
        ),
        (
            "gcl fuzz host --ops delay-above,truncate --runs 200 -- ./host_c --port {port}".into(),
            sh_as(leak(format!("gcl fuzz host --ops delay-above,truncate --runs 10 -- {}", host("bh8-262"))), 0),
        ),
        // A bundle the line needs: a campaign against a host that talks (a ^C) and exits 3 writes one.
        (
            "gcl fuzz host --replay fuzz-host-findings/hang-1a2b3c4d -- python3 my_host.py {port}".into(),
            sh_as(
                r#"h='exec 3<>"$GCL_PORT"; printf "\003" >&3; exit 3'; gcl fuzz host --runs 2 --out fuzz-host-findings -- sh -c "$h"; gcl fuzz host --replay fuzz-host-findings/exit-code-* -- sh -c "$h""#,
                1,
            ),
        ),
        // gcl check-host --help
        (
            "gcl check-host --profile seed --report reports/host -- python3 my_host.py {port}".into(),
            sh_as(leak(format!("gcl check-host --profile seed --report reports/host -- {}", host("seed"))), 0),
        ),
    ]
}

const BENCH: &str = "a benchmark; `cargo test --all-targets` runs each one as a smoke test";

/// The files examples read that a user writes.
const USER_FILES: &[(&str, &str)] = &[
    (
        "known.toml",
        "[[failure]]\ncase = \"no-such-case\"\nreason = \"an entry that matches nothing is warned about\"\n",
    ),
    ("my.script", "# FGET DP after a reset\nid: my\ntitle: FGET DP after a reset\nabort\nRESET\nFGET DP\n"),
];

/// The example lines of the `sh` blocks of README.md and the guides (`docs/src/`): continuations joined, comments dropped.
fn readme_examples() -> Vec<String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut files: Vec<PathBuf> = std::fs::read_dir(root.join("docs/src"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    files.sort();
    files.insert(0, root.join("README.md"));
    let readme = files.iter().map(|f| std::fs::read_to_string(f).unwrap()).collect::<Vec<_>>().join("\n");
    let mut out = Vec::new();
    let mut in_sh = false;
    let mut cur = String::new();
    for line in readme.lines() {
        if line.starts_with("```") {
            in_sh = line == "```sh";
            continue;
        }
        if !in_sh {
            continue;
        }
        let line = line.trim();
        let joined = if cur.is_empty() { line.to_string() } else { format!("{cur} {line}") };
        if let Some(head) = joined.strip_suffix('\\') {
            cur = head.trim_end().to_string();
            continue;
        }
        cur.clear();
        if joined.is_empty() || joined.starts_with('#') {
            continue;
        }
        // A comment after the command: two or more spaces, then `# `.
        let cmd = match joined.find("  #") {
            Some(i) => joined[..i].trim_end().to_string(),
            None => joined,
        };
        out.push(cmd);
    }
    out
}

fn help(path: &[&str]) -> String {
    let o = Command::new(GCL).args(path).arg("--help").output().unwrap();
    assert!(o.status.success(), "gcl {path:?} --help");
    String::from_utf8(o.stdout).unwrap()
}

/// Every subcommand path, from the `Commands:` lists of the help texts.
fn command_paths() -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let mut todo: Vec<Vec<String>> = vec![vec![]];
    while let Some(p) = todo.pop() {
        let args: Vec<&str> = p.iter().map(String::as_str).collect();
        let text = help(&args);
        if let Some(i) = text.find("\nCommands:\n") {
            for l in text[i + 11..].lines().take_while(|l| !l.trim().is_empty()) {
                // A name starts two spaces in; a wrapped description sits deeper.
                if let Some(name) =
                    l.strip_prefix("  ").filter(|r| !r.starts_with(' ')).and_then(|r| r.split_whitespace().next())
                    && name != "help"
                {
                    let mut q = p.clone();
                    q.push(name.to_string());
                    todo.push(q);
                }
            }
        }
        out.push(p);
    }
    out
}

/// The example lines of every `--help`: the lines of its `Example(s):` section, and any other
/// line that starts with `cargo run`. A line of an examples section that does not start a
/// command is one that wrapped.
fn help_examples() -> (Vec<String>, Vec<String>) {
    let (mut out, mut wrapped) = (Vec::new(), Vec::new());
    for p in command_paths() {
        let args: Vec<&str> = p.iter().map(String::as_str).collect();
        let text = help(&args);
        let mut in_examples = false;
        let mut cur = String::new();
        for l in text.lines() {
            // A line ending in `\` goes on, as in a shell.
            let joined = if cur.is_empty() { l.trim().to_string() } else { format!("{cur} {}", l.trim()) };
            if in_examples && let Some(head) = joined.strip_suffix('\\') {
                cur = head.trim_end().to_string();
                continue;
            }
            cur.clear();
            let t = joined.as_str();
            if t == "Example:" || t == "Examples:" {
                in_examples = true;
                continue;
            }
            if t.is_empty() {
                in_examples = false;
                continue;
            }
            let starts = t.starts_with("gcl ") || t.starts_with("cargo run");
            if in_examples && !starts {
                wrapped.push(format!("gcl {}: {t}", p.join(" ")));
            } else if in_examples || t.starts_with("cargo run") {
                out.push(t.to_string());
            }
        }
    }
    (out, wrapped)
}

struct Ran {
    code: Option<i32>,
    output: String,
}

/// Runs `script` with `sh -c` in `dir` in its own process group, killed after `limit`.
fn run_sh(dir: &Path, script: &str, path: &str, limit: Duration) -> Ran {
    let mut child = Command::new("sh")
        .arg("-c")
        .arg(format!("{PRELUDE}\n{script}"))
        .current_dir(dir)
        .env("PATH", path)
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .process_group(0)
        .spawn()
        .unwrap();
    let mut out = child.stdout.take().unwrap();
    let mut err = child.stderr.take().unwrap();
    let t_out = std::thread::spawn(move || {
        let mut s = Vec::new();
        let _ = out.read_to_end(&mut s);
        s
    });
    let t_err = std::thread::spawn(move || {
        let mut s = Vec::new();
        let _ = err.read_to_end(&mut s);
        s
    });
    let start = Instant::now();
    let code = loop {
        if let Some(st) = child.try_wait().unwrap() {
            break st.code();
        }
        if start.elapsed() > limit {
            kill_group(&child);
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    kill_group(&child);
    let output = format!(
        "{}{}",
        String::from_utf8_lossy(&t_out.join().unwrap()),
        String::from_utf8_lossy(&t_err.join().unwrap())
    );
    Ran { code, output }
}

fn kill_group(child: &std::process::Child) {
    let pgid = nix::unistd::Pid::from_raw(child.id() as i32);
    let _ = nix::sys::signal::killpg(pgid, nix::sys::signal::Signal::SIGKILL);
}

/// Starts a server, waits for its first line of stdout, and stops it.
fn serve(dir: &Path, command: &str, path: &str) -> Result<String, String> {
    let mut child = Command::new("sh")
        .arg("-c")
        .arg(format!("exec {command}"))
        .current_dir(dir)
        .env("PATH", path)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .process_group(0)
        .spawn()
        .unwrap();
    let stdout = child.stdout.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut line = String::new();
        let _ = BufReader::new(stdout).read_line(&mut line);
        let _ = tx.send(line);
    });
    let got = rx.recv_timeout(Duration::from_secs(30));
    let alive = child.try_wait().unwrap().is_none();
    let pid = nix::unistd::Pid::from_raw(child.id() as i32);
    let _ = nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGTERM);
    let status = child.wait().unwrap();
    kill_group(&child);
    match got {
        Ok(l) if !l.trim().is_empty() && alive => {
            if status.success() {
                Ok(l.trim().to_string())
            } else {
                Err(format!("printed {l:?} but exited {status} on SIGTERM"))
            }
        }
        Ok(l) => Err(format!("printed {l:?}, running: {alive}")),
        Err(_) => Err("printed nothing in 30 s".into()),
    }
}

#[test]
fn every_example_in_the_readme_and_the_help_runs_as_written() {
    let plans = plans();
    let listed: BTreeSet<&str> = plans.iter().map(|(e, _)| e.as_str()).collect();
    assert_eq!(listed.len(), plans.len(), "an example is listed twice");
    let (from_help, wrapped) = help_examples();
    assert!(wrapped.is_empty(), "--help examples that wrap (cannot be pasted):\n{}", wrapped.join("\n"));
    let found: Vec<String> = readme_examples().into_iter().chain(from_help).collect();
    let found_set: BTreeSet<&str> = found.iter().map(String::as_str).collect();
    let unlisted: Vec<&&str> = found_set.difference(&listed).collect();
    let stale: Vec<&&str> = listed.difference(&found_set).collect();
    assert!(unlisted.is_empty(), "examples with no plan here (add them to `plans`):\n{unlisted:#?}");
    assert!(stale.is_empty(), "plans for examples no document has any more:\n{stale:#?}");

    let Some(python) = deps::python_with(&[]) else { return };
    let dir = tempfile::tempdir().unwrap();
    for (name, text) in USER_FILES {
        std::fs::write(dir.path().join(name), text).unwrap();
    }
    std::fs::copy(dir.path().join("my.script"), dir.path().join("my-case.script")).unwrap();
    let bin = Path::new(GCL).parent().unwrap();
    let examples = bin.join("examples");
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap_or_default());
    let repo: PathBuf = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let fill = |s: &str| s.replace("{examples}", &examples.display().to_string()).replace("{python}", &python);
    let mut failures = Vec::new();
    // In document order, each example once (the README's keygen comes before certify's help).
    for (example, run) in &plans {
        match run {
            Run::Not(why) => eprintln!("not run: {example} ({why})"),
            Run::Serve { as_run } => {
                if let Err(e) = serve(dir.path(), &fill(as_run.unwrap_or(example)), &path) {
                    failures.push(format!("{example}\n  served as {}: {e}", as_run.unwrap_or(example)));
                }
            }
            Run::Sh { as_run, code, in_repo } => {
                let cwd = if *in_repo { repo.as_path() } else { dir.path() };
                let script = fill(as_run.unwrap_or(example));
                let r = run_sh(cwd, &script, &path, Duration::from_secs(300));
                if r.code != Some(*code) {
                    failures.push(format!(
                        "{example}\n  run as: {script}\n  exit {:?}, expected {code}\n{}",
                        r.code,
                        r.output
                            .lines()
                            .rev()
                            .take(15)
                            .collect::<Vec<_>>()
                            .into_iter()
                            .rev()
                            .collect::<Vec<_>>()
                            .join("\n")
                    ));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{} example(s) do not run as written:\n\n{}", failures.len(), failures.join("\n\n"));
}
