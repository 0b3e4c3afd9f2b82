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

use std::collections::BTreeMap;
use std::sync::Arc;

use gcl_model::Profile;
use gcl_model::grammar::{Line, parse_line};

use crate::replay::ReplayOutcome;
use crate::report::{CaseResult, FailureGroup};
use crate::suite::Case;
use gcl_transcript::Form;

/// Where one failing case parts from its golden.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Signature {
    /// What groups compare: one bug, one key ([`crate::align::FindingSignature::key`]).
    pub key: String,
    /// The command being answered.
    pub command: String,
    /// The kind of difference (see [`crate::align`]).
    pub kind: String,
    /// What the difference concerns (a parameter, a RealTime field, status bits), if anything.
    pub detail: String,
    /// For a value read back: the command before it that decided the value.
    pub cause: String,
}

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

/// The signature of a failed replay by the step it failed in, the command that step sent
/// and the first differing line: what [`crate::align`] falls back on when the model's run of
/// the case cannot be tagged. Kinds: framing, status, order, value, missing-answer, flood,
/// link.
pub fn step_signature(case: &Case, outcome: &ReplayOutcome, profile: &Profile) -> Option<(Signature, Option<String>)> {
    let step = outcome.failed_step()?;
    let t = &case.transcript;
    let golden = t.steps.get(step.min(t.steps.len().saturating_sub(1)));
    let sent = golden.and_then(|s| s.send.as_ref()).map(|h| h.bytes.as_slice()).unwrap_or_default();
    let hex = golden.is_some_and(|s| s.expect.segments.iter().any(|g| g.form == Form::Hex))
        || golden.and_then(|s| s.send.as_ref()).is_some_and(|h| h.form == Form::Hex);
    let command = command_of(sent, hex, profile);
    let eol = profile.framing.line_ending.as_bytes();
    let prompt = profile.framing.prompt.as_bytes();
    let framing_text = gcl_transcript::escape_text(&[eol, prompt].concat());
    let (kind, hint) = match outcome {
        ReplayOutcome::Pass(_) => return None,
        ReplayOutcome::Disconnected(_) => ("link", None),
        ReplayOutcome::Flooded(_) => ("flood", None),
        ReplayOutcome::Timeout(to) => {
            if to.offset > 0 && !to.expected.is_empty() && framing_text.ends_with(&to.expected) {
                ("framing", None)
            } else {
                ("missing-answer", None)
            }
        }
        ReplayOutcome::Mismatch(m) if m.trailing => ("framing", None),
        ReplayOutcome::Mismatch(m) => {
            let got = m.exchange.last().map(|e| e.received.as_slice()).unwrap_or_default();
            classify(got, m.offset, &m.expected, &m.expected_full, sent, profile)
        }
    };
    let key = format!("{kind} at {command}");
    Some((Signature { key, command, kind: kind.to_string(), detail: String::new(), cause: String::new() }, hint))
}

/// The command word of a step's first line: `^C`, `CR`, `RealTime block`, or the word itself
/// without its motor prefix.
pub(crate) fn command_of(sent: &[u8], hex: bool, profile: &Profile) -> String {
    let fr = &profile.framing;
    if sent.first() == Some(&fr.abort) {
        return "^C".to_string();
    }
    if hex {
        return "RealTime block".to_string();
    }
    let line = sent.split(|b| *b == fr.terminator).next().unwrap_or_default();
    if line.iter().all(|b| b.is_ascii_whitespace()) {
        return "CR".to_string();
    }
    if let Ok(Line::Command(c)) = parse_line(profile, line) {
        return profile.command(c.command).name.clone();
    }
    // A line the model refuses: its first word, without a motor prefix, as sent.
    let text = String::from_utf8_lossy(line);
    let word = text.split_whitespace().next().unwrap_or_default();
    let bare = word.trim_start_matches(|c: char| profile.prefixes.iter().any(|p| p.char == c.to_ascii_uppercase()));
    let w = if bare.is_empty() { word } else { bare };
    w.chars().take(16).collect::<String>().to_ascii_uppercase()
}

fn classify(
    got: &[u8],
    offset: usize,
    expected_rest: &str,
    golden: &str,
    sent: &[u8],
    profile: &Profile,
) -> (&'static str, Option<String>) {
    let fr = &profile.framing;
    let offset = offset.min(got.len());
    let echo_len =
        if fr.echo { sent.iter().take_while(|b| **b != fr.terminator && **b != fr.abort).count() } else { 0 };
    if offset < echo_len {
        return ("framing", Some("echo".to_string()));
    }
    let is_eol = |b: &u8| matches!(b, b'\n' | b'\r');
    let line_start = got[..offset].iter().rposition(is_eol).map_or(0, |i| i + 1);
    let line_end = got[offset..].iter().position(is_eol).map_or(got.len(), |i| offset + i);
    let actual_line = &got[line_start..line_end];
    // The golden's line at the same place: as many line endings in as the answer has.
    let line_no = {
        let eol = fr.line_ending.as_bytes();
        got[..line_start].windows(eol.len().max(1)).filter(|w| *w == eol).count()
    };
    let expected_line = {
        let text = golden.trim_matches('"');
        let eol = gcl_transcript::escape_text(fr.line_ending.as_bytes());
        match text.split(eol.as_str()).nth(line_no) {
            Some(l) if !eol.is_empty() => l.to_string(),
            _ => {
                let mut s = gcl_transcript::escape_text(&got[line_start..offset]);
                let rest = expected_rest.split("\\n").next().unwrap_or_default();
                s.push_str(rest.split("\\r").next().unwrap_or_default());
                s
            }
        }
    };
    let status_word = b"ERR";
    let is_status = |l: &[u8]| l.starts_with(status_word);
    if is_status(actual_line) || expected_line.starts_with("ERR") {
        let number =
            |l: &str| l.split_whitespace().nth(1).filter(|n| n.bytes().all(|b| b.is_ascii_digit())).map(str::to_string);
        let hint = if expected_line.starts_with("ERR") {
            number(&expected_line)
        } else {
            number(&String::from_utf8_lossy(actual_line))
        };
        return ("status", hint);
    }
    let prompt = fr.prompt.trim_end();
    if actual_line.starts_with(prompt.as_bytes()) || expected_line.starts_with(prompt) {
        return ("framing", None);
    }
    let a_eol = got.get(offset).is_some_and(is_eol);
    let e_eol = expected_rest.starts_with("\\n") || expected_rest.starts_with("\\r");
    if a_eol && e_eol {
        return ("framing", None);
    }
    // One side ends the line where the other goes on, or the content differs.
    let kind = if is_reordering(&String::from_utf8_lossy(actual_line), &expected_line) { "order" } else { "value" };
    (kind, None)
}

/// Whether `actual` holds the tokens of `expected` in another order: the tokens do not match
/// in place, but each expected token (a literal, or an elision `{int A..B}` with its range,
/// or any other elision) matches a different actual token. A wrong value that happens to fit
/// a wide elision elsewhere is still a wrong value unless every token finds a partner.
pub fn is_reordering(actual: &str, expected: &str) -> bool {
    let a: Vec<&str> = actual.split_whitespace().collect();
    let e = expected_tokens(expected);
    if a.len() != e.len() || a.len() < 2 || a.len() > 64 {
        return false;
    }
    if a.iter().zip(&e).all(|(x, t)| t.accepts(x)) {
        return false;
    }
    // A perfect matching of expected tokens to actual ones (Kuhn's augmenting paths).
    fn augment(i: usize, e: &[Token], a: &[&str], seen: &mut [bool], owner: &mut [Option<usize>]) -> bool {
        for j in 0..a.len() {
            if !seen[j] && e[i].accepts(a[j]) {
                seen[j] = true;
                if owner[j].is_none_or(|k| augment(k, e, a, seen, owner)) {
                    owner[j] = Some(i);
                    return true;
                }
            }
        }
        false
    }
    let mut owner = vec![None; a.len()];
    (0..e.len()).all(|i| augment(i, &e, &a, &mut vec![false; a.len()], &mut owner))
}

/// One expected token of a golden line: a literal, an integer in a range, or anything.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Token {
    /// These characters exactly.
    Literal(String),
    /// A decimal integer within the range (inclusive).
    Int(i64, i64),
    /// Any token (an elision without a range).
    Any,
}

impl Token {
    /// Whether an actual token fits.
    pub fn accepts(&self, actual: &str) -> bool {
        match self {
            Token::Literal(l) => l == actual,
            Token::Int(lo, hi) => actual.parse::<i64>().is_ok_and(|v| (*lo..=*hi).contains(&v)),
            Token::Any => true,
        }
    }
}

/// The tokens of a golden line as written (escaped text with elisions): `{int A..B}` keeps its
/// range, any other elision matches anything.
pub fn expected_tokens(text: &str) -> Vec<Token> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut elision: Option<String> = None;
    let flush = |cur: &mut String, out: &mut Vec<Token>| {
        if !cur.is_empty() {
            out.push(Token::Literal(std::mem::take(cur)));
        }
    };
    for ch in text.chars() {
        match (&mut elision, ch) {
            (None, '{') => {
                flush(&mut cur, &mut out);
                elision = Some(String::new());
            }
            (Some(body), '}') => {
                let body = std::mem::take(body);
                elision = None;
                let range = body.strip_prefix("int ").and_then(|r| {
                    let (lo, hi) = r.trim().split_once("..")?;
                    Some((lo.parse().ok()?, hi.parse().ok()?))
                });
                out.push(range.map_or(Token::Any, |(lo, hi)| Token::Int(lo, hi)));
            }
            (Some(body), c) => body.push(c),
            (None, c) if c.is_whitespace() => flush(&mut cur, &mut out),
            (None, c) => cur.push(c),
        }
    }
    flush(&mut cur, &mut out);
    out
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reordered_values_are_told_from_changed_ones() {
        assert!(is_reordering("150 1000 1000 1000", "1000 1000 1000 150"));
        assert!(is_reordering("150 1000 1000 1000", "{int 990..1010} 1000 1000 150"));
        assert!(!is_reordering("150 1000 1000 1001", "1000 1000 1000 150"));
        assert!(!is_reordering("1000 1000 1000 150", "1000 1000 1000 150"));
        // A wrong value is not an order because an elision elsewhere is wide (mcv-ignored).
        assert!(!is_reordering("793 793", "{int 144..298} {int 765..1744}"));
        assert!(is_reordering("800 200", "{int 144..298} {int 765..1744}"));
    }
}
