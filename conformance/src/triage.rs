//! Root causes first: failures grouped by where they part from their goldens.
//!
//! One firmware bug often fails a hundred cases (every case that reads parameters back trips
//! over an FGET that prints the motors in reverse). A failure's *signature* is the command
//! being answered where it parts from the golden (`FGET`, `^C`, `CR`, `RealTime block`) and
//! the kind of difference:
//!
//! - `framing`: the echo, a line ending or the prompt (also bytes after the last answer);
//! - `status`: an `ERR n` line where none was expected, none where one was, or another one;
//! - `order`: the answer's line holds the expected values in another order;
//! - `value`: anything else in the answer's content;
//! - `missing-answer`: the answer never came, or stopped short of anything but framing;
//! - `flood`: the hand sent more than the step's ceiling;
//! - `link`: the link failed (the hand vanished).
//!
//! Cases with one signature form a group; groups are listed largest first, each with the
//! case of the smallest golden transcript as its representative, whose clause is named as the
//! one most likely at fault (the smallest case exercises least besides its own clause).
//!
//! Groups are keyed by `align`'s key; link failures form no group (a vanished hand ends the run). A
//! group's cases that do not check its clause are *blocked* by it (`FailureGroup::blocked`), and
//! the
//! clause table (`ClauseCoverage::blocked`) counts as failing only the clauses groups name.

use std::collections::BTreeMap;
use std::sync::Arc;

use gcl_model::Profile;

use crate::align::Signature;
use crate::replay::ReplayOutcome;
use crate::report::{CaseResult, FailureGroup};
use crate::suite::Case;

/// One failing case as the grouping sees it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Failure {
    /// Its index among the run's results.
    pub result: usize,
    /// The failing step, 0-based.
    pub step: usize,
    /// Where it parts from its golden.
    pub signature: Signature,
    /// A word the clause at fault likely holds: the status number expected (or given) for a
    /// status difference, `echo` for a difference in the echo.
    pub hint: Option<String>,
}

/// The signature of a failed replay of `case` and a hint at its clause; `None` for a pass.
///
/// The difference is named by the input the model was answering there ([`crate::align`]:
/// the model's own run of the case tags its answers), so a case that sends lines behind a
/// motion or a ^C is grouped with the command that broke, not the one read after it.
/// `whole_reads`: the link hands answers over whole (the in-process sim).
pub fn signature(
    case: &Case,
    outcome: &ReplayOutcome,
    profile: &Arc<Profile>,
    whole_reads: bool,
) -> Option<(Signature, Option<String>)> {
    outcome.failed_step()?;
    if outcome.is_pass() {
        return None;
    }
    let run = crate::align::model_run(profile, &case.transcript).unwrap_or_default();
    let f = crate::align::signature(profile, &case.transcript, &run, outcome, whole_reads)?;
    let hint = match f.kind.as_str() {
        "status" => {
            // The bits the key names: the clause of that status holds the number.
            let key = f.key();
            let bits = key.strip_prefix("status ").unwrap_or_default();
            bits.split(' ').next().and_then(|b| b.split('+').next()).map(str::to_string)
        }
        _ if f.detail == "echo" => Some("echo".to_string()),
        _ => None,
    };
    let key = f.key();
    Some((Signature { key, command: f.command, kind: f.kind, detail: f.detail, cause: f.cause }, hint))
}

fn phrase(kind: &str) -> &'static str {
    match kind {
        "order" => "the values come in another order",
        "value" => "a value differs",
        "framing" => "the framing differs (echo, line ending or prompt)",
        "status" => "the status differs",
        "missing-answer" | "missing" => "the answer is missing or stops short",
        "extra" => "the hand says more than the answer",
        "restart" => "the hand restarts (a banner nobody asked for)",
        "flood" => "the hand floods the answer",
        _ => "the link failed",
    }
}

/// Where a case's own check begins: the first step after a `# the check` comment (0 when the
/// case has none: all of it is its check).
fn check_start(case: &Case) -> usize {
    case.transcript
        .steps
        .iter()
        .position(|s| s.comments.iter().any(|c| c.contains(crate::suite::build::CHECK_COMMENT)))
        .unwrap_or(0)
}

fn size(case: &Case) -> (usize, usize) {
    (case.transcript.steps.len(), case.text().len())
}

/// The case that owns a failure of `case` at `step`: the case itself when the step is part of
/// its own check; otherwise (it failed in its preamble, on something it does not check) the
/// smallest case of the suite whose check holds that very exchange.
fn owner<'c>(case: &'c Case, step: usize, all: &'c [Case]) -> (&'c Case, bool) {
    if step >= check_start(case) {
        return (case, true);
    }
    let Some(s) = case.transcript.steps.get(step) else { return (case, false) };
    all.iter()
        .filter(|c| c.profile == case.profile)
        .filter(|c| c.transcript.steps[check_start(c)..].iter().any(|t| t.send == s.send && t.expect == s.expect))
        .min_by_key(|c| size(c))
        .map_or((case, false), |c| (c, true))
}

/// A group member: result index, failing step, hint.
type Member<'a> = (usize, usize, Option<&'a str>);

/// Groups the failing cases, largest group first. `failures` holds one entry per failing
/// case (cases whose result does not fail the run, such as XFAIL, are left out; so are link
/// failures: a hand that vanished is the run's end, not a clause's). `framing` holds the
/// clauses of the framing faults the pre-flight named: a group of framing differences takes
/// the first of them.
///
/// A group names the clause of the case most likely at fault: among the cases that own the
/// group's failures (the case itself when the failing step is part of its own check, else
/// the smallest case whose check holds that exchange), those whose clause holds a failure's
/// hint first (the status number, `echo`), then those whose clause names the command being
/// answered, then the smallest golden transcript.
///
/// A member case that does not check the group's clause is *blocked* by it (listed in the
/// group's `blocked`): its failure is that clause's bug met on the way (a read-back with a
/// broken FGET), not a verdict on its own clause. In a group none of whose cases checks its
/// clause, the representative is not blocked.
pub fn group(cases: &[Case], results: &[CaseResult], failures: &[Failure], framing: &[String]) -> Vec<FailureGroup> {
    let find = |id: &str| cases.iter().find(|c| c.id() == id);
    let mut by: BTreeMap<&str, (&Signature, Vec<Member<'_>>)> = BTreeMap::new();
    for f in failures
        .iter()
        .filter(|f| f.signature.kind != "link")
        .filter(|f| results.get(f.result).is_some_and(|r| r.verdict.fails_run()))
    {
        by.entry(&f.signature.key).or_insert((&f.signature, Vec::new())).1.push((f.result, f.step, f.hint.as_deref()));
    }
    let mut groups: Vec<FailureGroup> = by
        .into_values()
        .map(|(sig, idx)| {
            let small = |i: usize| find(&results[i].id).map_or((usize::MAX, usize::MAX), size);
            let rep =
                idx.iter().map(|(i, _, _)| *i).min_by_key(|i| (small(*i), results[*i].id.clone())).unwrap_or(idx[0].0);
            let r = &results[rep];
            let has_word = |clause: &str, w: &str| {
                clause.split(|c: char| c.is_whitespace() || c == '-' || c == ':').any(|x| x.eq_ignore_ascii_case(w))
            };
            let hints: Vec<&str> = idx.iter().filter_map(|(_, _, h)| *h).collect();
            let owned = idx
                .iter()
                .filter_map(|(i, step, _)| find(&results[*i].id).map(|c| owner(c, *step, cases)))
                .chain(idx.iter().filter_map(|(i, _, _)| find(&results[*i].id).map(|c| (c, false))))
                .map(|(c, owns)| (c.header().clauses.first().cloned().unwrap_or_default(), owns, size(c)))
                .min_by_key(|(clause, owns, size)| {
                    let hinted = hints.iter().any(|h| has_word(clause, h));
                    (!hinted, !owns, !has_word(clause, &sig.command), *size, clause.clone())
                })
                .map(|(clause, _, _)| clause)
                .unwrap_or_else(|| r.clauses.first().cloned().unwrap_or_default());
            let clause = match framing.first() {
                Some(f) if sig.kind == "framing" => f.clone(),
                _ => owned,
            };
            let n = idx.len();
            // (when no member checks the clause, as with the pre-flight's framing clause, the
            // representative stands for it and is not blocked)
            let checks = |i: usize| results[i].clauses.iter().any(|c| c == &clause);
            let any_checks = idx.iter().any(|(i, _, _)| checks(*i));
            let blocked: Vec<String> = idx
                .iter()
                .filter(|(i, _, _)| !checks(*i) && (any_checks || *i != rep))
                .map(|(i, _, _)| results[*i].id.clone())
                .collect();
            let what = match (sig.kind.as_str(), sig.detail.as_str(), sig.cause.as_str()) {
                ("status", d, _) if !d.is_empty() => format!(" ({d})"),
                (_, _, c) if !c.is_empty() => format!(" after {c}"),
                ("order", _, _) => String::new(),
                (_, d, _) if !d.is_empty() => format!(" ({d})"),
                _ => String::new(),
            };
            let held = if blocked.is_empty() { String::new() } else { format!(", {} of them blocked", blocked.len()) };
            FailureGroup {
                command: sig.command.clone(),
                kind: sig.kind.clone(),
                summary: format!(
                    "{n} case{}: {}: {}{what}; likely clause `{clause}` (e.g. case {}){held}",
                    if n == 1 { "" } else { "s" },
                    sig.command,
                    phrase(&sig.kind),
                    r.id
                ),
                clause,
                representative: r.id.clone(),
                diff: r.diff.clone(),
                cases: idx.iter().map(|(i, _, _)| results[*i].id.clone()).collect(),
                blocked,
            }
        })
        .collect();
    groups.sort_by(|a, b| b.cases.len().cmp(&a.cases.len()).then_with(|| a.summary.cmp(&b.summary)));
    groups
}
