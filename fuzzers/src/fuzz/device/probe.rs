//! Asking the hand where a wrong value began, and whether the value itself is wrong.
//!
//! A value read back wrong is named by the command before the read that decided it
//! ([`crate::align`]'s `cause`): for a position the last motion that moved the differing
//! motors, for a stored parameter the last line that set, restored, loaded or reset it. When
//! the value was already wrong before that command (a hand that stayed in a RealTime loop the
//! model left, a loop block's velocity read unsigned; a hand whose FDEF skips a parameter, whose
//! wrong value a later save and RESET carry on), the name points at an innocent command. The
//! hand can tell: the case is built again with a read of the value (the parameter's own getter:
//! `FGET P`, `FGET MCV`) inserted just before the cause, at a quiescent point (before an action,
//! all of whose steps end answered, outside RealTime mode), and run on the hand. If the
//! inserted read already fails, the cause lies earlier: the cause as of that read (the same
//! rule) is asked the same way, up to [`PROBES`] reads. If the read passes, or no such case can
//! be built, or the hand parts from the model before the read, the cause stays.
//!
//! A stored value read wrong by another command than its getter (a listing: `FLISTV`,
//! `FLISTAV`) is first asked by the getter, just before that read: if the getter reads it
//! wrong too, the value is wrong whatever reads it, and the finding is the getter's (`value at
//! FGET after FDEF`, one finding however many commands list the value); if the getter reads it
//! right, the listing itself is at fault and the finding stays the listing's.
//!
//! A cause sent inside a RealTime session (a line the model takes as blocks, a block) has no
//! quiescent point before it but the one before the session: for a block, the session's LOOP
//! is named and asked about in turn; for a line sent in the loop, the session is ended there by
//! ^C instead and the value read after it.

use gcl_model::spec::{CommandKind, Role, Scope};
use gcl_model::{Line, Profile, parse_line};
use gcl_transcript::{Expect, Piece};

use super::action::HostAction;
use super::case::BuiltCase;
use super::{FuzzError, FuzzOptions, Hand, build_for_sending, signature};
use crate::align::FindingSignature;
use crate::replay::ReplayOutcome;

/// At most this many reads inserted for one finding (one run of the case on the hand each).
pub(super) const PROBES: usize = 4;

/// The finding's signature with the read and the cause the hand's answers point at, when that
/// is another than `sig`'s; `None` when both stay (or `sig` is no value read back that a
/// command decided, or an explanation names it).
///
/// `built` and `out` are the case as reported and its thorough run on the hand; `actions`
/// the actions it was built from.
pub(super) fn named(
    opts: &FuzzOptions,
    hand: &mut Hand<'_>,
    actions: &[HostAction],
    built: &BuiltCase,
    out: &ReplayOutcome,
    sig: &FindingSignature,
) -> Result<Option<FindingSignature>, FuzzError> {
    let p = &opts.profile;
    if sig.kind != "value" || sig.cause.is_empty() || !sig.explanation.is_empty() {
        return Ok(None);
    }
    // (the value's parameter, and its getter)
    let Some(id) = p.param_id(&sig.detail) else { return Ok(None) };
    let position = p.role(Role::Position) == Some(id);
    let spec = p.param(id);
    if spec.live && !position {
        return Ok(None);
    }
    let getter_kind = if spec.scope == Scope::Global { CommandKind::GlobalGet } else { CommandKind::MotorGet };
    let Some(getter) = p.command_of_kind(getter_kind).map(|g| p.command(g).name.clone()) else { return Ok(None) };
    let read = format!("{getter} {}", spec.name);
    // (the case as reported, run again: where its cause was sent)
    let Some(now) = signature(p, built, out, !opts.wide()).filter(|s| s.key() == sig.key()) else { return Ok(None) };
    let mut command = sig.command.clone();
    let mut cause = (sig.cause.clone(), now.cause_step);
    // The read itself, when another command than the getter made it: asked by the getter.
    if command != getter {
        let Some(at) = out.failed_step() else { return Ok(None) };
        let Some(i) = built.action_steps.iter().rposition(|(s, _)| *s <= at) else { return Ok(None) };
        if !built.action_steps[i].1 {
            return Ok(None);
        }
        let variant = [&actions[..i], &[HostAction::Line(read.clone())], &actions[i..]].concat();
        match ask(opts, hand, built, &variant, i, &read, id)? {
            Some(v) => {
                command = getter.clone();
                cause = v;
            }
            // (the getter reads it right, or the hand parted elsewhere: the read stays named)
            None => return Ok(None),
        }
    }
    for _ in 0..PROBES {
        let Some(step) = cause.1 else { break };
        // The action that sent the cause (none: the preamble's), and where the read goes.
        let Some(i) = built.action_steps.iter().rposition(|(s, _)| *s <= step) else { break };
        let read_line = HostAction::Line(read.clone());
        // (the variant, and the read's place in it)
        let (variant, j) = if built.action_steps[i].1 {
            // (before the cause, which starts at a quiescent point)
            ([&actions[..i], &[read_line], &actions[i..]].concat(), i)
        } else if matches!(actions[i], HostAction::Block { .. }) {
            // (a block: the session is the cause, read before its LOOP)
            let Some(j) = built.action_steps[..i].iter().rposition(|(_, quiet)| *quiet) else { break };
            if let Some(name) = session_opener(p, &actions[j]) {
                cause = (name, Some(built.action_steps[j].0));
            }
            ([&actions[..j], &[read_line], &actions[j..]].concat(), j)
        } else {
            // (a line sent in the loop, that the model leaves it on and runs the rest of: the
            // session ended there by ^C instead, then read; what the session did shows there)
            ([&actions[..i], &[HostAction::Abort, read_line]].concat(), i + 1)
        };
        match ask(opts, hand, built, &variant, j, &read, id)? {
            Some(v) => cause = v,
            None => break,
        }
    }
    if (command.as_str(), cause.0.as_str()) == (sig.command.as_str(), sig.cause.as_str()) {
        return Ok(None);
    }
    Ok(Some(FindingSignature { command, cause: cause.0, cause_step: cause.1, ..sig.clone() }))
}

/// Runs `variant` (the case's actions with `read` of parameter `id` as action `j`) on the hand:
/// the cause of the value as that read has it (the command and its step), when the read fails
/// on it; `None` when it passes there, the hand parts from the model before it, or no such case
/// can be built.
fn ask(
    opts: &FuzzOptions,
    hand: &mut Hand<'_>,
    built: &BuiltCase,
    variant: &[HostAction],
    j: usize,
    read: &str,
    id: gcl_model::spec::ParamId,
) -> Result<Option<(String, Option<usize>)>, FuzzError> {
    let p = &opts.profile;
    let Ok(mut b) = build_for_sending(opts, variant, "fuzz", "probe", &built.block_bytes) else { return Ok(None) };
    let Some(&(at, true)) = b.action_steps.get(j) else { return Ok(None) };
    let sends_read =
        b.transcript.steps.get(at).and_then(|s| s.send.as_ref()).is_some_and(|h| h.bytes.starts_with(read.as_bytes()));
    if !sends_read {
        return Ok(None);
    }
    if !opts.wide() && p.role(Role::Position) == Some(id) {
        let Some(e) = within_mpe(p, &b, at) else { return Ok(None) };
        b.transcript.steps[at].expect = e;
    }
    let vout = hand.run(&b.transcript, true)?;
    // (passed there, or parted earlier for another reason: the cause stays)
    if vout.failed_step() != Some(at) {
        return Ok(None);
    }
    let Some(v) = signature(p, &b, &vout, !opts.wide()) else { return Ok(None) };
    if v.kind != "value" || v.detail != p.param(id).name || v.cause.is_empty() {
        return Ok(None);
    }
    Ok(Some((v.cause, v.cause_step)))
}

/// The LOOP command an action opens a RealTime session with: the last line of it the model
/// reads as LOOP.
fn session_opener(p: &Profile, a: &HostAction) -> Option<String> {
    let bytes = match a {
        HostAction::Line(l) | HostAction::LineThenAbort { line: l, .. } => l.as_bytes().to_vec(),
        HostAction::Raw(b) => b.clone(),
        _ => return None,
    };
    bytes.split(|b| *b == p.framing.terminator).rev().find_map(|l| match parse_line(p, l) {
        Ok(Line::Command(c)) if c.kind(p) == CommandKind::Loop => Some(p.command(c.command).name.clone()),
        _ => None,
    })
}

/// The read's expectation at step `at` with each position within MPE of the model's, as a read
/// after a motion that ended has it: in process the hand runs on the model's clock, so a band
/// widened for uncertain timing (after ^C mid-motion, after RealTime control) would let a
/// position already wrong pass the read. `None` when the model's answer holds no positions.
fn within_mpe(p: &Profile, b: &BuiltCase, at: usize) -> Option<Expect> {
    let answer: Vec<u8> =
        b.model.stream.iter().zip(&b.model.tags).filter(|(_, t)| **t as usize == at).map(|(c, _)| *c).collect();
    let text = String::from_utf8_lossy(&answer);
    let values: Vec<i64> =
        text.split(p.framing.line_ending.as_str()).nth(1)?.split(' ').map(|t| t.parse().ok()).collect::<Option<_>>()?;
    let mut motor = 0;
    let mut e = Expect::nothing();
    for (form, piece) in b.transcript.steps.get(at)?.expect.pieces() {
        let piece = match piece {
            Piece::Int(Some((lo, hi))) => {
                let v = *values.get(motor)?;
                motor += 1;
                let band = super::case::mpe(p, motor as u8);
                Piece::Int(Some(((*lo).max(v - band), (*hi).min(v + band))))
            }
            other => other.clone(),
        };
        e.push(form, piece);
    }
    (motor == values.len()).then_some(e)
}

#[cfg(test)]
mod tests {
    use super::super::{FuzzOptions, Hand, build_for, signature};
    use super::*;
    use gcl_host::target::Target;

    /// The signature of `actions` on a sim with `fault`, and what asking the hand makes of it.
    fn asked(fault: gcl_model::Fault, actions: &[HostAction]) -> (FindingSignature, Option<FindingSignature>) {
        let p = gcl_model::Profile::builtin("bh8-262").unwrap();
        let mut opts = FuzzOptions::new(Target::Sim { profile: None }, p);
        opts.open.faults = vec![fault];
        let built = build_for(&opts, actions, "t", "t").unwrap();
        let mut hand = Hand::new(&opts);
        let out = hand.run(&built.transcript, true).unwrap();
        let sig = signature(&opts.profile, &built, &out, true).expect("the case fails");
        let named = named(&opts, &mut hand, actions, &built, &out, &sig).unwrap();
        (sig, named)
    }

    /// stay-in-loop's finding of seed 1 (2000 runs): a loop with a bad header the hand stays
    /// in, ^C, M and HOME cut short by ^C, then FGET P. Motor 4 reads wrong after HOME, but it
    /// was wrong before HOME (read there: wrong, after M) and before M (wrong, after the
    /// loop's block), and right before the loop: the loop is named, as in the finding the
    /// fault gives without the later motions (`value at FGET after LOOP`), which it joins.
    #[test]
    fn a_position_wrong_before_the_motion_named_is_named_by_where_the_hand_parted() {
        let actions = vec![
            HostAction::Line("4LOOP".into()),
            HostAction::Block {
                header: b'C',
                values: vec![i64::MAX, 79, -10, i64::MIN, 60, 108, i64::MAX, i64::MIN],
                extra: 1,
                pause_ms: 0,
            },
            HostAction::Abort,
            HostAction::LineThenAbort { line: "M 16789".into(), after_ms: 266 },
            HostAction::LineThenAbort { line: "44HOME".into(), after_ms: 0 },
            HostAction::Line("FGET P".into()),
        ];
        let (sig, named) = asked(gcl_model::Fault::StayInLoop, &actions);
        assert_eq!(sig.key(), "value at FGET after HOME");
        let named = named.expect("the hand had the position wrong before HOME");
        assert_eq!(named.key(), "value at FGET after LOOP");
        assert_eq!(named.motors, sig.motors, "the finding still shows where it showed");
    }

    /// lcv-unsigned's finding of seed 1: a block with a negative velocity (read unsigned by
    /// the hand), then `IC` sent in the loop (the model leaves it on `I` and closes on `C`),
    /// cut short by ^C. The loop ended by ^C at that line instead already reads motor 3
    /// wrong, by more than MPE though within the band ^C-timing widens reads to: the session
    /// is named (and the read before its LOOP is right).
    #[test]
    fn a_position_a_loop_left_wrong_is_named_by_the_loop_not_the_line_sent_in_it() {
        let actions = vec![
            HostAction::Line("G1LOOP".into()),
            HostAction::Block {
                header: b'c',
                values: vec![62, i64::MIN, -95, 0, -24, 99, i64::MAX, -26],
                extra: 0,
                pause_ms: 0,
            },
            HostAction::LineThenAbort { line: "IC".into(), after_ms: 0 },
            HostAction::Line("1O".into()),
            HostAction::Line("FGET P".into()),
        ];
        let (sig, named) = asked(gcl_model::Fault::LcvUnsigned, &actions);
        assert_eq!(sig.key(), "value at FGET after IC");
        assert_eq!(named.map(|s| s.key()).as_deref(), Some("value at FGET after LOOP"));
    }

    /// A hand whose FDEF skips MCV: the value a listing shows wrong after FDEF is wrong to
    /// FGET too, so the finding is FGET's, as when FGET reads it (over exec it was three
    /// findings, FGET's, FLISTV's and FLISTAV's); and a wrong value RESET loaded from the EEPROM
    /// after a save was wrong before RESET: FDEF is named, not RESET.
    #[test]
    fn a_stored_value_wrong_whatever_reads_it_is_named_by_its_getter_and_where_it_began() {
        let lines = |ls: &[&str]| ls.iter().map(|l| HostAction::Line(l.to_string())).collect::<Vec<_>>();
        let (sig, named) = asked(gcl_model::Fault::FdefSkipsMcv, &lines(&["FSET MCV 50", "FDEF", "FLISTV"]));
        assert_eq!(sig.key(), "value at FLISTV after FDEF");
        assert_eq!(named.map(|s| s.key()).as_deref(), Some("value at FGET after FDEF"));
        let (sig, named) =
            asked(gcl_model::Fault::FdefSkipsMcv, &lines(&["FSET MCV 50", "FDEF", "FSAVE", "RESET", "FGET MCV"]));
        assert_eq!(sig.key(), "value at FGET after RESET");
        assert_eq!(named.map(|s| s.key()).as_deref(), Some("value at FGET after FDEF"));
    }

    /// A position the motion named gets wrong (M to a DP the hand ignores) is right when read
    /// just before it: the cause stays.
    #[test]
    fn a_position_right_before_the_motion_named_keeps_its_cause() {
        let actions: Vec<HostAction> =
            ["FSET DP 3000", "M", "FGET P"].iter().map(|l| HostAction::Line(l.to_string())).collect();
        let (sig, named) = asked(gcl_model::Fault::DpIgnored, &actions);
        assert_eq!(sig.key(), "value at FGET after M");
        assert_eq!(named, None);
    }
}
