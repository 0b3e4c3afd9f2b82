//! The runner as a user meets it through the `gcl` binary: the framing pre-flight line,
//! `--max-failures` and `--fail-fast`, the early end on a hand that stops answering, clean
//! reconnects to a hand that restarts, and what the summary and reports say about them.
//!
//! Hands that misbehave in time are small shell scripts around `gcl sim --stdio` (run as
//! `exec:` targets), started and killed by the runner itself; every run here is bounded by
//! the runner's own deadlines.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use gcl_harness::report::{RunReport, StopCause, Verdict};

use crate::sim_support;

const GCL: &str = env!("CARGO_BIN_EXE_gcl");

fn gcl(args: &[&str]) -> Output {
    Command::new(GCL).args(args).output().expect("gcl runs")
}

fn report(dir: &Path) -> RunReport {
    serde_json::from_slice(&std::fs::read(dir.join("report.json")).unwrap()).unwrap()
}

/// A hand written as a shell script (`exec:sh FILE`); `{gcl}` in `body` is the binary.
fn script(dir: &Path, name: &str, body: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, body.replace("{gcl}", GCL)).unwrap();
    p
}

fn text(o: &Output) -> (String, String) {
    (String::from_utf8_lossy(&o.stdout).into_owned(), String::from_utf8_lossy(&o.stderr).into_owned())
}

#[test]
fn the_pre_flight_names_a_broken_prompt_first_in_the_console_and_in_every_report() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("r");
    let o = gcl(&[
        "conform",
        "--target",
        "sim:seed",
        "--fault",
        "prompt-no-space",
        "--only",
        "framing-*",
        "--report",
        out.to_str().unwrap(),
    ]);
    let (stdout, stderr) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{stdout}{stderr}");
    let line = "pre-flight: the hand's prompt is `=>` without the trailing space";
    assert!(stderr.starts_with(line), "the first line of the run: {stderr}");
    // Said once: stderr has it as it happens; the summary on stdout does not repeat it (the
    // reports keep it).
    assert!(!stdout.contains(line), "not again in the summary: {stdout}");
    assert_eq!(stderr.matches(line).count(), 1, "{stderr}");
    // The suite still ran: every case is listed.
    let r = report(&out);
    assert_eq!(r.preflight.as_deref(), Some(line));
    assert!(r.cases.len() > 5 && r.cases.iter().all(|c| c.verdict == Verdict::Timeout), "{:?}", r.summary);
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(html.contains("the hand&#39;s prompt is `=&gt;` without the trailing space"), "{html}");
    let junit = std::fs::read_to_string(out.join("junit.xml")).unwrap();
    assert!(junit.contains("name=\"preflight\""), "{junit}");

    let o = gcl(&["conform", "--target", "sim:seed", "--only", "framing-echo"]);
    let (stdout, stderr) = text(&o);
    assert_eq!(o.status.code(), Some(0), "{stdout}{stderr}");
    assert!(stderr.starts_with("pre-flight: framing as the profile says"), "{stderr}");
}

#[test]
fn fail_fast_and_max_failures_stop_the_run_and_list_the_rest_as_not_run() {
    let dir = tempfile::tempdir().unwrap();
    for (flag, n) in [(vec!["--fail-fast"], 1usize), (vec!["--max-failures", "3"], 3)] {
        let out = dir.path().join(format!("r{n}"));
        let mut args = vec!["conform", "--target", "sim:seed", "--fault", "fget-reversed", "--report"];
        args.push(out.to_str().unwrap());
        args.extend(flag.iter().copied());
        let o = gcl(&args);
        let (stdout, stderr) = text(&o);
        assert_eq!(o.status.code(), Some(1), "failures, not an infrastructure error: {stdout}{stderr}");
        let r = report(&out);
        let failing = r.cases.iter().filter(|c| c.verdict.fails_run()).count();
        assert_eq!(failing, n, "{flag:?}");
        let st = r.stopped.as_ref().expect("the report says the run ended early");
        assert_eq!(st.cause, StopCause::MaxFailures);
        // The reason once, on stderr as it happened; the summary says where the run ended.
        assert_eq!(stderr.matches(&st.message).count(), 1, "{stderr}");
        assert!(!stdout.contains(&st.message), "{stdout}");
        assert!(stdout.contains(&format!("ended early at case {}", st.case)), "{stdout}");
        let not_run =
            r.cases.iter().filter(|c| c.message.as_deref().is_some_and(|m| m.starts_with("not run:"))).count();
        assert!(not_run > 50, "the rest are listed as not run: {not_run}");
        assert!(
            r.cases
                .iter()
                .filter(|c| c.message.as_deref().is_some_and(|m| m.starts_with("not run:")))
                .all(|c| c.verdict == Verdict::Skip)
        );
        let suite_cases = std::fs::read_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/../vectors/suite/seed"))
            .unwrap()
            .filter(|e| e.as_ref().unwrap().path().extension().is_some_and(|x| x == "gcl"))
            .count();
        assert_eq!(r.cases.len(), suite_cases, "every case of the suite is in the report");
    }
}

#[test]
fn a_hand_that_stops_answering_ends_the_run_early_with_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    // The hand answers its first 1200 bytes of input, then stays connected and says nothing
    // (`dd bs=1` passes each byte on at once, where `head` would hold them in a buffer).
    let hand = script(
        dir.path(),
        "dead.sh",
        "dd bs=1 count=1200 2>/dev/null | {gcl} sim --stdio --profile seed 2>/dev/null\nexec sleep 60\n",
    );
    let out = dir.path().join("r");
    let target = format!("exec:sh {}", hand.display());
    let o = gcl(&[
        "conform",
        "--target",
        &target,
        "--profile",
        "seed",
        "--only",
        "param-*",
        "--dead-after",
        "2",
        // (the fast-time sim would have its abort-timing cases SKIP: this test counts runs)
        "--assume-real-time",
        "--report",
        out.to_str().unwrap(),
    ]);
    let (stdout, stderr) = text(&o);
    assert_eq!(o.status.code(), Some(2), "{stdout}{stderr}");
    let r = report(&out);
    let st = r.stopped.as_ref().expect("stopped early");
    assert_eq!(st.cause, StopCause::DeadHand);
    let line = format!("gcl conform: the hand stopped answering at case {}", st.case);
    assert_eq!(stderr.lines().filter(|l| l.starts_with(&line)).count(), 1, "one line says where: {stderr}");
    assert!(!stdout.contains("stopped answering"), "and only once: {stdout}");
    let timeouts = r.cases.iter().filter(|c| c.verdict == Verdict::Timeout).count();
    assert_eq!(timeouts, 2, "{:?}", r.summary);
    let first = r.cases.iter().find(|c| c.verdict == Verdict::Timeout).unwrap();
    assert_eq!(st.case, first.id, "the case where it stopped answering is the first of the timeouts");
    let passed = r.cases.iter().filter(|c| c.verdict == Verdict::Pass).count();
    assert!(passed > 3, "the hand answered at first: {:?}", r.summary);
    let not_run = r.cases.iter().filter(|c| c.message.as_deref().is_some_and(|m| m.starts_with("not run:"))).count();
    // The cases that need an object gcl cannot place on this hand are SKIP before the run.
    let unplaced =
        r.cases.iter().filter(|c| c.message.as_deref().is_some_and(|m| m.contains("--fixture object"))).count();
    assert_eq!(passed + timeouts + not_run + unplaced, r.cases.len(), "{:?}", r.summary);
    assert!(not_run > 20, "{:?}", r.summary);
    assert!(!r.liveness.after && !r.passed());
}

#[test]
fn a_hand_that_floods_costs_bounded_memory_and_reports_and_ends_the_run() {
    let dir = tempfile::tempdir().unwrap();
    // Prompts enough for the liveness probe, then an endless stream of zero bytes.
    let hand = script(dir.path(), "flood.sh", "printf '\\n\\r=> \\n\\r=> \\n\\r=> '\nsleep 0.4\nexec cat /dev/zero\n");
    let out = dir.path().join("r");
    let target = format!("exec:sh {}", hand.display());
    let o = gcl(&[
        "conform",
        "--target",
        &target,
        "--profile",
        "seed",
        "--dead-after",
        "2",
        "--report",
        out.to_str().unwrap(),
    ]);
    let (stdout, stderr) = text(&o);
    assert_eq!(o.status.code(), Some(2), "{stdout}{stderr}");
    let r = report(&out);
    let st = r.stopped.as_ref().expect("stopped early");
    assert_eq!(st.cause, StopCause::Flooding, "{st:?}");
    assert!(stderr.contains("the hand floods"), "{stderr}");
    for f in ["report.json", "junit.xml", "report.html", "results.jsonl"] {
        let len = std::fs::metadata(out.join(f)).unwrap().len();
        assert!(len < 2 << 20, "{f} is {len} bytes");
    }
    // The flood starts 0.4 s (wall time) after the process does, so how many cases fail
    // before it begins (this hand echoes nothing) depends on the machine's load. What does
    // not: the run ends at the case that met the flood, and no case runs after it.
    let not_run =
        |c: &&gcl_harness::report::CaseResult| c.message.as_deref().is_some_and(|m| m.starts_with("not run:"));
    let ran = r.cases.iter().take_while(|c| !not_run(c)).count();
    assert!(ran < r.cases.len(), "cases after the flood are not run: {:?}", r.summary);
    assert!(r.cases[ran..].iter().all(|c| not_run(&c)), "no case runs after the flood: {:?}", r.summary);
    assert!(r.cases[..ran].iter().any(|c| c.id == st.case), "the stop names a case that ran: {st:?}");
    let failed: Vec<_> = r.cases.iter().filter(|c| c.verdict.fails_run()).collect();
    assert!(!failed.is_empty(), "{:?}", r.summary);
    for c in failed {
        let d = c.diff.as_ref().unwrap();
        assert!(d.actual.len() <= gcl_harness::report::MAX_SHOWN + 64, "{}", d.actual.len());
    }
}

#[test]
fn a_hand_that_restarts_is_drained_and_probed_before_the_next_case() {
    let dir = tempfile::tempdir().unwrap();
    let flag = dir.path().join("started-once");
    // The first process ends after 1200 bytes of input; the one started after it runs on.
    let hand = script(
        dir.path(),
        "once.sh",
        &format!(
            "if [ -e {f} ]; then exec {{gcl}} sim --stdio --profile seed; fi\ntouch {f}\ndd bs=1 count=1200 2>/dev/null | {{gcl}} sim --stdio --profile seed 2>/dev/null\n",
            f = flag.display()
        ),
    );
    let out = dir.path().join("r");
    let target = format!("exec:sh {}", hand.display());
    let o = gcl(&[
        "conform",
        "--target",
        &target,
        "--profile",
        "seed",
        "--only",
        "param-*",
        // A fast-time simulator finishes a motion before a ^C can land (README).
        "--no",
        "abort-timing",
        "--report",
        out.to_str().unwrap(),
    ]);
    let (stdout, stderr) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{stdout}{stderr}");
    let r = report(&out);
    let errors: Vec<usize> =
        r.cases.iter().enumerate().filter(|(_, c)| c.verdict == Verdict::Error).map(|(i, _)| i).collect();
    assert_eq!(errors.len(), 1, "only the case the hand vanished in: {:?}", r.summary);
    let after = &r.cases[errors[0] + 1];
    assert_eq!(after.verdict, Verdict::Pass, "the next case is not blamed for the restart: {after:?}");
    let skipped = r.summary.get(&Verdict::Skip).copied().unwrap_or(0);
    assert_eq!(r.summary[&Verdict::Pass], r.cases.len() - 1 - skipped, "{:?}", r.summary);
    assert!(r.liveness.after);
}

#[test]
fn a_failures_diff_numbers_its_step_as_its_message_does() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("r");
    let o = gcl(&[
        "conform",
        "--target",
        "sim:seed",
        "--fault",
        "fget-reversed",
        "--only",
        "param-dp-default",
        "--report",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let r = report(&out);
    let c = &r.cases[0];
    let d = c.diff.as_ref().unwrap();
    // ^C, RESET, FDEF, then the check: FGET DP is the 4th step.
    assert_eq!(d.step, 4);
    assert!(c.message.as_deref().unwrap().contains("step 4"), "{:?}", c.message);
    // The answer parts at byte 10: `1` of `150` still fits the elision `{int 990..1010}`.
    assert_eq!(d.offset, 10);
    assert_eq!(d.before, "FGET DP\\n\\r1", "the agreed bytes before the parting one");
    // The golden in the form of expected and actual (issue 21 item 4): unquoted, escaped, and
    // the expected rest is its tail.
    assert_eq!(d.golden, "FGET DP\\n\\r1000 1000 1000 150\\n\\r=> ");
    assert!(d.golden.ends_with(&d.expected) && d.golden.ends_with("=> "), "{} / {}", d.golden, d.expected);
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(html.contains("^ byte 10 of step 4&#39;s answer"), "{html}");
    assert!(html.contains("golden: &quot;FGET DP"), "{html}");
}

#[test]
fn skipped_clauses_are_not_counted_as_failing() {
    let o = gcl(&["conform", "--target", "sim:seed", "--only", "cmd-hi*", "--no", "motion"]);
    let (stdout, stderr) = text(&o);
    assert_eq!(o.status.code(), Some(0), "{stdout}{stderr}");
    let line = stdout.lines().find(|l| l.trim_start().starts_with("clauses:")).unwrap();
    assert!(line.contains(" 0 failing"), "{line}");
    assert!(!line.contains(" 0 not fully judged"), "skipped clauses are counted as such: {line}");
}

/// Issue 20 item 2: a known failure (XFAIL) stops reading mid-answer as a FAIL does, so it
/// must leave the link as clean as any other end of a case. Against a hand that reverses FGET,
/// `framing-echo` and `framing-empty-line` fail and are listed; `framing-errors-combine`, run
/// after them, passes, and must not meet the rest of their answers (over a real-time pty it
/// failed at step 1, byte 0, on them).
#[test]
fn a_known_failure_leaves_the_link_as_clean_as_a_pass() {
    use sim_support::{SimProcess, Transport};
    let dir = tempfile::tempdir().unwrap();
    let known = dir.path().join("kf.toml");
    std::fs::write(&known, "[[failure]]\ncase = \"framing-e[cm]*\"\nreason = \"FGET reversed\"\n").unwrap();
    // Real time on both, so the rest of an answer is still on its way when a case parts.
    let mut pty = SimProcess::start_exact(Transport::Pty, &["--profile", "seed", "--fault", "fget-reversed"]);
    let exec = format!("exec:{GCL} sim --stdio --time real --profile seed --fault fget-reversed");
    for target in [pty.target(), exec] {
        let out = dir.path().join(format!("r{}", target.len()));
        let o = gcl(&[
            "conform",
            "--target",
            &target,
            "--profile",
            "seed",
            "--only",
            "framing-e*",
            "--known-failures",
            known.to_str().unwrap(),
            "--report",
            out.to_str().unwrap(),
        ]);
        let (stdout, stderr) = text(&o);
        let r = report(&out);
        let verdicts: Vec<(&str, Verdict)> = r.cases.iter().map(|c| (c.id.as_str(), c.verdict)).collect();
        assert_eq!(
            verdicts,
            [
                ("framing-echo", Verdict::Xfail),
                ("framing-empty-line", Verdict::Xfail),
                ("framing-errors-combine", Verdict::Pass)
            ],
            "{target}: {stdout}{stderr}"
        );
        assert_eq!(o.status.code(), Some(0), "{target}: {stdout}{stderr}");
    }
    pty.terminate();
}

/// Issue 37: a hand that names another firmware than the profile (its banner and VERS say 4.4,
/// the run was given bh8-262-4.3) is told so in the run's first line, with the profile to use,
/// and at the top of the report; a hand of the profile's own firmware hears nothing of it.
#[test]
fn a_hand_of_another_firmware_is_named_first() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("r");
    let o = gcl(&[
        "conform",
        "--target",
        "sim:bh8-262-4.4",
        "--profile",
        "bh8-262-4.3",
        "--only",
        "cmd-vers",
        "--report",
        out.to_str().unwrap(),
    ]);
    let (stdout, stderr) = text(&o);
    let line =
        "identity: the hand says firmware 4.4; you chose bh8-262-4.3 (firmware 4.3): run with --profile bh8-262-4.4";
    assert!(stderr.starts_with(line), "the first line of the run: {stderr}{stdout}");
    assert!(report(&out).preflight.is_some_and(|p| p.starts_with(line)), "the report's first line too");

    for (target, profile) in
        [("sim:bh8-262-4.3", "bh8-262-4.3"), ("sim:bh8-262-4.4", "bh8-262-4.4"), ("sim:seed", "seed")]
    {
        let o = gcl(&["conform", "--target", target, "--profile", profile, "--only", "cmd-vers"]);
        let (stdout, stderr) = text(&o);
        assert_eq!(o.status.code(), Some(0), "{stdout}{stderr}");
        assert!(!stderr.contains("identity:"), "{target}: {stderr}");
    }
}

/// Issue 37: a relation read after a number of RealTime cycles needs no clock. On a hand whose
/// motions end at once (`gcl sim --stdio`, fast time), the LCVC twin `rt-lcvc-positions` is
/// run, not skipped as needing abort timing: the correct hand passes it and a hand that
/// ignores LCVC fails it, while the cases that do need the clock are still SKIP with why.
#[test]
fn a_relation_read_over_cycles_is_judged_on_a_hand_without_a_clock() {
    let dir = tempfile::tempdir().unwrap();
    let run = |fault: &str| {
        let target = format!("exec:{GCL} sim --stdio{fault}");
        let out = dir.path().join(format!("r{}", fault.len()));
        let o = gcl(&[
            "conform",
            "--target",
            &target,
            "--only",
            "rt-lcvc-positions",
            "--only",
            "abort-motion",
            "--report",
            out.to_str().unwrap(),
        ]);
        let r = report(&out);
        let verdict = |id: &str| r.cases.iter().find(|c| c.id == id).map(|c| (c.verdict, c.message.clone()));
        (o.status.code(), verdict("rt-lcvc-positions"), verdict("abort-motion"))
    };
    let (code, lcvc, abort) = run("");
    assert_eq!(code, Some(0));
    assert_eq!(lcvc.map(|v| v.0), Some(Verdict::Pass));
    let (v, why) = abort.unwrap();
    assert_eq!(v, Verdict::Skip);
    assert!(why.is_some_and(|w| w.contains("requires abort-timing")), "the skip says why");
    let (code, lcvc, _) = run(" --fault lcvc-ignored");
    assert_eq!(code, Some(1));
    assert_eq!(lcvc.map(|v| v.0), Some(Verdict::Fail));
}
