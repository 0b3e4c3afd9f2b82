//! Naming a bug by a model that has it: a failing case replayed on models that each hold one
//! hypothesis about the hand, the one that answers as the hand did naming the bug.
//!
//! [`super::explain`] rewrites a case's *actions* as a hand with a bug would take them and
//! rebuilds it on the model. A rewrite that changes when a motion ends cannot be followed
//! through the case (a ^C it would land elsewhere, answers recorded a step behind their lines
//! after a motion ended in the pause before its ^C), and a rewrite cannot say "the hand's
//! blocks have another layout" at all, so such bugs showed under the motion or block where
//! they surfaced (`value at FGET (P) after TO`, `status at ^C (2048 extra)`) rather than under
//! their cause. Here the case is not rewritten: the very transcript the hand failed is
//! replayed, with the same waits, on a model unlike the profile's in one way (see
//! [`variants`]: a parameter stored but without effect, a letter prefix naming one motor more,
//! the other side of a decision the model takes on line atomicity, prefixes or RESET). Where
//! that model answers every step up to the failing one byte for byte as the hand did, and
//! fails where the hand failed, it names the bug; the key is the one [`super::explain`]'s
//! rewrite gives the same bug, so both ways join one finding.
//!
//! Byte for byte only where the hand's answers are exact (the in-process sim, whose noise and
//! clock are the model's). A hand outside this process answers with its own noise and timing:
//! there the case is built anew from the same actions on the model holding the hypothesis,
//! shaped as any case for such a hand (positions within their bands, the ratios of
//! `super::relate` from the coefficients that model acts on), and the hand's answers up to the
//! failing step must be what that case expects, the failing step's otherwise than the case
//! did, and the profile's model's not (`fits_within`: a hypothesis whose case judges no closer
//! than the case tells nothing). A new one is then asked of the hand: it answers the
//! hypothesis's case as it expects up to the step where it parted (`super::confirms`). The
//! same failures as in process (a value, a block, an answer cut short) are explained so. A
//! hypothesis that changes the control block's size (a control flag without effect) is not
//! expressible there: its case encodes other bytes than the hand was sent.

use std::sync::Arc;

use gcl_model::Profile;
use gcl_model::grammar::{Args, Line, parse_line};
use gcl_model::spec::{CommandKind, ParamId};
use gcl_transcript::{Form, Transcript};

use super::action::HostAction;
use super::case::BuiltCase;
use super::{Fresh, FuzzError, FuzzOptions, Hand};
use crate::replay::{ReplayOutcome, replay};

/// The explanation of a set line the hand refuses and still applies in its valid pairs.
const REFUSED_SET_APPLIED: &str = "set refused but applied in part";

/// One hypothesis: what it says, and the model that holds it (the profile, or a patch of it,
/// and the device's configuration).
struct Variant {
    says: String,
    profile: Arc<Profile>,
    config: gcl_model::DeviceConfig,
    /// The other side of a decision the model takes (see [`Fresh::decision`]).
    decision: bool,
}

/// The hypotheses a case allows, each a model unlike the profile's in one way:
/// - a parameter the case sets, stored but without effect (`LSG set without effect`);
/// - a letter prefix the case sends, naming one motor more (`prefix 123+4`, the key
///   [`super::explain`]'s prefix rewrite gives the same bug);
/// - the other side of a decision the model takes, where the case meets it: a set the model
///   refuses applied in its valid pairs (`set refused but applied in part`, FSET or PSET; decision
///   framing-line-atomic), a prefix on a command that takes none ignored (`prefix accepted on
///   a command that takes none`, the rewrite's key; seed-prefix-rules), RESET keeping the
///   values in RAM (`RESET keeps the values set`; bh8-reset). The model plays each as it plays
///   the fault of that name.
fn variants(opts: &FuzzOptions, built: &BuiltCase, upto: usize) -> Vec<Variant> {
    let p = &opts.profile;
    // (the in-process hand's world: its noise seed, scenario and EEPROM, without its faults)
    let base = if opts.wide() {
        crate::suite::model_config(&built.transcript.header)
    } else {
        gcl_model::DeviceConfig {
            seed: opts.open.seed,
            scenario: opts.open.scenario.clone().unwrap_or_default(),
            nv: opts.open.nv.clone().unwrap_or_default(),
            ..crate::suite::model_config(&built.transcript.header)
        }
    };
    let lines = sent_lines(opts, built, upto);
    let parsed: Vec<_> = lines.iter().map(|l| parse_line(p, l)).collect();
    // Parameters set by name, in the order first set.
    let mut set: Vec<ParamId> = Vec::new();
    for r in &parsed {
        let Ok(Line::Command(c)) = r else { continue };
        let (CommandKind::MotorSet | CommandKind::GlobalSet, Args::Pairs(pairs)) = (c.kind(p), &c.args) else {
            continue;
        };
        for (id, _) in pairs {
            if !set.contains(id) {
                set.push(*id);
            }
        }
    }
    let mut out: Vec<Variant> = set
        .into_iter()
        .map(|id| Variant {
            says: format!("{} set without effect", p.param(id).name),
            profile: p.clone(),
            config: gcl_model::DeviceConfig { without_effect: vec![id], ..base.clone() },
            decision: false,
        })
        .collect();
    for (k, pre) in p.prefixes.iter().enumerate() {
        // (a prefix is a run of prefix characters before the command word: `2gLOOP`)
        let used = lines.iter().zip(&parsed).any(|(l, r)| {
            let mut head =
                l.iter().map(|b| char::from(*b)).take_while(|c| c.is_ascii() && p.prefix_motors(*c).is_some());
            matches!(r, Ok(Line::Command(c)) if c.prefix.is_some()) && head.any(|c| c.eq_ignore_ascii_case(&pre.char))
        });
        if !used {
            continue;
        }
        for m in 1..=4u8 {
            if pre.motors.contains(&m) {
                continue;
            }
            let mut patched = (**p).clone();
            patched.prefixes[k].motors.push(m);
            patched.prefixes[k].motors.sort_unstable();
            let digits: String = pre.motors.iter().map(u8::to_string).collect();
            out.push(Variant {
                says: format!("prefix {digits}+{m}"),
                profile: Arc::new(patched),
                config: base.clone(),
                decision: false,
            });
        }
    }
    let refused_set = parsed
        .iter()
        .any(|r| matches!(r, Err(r) if r.partial.as_ref().is_some_and(|c| matches!(c.args, Args::Pairs(_)))));
    let mut other_side = |says: String, fault: gcl_model::Fault| {
        out.push(Variant {
            says,
            profile: p.clone(),
            config: gcl_model::DeviceConfig { faults: vec![fault], ..base.clone() },
            decision: true,
        });
    };
    if parsed.iter().any(|r| matches!(r, Err(r) if r.problems == [gcl_model::grammar::Problem::PrefixNotAllowed])) {
        other_side(super::PREFIX_ACCEPTED.into(), gcl_model::Fault::PrefixNotRefused);
    }
    if parsed.iter().any(|r| matches!(r, Ok(Line::Command(c)) if c.kind(p) == CommandKind::Reset)) {
        other_side("RESET keeps the values set".into(), gcl_model::Fault::ResetKeepsRam);
    }
    // (the hypothesis is every set line's, FSET's and PSET's alike: one key whichever shows it)
    if refused_set {
        other_side(REFUSED_SET_APPLIED.into(), gcl_model::Fault::PartialSetApplied);
    }
    out
}

/// The command lines the case sends up to step `upto` (not RealTime blocks).
fn sent_lines(opts: &FuzzOptions, built: &BuiltCase, upto: usize) -> Vec<Vec<u8>> {
    let term = opts.profile.framing.terminator;
    built
        .transcript
        .steps
        .iter()
        .take(upto + 1)
        .filter_map(|s| s.send.as_ref().filter(|h| h.form != Form::Hex))
        .flat_map(|h| h.bytes.split(|b| *b == term).filter(|l| !l.is_empty()).map(<[u8]>::to_vec).collect::<Vec<_>>())
        .collect()
}

/// What the hand is shown to do by a model that holds one hypothesis (see [`variants`]) and
/// answers as the hand did (see the module documentation): `None` where none or more than one
/// does. `known`: explanations this campaign already holds, tried first (one of them that fits
/// is taken whatever else does); others only as `fresh` allows: in process from a wrong or
/// cut-short answer (a silence, a timeout with nothing said, many models reproduce alike,
/// whatever the bug), outside it only from a value read back (`Fresh::rewrite`).
pub(super) fn explains(
    opts: &FuzzOptions,
    hand: &mut Hand<'_>,
    actions: &[HostAction],
    built: &BuiltCase,
    out: &ReplayOutcome,
    known: &[String],
    fresh: Fresh,
) -> Result<Option<String>, FuzzError> {
    let Some(failed) = out.failed_step() else { return Ok(None) };
    let said = out.exchange().iter().find(|e| e.step == failed).is_some_and(|e| !e.received.is_empty());
    let wrong = matches!(out, ReplayOutcome::Mismatch(_));
    let fresh_one = |v: &Variant| (fresh.exact && (wrong || said)) || (fresh.decision && wrong && v.decision);
    let mut candidates: Vec<Variant> =
        variants(opts, built, failed).into_iter().filter(|v| fresh_one(v) || known.contains(&v.says)).collect();
    candidates.sort_by_key(|v| !known.contains(&v.says));
    let mut found = None;
    for v in candidates {
        let known_one = known.contains(&v.says);
        let fits = if opts.wide() {
            match fits_within(opts, actions, built, out, v.profile.clone(), &v.config) {
                // A new one is asked of the hand: the case built on the hypothesis's model,
                // replayed, is answered as it expects up to the step where the hand parted.
                Some(t) if !known_one => super::confirms(opts, &hand.run(&t, true)?, out),
                Some(_) => true,
                None => false,
            }
        } else {
            answers_alike(built, out, v.profile, v.config)
        };
        if !fits {
            continue;
        }
        if known_one {
            return Ok(Some(v.says));
        }
        // (two hypotheses that explain the case alike tell neither)
        if found.is_some() {
            return Ok(None);
        }
        found = Some(v.says);
    }
    Ok(found)
}

/// In process: the model built from `config` answers every step of the failing transcript up
/// to the failing one byte for byte as the hand did, and fails where it failed.
fn answers_alike(
    built: &BuiltCase,
    out: &ReplayOutcome,
    profile: Arc<Profile>,
    config: gcl_model::DeviceConfig,
) -> bool {
    let failed = out.failed_step();
    let got = |x: &[crate::replay::Exchanged], s: usize| x.iter().find(|e| e.step == s).map(|e| e.received.clone());
    let mut link = gcl_host::SimLink::new(profile, config);
    let r = replay(&built.transcript, &mut link, &crate::suite::replay_options());
    r.failed_step() == failed && (0..=failed.unwrap_or(0)).all(|s| got(r.exchange(), s) == got(out.exchange(), s))
}

/// Outside this process: the case built anew from the same actions on the model from
/// `config`, shaped as any case for such a hand (its bands for noise and timing), expects what
/// the hand answered at every step up to the failing one, expects otherwise than the case did
/// somewhere up to there, and does not expect what the profile's model answered: a hypothesis whose case
/// judges the hand's answers no closer than the case did (a relation it cannot make, a band
/// wide enough for both) tells nothing of the hand. The hand's answers are matched as one
/// stream (the variant's answers may end a step earlier or later than the case's did).
/// Returns the hypothesis's case, for the hand to answer (see [`explains`]).
fn fits_within(
    opts: &FuzzOptions,
    actions: &[HostAction],
    built: &BuiltCase,
    out: &ReplayOutcome,
    profile: Arc<Profile>,
    config: &gcl_model::DeviceConfig,
) -> Option<Transcript> {
    let failed = out.failed_step()?;
    let on = (config, super::case::Model::Hypothesis);
    let v = super::case::build_case_on(&profile, on, actions, "fuzz", "variant", true, opts.home(), &built.block_bytes)
        .ok()?;
    let (old, new) = (&built.transcript.steps, &v.transcript.steps);
    let send = |s: &gcl_transcript::Step| s.send.as_ref().map(|h| h.bytes.clone());
    // (a difference may show a step late: on a serial line a block a byte longer than the
    // case's is read into the next step's answer)
    if new.len() != old.len()
        || (0..=failed).any(|s| send(&old[s]) != send(&new[s]))
        || (0..=failed).all(|s| new[s].expect == old[s].expect)
    {
        return None;
    }
    let stream = (0..=failed)
        .map(|s| out.exchange().iter().find(|e| e.step == s).map(|e| e.received.clone()))
        .collect::<Option<Vec<Vec<u8>>>>()?;
    let judges: Vec<&gcl_transcript::Step> = new.iter().collect();
    let none = gcl_transcript::Captures::new();
    let short = matches!(out, ReplayOutcome::Mismatch(_));
    // (what the profile's model answered up to the end of the failing step, by its tags)
    let run = &built.model;
    if run.tags.len() != run.stream.len() || run.tags.is_empty() {
        return None;
    }
    let model: Vec<u8> =
        run.stream.iter().zip(&run.tags).take_while(|(_, t)| **t as usize <= failed).map(|(b, _)| *b).collect();
    let tells = !super::follows(&judges, &model, failed + 1, false, &none);
    (tells && super::follows(&judges, &stream.concat(), failed + 1, short, &none)).then_some(v.transcript)
}
