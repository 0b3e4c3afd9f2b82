//! Which decisions a case rests on besides the ones it checks: found from what the case sends
//! and what the model answers, never declared by hand.
//!
//! A case *checks* the decisions its catalogue entry names (its subject). Everything else it
//! does (the preamble, read-backs, teardown) also rests on decisions: the echo, the line
//! ending and the prompt on every step, ^C and RESET in the preamble, the FGET line format in
//! read-backs. Those framing decisions are fine; any other decision found here that the case
//! does not check means the case's answer also depends on an unrelated choice, so a hand that
//! chose differently fails it for the wrong reason. `harness/tests/it/suite_decisions.rs` holds
//! every case to that.

use gcl_model::Profile;
use gcl_model::grammar::{self, Args, Line};
use gcl_model::spec::CommandKind;

use super::plan::Plan;
use crate::record::Captured;
use gcl_transcript::script::Action;

/// Decisions every case rests on through its framing, preamble, read-backs and teardown: the
/// echo, the LF CR line ending and the `=> ` prompt (every step); ^C at an idle prompt and
/// leaving LOOP (preamble and teardown); RESET and its banner (preamble); the FGET/PGET line
/// format (read-backs). Ids a profile lacks are ignored.
pub const FRAMING: &[&str] = &[
    "framing-echo",
    "framing-line-ending",
    "framing-prompt",
    "framing-abort-idle",
    "seed-abort",
    "bh8-abort-loop",
    "seed-reset-output",
    "bh8-reset",
    "bh8-banner-text",
    "seed-fget-format",
    "bh8-fget-format",
];

/// The longest command line with evidence behind it: Barrett's host library sends
/// `123FSET LCV 1 LCVC 1 LCPG 0 LFV 0 LFVC 1 LFS 0 LFAP 1 LFDP 0 LFDPC 1` (68 bytes;
/// protocol-notes, "Two profiles, one engine"). A longer line rests on framing-max-line.
pub const SAFE_LINE: usize = 68;

/// Decision ids by topic: the first ids the profile has are used.
fn topic(p: &Profile, ids: &[&str], out: &mut Vec<String>) {
    for id in ids {
        // (the short list first: most ids asked for are found already)
        if !out.iter().any(|x| x == id) && p.decisions.iter().any(|d| d.id == *id) {
            out.push((*id).to_string());
        }
    }
}

/// The command a line names, if it names one (even a line the grammar refuses).
fn command_of(p: &Profile, line: &[u8]) -> Option<(Vec<u8>, CommandKind, String)> {
    let text = std::str::from_utf8(line).ok()?;
    let t = text.trim_start_matches([' ', '\t', '\n']);
    let word_start = t.find(|c: char| !(c.is_ascii() && p.prefix_motors(c).is_some())).unwrap_or(t.len());
    let prefix = &t[..word_start];
    let rest = t[word_start..].trim_start_matches([' ', '\t', '\n']);
    let word = rest.split([' ', '\t', '\n']).next().unwrap_or_default();
    let id = p.command_id(word)?;
    let motors = prefix_motors(p, prefix);
    Some((motors, p.command(id).kind, p.command(id).name.clone()))
}

/// The status an answer reports (`ERR n`), if any.
pub(crate) fn status_in(output: &[u8]) -> Option<u32> {
    // (on the bytes: `ERR ` and digits are ASCII, which no invalid UTF-8 around them changes)
    let at = output.windows(4).position(|w| w == b"ERR ")? + 4;
    let rest = output.get(at..).unwrap_or_default();
    let digits = rest.get(..rest.iter().take_while(|b| b.is_ascii_digit()).count()).unwrap_or_default();
    std::str::from_utf8(digits).ok()?.parse().ok()
}

/// What the analysis remembers between lines.
#[derive(Debug, Clone, Default)]
struct State {
    /// Which motors an earlier HI initialised (RESET forgets).
    initialized: [bool; 4],
    /// In RealTime mode.
    in_loop: bool,
    /// The last motion was a C that ended without a status.
    closed: bool,
    /// The decisions the step being read rests on.
    found: Vec<String>,
}

/// The decisions every step rests on: its echo, line ending and prompt.
const EVERY_STEP: &[&str] = &["framing-echo", "framing-line-ending", "framing-prompt"];

/// Decisions that concern only the answer of the step that rests on them, never what the
/// hand does afterwards: the text of the answer (a line format: FGET/PGET values, listings,
/// help, ERR's lines, the version and banner text; what a read of S says; the echo, the line
/// ending and the prompt) or whether the step's line is accepted at all, which its answer
/// shows (a refused line gets a status and changes nothing, an accepted one never gets the
/// refusal's status: the case of words, separators, how values are written, the line's
/// length, control bytes, the status of a missing value and how a refusal's bits combine).
///
/// The rule (`fuzz::device`'s findings apply it): a failure rests on every decision of its
/// failing step, and on an earlier step's decisions only where they can change the hand's
/// state, which a later answer reads. An earlier step's decisions in this list do not: its
/// answer passed (the case got past it), so the hand decided them as the model did. Every
/// other decision is a state decision: what a line does beyond its answer (RESET, ^C, LOOP's
/// motors, where motion stops, whether a refused line changes anything, what a line that
/// fails to parse still runs, lines typed while busy, a coefficient of 0). Listed by id from
/// the profiles' decision tables (`spec/`): an id not listed, or added later, is a state
/// decision until it is.
pub(crate) const ANSWER_ONLY: &[&str] = &[
    "framing-echo",
    "framing-line-ending",
    "framing-prompt",
    "framing-empty-line",
    "framing-case",
    "framing-whitespace",
    "framing-numbers",
    "framing-max-line",
    "framing-backspace",
    "framing-missing-value",
    "framing-errors-combine",
    "seed-err-command",
    "bh8-err-format",
    "seed-fget-format",
    "bh8-fget-format",
    "seed-flista",
    "bh8-list-names-format",
    "bh8-list-values-format",
    "bh8-listing-order",
    "bh8-44-listing-order",
    "seed-help",
    "bh8-help-format",
    "bh8-vers-text",
    "seed-banner-text",
    "bh8-banner-text",
    "seed-s-values",
    "bh8-s-before-hi",
];

/// Whether decision `id` concerns only the answer text of the step that rests on it (see
/// [`ANSWER_ONLY`]).
pub(crate) fn answer_only(id: &str) -> bool {
    ANSWER_ONLY.contains(&id)
}

/// Every decision a case's steps rest on, in the profile's order: [`EVERY_STEP`]'s and the union
/// of what [`decisions_by_step`] gave for the case's plans and the model's answers.
pub(crate) fn decisions_of(p: &Profile, by_step: &[Vec<String>]) -> Vec<String> {
    let mut found = Vec::new();
    topic(p, EVERY_STEP, &mut found);
    for d in by_step.iter().flatten() {
        if !found.contains(d) {
            found.push(d.clone());
        }
    }
    let order = |id: &String| p.decisions.iter().position(|d| &d.id == id).unwrap_or(usize::MAX);
    found.sort_by_cached_key(order);
    found
}

/// The decisions each step of a case rests on (one list per plan, in the order found), given
/// the plan and what the model answered to each step: [`EVERY_STEP`]'s, then those of what
/// the step sends, read with what earlier steps did (a motion before HI, a read of P after C).
pub(crate) fn decisions_by_step(p: &Profile, plans: &[Plan], caps: &[Captured]) -> Vec<Vec<String>> {
    let mut so_far = DecisionsSoFar::default();
    so_far.go_on(p, plans, caps, false);
    so_far.steps
}

/// [`decisions_by_step`] of a case's first steps, and where its reading stands after them: the
/// steps that follow can be read from here (a campaign's cases all begin with the same
/// preamble and the model's same answers to it).
#[derive(Debug, Clone, Default)]
pub(crate) struct DecisionsSoFar {
    st: State,
    busy: bool,
    /// What each step read sent, and the model's answer to it.
    read: Vec<(Action, Vec<u8>)>,
    /// The decisions of each step read.
    steps: Vec<Vec<String>>,
}

impl DecisionsSoFar {
    /// The reading of `plans` answered by `caps`.
    pub(crate) fn of(p: &Profile, plans: &[Plan], caps: &[Captured]) -> DecisionsSoFar {
        let mut so_far = DecisionsSoFar::default();
        so_far.go_on(p, plans, caps, true);
        so_far
    }

    /// [`decisions_by_step`] of a case, going on from this reading when the case begins with
    /// the very steps and answers read (reading every step afresh otherwise).
    pub(crate) fn then(&self, p: &Profile, plans: &[Plan], caps: &[Captured]) -> Vec<Vec<String>> {
        let n = self.read.len();
        let same = plans.len() >= n
            && caps.len() >= n
            && self
                .read
                .iter()
                .zip(plans)
                .zip(caps)
                .all(|(((a, out), plan), c)| *a == plan.step.action && *out == c.output);
        if !same {
            return decisions_by_step(p, plans, caps);
        }
        let mut so_far = self.clone();
        so_far.go_on(p, &plans[n..], &caps[n..], false);
        so_far.steps
    }

    /// Reads more steps (keeping what they sent and the answers when `remember`, to go on from).
    fn go_on(&mut self, p: &Profile, plans: &[Plan], caps: &[Captured], remember: bool) {
        let DecisionsSoFar { st, busy, read, steps } = self;
        for (plan, c) in plans.iter().zip(caps) {
            if remember {
                read.push((plan.step.action.clone(), c.output.clone()));
            }
            steps.push(read_step(p, st, busy, plan, c));
        }
    }
}

/// The decisions of one step, given the reading so far (which it moves on).
fn read_step(p: &Profile, st: &mut State, busy: &mut bool, plan: &Plan, c: &Captured) -> Vec<String> {
    topic(p, EVERY_STEP, &mut st.found);
    let status = status_in(&c.output);
    match &plan.step.action {
        Action::Bytes { bytes, .. } if bytes.as_slice() == [p.framing.abort] => {
            if st.in_loop {
                topic(p, &["seed-abort", "bh8-abort-loop"], &mut st.found);
            } else if *busy {
                topic(p, &["seed-abort", "bh8-abort-motion"], &mut st.found);
            } else {
                topic(p, &["framing-abort-idle"], &mut st.found);
            }
            st.in_loop = false;
            *busy = false;
        }
        Action::Line(line) => {
            *busy = false;
            line_decisions(p, line, status, &c.output, st);
        }
        Action::NoWait(line) => {
            if line.contains(&p.framing.terminator) {
                topic(p, &["framing-busy-input"], &mut st.found);
            }
            *busy = true;
        }
        Action::Bytes { .. } if st.in_loop => {
            if status.is_some() {
                st.in_loop = false;
            }
        }
        Action::Bytes { bytes, .. } => {
            if bytes.iter().filter(|b| **b == p.framing.terminator).count() > 1 {
                topic(p, &["framing-busy-input"], &mut st.found);
            }
            for l in bytes.split(|b| *b == p.framing.terminator).filter(|l| !l.is_empty()) {
                line_decisions(p, l, None, &c.output, st);
            }
        }
        Action::Partial(_) | Action::Wait => {}
    }
    std::mem::take(&mut st.found)
}

fn line_decisions(p: &Profile, line: &[u8], status: Option<u32>, output: &[u8], st: &mut State) {
    let State { initialized, in_loop, closed, found } = st;
    let text = String::from_utf8_lossy(line);
    if line.iter().all(|b| matches!(b, b' ' | b'\t' | b'\n')) {
        topic(p, &["framing-empty-line"], found);
        return;
    }
    // Command words and names in lower case (a value such as 0x10 is another matter).
    if text.split_ascii_whitespace().any(|t| {
        !t.starts_with(|c: char| c.is_ascii_digit() || c == '-' || c == '+')
            && t.bytes().any(|b| b.is_ascii_lowercase())
    }) {
        topic(p, &["framing-case"], found);
    }
    if line.contains(&b'\t')
        || line.contains(&b'\n')
        || text.starts_with(' ')
        || text.ends_with(' ')
        || text.contains("  ")
        || text.split(' ').next().is_some_and(|t| {
            !t.is_empty() && t.chars().all(|c| c.is_ascii() && p.prefix_motors(c).is_some()) && text.contains(' ')
        })
    {
        topic(p, &["framing-whitespace"], found);
    }
    if line.len() > p.framing.max_line.min(SAFE_LINE) {
        topic(p, &["framing-max-line"], found);
    }
    // Backspace, DEL and every other control byte but the separators (tab, LF), the
    // terminator and ^C.
    if line.iter().any(|b| {
        *b == 127 || *b < 0x20 && !matches!(b, b'\t' | b'\n') && *b != p.framing.abort && *b != p.framing.terminator
    }) {
        topic(p, &["framing-backspace"], found);
    }
    let cmd = command_of(p, line);
    // Values that are not plain decimal integers.
    if let Some((_, kind, _)) = &cmd
        && matches!(kind, CommandKind::MotorSet | CommandKind::GlobalSet | CommandKind::ErrorText) | kind.is_motion()
    {
        let toks: Vec<&str> = text.split_ascii_whitespace().skip(1).collect();
        let values: Vec<&str> = if matches!(kind, CommandKind::MotorSet | CommandKind::GlobalSet) {
            toks.iter().skip(1).step_by(2).copied().collect()
        } else {
            toks
        };
        if values.iter().any(|v| {
            let digits = v.strip_prefix('-').unwrap_or(v);
            digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit())
        }) {
            topic(p, &["framing-numbers"], found);
        }
    }
    let parsed = grammar::parse_line(p, line);
    match (&parsed, &cmd) {
        (Err(r), _) => {
            if r.status.bits().count_ones() > 1 {
                topic(p, &["framing-errors-combine"], found);
            }
            if let Some((motors, kind, _)) = &cmd {
                if partly_valid(p, &text, *kind) {
                    topic(p, &["framing-line-atomic", "bh8-partial-errors"], found);
                }
                // ERR's range of codes is the ERR decision's.
                if *kind == CommandKind::ErrorText
                    && r.problems.iter().any(|x| matches!(x, grammar::Problem::InvalidValue(_)))
                {
                    topic(p, &["seed-err-command", "bh8-err-format"], found);
                }
                if r.problems.iter().any(|x| matches!(x, grammar::Problem::InvalidValue(v) if v.contains("required")))
                    || matches!(kind, CommandKind::MotorSet | CommandKind::GlobalSet)
                        && text.split_ascii_whitespace().count().is_multiple_of(2)
                {
                    topic(p, &["framing-missing-value"], found);
                }
                let needs_init = kind.is_motion() || *kind == CommandKind::Loop;
                if needs_init && motors.iter().any(|m| !initialized[*m as usize - 1]) {
                    topic(p, &["framing-parse-before-run"], found);
                }
            }
        }
        (Ok(Line::Command(c)), Some((_, kind, _))) => {
            let motors: Vec<u8> = match c.prefix {
                Some(ms) => ms.iter().collect(),
                None => vec![1, 2, 3, 4],
            };
            let uninit = motors.iter().any(|m| !initialized[*m as usize - 1]);
            match kind {
                CommandKind::Reset => {
                    topic(p, &["seed-reset-output", "bh8-reset", "bh8-banner-text"], found);
                    *initialized = [false; 4];
                }
                CommandKind::MotorGet | CommandKind::GlobalGet => {
                    topic(p, &["seed-fget-format", "bh8-fget-format"], found);
                    if let Args::Names(names) = &c.args
                        && names.iter().any(|id| p.param(*id).name == "S")
                        && uninit
                    {
                        topic(p, &["seed-s-values", "bh8-s-before-hi"], found);
                    }
                    if let Args::Names(names) = &c.args
                        && names.iter().any(|id| p.param(*id).name == "P")
                        && *closed
                    {
                        topic(p, &["seed-close-open-targets"], found);
                    }
                }
                CommandKind::MotorList
                | CommandKind::MotorListAll
                | CommandKind::GlobalList
                | CommandKind::GlobalListAll => topic(p, &["seed-flista", "bh8-list-names-format"], found),
                CommandKind::MotorListValues
                | CommandKind::MotorListAllValues
                | CommandKind::GlobalListValues
                | CommandKind::GlobalListAllValues => topic(p, &["seed-flista", "bh8-list-values-format"], found),
                CommandKind::ErrorText => topic(p, &["seed-err-command", "bh8-err-format"], found),
                CommandKind::Help | CommandKind::HelpAll => topic(p, &["seed-help", "bh8-help-format"], found),
                CommandKind::Version => topic(p, &["seed-vers-text", "bh8-vers-text"], found),
                CommandKind::Initialize if status.is_none() => {
                    for m in &motors {
                        initialized[*m as usize - 1] = true;
                    }
                }
                CommandKind::Terminate if status.is_some() => {
                    topic(p, &["seed-terminate-uninitialized", "bh8-terminate-uninitialized"], found)
                }
                CommandKind::Loop => {
                    if c.prefix.is_none() {
                        topic(p, &["seed-param-prefix-en", "bh8-loop-motors"], found);
                    }
                    if status.is_some() {
                        topic(p, &["bh8-loop-failure"], found);
                    }
                    *in_loop = output.ends_with(b"*");
                }
                CommandKind::MotorSet | CommandKind::GlobalSet => {
                    if let Args::Pairs(pairs) = &c.args {
                        for (id, v) in pairs {
                            let name = p.param(*id).name.as_str();
                            if *v == 0 && matches!(name, "LCVC" | "LFVC" | "LFDPC") {
                                topic(p, &["bh8-coefficient-range"], found);
                            }
                        }
                    }
                }
                k if k.is_motion() => {
                    // The seed gives C no target: where it closes to is a decision, seen by a
                    // read of P before the next move.
                    *closed = *k == CommandKind::Close && status.is_none();
                    if status.is_some_and(|s| s & p.hand.uninitialized_status != 0) || uninit {
                        topic(p, &["seed-motion-before-hi", "bh8-motion-before-hi"], found);
                    }
                    let limit = |m: u8| if m == 4 { p.hand.spread_limit } else { p.hand.finger_limit };
                    if let Args::Integer(v) = c.args
                        && matches!(k, CommandKind::Move)
                        && motors.iter().any(|m| v > limit(*m))
                    {
                        topic(p, &["seed-motion-model", "bh8-position-bounds"], found);
                    }
                }
                _ => {}
            }
        }
        _ => {}
    }
}

/// Whether a refused set or get line holds, besides what is wrong, a pair or name that would
/// be accepted alone: then whether that part took effect is the open point of atomicity.
fn partly_valid(p: &Profile, text: &str, kind: CommandKind) -> bool {
    let mut toks = text.split_ascii_whitespace();
    let Some(word) = toks.next() else { return false };
    let rest: Vec<&str> = toks.collect();
    let items: Vec<String> = match kind {
        CommandKind::MotorSet | CommandKind::GlobalSet => rest.chunks(2).map(|c| c.join(" ")).collect(),
        CommandKind::MotorGet | CommandKind::GlobalGet => rest.iter().map(|s| s.to_string()).collect(),
        _ => return false,
    };
    items.len() > 1
        && items
            .iter()
            .any(|i| matches!(grammar::parse_line(p, format!("{word} {i}").as_bytes()), Ok(Line::Command(_))))
}

/// The motors a prefix names (all four when none), ascending.
pub(crate) fn prefix_motors(p: &Profile, prefix: &str) -> Vec<u8> {
    if prefix.is_empty() {
        return vec![1, 2, 3, 4];
    }
    let mut ms: Vec<u8> = prefix.chars().filter_map(|c| p.prefix_motors(c)).flatten().copied().collect();
    ms.sort_unstable();
    ms.dedup();
    ms
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What `status_in` read before it read bytes: the answer as text (invalid UTF-8 replaced),
    /// the digits after its first `ERR `.
    fn status_as_text(output: &[u8]) -> Option<u32> {
        let text = String::from_utf8_lossy(output);
        let at = text.find("ERR ")?;
        text[at + 4..].chars().take_while(char::is_ascii_digit).collect::<String>().parse().ok()
    }

    proptest::proptest! {
        /// Reading the status from the bytes gives what reading it from the text gave, invalid
        /// UTF-8, several statuses, a status too big for a u32 and none at all included.
        #[test]
        fn a_status_read_from_the_bytes_is_the_one_the_text_shows(
            parts in proptest::collection::vec(
                proptest::prop_oneof![
                    proptest::collection::vec(proptest::sample::select(b"ER 019\n\r=>\xff\xe2\x82".to_vec()), 0..8),
                    proptest::strategy::Strategy::prop_map(0u64..10_000_000_000, |n| format!("ERR {n}").into_bytes()),
                ],
                0..6,
            ),
        ) {
            let output = parts.concat();
            proptest::prop_assert_eq!(status_in(&output), status_as_text(&output));
        }
    }

    /// Every listed answer-only decision is one a profile has (a misspelt id would silently
    /// make its decision a state decision).
    #[test]
    fn every_answer_only_decision_is_a_profiles() {
        let profiles: Vec<std::sync::Arc<Profile>> =
            ["seed", "bh8-262-4.3", "bh8-262-4.4"].iter().map(|id| Profile::builtin(id).unwrap()).collect();
        for id in ANSWER_ONLY {
            assert!(profiles.iter().any(|p| p.decisions.iter().any(|d| d.id == *id)), "{id} is no profile's decision");
        }
    }
}
