//! The motion-time probe: whether a hand moves in real time. It closes the hand from its home
//! position once and compares the time with the model's; a target whose motion ends far
//! sooner (a simulator with `--time fast`) cannot have ^C land mid-motion. `gcl conform` runs
//! it and skips its abort-timing cases on such a hand; `gcl fuzz device` refuses the target.

use std::sync::Arc;
use std::time::Duration;

use gcl_model::Profile;
use gcl_transcript::Transcript;

use crate::actions::HostAction;
use crate::actions::case::build_case;
use crate::deadline;
use crate::replay::ReplayOutcome;
use crate::suite::Case;

/// A target whose motion takes under this share of the model's time does not move in real time.
const REAL_TIME_SHARE: u32 = 4;

/// A hand whose motion from home ended far sooner than the model's: a simulator whose time
/// follows the wire (`gcl sim --time fast`). ^C cannot land mid-motion on it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NotRealTime {
    /// The motion command of the probe.
    pub command: String,
    /// How long the target took for it, bytes included.
    pub took_ms: u64,
    /// How long the model's hand moves for it, bytes aside.
    pub model_ms: u64,
}

impl std::fmt::Display for NotRealTime {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the target's motions end at once: `{}` from the home position took {} ms, where the model's hand \
             takes {} ms (a simulator with `--time fast`?)",
            self.command, self.took_ms, self.model_ms
        )
    }
}

/// The motion-time probe: the case (the suite's preamble, HI, then the profile's close
/// command) and what judges its replay. `None` when the profile has no close command.
pub struct MotionProbe {
    /// The probe's transcript.
    pub transcript: Transcript,
    command: String,
    model: Vec<deadline::StepPrediction>,
}

impl MotionProbe {
    /// The probe for a profile.
    pub fn new(p: &Arc<Profile>) -> Option<MotionProbe> {
        let close = p.commands.iter().find(|c| c.kind == gcl_model::spec::CommandKind::Close)?;
        let command = close.name.clone();
        let built = build_case(p, &[HostAction::Line(command.clone())], "probe", "real-time probe", true, true).ok()?;
        let case = Case { profile: p.id.clone(), transcript: built.transcript.clone() };
        let model = deadline::predict(&case, p)?;
        Some(MotionProbe { transcript: built.transcript, command, model })
    }

    /// The probe for a hand that has just answered RESET at an idle prompt (a runner's
    /// pre-flight ends so): the preamble's ^C and RESET are left out, FDEF, HI and the close
    /// kept. `None` when the probe does not start with them.
    pub fn after_reset(&self, p: &Arc<Profile>) -> Option<MotionProbe> {
        let mut transcript = self.transcript.clone();
        let sends = |i: usize, bytes: &[u8]| {
            transcript.steps.get(i).and_then(|s| s.send.as_ref()).is_some_and(|h| h.bytes == bytes)
        };
        let reset = [b"RESET".as_slice(), &[p.framing.terminator]].concat();
        if !(sends(0, &[p.framing.abort]) && sends(1, &reset)) {
            return None;
        }
        transcript.steps.drain(..2);
        let case = Case { profile: p.id.clone(), transcript: transcript.clone() };
        let model = deadline::predict(&case, p)?;
        Some(MotionProbe { transcript, command: self.command.clone(), model })
    }

    /// The close step (0-based) and how long after its command a hand that moves in real time
    /// is still moving (a quarter of the model's time for it): a run may stop the probe there
    /// (^C) with the judgement already made, rather than wait for the hand to close.
    pub fn decided_after(&self, p: &Profile) -> Option<(usize, Duration)> {
        let sent = format!("{}{}", self.command, p.framing.terminator as char);
        let step =
            self.transcript.steps.iter().position(|s| s.send.as_ref().is_some_and(|h| h.bytes == sent.as_bytes()))?;
        let model = self.model.get(step)?.busy();
        (model > deadline::BUSY).then_some((step, model / REAL_TIME_SHARE))
    }

    /// Judges a replay of the probe: the target moved in far less time than the model's hand
    /// (under a quarter of it). A slow or loaded target only takes longer, never shorter; a
    /// probe that did not pass decides nothing.
    pub fn judge(&self, p: &Profile, out: &ReplayOutcome) -> Option<NotRealTime> {
        let sent = format!("{}{}", self.command, p.framing.terminator as char);
        let done = out.failed_step().unwrap_or(usize::MAX);
        let e = out.exchange().iter().find(|e| e.step < done && e.sent == sent.as_bytes())?;
        let model = self.model.get(e.step).map_or(Duration::ZERO, |s| s.busy());
        (model > deadline::BUSY && e.took < model / REAL_TIME_SHARE).then(|| NotRealTime {
            command: self.command.clone(),
            took_ms: e.took.as_millis() as u64,
            model_ms: model.as_millis() as u64,
        })
    }
}
