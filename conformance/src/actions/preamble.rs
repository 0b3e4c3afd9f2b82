//! A case's preamble (`CaseB::preamble`: ^C, RESET, FDEF, PDEF, HI), walked and captured once
//! per profile, model and steps instead of once per case.
//!
//! Every case `case::assemble` builds begins with the same few steps, and building it runs
//! them on the model twice over: on the walker's shadow, and on the capture's link with the
//! recorder's own shadow beside it. Each of those runs is a value of the profile, the model's
//! config and the steps (simulated time, a seeded generator), so the state a run leaves after
//! the preamble is kept here and a clone of it goes on with the next case's steps: the answers
//! and states that follow are bit for bit those of running the preamble again (held by the
//! unit test `tests::a_kept_preamble_builds_the_case_a_fresh_one_does`). The transcript's
//! steps and the decisions each step rests on are made of those answers once too.
//!
//! Only the reference model's runs are kept: the hand under test (the in-process sim, with its
//! fault if it has one) is replayed the whole case, preamble included, and judged on that.

use std::sync::{Arc, Mutex};

use gcl_host::SimLink;
use gcl_host::link::LinkError;
use gcl_model::{Device, DeviceConfig, Profile};
use gcl_transcript::script::ScriptStep;

use crate::record::{Captured, Recorder, ShadowStep};
use crate::suite::build::{BuiltSteps, capture_options};
use crate::suite::depends::DecisionsSoFar;
use crate::suite::plan::Plan;

/// The model's runs of a preamble, at its end.
pub(crate) struct Ran {
    /// The walker's shadow after walking the steps (`case::Walk::feed`).
    pub(crate) walked: Device,
    /// The capture's link after the steps.
    pub(crate) link: SimLink,
    /// The recording on that link after the steps.
    pub(crate) recorder: Recorder,
    /// What the link answered to each step.
    pub(crate) caps: Vec<Captured>,
    /// The transcript's steps made of them (`suite::build::build_from`'s).
    pub(crate) built: Option<BuiltSteps>,
    /// The decisions each of them rests on, and the reading after them.
    pub(crate) decisions: DecisionsSoFar,
    /// Whether a step of the preamble ends on quiet (where the walker's shadow and the
    /// recorder's part).
    preamble_quiet: bool,
}

/// One kept preamble and what it is kept for.
struct Kept {
    profile: Arc<Profile>,
    config: DeviceConfig,
    steps: Vec<ScriptStep>,
    ran: Arc<Ran>,
}

/// The kept preambles, the latest last. A campaign builds on one profile and model with two
/// preambles (with and without HI); variants and tests bring a few more.
static KEPT: Mutex<Vec<Kept>> = Mutex::new(Vec::new());

/// How many preambles are kept at most.
const KEEP: usize = 8;

/// The model's runs of `steps` on `profile` built from `config`, if they were kept
/// ([`keep`]) for the same profile (by identity), config and steps.
pub(crate) fn kept(profile: &Arc<Profile>, config: &DeviceConfig, steps: &[ScriptStep]) -> Option<Arc<Ran>> {
    lock().iter().find(|k| k.is(profile, config, steps)).map(|k| k.ran.clone())
}

/// Keeps the model's runs of the steps of `plans` on `profile` built from `config`: `walked`,
/// the walker's shadow that walked them fresh, a fresh capture of them run here, and the
/// transcript's steps made of that.
pub(crate) fn keep(
    profile: &Arc<Profile>,
    config: &DeviceConfig,
    plans: &[Plan],
    walked: Device,
) -> Result<(), LinkError> {
    let steps: &[ScriptStep] = &plans.iter().map(|p| p.step.clone()).collect::<Vec<_>>();
    let opts = capture_options(profile, config);
    let mut link = SimLink::new(profile.clone(), config.clone());
    let mut recorder = Recorder::start(&mut link, &opts)?;
    let caps = recorder.capture(&mut link, steps, &opts)?;
    let preamble_quiet = steps.iter().any(|s| s.action.ends_on_quiet());
    let built = BuiltSteps::of(profile, plans, &caps);
    let decisions = DecisionsSoFar::of(profile, plans, &caps);
    let ran = Arc::new(Ran { walked, link, recorder, caps, built, decisions, preamble_quiet });
    let mut kept = lock();
    if !kept.iter().any(|k| k.is(profile, config, steps)) {
        if kept.len() >= KEEP {
            kept.remove(0);
        }
        // (the profile is held here, so no other profile can come to share its address)
        kept.push(Kept { profile: profile.clone(), config: config.clone(), steps: steps.to_vec(), ran });
    }
    Ok(())
}

impl Kept {
    fn is(&self, profile: &Arc<Profile>, config: &DeviceConfig, steps: &[ScriptStep]) -> bool {
        Arc::ptr_eq(&self.profile, profile) && self.config == *config && self.steps == steps
    }
}

fn lock() -> std::sync::MutexGuard<'static, Vec<Kept>> {
    KEPT.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// The answers to `steps` (which begin with the `ran.caps.len()` steps `ran` ran) on the link
/// `ran` left: the kept answers, then the rest recorded on clones. `seen` is what the walker
/// saw of the steps after the preamble (see `case::Walk::seen`) and the recorder's shadow after
/// them: where the walker's shadow and the recorder's are the same model (the same config
/// and a preamble with no step that ends on quiet) and the walker walked these very steps,
/// the recorder runs no shadow of its own for them.
pub(crate) fn capture_after(
    profile: &Arc<Profile>,
    config: &DeviceConfig,
    ran: &Ran,
    steps: &[ScriptStep],
    seen: Option<(Vec<(ScriptStep, ShadowStep)>, Device)>,
) -> Result<Vec<Captured>, LinkError> {
    let mut caps = ran.caps.clone();
    if caps.last().is_some_and(|c| c.flooded) {
        return Ok(caps);
    }
    let opts = capture_options(profile, config);
    let (mut link, mut recorder) = (ran.link.clone(), ran.recorder.clone());
    let mut rest = &steps[caps.len().min(steps.len())..];
    let same_model = opts.shadow == *config && !ran.preamble_quiet;
    let walked_these = |seen: &[(ScriptStep, ShadowStep)]| {
        seen.len() <= rest.len() && seen.iter().zip(rest).all(|((s, _), r)| s.action == r.action && s.pause == r.pause)
    };
    if let Some((seen, shadow)) = seen.filter(|(seen, _)| same_model && walked_these(seen)) {
        for ((_, s), step) in seen.into_iter().zip(rest) {
            let c = recorder.step_seen(&mut link, step, &opts, s)?;
            let flooded = c.flooded;
            caps.push(c);
            if flooded {
                return Ok(caps);
            }
        }
        rest = &rest[caps.len() - ran.caps.len()..];
        recorder = recorder.with_shadow(shadow);
    }
    caps.extend(recorder.capture(&mut link, rest, &opts)?);
    Ok(caps)
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;
    use crate::actions::case::{BuiltCase, build_case_unchecked};
    use crate::actions::{Allowed, Dice, Generator};

    /// Everything a built case holds, as text (floats print exactly).
    fn shown(b: &Result<BuiltCase, crate::actions::case::NotACase>) -> String {
        match b {
            Ok(b) => format!("{}\n{b:?}", b.transcript.to_text()),
            Err(e) => format!("no case: {e}"),
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

        /// A case built on a kept preamble (the profile's, kept by an earlier case) is the case
        /// built with the preamble run afresh (a copy of the profile, which nothing kept was
        /// run on): transcript, features, decisions, blocks, steps, and why a case is refused.
        #[test]
        fn a_kept_preamble_builds_the_case_a_fresh_one_does(
            seed in any::<u64>(),
            bh8 in any::<bool>(),
            wide in any::<bool>(),
            home in any::<bool>(),
            mutations in 0usize..3,
        ) {
            let p = Profile::builtin(if bh8 { "bh8-262" } else { "seed" }).unwrap();
            let g = Generator::new(&p, Allowed::default());
            let mut d = Dice::new(seed);
            let mut actions = g.case(&mut d);
            for _ in 0..mutations {
                actions = g.mutate(&mut d, &actions);
            }
            // (an earlier case on the same profile leaves its preamble kept, and so does this
            // case's first build)
            let _ = build_case_unchecked(&p, &g.case(&mut d), "warm", "a case", wide, home);
            let _ = build_case_unchecked(&p, &actions, "fuzz", "a case", wide, home);
            let kept = build_case_unchecked(&p, &actions, "fuzz", "a case", wide, home);
            let fresh_profile = Arc::new((*p).clone());
            let fresh = build_case_unchecked(&fresh_profile, &actions, "fuzz", "a case", wide, home);
            prop_assert_eq!(shown(&kept), shown(&fresh));
        }
    }
}
