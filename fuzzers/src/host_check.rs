//! `gcl check-host`: host conformance. A perfect simulated hand (no misbehaviour) runs the host
//! command once and grades its traffic clause by clause ([`HostClause`]); the result is a
//! [`RunReport`] like `conform`'s, one case per clause, so the same JSON, JUnit and HTML
//! writers serve. Optionally the bytes the host sent are compared with the `send` steps of a
//! golden host transcript.

use std::time::Instant;

use crate::fuzz::host::bundle::session_transcript;
use crate::fuzz::host::{FindingKind, HostClause, HostEnd, HostRun, RunError, RunResult, judge, run_once_until};
pub use crate::report::SESSION_CASE;
use crate::report::{CaseResult, Diff, Liveness, RunOptions, RunReport, Verdict};
use crate::sim::misbehave::Schedule;
use gcl_transcript::Transcript;

/// What `check_host` needs.
#[derive(Debug, Clone)]
pub struct CheckHostOptions {
    /// The run (its schedule is empty).
    pub run: HostRun,
    /// Exit codes that pass.
    pub ok_exit_codes: Vec<i32>,
    /// A golden host transcript whose `send` steps the host's bytes must equal.
    pub golden: Option<Transcript>,
}

/// What `check_host` found.
#[derive(Debug, Clone)]
pub struct CheckHostOutcome {
    /// One case per clause (and the golden comparison), as `conform` reports.
    pub report: RunReport,
    /// The run itself.
    pub run: RunResult,
    /// The session as a `gcl-transcript 1` (usable as a golden for later checks).
    pub session: String,
}

/// Runs the host once against a perfect hand and grades it.
pub fn check_host(opts: &CheckHostOptions) -> Result<CheckHostOutcome, RunError> {
    check_host_until(opts, &std::sync::atomic::AtomicBool::new(false))
}

/// [`check_host`], called off once `stop` is set ([`RunError::Cancelled`]: the host's
/// process group stopped, its run folder removed).
pub fn check_host_until(
    opts: &CheckHostOptions,
    stop: &std::sync::atomic::AtomicBool,
) -> Result<CheckHostOutcome, RunError> {
    let started = time::OffsetDateTime::now_utc();
    let t0 = Instant::now();
    let r = run_once_until(&opts.run, &Schedule::default(), stop)?;
    Ok(grade(opts, r, started, t0))
}

/// The report of a check stopped before the host ended (`why`: `stopped by SIGTERM`): an
/// ERROR that says so, and no clause judged.
pub fn stopped_report(opts: &CheckHostOptions, why: &str, started: time::OffsetDateTime, t0: Instant) -> RunReport {
    let elapsed = t0.elapsed().as_secs_f64() * 1000.0;
    let message = format!("{why} before the host ended: nothing judged");
    let mut cases = vec![case(SESSION_CASE, "the host talks to the hand", "host: process", Verdict::Error, &[], "")];
    cases[0].message = Some(message.clone());
    cases[0].transcript = None;
    for clause in HostClause::ALL {
        let mut c =
            case(&format!("host-{}", clause.id()), clause.title(), clause.spec_clause(), Verdict::Skip, &[], "");
        c.message = Some("not exercised: the check was stopped".into());
        c.transcript = None;
        cases.push(c);
    }
    for c in &mut cases {
        c.duration_ms = elapsed;
    }
    let mut report =
        host_report(&opts.run.command, &opts.run.profile.id, started, elapsed, opts.run.hand_seed, false, cases);
    report.stopped =
        Some(crate::report::Stopped { cause: crate::report::StopCause::Signal, case: SESSION_CASE.into(), message });
    report
}

/// Grades a run (the host's traffic clause by clause, how it ended, the golden): the body of
/// [`check_host`].
pub fn grade(opts: &CheckHostOptions, r: RunResult, started: time::OffsetDateTime, t0: Instant) -> CheckHostOutcome {
    let unreached = crate::fuzz::host::unreached(&r, &opts.run.command);
    grade_as(opts, r, started, t0, unreached)
}

/// [`grade`] for a session `gcl check-host --serve` served until it was stopped: one nobody
/// opened, or in which nobody sent a byte, judged nothing.
pub fn grade_served(
    opts: &CheckHostOptions,
    r: RunResult,
    started: time::OffsetDateTime,
    t0: Instant,
) -> CheckHostOutcome {
    let sent = r.exchanges.iter().any(|e| e.dir == crate::fuzz::host::Dir::Host && !e.bytes.is_empty());
    let unreached = match (r.port_opened, sent) {
        (_, true) => None,
        (false, _) => Some("nobody opened the port before the hand was stopped".to_string()),
        (true, false) => {
            Some("the port was opened, but nothing was sent to the hand before it was stopped".to_string())
        }
    };
    grade_as(opts, r, started, t0, unreached)
}

/// Whether a clause was exercised by the host's traffic, and if not, why: a clause that no
/// byte of the host exercised is "not exercised", never PASS.
fn not_exercised(clause: HostClause, r: &RunResult) -> Option<&'static str> {
    let rt = r.commands.iter().any(|c| c.ends_with("LOOP"));
    // Host bytes after the hand's: it sent again once an answer had come (or was coming).
    let after_answer = r
        .exchanges
        .iter()
        .skip_while(|e| e.dir != crate::fuzz::host::Dir::Hand || e.bytes.is_empty())
        .any(|e| e.dir == crate::fuzz::host::Dir::Host && !e.bytes.is_empty());
    // ^C is no line: a host that sent nothing else has ended no line.
    let lines = r.exchanges.iter().any(|e| e.dir == crate::fuzz::host::Dir::Host && e.bytes.iter().any(|&b| b != 0x03));
    match clause {
        HostClause::LineEnding if !lines => Some("the host sent nothing but ^C"),
        HostClause::ValidCommands if r.commands.is_empty() => Some("the host sent no command"),
        HostClause::WaitsForAnswer if !after_answer => Some("the host sent nothing after an answer began"),
        HostClause::RealtimeBlocks | HostClause::LeavesCleanly if !rt => Some("the host never entered RealTime"),
        HostClause::ExitsCleanly if r.end == HostEnd::Served => {
            Some("a served session has no host process: how its client ended is not seen")
        }
        _ => None,
    }
}

fn grade_as(
    opts: &CheckHostOptions,
    r: RunResult,
    started: time::OffsetDateTime,
    t0: Instant,
    unreached: Option<String>,
) -> CheckHostOutcome {
    let verdicts = judge(&r, &opts.ok_exit_codes);
    let header = format!(
        "id: check-host-session\ntitle: {}\nclause: host: gcl check-host\nlevel: INFO\nprofile: {}\n",
        opts.run.command.join(" ").chars().filter(|c| !c.is_control()).collect::<String>(),
        opts.run.profile.id
    );
    let session = session_transcript(&header, &r.exchanges);
    let mut cases = Vec::new();
    if let Some(why) = &unreached {
        // Nothing to judge: one ERROR that says why, and no clause judged.
        let mut c = case(SESSION_CASE, "the host talks to the hand", "host: process", Verdict::Error, &[], &session);
        c.message = Some(format!("nothing judged: {why}"));
        c.transcript = None;
        c.duration_ms = r.elapsed.as_secs_f64() * 1000.0;
        cases.push(c);
    }
    for clause in HostClause::ALL {
        let broken: Vec<String> = if clause == HostClause::ExitsCleanly {
            verdicts.iter().filter(|v| v.kind != FindingKind::Violation).map(|v| v.message.clone()).collect()
        } else {
            r.violations.iter().filter(|v| v.clause == clause).map(|v| format!("{}: {}", v.kind, v.detail)).collect()
        };
        let idle = if unreached.is_some() {
            Some("the host never talked to the hand")
        } else if broken.is_empty() {
            not_exercised(clause, &r)
        } else {
            None
        };
        let verdict = match (&r.end, clause, broken.is_empty()) {
            _ if idle.is_some() => Verdict::Skip,
            (_, _, true) => Verdict::Pass,
            (HostEnd::Hung(_) | HostEnd::OverBudget(_), HostClause::ExitsCleanly, _) => Verdict::Timeout,
            _ => Verdict::Fail,
        };
        let mut c =
            case(&format!("host-{}", clause.id()), clause.title(), clause.spec_clause(), verdict, &broken, &session);
        if let Some(why) = idle {
            c.message = Some(format!("not exercised: {why}"));
            c.transcript = None;
        }
        // Every clause is judged over the whole session (one not exercised found so there):
        // its time is the session's.
        c.duration_ms = r.elapsed.as_secs_f64() * 1000.0;
        cases.push(c);
    }
    if let Some(g) = &opts.golden {
        let want = g.host_bytes();
        let got: Vec<u8> = r
            .exchanges
            .iter()
            .filter(|e| e.dir == crate::fuzz::host::Dir::Host)
            .flat_map(|e| e.bytes.iter().copied())
            .collect();
        let mut c = case(
            "host-golden",
            &format!("the host sends what golden transcript {} sends", g.header.id),
            "host: golden transcript",
            Verdict::Pass,
            &[],
            &session,
        );
        c.duration_ms = r.elapsed.as_secs_f64() * 1000.0;
        if want != got {
            let at = want.iter().zip(&got).take_while(|(a, b)| a == b).count();
            let esc = |b: &[u8]| gcl_model::escape::escape(&b[at.min(b.len())..(at + 60).min(b.len())]);
            c.verdict = Verdict::Fail;
            c.message = Some(format!("the host's bytes part from the golden's at byte {at}"));
            c.diff = Some(Diff {
                step: 1,
                offset: at,
                expected: esc(&want),
                actual: esc(&got),
                before: gcl_model::escape::escape(&want[at.saturating_sub(40)..at]),
                golden: String::new(),
                form: Some(crate::report::AnswerForm::Text),
            });
            c.transcript = Some(crate::report::truncate_note(&session, crate::report::MAX_SHOWN));
        }
        cases.push(c);
    }
    // A host that reached the hand but exercised no clause and matched no golden (a served client that sent only
    // ^C) judged nothing: an ERROR that says so, never a pass.
    if unreached.is_none() && cases.iter().all(|c| c.verdict == Verdict::Skip) {
        let mut c = case(SESSION_CASE, "the host talks to the hand", "host: process", Verdict::Error, &[], &session);
        c.message = Some("nothing judged: the host exercised no clause".into());
        c.transcript = None;
        c.duration_ms = r.elapsed.as_secs_f64() * 1000.0;
        cases.insert(0, c);
    }
    let report = host_report(
        &opts.run.command,
        &opts.run.profile.id,
        started,
        t0.elapsed().as_secs_f64() * 1000.0,
        opts.run.hand_seed,
        false,
        cases,
    );
    CheckHostOutcome { report, run: r, session }
}

/// A conformance report over host runs (`gcl check-host`, and `gcl fuzz host` with
/// `fuzz = true`): one case per clause or finding, tallied, its suite hash over the host
/// clauses (and the operators when fuzzing).
pub fn host_report(
    command: &[String],
    profile: &str,
    started: time::OffsetDateTime,
    duration_ms: f64,
    seed: u64,
    fuzz: bool,
    cases: Vec<crate::report::CaseResult>,
) -> RunReport {
    let mut report = RunReport {
        kind: if fuzz { crate::report::ReportKind::FuzzHost } else { crate::report::ReportKind::CheckHost },
        host: None,
        verdict: String::new(),
        profile_spec: None,
        certificate: None,
        format: crate::report::REPORT_FORMAT,
        tool: format!("gcl {}", env!("CARGO_PKG_VERSION")),
        target: format!("host: {}", command.join(" ")),
        profile: profile.to_string(),
        level: "all".into(),
        started: started
            .replace_nanosecond(0)
            .unwrap_or(started)
            .format(&time::format_description::well_known::Rfc3339)
            .unwrap_or_default(),
        duration_ms,
        suite_hash: host_suite_hash(fuzz),
        liveness: Liveness { before: true, after: true },
        options: RunOptions { seed: Some(seed), ..Default::default() },
        preflight: None,
        stopped: None,
        groups: Vec::new(),
        wire: None,
        summary: Default::default(),
        clauses: Vec::new(),
        cases,
    };
    report.tally();
    report
}

/// The version of the host clauses, where a conformance report has its suite hash: SHA-256
/// over each clause's id and title (and, for `gcl fuzz host`, each operator's name).
pub fn host_suite_hash(with_operators: bool) -> String {
    use sha2::{Digest, Sha256};
    let mut h = Sha256::new();
    for c in HostClause::ALL {
        h.update(format!("{}\t{}\n", c.id(), c.title()));
    }
    if with_operators {
        for o in crate::sim::misbehave::Operator::ALL {
            h.update(format!("{}\n", o.name()));
        }
    }
    crate::digest::hex(&h.finalize())
}

fn case(id: &str, title: &str, clause: &str, verdict: Verdict, broken: &[String], session: &str) -> CaseResult {
    let failed = verdict != Verdict::Pass;
    CaseResult {
        id: id.to_string(),
        title: title.to_string(),
        clauses: vec![clause.to_string()],
        decisions: Vec::new(),
        level: "MUST".into(),
        verdict,
        duration_ms: 0.0,
        message: failed.then(|| crate::report::truncate_note(&broken.join("; "), 1000)),
        diff: None,
        failure: None,
        transcript: failed.then(|| crate::report::truncate_note(session, crate::report::MAX_SHOWN)),
    }
}
