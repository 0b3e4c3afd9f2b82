//! Asking the hand where a wrong position began.
//!
//! A position read back wrong is named by the last motion before the read that moved the
//! differing motors ([`crate::align`]'s `cause`). When the position was already wrong before
//! that motion (a hand that stayed in a RealTime loop the model left, a loop block's velocity
//! read unsigned), the name points at an innocent command. The hand can tell: the case is
//! built again with a read of the positions inserted just before the cause, at a quiescent
//! point (before an action, all of whose steps end answered, outside RealTime mode), and run on
//! the hand. If the inserted read already fails, the cause lies earlier: the cause as of that
//! read (the same rule, the last motion, LOOP, HI or RESET before it that touches the motors
//! that differ there) is asked the same way, up to [`PROBES`] reads. If the read passes, or no
//! such case can be built, or the hand parts from the model before the read, the cause stays.
//!
//! A cause sent inside a RealTime session (a line the model takes as blocks, a block) has no
//! quiescent point before it but the one before the session: the session's LOOP is named, and
//! asked about in turn.

use gcl_model::spec::{CommandKind, Role};
use gcl_model::{Line, Profile, parse_line};
use gcl_transcript::{Expect, Piece};

use super::action::HostAction;
use super::case::BuiltCase;
use super::{FuzzError, FuzzOptions, Hand, build_for_sending, signature};
use crate::align::FindingSignature;
use crate::replay::ReplayOutcome;

/// At most this many reads inserted for one finding (one run of the case on the hand each).
pub(super) const PROBES: usize = 4;

/// The finding's signature with the cause the hand's answers point at, when that is another
/// command than `sig`'s; `None` when the cause stays (or `sig` is no position read back that a
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
    let Some(position) = p.role(Role::Position).map(|id| p.param(id).name.clone()) else { return Ok(None) };
    if sig.kind != "value" || sig.detail != position || sig.cause.is_empty() || !sig.explanation.is_empty() {
        return Ok(None);
    }
    let Some(read) = p.command_of_kind(CommandKind::MotorGet).map(|id| format!("{} {position}", p.command(id).name))
    else {
        return Ok(None);
    };
    // (the case as reported, run again: where its cause was sent)
    let Some(now) = signature(p, built, out, !opts.wide()).filter(|s| s.key() == sig.key()) else { return Ok(None) };
    let mut cause = (sig.cause.clone(), now.cause_step);
    for _ in 0..PROBES {
        let Some(step) = cause.1 else { break };
        // The action that sent the cause (none: the preamble's), and where the read goes.
        let Some(i) = built.action_steps.iter().rposition(|(s, _)| *s <= step) else { break };
        let variant = if built.action_steps[i].1 {
            // (before the cause, which starts at a quiescent point)
            [&actions[..i], &[HostAction::Line(read.clone())], &actions[i..]].concat()
        } else if matches!(actions[i], HostAction::Block { .. }) {
            // (a block: the session is the cause, read before its LOOP)
            let Some(j) = built.action_steps[..i].iter().rposition(|(_, quiet)| *quiet) else { break };
            if let Some(name) = session_opener(p, &actions[j]) {
                cause = (name, Some(built.action_steps[j].0));
            }
            [&actions[..j], &[HostAction::Line(read.clone())], &actions[j..]].concat()
        } else {
            // (a line sent in the loop, that the model leaves it on and runs the rest of: the
            // session ended there by ^C instead, then read; what the session did shows there)
            [&actions[..i], &[HostAction::Abort, HostAction::Line(read.clone())]].concat()
        };
        let Some(j) = variant.iter().position(|a| *a == HostAction::Line(read.clone())) else { break };
        let Ok(mut b) = build_for_sending(opts, &variant, "fuzz", "probe", &built.block_bytes) else { break };
        let Some(&(at, true)) = b.action_steps.get(j) else { break };
        let sends_read = b
            .transcript
            .steps
            .get(at)
            .and_then(|s| s.send.as_ref())
            .is_some_and(|h| h.bytes.starts_with(read.as_bytes()));
        if !sends_read {
            break;
        }
        if !opts.wide() {
            let Some(e) = within_mpe(p, &b, at) else { break };
            b.transcript.steps[at].expect = e;
        }
        let vout = hand.run(&b.transcript, true)?;
        // (passed there, or parted earlier for another reason: the cause stays)
        if vout.failed_step() != Some(at) {
            break;
        }
        let Some(v) = signature(p, &b, &vout, !opts.wide()) else { break };
        if v.kind != "value" || v.detail != position || v.cause.is_empty() {
            break;
        }
        cause = (v.cause, v.cause_step);
    }
    if cause.0 == sig.cause {
        return Ok(None);
    }
    Ok(Some(FindingSignature { cause: cause.0, cause_step: cause.1, ..sig.clone() }))
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
