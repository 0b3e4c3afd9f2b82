//! Step deadlines and answer ceilings from the model: before a run, each case runs once on
//! the in-process reference model ([`SimLink`], simulated time, so the whole suite takes well
//! under a second), which says how long every step takes (bytes on the wire at the hand's
//! BAUD, plus motion and processing time) and how long every answer is. A runner then gives
//! each step
//!
//! - a deadline of `max(floor, predicted × factor + margin)`, where `predicted` is the model's
//!   time with the bytes re-timed at the link's baud (the hand's own BAUD when the link does
//!   not say); a step that moves or resets the hand keeps at least its golden `within`
//!   ([`budgets`]: motion time depends on where earlier cases left the fingers), and
//! - an answer ceiling of `expected length × 16 + 4 KiB` ([`crate::replay::ceiling_for`]).
//!
//! The defaults ([`DeadlinePolicy::for_target`]): factor 2, margin 50 ms; a floor of 500 ms
//! on serial links and 200 ms on TCP (real hands, USB adapters and bridges add latency the
//! model does not know), none for a child process or the in-process model. A step that has
//! received not one byte by its deadline waits on until [`DeadlinePolicy::silent_wait`] (2 s)
//! has passed: a hand that says nothing may only be slow to start, and a run of such steps
//! is ended by the runner's dead-hand rule. A hand whose answer stops short (a prompt
//! without its space) is judged at the deadline, which is what makes a verdict on a broken
//! hand take seconds.
//!
//! Nothing here does I/O beyond the in-process model.

use std::sync::Arc;
use std::time::Duration;

use gcl_model::Profile;

use crate::replay::{ReplayOptions, StepBudget, ceiling_for};
use crate::suite::{self, Case};
use gcl_host::link::{SimLink, byte_time};
use gcl_host::target::Target;
use gcl_transcript::DEFAULT_STEP_TIMEOUT;

/// How deadlines are derived from the model's prediction.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DeadlinePolicy {
    /// The prediction is multiplied by this (percent): 200 doubles it.
    pub factor_percent: u32,
    /// Added to every step.
    pub margin: Duration,
    /// No step's deadline is shorter.
    pub floor: Duration,
    /// How long a step that received nothing at all may wait in all.
    pub silent_wait: Duration,
}

/// The default margin added to every step's predicted time.
pub const DEFAULT_MARGIN: Duration = Duration::from_millis(50);

/// The default wait of a step whose answer never started.
pub const DEFAULT_SILENT_WAIT: Duration = Duration::from_secs(2);

impl DeadlinePolicy {
    /// The defaults for a kind of target (see the module documentation).
    pub fn for_target(target: &Target) -> DeadlinePolicy {
        let floor = match target {
            Target::Serial { .. } => Duration::from_millis(500),
            Target::Tcp { .. } => Duration::from_millis(200),
            _ => Duration::ZERO,
        };
        DeadlinePolicy { factor_percent: 200, margin: DEFAULT_MARGIN, floor, silent_wait: DEFAULT_SILENT_WAIT }
    }

    /// The deadline of a step the model says takes `predicted`.
    pub fn deadline(&self, predicted: Duration) -> Duration {
        let scaled = predicted.saturating_mul(self.factor_percent) / 100;
        (scaled + self.margin).max(self.floor)
    }
}

/// What the model says about one step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StepPrediction {
    /// Time from just before the step's bytes are sent until its answer is complete, on the
    /// model's clock (bytes at the model's BAUD).
    pub took: Duration,
    /// Bytes sent and received in the step.
    pub wire_bytes: usize,
    /// Length of the model's answer.
    pub answer_len: usize,
    /// The model's BAUD during the step (bit/s).
    pub baud: u32,
}

impl StepPrediction {
    /// The step's time with its bytes re-timed at `link_baud` (the model's own when `None`).
    pub fn at_baud(&self, link_baud: Option<u32>) -> Duration {
        let Some(link) = link_baud else { return self.took };
        let n = u32::try_from(self.wire_bytes).unwrap_or(u32::MAX);
        let model_wire = byte_time(self.baud).saturating_mul(n);
        self.took.saturating_sub(model_wire) + byte_time(link).saturating_mul(n)
    }
}

/// The model's run of one case: one prediction per step. `None` when the case does not pass
/// on the model (a stale suite file): such a case keeps its goldens' `within`.
pub fn predict(case: &Case, profile: &Arc<Profile>) -> Option<Vec<StepPrediction>> {
    // With the case's objects in place, as the hand it predicts has them.
    let mut link = SimLink::new(profile.clone(), suite::model_config(case.header()));
    let opts = ReplayOptions { trailing: Duration::ZERO, drain_quiet: Duration::ZERO, ..suite::replay_options() };
    let baud = link.device().baud();
    let out = suite::run_case(case, &mut link, &opts);
    if !out.is_pass() {
        return None;
    }
    Some(
        out.exchange()
            .iter()
            .map(|e| StepPrediction {
                took: e.took,
                wire_bytes: e.sent.len() + e.received.len(),
                answer_len: e.received.len(),
                baud,
            })
            .collect(),
    )
}

/// Time the model's hand may spend on a step beyond its bytes before the step counts as one
/// that moves or resets the hand ([`budgets`]).
pub const BUSY: Duration = Duration::from_millis(20);

impl StepPrediction {
    /// Time the model's hand spent on the step beyond its bytes on the wire: motion, a reset.
    pub fn busy(&self) -> Duration {
        let n = u32::try_from(self.wire_bytes).unwrap_or(u32::MAX);
        self.took.saturating_sub(byte_time(self.baud).saturating_mul(n))
    }
}

/// Whether `sent` holds a command that reads or writes the hand's EEPROM (FSAVE, FLOAD,
/// PSAVE, PLOAD), whose time on a real hand the model does not know.
fn touches_memory(profile: &Profile, sent: &[u8]) -> bool {
    use gcl_model::grammar::{Line, parse_line};
    use gcl_model::spec::CommandKind::{GlobalLoad, GlobalSave, MotorLoad, MotorSave};
    sent.split(|b| *b == profile.framing.terminator).any(|line| {
        matches!(parse_line(profile, line), Ok(Line::Command(c))
            if matches!(c.kind(profile), MotorSave | MotorLoad | GlobalSave | GlobalLoad))
    })
}

/// Budgets for every step of a case from its predictions.
///
/// A step during which the model's hand is busy for more than [`BUSY`] (it moves or resets),
/// or that reads or writes the EEPROM, keeps at least its golden deadline (`within`, or the transcript default): how long a
/// motion takes depends on where the fingers start, which on a shared hand earlier cases
/// decide, so the model's time from its own fresh start is a lower bound there, not a
/// deadline. Every other step gets the model's time.
pub fn budgets(
    profile: &Profile,
    case: &Case,
    pred: &[StepPrediction],
    policy: &DeadlinePolicy,
    link_baud: Option<u32>,
) -> Vec<StepBudget> {
    pred.iter()
        .zip(&case.transcript.steps)
        .map(|(p, step)| {
            let mut deadline = policy.deadline(p.at_baud(link_baud));
            let sent = step.send.as_ref().map(|h| h.bytes.as_slice()).unwrap_or_default();
            if p.busy() > BUSY || touches_memory(profile, sent) {
                deadline = deadline.max(step.within.unwrap_or(DEFAULT_STEP_TIMEOUT));
            }
            StepBudget { deadline, ceiling: ceiling_for(p.answer_len) }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deadlines_follow_the_model_with_a_margin_and_a_floor() {
        let exec = DeadlinePolicy::for_target(&"exec:x".parse().unwrap());
        assert_eq!(exec.deadline(Duration::from_millis(10)), Duration::from_millis(70));
        let serial = DeadlinePolicy::for_target(&"serial:/dev/null".parse().unwrap());
        assert_eq!(serial.deadline(Duration::from_millis(10)), Duration::from_millis(500));
        assert_eq!(serial.deadline(Duration::from_secs(3)), Duration::from_millis(6050));
        let tcp = DeadlinePolicy::for_target(&"tcp://127.0.0.1:1".parse().unwrap());
        assert_eq!(tcp.deadline(Duration::from_millis(10)), Duration::from_millis(200));
        // README: a step whose answer has not started by its deadline waits up to 2 s.
        for p in [&exec, &serial, &tcp] {
            assert_eq!(p.silent_wait, Duration::from_secs(2));
        }
    }

    #[test]
    fn eeprom_steps_keep_their_golden_deadline() {
        let p = Profile::builtin("seed").unwrap();
        let cases = suite::generate(&p).unwrap();
        let case = cases.iter().find(|c| c.id() == "persist-fsave-reset").expect("an FSAVE case");
        let pred = predict(case, &p).unwrap();
        let b = budgets(&p, case, &pred, &DeadlinePolicy::for_target(&"exec:x".parse().unwrap()), None);
        let i =
            case.transcript.steps.iter().position(|s| s.send.as_ref().is_some_and(|h| h.bytes == b"FSAVE\r")).unwrap();
        assert!(b[i].deadline >= DEFAULT_STEP_TIMEOUT, "{:?}", b[i]);
        assert!(b[i - 1].deadline < Duration::from_secs(1) || pred[i - 1].busy() > BUSY, "{:?}", b[i - 1]);
    }

    #[test]
    fn the_model_predicts_motion_and_wire_time_per_step() {
        let p = Profile::builtin("seed").unwrap();
        let cases = suite::generate(&p).unwrap();
        let hi = cases.iter().find(|c| c.id() == "cmd-hi").expect("a HI case");
        let pred = predict(hi, &p).expect("passes on the model");
        assert_eq!(pred.len(), hi.transcript.steps.len());
        let longest = pred.iter().map(|s| s.took).max().unwrap();
        let s = pred.iter().find(|s| s.took == longest).unwrap();
        let wire = byte_time(s.baud) * s.wire_bytes as u32;
        assert!(longest > wire * 5, "HI moves the fingers: {longest:?}, of which {wire:?} on the wire");
        // At a slower line the same step takes longer; motion time stays.
        assert!(s.at_baud(Some(600)) > s.at_baud(None));
        let b = budgets(&p, hi, &pred, &DeadlinePolicy::for_target(&Target::Sim { profile: None }), None);
        assert!(b.iter().zip(&pred).all(|(b, p)| b.deadline > p.took && b.ceiling > p.answer_len));
        // HI moves the fingers: how long depends on where they start, so it keeps its golden
        // deadline; a step that only talks gets the model's time.
        let i = pred.iter().position(|s| s.took == longest).unwrap();
        assert_eq!(Some(b[i].deadline), hi.transcript.steps[i].within);
        let j = pred.iter().position(|s| s.busy() <= BUSY).unwrap();
        assert!(b[j].deadline < Duration::from_secs(1), "{:?}", b[j]);
        // A case whose setup places an object is predicted with the object there: it passes on
        // the model, so its steps get the model's deadlines like any other.
        let hold = cases.iter().find(|c| !c.header().setup.is_empty()).expect("a case with a setup");
        assert!(predict(hold, &p).is_some(), "{} does not pass on the model with its objects", hold.id());
    }
}
