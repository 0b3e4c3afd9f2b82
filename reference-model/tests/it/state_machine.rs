//! A state-machine test of the simulated hand against a small abstract model of it: the
//! values of a handful of writable motor parameters, their saved copy in EEPROM, and which
//! motors HI has initialised. Every transition is a command line; after each one the hand's
//! exact answer must be the one the model predicts.
use gcl_model::{Device, DeviceConfig, Mode, MotorSet, Profile};
use proptest::prelude::*;
use proptest::sample::select;
use proptest_state_machine::{ReferenceStateMachine, StateMachineTest, prop_state_machine};

use crate::support;

/// The profiles under test.
const PROFILES: [&str; 2] = ["seed", "bh8-262"];

/// The parameters the model tracks.
const PARAMS: [&str; 4] = ["DP", "DS", "MCV", "HOLD"];

type PerMotor = [[i64; 4]; PARAMS.len()];

/// What the model knows of the hand.
#[derive(Clone, Debug)]
struct Hand {
    profile: &'static str,
    /// Working values, per parameter, per motor.
    values: PerMotor,
    /// The EEPROM copy.
    saved: PerMotor,
    /// Motors HI has initialised.
    initialized: [bool; 4],
}

impl Hand {
    fn defaults(profile: &str) -> PerMotor {
        let p = Profile::builtin(profile).unwrap();
        PARAMS.map(|n| {
            let id = p.param_id(n).unwrap();
            [1, 2, 3, 4].map(|m| p.default_for(id, m))
        })
    }

    fn range(profile: &str, param: usize) -> (i64, i64) {
        let p = Profile::builtin(profile).unwrap();
        let q = p.param(p.param_id(PARAMS[param]).unwrap());
        (q.min, q.max)
    }
}

/// The motors a command names: its prefix, or all four (EN is never changed here).
fn motors(prefix: Option<MotorSet>) -> MotorSet {
    prefix.unwrap_or(MotorSet::ALL)
}

fn prefix_text(prefix: Option<MotorSet>) -> String {
    prefix.map(|s| s.to_string()).unwrap_or_default()
}

/// One command line.
#[derive(Clone, Debug)]
enum Step {
    /// `FSET` with one or two pairs, `(param, value, in range)`.
    Set(Option<MotorSet>, Vec<(usize, i64, bool)>),
    /// `FGET` of some tracked parameters.
    Get(Option<MotorSet>, Vec<usize>),
    /// `FGET S`: initialised or not.
    State(Option<MotorSet>),
    Save(Option<MotorSet>),
    Load(Option<MotorSet>),
    Defaults(Option<MotorSet>),
    Reset,
    Init(Option<MotorSet>),
    /// `C` or `O`: need every selected motor initialised.
    Motion(&'static str, Option<MotorSet>),
    Terminate(Option<MotorSet>),
}

impl Step {
    fn line(&self) -> String {
        let with = |p: &Option<MotorSet>, w: &str| format!("{}{w}", prefix_text(*p));
        match self {
            Step::Set(p, pairs) => {
                let mut s = with(p, "FSET");
                for (i, v, _) in pairs {
                    s.push_str(&format!(" {} {v}", PARAMS[*i]));
                }
                s
            }
            Step::Get(p, params) => {
                let mut s = with(p, "FGET");
                for i in params {
                    s.push_str(&format!(" {}", PARAMS[*i]));
                }
                s
            }
            Step::State(p) => with(p, "FGET S"),
            Step::Save(p) => with(p, "FSAVE"),
            Step::Load(p) => with(p, "FLOAD"),
            Step::Defaults(p) => with(p, "FDEF"),
            Step::Reset => "RESET".into(),
            Step::Init(p) => with(p, "HI"),
            Step::Motion(w, p) => with(p, w),
            Step::Terminate(p) => with(p, "T"),
        }
    }
}

fn prefix() -> impl Strategy<Value = Option<MotorSet>> {
    proptest::option::of((1u8..16).prop_map(MotorSet::from_bits))
}

/// A value for a tracked parameter, in range or not. Close velocities stay at least 20 (or
/// exactly the minimum) so that a close in the seed's units does not take minutes.
fn value(profile: &'static str, param: usize) -> BoxedStrategy<(usize, i64, bool)> {
    let (min, max) = Hand::range(profile, param);
    let low = if PARAMS[param] == "MCV" { min.max(20) } else { min };
    prop_oneof![
        3 => prop_oneof![Just(min), Just(max), low..=max].prop_map(move |v| (param, v, true)),
        1 => prop_oneof![(max + 1)..(max + 70_000), (min - 1000)..min].prop_map(move |v| (param, v, false)),
    ]
    .boxed()
}

/// Copies the values of the motors a command names, every tracked parameter.
fn copy_motors(from: &PerMotor, to: &mut PerMotor, prefix: Option<MotorSet>) {
    for (src, dst) in from.iter().zip(to.iter_mut()) {
        for m in motors(prefix).iter() {
            dst[m as usize - 1] = src[m as usize - 1];
        }
    }
}

struct Model;

impl ReferenceStateMachine for Model {
    type State = Hand;
    type Transition = Step;

    fn init_state() -> BoxedStrategy<Hand> {
        select(PROFILES.to_vec())
            .prop_map(|profile| Hand {
                profile,
                values: Hand::defaults(profile),
                saved: Hand::defaults(profile),
                initialized: [false; 4],
            })
            .boxed()
    }

    fn transitions(state: &Hand) -> BoxedStrategy<Step> {
        let profile = state.profile;
        let pair = (0..PARAMS.len()).prop_flat_map(move |i| value(profile, i));
        prop_oneof![
            6 => (prefix(), proptest::collection::vec(pair, 1..3)).prop_map(|(p, pairs)| Step::Set(p, pairs)),
            3 => (prefix(), proptest::collection::vec(0..PARAMS.len(), 1..4)).prop_map(|(p, ps)| Step::Get(p, ps)),
            1 => prefix().prop_map(Step::State),
            2 => prefix().prop_map(Step::Save),
            2 => prefix().prop_map(Step::Load),
            1 => prefix().prop_map(Step::Defaults),
            1 => Just(Step::Reset),
            2 => prefix().prop_map(Step::Init),
            2 => (select(vec!["C", "O"]), prefix()).prop_map(|(w, p)| Step::Motion(w, p)),
            1 => prefix().prop_map(Step::Terminate),
        ]
        .boxed()
    }

    fn apply(mut state: Hand, step: &Step) -> Hand {
        match step {
            Step::Set(p, pairs) if pairs.iter().all(|(_, _, ok)| *ok) => {
                for (i, v, _) in pairs {
                    for m in motors(*p).iter() {
                        state.values[*i][m as usize - 1] = *v;
                    }
                }
            }
            Step::Save(p) => copy_motors(&state.values.clone(), &mut state.saved, *p),
            Step::Load(p) => copy_motors(&state.saved.clone(), &mut state.values, *p),
            Step::Defaults(p) => copy_motors(&Hand::defaults(state.profile), &mut state.values, *p),
            Step::Reset => {
                state.values = state.saved;
                state.initialized = [false; 4];
            }
            Step::Init(p) => {
                for m in motors(*p).iter() {
                    state.initialized[m as usize - 1] = true;
                }
            }
            _ => {}
        }
        state
    }
}

/// What the hand must answer to `step`, given the model before and after it.
fn expected(before: &Hand, after: &Hand, step: &Step) -> String {
    let p = Profile::builtin(before.profile).unwrap();
    let line = step.line();
    let ok = format!("{line}\n\r=> ");
    let err = |n: u32| format!("{line}\n\rERR {n}\n\r=> ");
    let all_initialized = |pre: &Option<MotorSet>| motors(*pre).iter().all(|m| before.initialized[m as usize - 1]);
    match step {
        Step::Set(_, pairs) if pairs.iter().any(|(_, _, ok)| !ok) => err(128),
        Step::Get(pre, params) => {
            let mut s = line.clone();
            for i in params {
                let vals: Vec<String> =
                    motors(*pre).iter().map(|m| after.values[*i][m as usize - 1].to_string()).collect();
                s.push_str(&format!("\n\r{}", vals.join(" ")));
            }
            s + "\n\r=> "
        }
        Step::State(pre) => {
            let vals: Vec<String> = motors(*pre)
                .iter()
                .map(|m| if before.initialized[m as usize - 1] { 0 } else { p.hand.uninitialized_state_value })
                .map(|v| v.to_string())
                .collect();
            format!("{line}\n\r{}\n\r=> ", vals.join(" "))
        }
        Step::Reset => {
            let banner: String = p.banner.iter().map(|b| format!("\n\r{b}")).collect();
            format!("{line}{banner}\n\r=> ")
        }
        Step::Motion(_, pre) if !all_initialized(pre) => err(p.hand.uninitialized_status),
        Step::Terminate(pre) if !all_initialized(pre) => err(p.hand.terminate_uninitialized_status),
        _ => ok,
    }
}

/// The hand under test, and the model as it was before the step being applied.
struct Sut {
    device: Device,
    model: Hand,
}

impl StateMachineTest for Sut {
    type SystemUnderTest = Sut;
    type Reference = Model;

    fn init_test(state: &Hand) -> Sut {
        let device =
            support::hand_with(support::profile(state.profile), DeviceConfig { seed: 3, ..DeviceConfig::default() });
        Sut { device, model: state.clone() }
    }

    fn apply(mut sut: Sut, after: &Hand, step: Step) -> Sut {
        let want = expected(&sut.model, after, &step);
        let got = support::send(&mut sut.device, &step.line());
        assert_eq!(got, want, "answer to {:?} ({})", step.line(), sut.model.profile);
        sut.model = after.clone();
        sut
    }

    fn check_invariants(sut: &Sut, model: &Hand) {
        let d = &sut.device;
        let p = d.profile().clone();
        assert_eq!(d.mode(), Mode::Idle);
        for m in 1..=4u8 {
            assert_eq!(
                d.initialized(gcl_model::Motor::new(m).unwrap()),
                model.initialized[m as usize - 1],
                "motor {m} initialised"
            );
            for (i, name) in PARAMS.iter().enumerate() {
                assert_eq!(d.params().get_named(&p, name, m), Some(model.values[i][m as usize - 1]), "{name} of {m}");
            }
        }
    }
}

prop_state_machine! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn the_hand_follows_the_model(sequential 1..40 => Sut);
}
