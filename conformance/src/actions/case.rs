//! From host actions to a golden transcript, the suite's way: the actions follow the suite's
//! preamble in a `CaseB`, each answer gets the suite's `Shape` (positions in a band of
//! MPE around the model's, other live values in their ranges, banners elided, feedback
//! blocks with the suite's field rules), and `suite::build` runs the host side against the
//! in-process model and checks every shaped answer against the model's own. The transcript
//! is then the set of answers the model accepts.
//!
//! A shadow [`Device`] walks the same bytes while the case is assembled: it gives the
//! RealTime layout a block is encoded with, the model's positions for the bands, and the
//! coverage features (`fuzz::device::coverage` counts them), all through the model's public API.

use std::collections::BTreeSet;
use std::sync::Arc;
use std::time::Duration;

use gcl_model::spec::{CommandKind, Role, Scope};
use gcl_model::{Args, ControlHeader, Device, DeviceConfig, Line, Mode, Profile, StatusBits, parse_line};

use super::HostAction;
use super::relate::{BlockNote, LoopTrack, Relations};
use crate::record::{Captured, ShadowStep, shadow_step};
use crate::suite::build::{CaseB, CaseDef, build_after, capture_plan, capture_plan_on, value_range};
use crate::suite::plan::{FieldRule, Plan, Range, Shape};
use gcl_transcript::script::ScriptStep;
use gcl_transcript::{Requirement, Transcript};

/// A case the model has answered.
#[derive(Debug, Clone)]
pub struct BuiltCase {
    /// The golden transcript (preamble, the actions, a restore of the EEPROM if it was written).
    pub transcript: Transcript,
    /// Coverage features the shadow model reached (counted by `fuzz::device::coverage`).
    pub features: BTreeSet<String>,
    /// EEPROM writes the transcript makes (FSAVE, PSAVE), restores included.
    pub eeprom_writes: usize,
    /// The unmutated model's run of the transcript, each answer byte tagged with the step it
    /// answers (see [`crate::align`]). Empty until [`BuiltCase::check`] made it (a case built
    /// with [`build_case_sending`] and friends is checked).
    pub model: crate::align::ModelRun,
    /// Whether the transcript was checked to pass on the model as a fresh hand meets it, and
    /// `model` holds that run.
    pub checked: bool,
    /// The bytes each [`HostAction::Block`] sent, in the order of the blocks among the actions
    /// (`None` for a block outside the loop, which sends nothing).
    pub block_bytes: Vec<Option<Vec<u8>>>,
    /// The decisions each step of the transcript rests on (`suite::depends::decisions_by_step`,
    /// the analysis behind `x-decisions`, which is their union with the `decision:` clauses).
    pub step_decisions: Vec<Vec<String>>,
    /// For each action, the transcript step its steps begin at, and whether the model was
    /// outside RealTime mode there (every action ends answered, so a line inserted before
    /// one that begins outside the loop is sent at a quiescent point; one inside it would be
    /// blocks, and the builder drops it).
    pub action_steps: Vec<(usize, bool)>,
}

impl BuiltCase {
    /// The decisions a failure of this case at the steps `failing` rests on: every decision
    /// of the failing steps, and the state decisions of the steps before them (not those that
    /// concern only an earlier answer, which passed; the list and the rule are
    /// `suite::depends::ANSWER_ONLY`'s). Where the model's joint stops are (a state decision)
    /// counts from the first step whose answer rests on them; any other `decision:` clause of
    /// the case counts whatever the step. `None` (no failing step known): every decision of
    /// every step.
    pub fn rests_on(&self, failing: Option<std::ops::RangeInclusive<usize>>) -> Vec<String> {
        let mut out: Vec<String> = self
            .transcript
            .header
            .clauses
            .iter()
            .filter_map(|c| c.strip_prefix(crate::suite::build::DECISION_CLAUSE))
            .filter(|d| !self.step_decisions.iter().any(|s| s.iter().any(|x| x == d)))
            .map(str::to_string)
            .collect();
        let last = failing.as_ref().map_or(usize::MAX, |r| *r.end());
        for (i, step) in self.step_decisions.iter().enumerate().take_while(|(i, _)| *i <= last) {
            let at_failure = failing.as_ref().is_none_or(|r| r.contains(&i));
            for d in step {
                if (at_failure || !crate::suite::depends::answer_only(d)) && !out.contains(d) {
                    out.push(d.clone());
                }
            }
        }
        out
    }
}

/// Why actions did not make a case: the model itself gave no complete answer, or an answer
/// the shapes do not cover (the case is dropped, never reported).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("the model could not make a case of these actions: {0}")]
pub struct NotACase(pub String);

/// The shadow model's quiet time after a step that ends on silence (the recorder's default).
const QUIET: Duration = Duration::from_millis(100);

struct Walk {
    shadow: Device,
    features: BTreeSet<String>,
    /// Whether the model's positions may differ from the hand's by more than a band (after
    /// ^C mid-motion).
    positions_uncertain: bool,
    /// Each step walked, with what the recorder's shadow makes of it (`record::shadow_step`):
    /// the capture of the case on a kept preamble needs no shadow of its own for these steps.
    seen: Vec<(ScriptStep, ShadowStep)>,
    /// The recorder's shadow, once it parts from this one: after a step that ends on quiet
    /// the walk lets [`QUIET`] pass, the recorder does not.
    twin: Option<Device>,
}

/// How near the end of a motion (by the model's clock) a ^C may not land on a hand outside
/// this process.
const ABORT_MARGIN: Duration = Duration::from_millis(150);

impl Walk {
    fn new(shadow: Device) -> Walk {
        Walk { shadow, features: BTreeSet::new(), positions_uncertain: false, seen: Vec::new(), twin: None }
    }

    /// Whether the shadow is still running a command after `t` more without input.
    fn busy_after(&self, t: Duration) -> bool {
        let mut d = self.shadow.clone();
        let at = d.now() + t;
        d.handle_timeout(at);
        d.mode() == Mode::Busy
    }

    /// Feeds one step to the shadow, the way the recorder's shadow does (and lets [`QUIET`] pass
    /// after a step that ends on quiet); returns its answer.
    fn feed(&mut self, step: &ScriptStep, terminator: u8) -> Vec<u8> {
        if let Some(p) = step.pause {
            let t = self.shadow.now() + p;
            self.shadow.handle_timeout(t);
            if let Some(twin) = &mut self.twin {
                let t = twin.now() + p;
                twin.handle_timeout(t);
            }
        }
        let before = self.shadow.mode();
        let mine = shadow_step(&mut self.shadow, step, terminator);
        let seen = match &mut self.twin {
            Some(twin) => shadow_step(twin, step, terminator),
            None => mine.clone(),
        };
        let mut answer = mine.out;
        if step.action.ends_on_quiet() {
            self.twin.get_or_insert_with(|| self.shadow.clone());
            let t = self.shadow.now() + QUIET;
            self.shadow.handle_timeout(t);
            answer.extend(self.shadow.take_output());
        }
        self.seen.push((step.clone(), seen));
        let after = self.shadow.mode();
        if before != after {
            self.features.insert(format!("mode:{before:?}->{after:?}"));
        }
        let st = self.shadow.last_status();
        for bit in st.iter() {
            self.features.insert(format!("status:{}", bit.code()));
        }
        if after == Mode::Loop
            && let Some(l) = self.shadow.rt_layout()
        {
            self.features.insert(format!("layout:{}/{}/{}", l.motors(), l.control().size(), l.feedback().size()));
        }
        answer
    }
}

/// How a step's answer is shaped once the model's answer is known.
enum ShapeKind {
    /// As [`Shape::Exact`], [`Shape::ListValues`] or [`Shape::Banner`].
    Fixed(Shape),
    /// A get line's values ([`get_shape`]); `true` after ^C mid-motion.
    Get(Vec<gcl_model::spec::ParamId>, bool),
    /// A feedback block: LFAP in a band around the model's; `true` after ^C mid-motion.
    Block(bool),
}

/// The profile's factory MPE (position error allowed) of `motor`, 0 when it has none.
pub fn mpe(p: &Profile, motor: u8) -> i64 {
    p.param_id("MPE").map_or(0, |id| p.default_for(id, motor))
}

/// The shape of a get line's answer, from the model's answer: positions in a band of MPE,
/// other live values in their ranges, everything else exact.
fn get_shape(p: &Profile, names: &[gcl_model::spec::ParamId], answer: &[u8], uncertain: bool, wide: bool) -> Shape {
    let eol = p.framing.line_ending.as_bytes();
    let text = String::from_utf8_lossy(answer);
    let lines: Vec<&str> = text.split(std::str::from_utf8(eol).unwrap_or("\n\r")).skip(1).collect();
    let mut out = Vec::new();
    for (i, id) in names.iter().enumerate() {
        let spec = p.param(*id);
        let tokens = lines.get(i).map(|l| l.split(' ').collect::<Vec<_>>()).unwrap_or_default();
        let ranges: Vec<Option<Range>> = tokens
            .iter()
            .enumerate()
            .map(|(j, tok)| {
                let motor = (j as u8 + 1).min(4);
                // Positions within MPE of the model's (wider after ^C mid-motion, where the
                // hand's timing and the model's part), strain within the free strain.
                let band = match spec.name.as_str() {
                    "P" if uncertain && wide => Some(spec.max - spec.min),
                    "P" if uncertain => Some(3 * mpe(p, motor)),
                    "P" => Some(mpe(p, motor)),
                    // (a hand outside this process reads its own strain at rest: the model's
                    // free strain is a constant of the model's hand, as the suite's FGET SG
                    // case has it)
                    "SG" if !wide => Some(p.hand.free_strain.max(1)),
                    _ => None,
                };
                if let (Some(band), Ok(v)) = (band, tok.parse::<i64>()) {
                    return Some(((v - band).max(spec.min), (v + band).min(spec.max)));
                }
                value_range(spec, if spec.scope == Scope::Global { 1 } else { motor }, None)
            })
            .collect();
        out.push(ranges);
    }
    Shape::Values(out)
}

/// The transcript and coverage of `actions` after the preamble. `id` names the case.
///
/// `wide` is for hands outside this process: there the model's clock and the hand's part as
/// soon as motors move under RealTime control or a ^C lands mid-motion (a wait advances the
/// in-process model's clock, not a child's or a real hand's), so what follows reads
/// positions, velocities and position changes in their whole range, except where their
/// clauses are ratios that hold on any clock (see `fuzz::device::relate`); in-process the model is
/// its own clock and only MPE bands apply.
///
/// `home` starts every case with HI (a hand outside this process keeps its positions across
/// RESET; the in-process sim is fresh for every case), which a case that moves does anyway.
pub fn build_case(
    p: &Arc<Profile>,
    actions: &[HostAction],
    id: &str,
    title: &str,
    wide: bool,
    home: bool,
) -> Result<BuiltCase, NotACase> {
    build_case_sending(p, actions, id, title, wide, home, &[])
}

/// [`build_case`], with the n-th block sending `blocks[n]` where that is given and of the size
/// the layout the model has then encodes, instead of its values encoded with that layout: a
/// case rewritten as a hand with another layout would take it is still sent the bytes the hand
/// was sent. (A rewrite whose control blocks have another size sends blocks encoded anew; the
/// explanation then does not compare their answers.)
pub fn build_case_sending(
    p: &Arc<Profile>,
    actions: &[HostAction],
    id: &str,
    title: &str,
    wide: bool,
    home: bool,
    blocks: &[Option<Vec<u8>>],
) -> Result<BuiltCase, NotACase> {
    build_case_on(p, (&DeviceConfig::default(), Model::Profile), actions, id, title, wide, home, blocks)
}

/// The model a case is built on: the profile's hand as the fuzzer judges it, or one that holds
/// a hypothesis about the hand (see `variant`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Model {
    /// The profile's hand.
    Profile,
    /// A hypothesis about the hand's, to be asked of the hand.
    Hypothesis,
}

/// [`build_case_sending`] without its last check, the model's own replay of the transcript
/// ([`BuiltCase::check`]): a campaign in this process runs that check only for a case the hand
/// fails, where a signature needs its tagged run (a case the hand passes finds nothing, and the
/// replay was a fifth of a case's cost). A case the model would not pass is then no finding.
pub fn build_case_unchecked(
    p: &Arc<Profile>,
    actions: &[HostAction],
    id: &str,
    title: &str,
    wide: bool,
    home: bool,
) -> Result<BuiltCase, NotACase> {
    assemble(p, (&DeviceConfig::default(), Model::Profile), actions, id, title, wide, home, &[])
}

impl BuiltCase {
    /// The last check of a case, deferred by [`build_case_unchecked`]: the transcript passes on
    /// the unmutated model as a fresh hand meets it (an answer that runs past its step, or timing
    /// the recorder's shadow does not follow, is no case), and that run, tagged, is kept.
    pub fn check(&mut self, p: &Arc<Profile>) -> Result<(), NotACase> {
        self.check_on(p, &DeviceConfig::default())
    }

    fn check_on(&mut self, p: &Arc<Profile>, config: &DeviceConfig) -> Result<(), NotACase> {
        if self.checked {
            return Ok(());
        }
        let mut run_config = config.clone();
        run_config.scenario.objects = self.transcript.header.objects();
        self.model =
            crate::align::model_run_on(p, run_config, &self.transcript).map_err(|out| NotACase(out.summary()))?;
        self.checked = true;
        Ok(())
    }
}

/// [`build_case_sending`] with a model built from `config`, not the profile's own hand: what a
/// hand with that difference would answer, shaped as any case (see `variant`).
#[allow(clippy::too_many_arguments)]
pub fn build_case_on(
    p: &Arc<Profile>,
    on: (&DeviceConfig, Model),
    actions: &[HostAction],
    id: &str,
    title: &str,
    wide: bool,
    home: bool,
    blocks: &[Option<Vec<u8>>],
) -> Result<BuiltCase, NotACase> {
    let mut b = assemble(p, on, actions, id, title, wide, home, blocks)?;
    b.check_on(p, on.0)?;
    Ok(b)
}

/// [`build_case_on`] but its last check ([`BuiltCase::check`]): walk the actions on a shadow →
/// capture the model's answers → mark what they rest on → shape them → the case.
#[allow(clippy::too_many_arguments)]
fn assemble(
    p: &Arc<Profile>,
    (config, model): (&DeviceConfig, Model),
    actions: &[HostAction],
    id: &str,
    title: &str,
    wide: bool,
    home: bool,
    blocks: &[Option<Vec<u8>>],
) -> Result<BuiltCase, NotACase> {
    let moves = moves_any(p, actions);
    let homed = moves || home;
    let mut k = CaseB::new(p, id, title).src("Supervisory mode").preamble(homed);
    // (the preamble is the same for many cases: the model's runs of it are kept, and a case
    // after the first goes on from clones of them; see `preamble`)
    let pre: Vec<ScriptStep> = k.def.plans.iter().map(|pl| pl.step.clone()).collect();
    let kept = super::preamble::kept(p, config, &pre);
    let shadow = match &kept {
        Some(ran) => ran.walked.clone(),
        None => {
            let shadow = Walker::walk_preamble(p, config, &pre);
            super::preamble::keep(p, config, &k.def.plans, shadow.clone()).map_err(|e| NotACase(e.to_string()))?;
            shadow
        }
    };
    let mut walker = Walker::start(p, shadow, wide, blocks);
    for a in actions {
        k = walker.action(k, a)?;
    }
    let mut walked = walker.close(k);
    // The model's answers as the wire meets them, then the shapes from them (and the
    // transcript from the same answers).
    let steps: Vec<ScriptStep> = walked.def.plans.iter().map(|pl| pl.step.clone()).collect();
    let caps = match &kept {
        Some(ran) if steps.starts_with(&pre) => {
            super::preamble::capture_after(p, config, ran, &steps, walked.seen.take())
        }
        _ => capture_plan_on(p, &walked.def.plans, config.clone()),
    }
    .map_err(|e| NotACase(e.to_string()))?;
    let stops_at = stops_stage(p, &mut walked, &caps, moves, wide);
    abort_timing_stage(p, &mut walked.def, &caps);
    if wide && model == Model::Profile {
        no_feedback_inside(&walked.kinds, &caps)?;
    }
    shape_stage(p, &mut walked, &caps, model, wide, homed)?;
    case_stage(p, walked, &caps, stops_at, kept.as_deref())
}

/// Takes the actions; gives whether any of them moves the hand (a motion, a loop, a ^C
/// mid-motion).
fn moves_any(p: &Arc<Profile>, actions: &[HostAction]) -> bool {
    actions.iter().any(|a| match a {
        HostAction::Line(l) => parsed_command(p, l).is_some_and(|c| {
            let k = c.kind(p);
            k.is_motion() || k == CommandKind::Loop
        }),
        HostAction::LineThenAbort { .. } => true,
        _ => false,
    })
}

/// Takes a line; gives its command, if it parses as one.
fn parsed_command(p: &Profile, l: &str) -> Option<gcl_model::Command> {
    match parse_line(p, l.as_bytes()) {
        Ok(Line::Command(c)) => Some(c),
        _ => None,
    }
}

/// What the actions stage gave: the case's steps and, by step, what the later stages need.
struct Walked {
    def: CaseDef,
    /// The coverage features the shadow reached.
    features: BTreeSet<String>,
    /// The shape each answered step gets, by step.
    kinds: Vec<(usize, ShapeKind)>,
    /// The bytes each block sent (see [`BuiltCase::block_bytes`]).
    block_bytes: Vec<Option<Vec<u8>>>,
    /// What each feedback block of a tracked loop may be related on, by step.
    notes: Vec<(usize, BlockNote)>,
    /// The first step whose motion the model stalls at a stop or short of its goal.
    stalls_at: Option<usize>,
    /// See [`BuiltCase::action_steps`].
    action_steps: Vec<(usize, bool)>,
    /// What the recorder's shadow makes of each step walked (see [`Walk::seen`]), and that
    /// shadow after them (taken by the capture).
    seen: Option<(Vec<(ScriptStep, ShadowStep)>, Device)>,
}

/// The actions stage as it goes: the shadow that walks the case's bytes, and what it noted.
struct Walker<'a> {
    p: &'a Arc<Profile>,
    term: u8,
    wide: bool,
    /// The bytes blocks are to send, where given (see [`build_case_sending`]).
    blocks: &'a [Option<Vec<u8>>],
    walk: Walk,
    eeprom: bool,
    kinds: Vec<(usize, ShapeKind)>,
    block_bytes: Vec<Option<Vec<u8>>>,
    /// The loop the shadow is in as the host drove it, and what each feedback block of it may
    /// be related on (see [`super::relate`]).
    track: Option<LoopTrack>,
    notes: Vec<(usize, BlockNote)>,
    stalls_at: Option<usize>,
    action_steps: Vec<(usize, bool)>,
}

impl<'a> Walker<'a> {
    /// Takes the case's preamble; gives a fresh shadow that has walked it.
    fn walk_preamble(p: &Arc<Profile>, config: &DeviceConfig, steps: &[ScriptStep]) -> Device {
        let mut walk = Walk::new(Device::new(p.clone(), config.clone()));
        walk.shadow.clear_output();
        for step in steps {
            walk.feed(step, p.framing.terminator);
        }
        walk.shadow
    }

    /// Takes a shadow that has walked the case's preamble ([`Walker::walk_preamble`]); gives
    /// the walker of the actions after it (the preamble's features forgotten).
    fn start(p: &'a Arc<Profile>, shadow: Device, wide: bool, blocks: &'a [Option<Vec<u8>>]) -> Walker<'a> {
        let term = p.framing.terminator;
        let walk = Walk::new(shadow);
        Walker {
            p,
            term,
            wide,
            blocks,
            walk,
            eeprom: false,
            kinds: Vec::new(),
            block_bytes: Vec::new(),
            track: None,
            notes: Vec::new(),
            stalls_at: None,
            action_steps: Vec::new(),
        }
    }

    /// Takes the case so far and one action: walks the action on the shadow; gives the case
    /// with its steps, or why the actions are no case.
    fn action(&mut self, k: CaseB, a: &HostAction) -> Result<CaseB, NotACase> {
        let in_loop = self.walk.shadow.mode() == Mode::Loop;
        self.action_steps.push((k.def.plans.len(), !in_loop));
        if !in_loop || !matches!(a, HostAction::Block { .. } | HostAction::Line(_)) {
            // (anything else sent in the loop drives it as the track does not follow)
            self.track = None;
        }
        match a {
            // A line in RealTime mode is a stream of invalid headers: not a case.
            HostAction::Line(_) if in_loop => Ok(k),
            HostAction::Line(l) => self.line(k, l),
            HostAction::Raw(b) => self.raw(k, b),
            HostAction::LineThenAbort { line, after_ms } => self.line_then_abort(k, line, *after_ms),
            HostAction::PartialThenAbort(text) => {
                let w = &mut self.walk;
                w.features.insert(if in_loop { "abort:mid-block" } else { "abort:mid-line" }.into());
                let s1 = ScriptStep::new(gcl_transcript::script::Action::Partial(text.as_bytes().to_vec()));
                w.feed(&s1, self.term);
                w.feed(&ScriptStep::new(gcl_transcript::script::Action::abort()), self.term);
                Ok(k.step(gcl_transcript::script::Action::Partial(text.as_bytes().to_vec())).abort())
            }
            HostAction::Abort => {
                self.walk.features.insert(if in_loop { "abort:loop" } else { "abort:idle" }.into());
                self.walk.feed(&ScriptStep::new(gcl_transcript::script::Action::abort()), self.term);
                Ok(k.abort())
            }
            HostAction::Block { header, values, extra, pause_ms } => {
                Ok(self.block(k, *header, values, *extra, *pause_ms, in_loop))
            }
        }
    }

    /// Takes a command line outside the loop: walks it, notes its shape and what it does to
    /// the model's positions; gives the case with the line.
    fn line(&mut self, mut k: CaseB, l: &str) -> Result<CaseB, NotACase> {
        let (p, wide) = (self.p, self.wide);
        let step = ScriptStep::new(gcl_transcript::script::Action::Line(l.as_bytes().to_vec()));
        let cmd = parsed_command(p, l);
        note_line(p, l, &mut self.walk.features);
        // Whether a motion trips the over-temperature limit depends on how warm the
        // hand is, which on a hand outside this process earlier cases and the room
        // decide, not the model's fresh start: such a case is not one the model can judge.
        if wide
            && cmd.as_ref().is_some_and(|c| c.kind(p).is_motion())
            && p.role(Role::OverTemperature).is_some_and(|id| self.walk.shadow.effective(id, 1) != 0)
        {
            return Err(NotACase(
                "a motion with the over-temperature limit set, on a hand outside this process".into(),
            ));
        }
        let answer = self.walk.feed(&step, self.term);
        // A motion the model stalls at a stop or short of its goal (16) rests on where
        // the model's motion ends, the stops at 0 included.
        if cmd.as_ref().is_some_and(|c| c.kind(p).is_motion())
            && crate::suite::depends::status_in(&answer).is_some_and(|s| s & StatusBits::MISSED_POSITION.bits() != 0)
        {
            self.stalls_at.get_or_insert(k.def.plans.len());
        }
        if self.walk.shadow.mode() == Mode::Loop {
            self.track = Some(LoopTrack::enter(p, &self.walk.shadow, k.def.plans.len()));
        }
        let refused = answer.windows(3).any(|w| w == b"ERR");
        let shape = line_shape(p, cmd.as_ref(), refused, wide, self.walk.positions_uncertain);
        if let Some(c) = &cmd {
            match c.kind(p) {
                CommandKind::MotorSave | CommandKind::GlobalSave => self.eeprom = true,
                CommandKind::Loop => k = k.requires(Requirement::Realtime),
                // A motion that leaves a motor out (a prefix, EN), or a step from where
                // the motor is (IC, IO), leaves positions as uncertain as they were: on a
                // hand outside this process a RealTime session after a pause moves
                // motors by the hand's speed and clock.
                kd if kd.is_motion()
                    && !refused
                    && (!wide
                        || !matches!(kd, CommandKind::IncrementalClose | CommandKind::IncrementalOpen)
                            && moves_all(p, c, &self.walk.shadow)) =>
                {
                    self.walk.positions_uncertain = false
                }
                _ => {}
            }
        }
        self.kinds.push((k.def.plans.len(), shape));
        Ok(k.line(l))
    }

    /// Takes raw bytes: walks them (answered exactly); gives the case with them, or no case
    /// when a read among them would judge live values on a hand outside this process.
    fn raw(&mut self, k: CaseB, b: &[u8]) -> Result<CaseB, NotACase> {
        let p = self.p;
        // Raw bytes are answered exactly; a read among them on a hand outside this
        // process would judge live values (temperature, time powered, positions) by
        // the model's fresh start.
        if self.wide
            && b.split(|c| *c == self.term).any(|l| {
                matches!(parse_line(p, l), Ok(Line::Command(c)) if matches!(c.kind(p),
                    CommandKind::MotorGet
                        | CommandKind::GlobalGet
                        | CommandKind::MotorListValues
                        | CommandKind::GlobalListValues
                        | CommandKind::MotorListAllValues
                        | CommandKind::GlobalListAllValues))
            })
        {
            return Err(NotACase("a read among raw bytes, on a hand outside this process".into()));
        }
        let step = ScriptStep::new(gcl_transcript::script::Action::Bytes {
            bytes: b.to_vec(),
            form: gcl_transcript::Form::Text,
        });
        self.walk.features.insert("framing:control-byte".into());
        self.walk.feed(&step, self.term);
        Ok(k.step(step.action.clone()))
    }

    /// Takes a motion line and when ^C follows it: walks both; gives the case with them, or
    /// no case when the ^C lands too near the motion's end on a hand outside this process.
    fn line_then_abort(&mut self, k: CaseB, line: &str, after_ms: u64) -> Result<CaseB, NotACase> {
        let (walk, term) = (&mut self.walk, self.term);
        note_line(self.p, line, &mut walk.features);
        walk.features.insert("abort:mid-motion".into());
        let s1 = ScriptStep::new(gcl_transcript::script::Action::NoWait(line.as_bytes().to_vec()));
        walk.feed(&s1, term);
        // On a hand outside this process the motion's end is known only roughly: a ^C
        // near it lands before or after as that hand's clock decides, not the model's.
        let at = Duration::from_millis(after_ms);
        if self.wide && walk.busy_after(at.saturating_sub(ABORT_MARGIN)) != walk.busy_after(at + ABORT_MARGIN) {
            return Err(NotACase("a ^C too near the end of the motion it is to stop".into()));
        }
        let s2 = ScriptStep {
            pause: Some(Duration::from_millis(after_ms)),
            ..ScriptStep::new(gcl_transcript::script::Action::abort())
        };
        walk.feed(&s2, term);
        walk.positions_uncertain = true;
        Ok(k.requires(Requirement::AbortTiming).nowait(line).pause_ms(after_ms).abort())
    }

    /// Takes a RealTime block: encodes it with the shadow's layout (or the bytes given for
    /// it), walks it and notes what its feedback may be related on; gives the case with it.
    /// Outside the loop a block sends nothing.
    fn block(&mut self, mut k: CaseB, header: u8, values: &[i64], extra: i8, pause_ms: u64, in_loop: bool) -> CaseB {
        let term = self.term;
        let given = self.blocks.get(self.block_bytes.len()).cloned().flatten();
        let Some(layout) = self.walk.shadow.rt_layout().cloned().filter(|_| in_loop) else {
            self.block_bytes.push(None);
            return k;
        };
        let h = ControlHeader::from_byte(header);
        self.walk
            .features
            .insert(format!("rt-header:{}", if h.is_some() { (header as char).to_string() } else { "invalid".into() }));
        let mut bytes = Vec::new();
        if h.is_some_and(|h| h.has_data()) {
            let n = layout.control().fields().len();
            let vals: Vec<i64> = (0..n).map(|i| values.get(i).copied().unwrap_or(0)).collect();
            layout.control().encode_clamped(header, &vals, &mut bytes);
        } else {
            bytes.push(header);
        }
        if extra > 0 {
            bytes.extend(std::iter::repeat_n(0u8, extra as usize));
        } else if extra < 0 && bytes.len() > 1 {
            bytes.pop();
        }
        // (bytes given for a block of another size are no block of this layout: the
        // model would wait for the rest, which is no case; the block is encoded anew)
        if let Some(b) = given.filter(|b| b.len() == bytes.len()) {
            bytes = b;
        }
        self.block_bytes.push(Some(bytes.clone()));
        let short = extra < 0;
        let pause = (pause_ms > 0).then(|| Duration::from_millis(pause_ms));
        let step = ScriptStep {
            pause,
            ..ScriptStep::new(if short {
                gcl_transcript::script::Action::Partial(bytes.clone())
            } else {
                gcl_transcript::script::Action::Bytes { bytes: bytes.clone(), form: gcl_transcript::Form::Hex }
            })
        };
        self.walk.feed(&step, term);
        if pause_ms > 0 {
            // Motors run over the pause only on a hand whose motions take time (as
            // the suite's rt-lfdpc-scaling): a hand whose motions end at once would
            // leave the model's positions behind.
            k = k.pause_ms(pause_ms).requires(Requirement::AbortTiming);
        }
        if short {
            self.walk.features.insert("abort:mid-block".into());
            self.walk.feed(&ScriptStep::new(gcl_transcript::script::Action::abort()), term);
            return k.step(gcl_transcript::script::Action::Partial(bytes.clone())).abort();
        }
        match self.track.as_mut() {
            Some(t) if extra == 0 => {
                if let Some(n) = t.block(&layout, &bytes) {
                    self.notes.push((k.def.plans.len(), n));
                }
            }
            _ => self.track = None,
        }
        self.kinds.push((k.def.plans.len(), ShapeKind::Block(self.walk.positions_uncertain)));
        // Motors that move under RealTime control leave the model's clock and the
        // hand's apart: what follows reads positions widely.
        self.walk.positions_uncertain = true;
        k.block(&bytes, Shape::Exact)
    }

    /// Takes the case after its last action: leaves the loop and restores the EEPROM where
    /// the actions need it; gives the case's steps and what the walk noted.
    fn close(self, mut k: CaseB) -> Walked {
        if self.walk.shadow.mode() == Mode::Loop {
            k = k.abort();
        }
        if self.eeprom {
            k = k.requires(Requirement::Eeprom);
        }
        Walked {
            def: k.finish(),
            features: self.walk.features,
            kinds: self.kinds,
            block_bytes: self.block_bytes,
            notes: self.notes,
            stalls_at: self.stalls_at,
            action_steps: self.action_steps,
            seen: Some((self.walk.seen, self.walk.twin.unwrap_or(self.walk.shadow))),
        }
    }
}

/// Takes a line's command and whether the model refused it; gives the shape its answer gets.
fn line_shape(p: &Profile, cmd: Option<&gcl_model::Command>, refused: bool, wide: bool, uncertain: bool) -> ShapeKind {
    match cmd {
        Some(c) if !refused => match (c.kind(p), &c.args) {
            (CommandKind::MotorGet | CommandKind::GlobalGet, Args::Names(ids)) => {
                ShapeKind::Get(ids.clone(), uncertain)
            }
            (
                CommandKind::MotorListValues
                | CommandKind::GlobalListValues
                | CommandKind::MotorListAllValues
                | CommandKind::GlobalListAllValues,
                _,
            ) => ShapeKind::Fixed(Shape::ListValues),
            (CommandKind::Reset, _) => ShapeKind::Fixed(Shape::Banner),
            // What VERS says on a hand outside this process is its own version
            // and contact text, as the suite's cmd-vers case has it.
            (CommandKind::Version, _) if wide => ShapeKind::Fixed(Shape::AnyLines),
            _ => ShapeKind::Fixed(Shape::Exact),
        },
        _ => ShapeKind::Fixed(Shape::Exact),
    }
}

/// Takes the walked case and the model's answers; gives the first step whose answer rests on
/// the model's joint stops, if any, and marks the case with those decisions.
fn stops_stage(p: &Arc<Profile>, walked: &mut Walked, caps: &[Captured], moves: bool, wide: bool) -> Option<usize> {
    // A case whose answers change when the model's joint stops are taken away rests on where
    // the model puts them (the `[hand]` limits, which the seed does not fix): it is judged at
    // that decision's level, and `--skip-decision` drops it. Asked only of a hand outside
    // this process (in process the stops are the model's, and the second capture cost a fifth
    // of the in-process campaign's speed).
    // The first step whose answer rests on the stops, where the finding's decisions place
    // them (see [`BuiltCase::rests_on`]).
    let stops_at = if !moves {
        None
    } else {
        walked.stalls_at.or_else(|| if wide { rests_on_stops(p, &walked.def.plans, caps) } else { None })
    };
    if stops_at.is_some() {
        for id in STOP_DECISIONS {
            walked.def.decision(p, id);
        }
    }
    stops_at
}

/// Takes the case and the model's answers: requires abort timing of a case where a ^C the
/// model answers with the abort status landed while a command ran.
fn abort_timing_stage(p: &Profile, def: &mut CaseDef, caps: &[Captured]) {
    // A ^C the model answers with the abort status landed while a command ran (queued lines
    // and RealTime exits can start a motion no action named): only a hand moving in real
    // time answers it so.
    let term = p.framing.terminator;
    let aborted = format!("ERR {}", p.hand.abort_status).into_bytes();
    if p.hand.abort_status != 0
        && def.plans.iter().zip(caps).any(|(pl, c)| {
            pl.step.action.wire_bytes(term) == [p.framing.abort]
                && c.output.windows(aborted.len()).any(|w| w == aborted)
        })
        && !def.requires.contains(&Requirement::AbortTiming)
    {
        def.requires.push(Requirement::AbortTiming);
    }
}

/// Takes the steps' shapes and the model's answers; gives no case where a feedback block
/// sits inside an answer shaped as text or bytes (for the profile's model outside this
/// process).
fn no_feedback_inside(kinds: &[(usize, ShapeKind)], caps: &[Captured]) -> Result<(), NotACase> {
    // A feedback block inside an answer shaped as text or bytes (a block with bytes too
    // many, the answer to ^C mid-block) holds strain and positions exactly: such a case
    // would judge a real hand by the model's noise. (A hypothesis's case may: judged
    // exactly it is only the harder to answer, and a hand that does not answer it as it
    // expects is not named by it.)
    let block_steps: BTreeSet<usize> =
        kinds.iter().filter(|(_, k)| matches!(k, ShapeKind::Block(_))).map(|(i, _)| *i).collect();
    for (i, c) in caps.iter().enumerate() {
        let fb = c.layout.as_ref().map(|l| l.feedback().size());
        let is_feedback =
            c.realtime && c.output.first() == Some(&gcl_model::realtime::FEEDBACK_HEADER) && c.output.len() > 1;
        if is_feedback && !(block_steps.contains(&i) && fb == Some(c.output.len())) {
            return Err(NotACase(format!("step {i}: a feedback block inside another answer")));
        }
    }
    Ok(())
}

/// Takes the walked case and the model's answers: gives each answered step its shape (and
/// the relations a block's feedback binds), adding the relations' features; or no case.
fn shape_stage(
    p: &Arc<Profile>,
    walked: &mut Walked,
    caps: &[Captured],
    model: Model,
    wide: bool,
    homed: bool,
) -> Result<(), NotACase> {
    let mut relations = Relations::new(model == Model::Hypothesis);
    for (i, kind) in std::mem::take(&mut walked.kinds) {
        let (Some(plan), Some(c)) = (walked.def.plans.get_mut(i), caps.get(i)) else { continue };
        if wide && let Some((_, note)) = walked.notes.iter().find(|(at, _)| *at == i) {
            let uncertain = matches!(kind, ShapeKind::Block(true));
            let binds = relations.binds(p, i, note, c, uncertain);
            if uncertain {
                plan.binds = binds;
            }
        }
        plan.shape = match kind {
            ShapeKind::Fixed(s) => s,
            ShapeKind::Get(_, _) if c.output.windows(3).any(|w| w == b"ERR") => Shape::Exact,
            ShapeKind::Get(ids, uncertain) => get_shape(p, &ids, &c.output, uncertain || !homed, wide),
            ShapeKind::Block(uncertain) => {
                let size = c.layout.as_ref().map(|l| l.feedback().size());
                // (a bare `*`, the acknowledgement of a block that asks for no feedback, holds
                // no value: judged exactly, it is what tells a hand that sends feedback for `c`)
                if wide
                    && c.output.first() == Some(&gcl_model::realtime::FEEDBACK_HEADER)
                    && c.output.len() > 1
                    && size != Some(c.output.len())
                {
                    return Err(NotACase("a block answer that is not a feedback block".into()));
                }
                Shape::Block(block_rules(p, c, uncertain, wide))
            }
        };
    }
    walked.features.extend(relations.features);
    Ok(())
}

/// Takes the shaped case, the model's answers and where the stops decisions begin; gives the
/// case: its transcript, features, EEPROM writes and the decisions of each step.
fn case_stage(
    p: &Arc<Profile>,
    walked: Walked,
    caps: &[Captured],
    stops_at: Option<usize>,
    preamble: Option<&super::preamble::Ran>,
) -> Result<BuiltCase, NotACase> {
    let def = &walked.def;
    let eeprom_writes = def
        .plans
        .iter()
        .filter(|pl| match &pl.step.action {
            gcl_transcript::script::Action::Line(l) => match parse_line(p, l) {
                Ok(Line::Command(c)) => matches!(c.kind(p), CommandKind::MotorSave | CommandKind::GlobalSave),
                _ => false,
            },
            _ => false,
        })
        .count();
    let mut step_decisions = match preamble {
        Some(ran) => ran.decisions.then(p, &def.plans, caps),
        None => crate::suite::depends::decisions_by_step(p, &def.plans, caps),
    };
    let transcript =
        build_after(p, def, caps, &step_decisions, preamble.and_then(|r| r.built.as_ref())).map_err(NotACase)?;
    if let Some(at) = stops_at.and_then(|at| step_decisions.len().checked_sub(1).map(|last| at.min(last))) {
        for id in STOP_DECISIONS.iter().filter(|id| p.decisions.iter().any(|d| d.id == **id)) {
            if !step_decisions[at].iter().any(|d| d == id) {
                step_decisions[at].push(id.to_string());
            }
        }
    }
    Ok(BuiltCase {
        transcript,
        features: walked.features,
        eeprom_writes,
        model: crate::align::ModelRun::default(),
        checked: false,
        block_bytes: walked.block_bytes,
        step_decisions,
        action_steps: walked.action_steps,
    })
}

/// The decisions of where the model's motion ends: its joint stops (`[hand]` constants the
/// seed does not fix). State decisions: a later answer reads where a motion ended.
const STOP_DECISIONS: [&str; 2] = ["seed-motion-model", "bh8-position-bounds"];

/// The first step the model answers otherwise once its joint stops lie at the end of P's
/// range, if any: from there on the case's answers rest on where the stops are.
fn rests_on_stops(p: &Arc<Profile>, plans: &[Plan], caps: &[Captured]) -> Option<usize> {
    let mut free = (**p).clone();
    let far = p.param_id("P").map_or(free.hand.finger_limit, |id| p.param(id).max);
    free.hand.finger_limit = free.hand.finger_limit.max(far);
    free.hand.spread_limit = free.hand.spread_limit.max(far);
    capture_plan(&Arc::new(free), plans)
        .map_or(Some(0), |other| other.iter().zip(caps).position(|(a, b)| a.output != b.output))
}

/// LFAP of a feedback block within MPE (3 × MPE after ^C mid-motion) of the model's; with
/// `wide` after motion, LFAP, LFV, LFDP and LFBP anywhere in their fields.
fn block_rules(p: &Profile, c: &Captured, uncertain: bool, wide: bool) -> Vec<FieldRule> {
    let Some(layout) = &c.layout else { return Vec::new() };
    if wide && uncertain {
        let any = Some((i64::MIN / 2, i64::MAX / 2));
        return layout
            .feedback()
            .fields()
            .iter()
            .filter(|f| matches!(f.name(), "LFAP" | "LFV" | "LFDP" | "LFBP"))
            .filter_map(|f| {
                let name = ["LFAP", "LFV", "LFDP", "LFBP"].into_iter().find(|n| *n == f.name())?;
                Some(FieldRule { motor: f.motor(), name, range: any })
            })
            .collect();
    }
    let Ok((_, values)) = layout.feedback().decode(&c.output) else { return Vec::new() };
    (1..=4u8)
        .filter_map(|m| {
            let v = layout.feedback().value_of(&values, Some(m), "LFAP")?;
            let band = if uncertain { 3 * mpe(p, m) } else { mpe(p, m) };
            Some(FieldRule { motor: Some(m), name: "LFAP", range: Some((v - band, v + band)) })
        })
        .collect()
}

/// Whether a command addresses every motor: its prefix, else the motors EN selects.
fn moves_all(p: &Profile, c: &gcl_model::Command, shadow: &Device) -> bool {
    match c.prefix {
        Some(set) => (1..=4u8).all(|m| set.contains(m)),
        None => p.role(Role::Enabled).is_none_or(|id| (1..=4u8).all(|m| shadow.effective(id, m) != 0)),
    }
}

/// Coverage features of a line as the model's grammar reads it.
fn note_line(p: &Profile, line: &str, f: &mut BTreeSet<String>) {
    match parse_line(p, line.as_bytes()) {
        Ok(Line::Empty) => {
            f.insert("command:(empty line)".into());
        }
        Ok(Line::Command(c)) => {
            let name = &p.command(c.command).name;
            f.insert(format!("command:{name}"));
            f.insert(format!("prefix:{}", c.prefix.map_or("none".to_string(), |m| m.to_string())));
            match &c.args {
                Args::Names(ids) => ids.iter().for_each(|id| {
                    f.insert(format!("param-read:{}", p.param(*id).name));
                }),
                Args::Pairs(ps) => ps.iter().for_each(|(id, _)| {
                    f.insert(format!("param-write:{}", p.param(*id).name));
                }),
                _ => {}
            }
        }
        Err(r) => {
            for bit in r.status.iter() {
                f.insert(format!("status:{}", StatusBits::code(bit)));
            }
            f.insert(format!("refused:{}", r.status.code()));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wide_case(actions: &[HostAction]) -> Result<BuiltCase, NotACase> {
        build_case(&Profile::builtin("seed").unwrap(), actions, "t", "t", true, true)
    }

    fn block(header: u8, pause_ms: u64) -> HostAction {
        HostAction::Block { header, values: vec![10, 10, 10, 10], extra: 0, pause_ms }
    }

    #[test]
    fn a_block_that_asks_for_no_feedback_is_judged_on_a_hand_outside_this_process() {
        // The bare `*` holds no value: a hand that sends feedback for `c` must meet it.
        let b = wide_case(&[HostAction::Line("LOOP".into()), block(b'c', 0), block(b'A', 20), HostAction::Abort])
            .expect("a case with a `c` block");
        let text = b.transcript.to_text();
        let answer = text.lines().skip_while(|l| *l != "send hex 63 0A 0A 0A 0A").nth(1).unwrap_or_default();
        assert!(answer.starts_with("expect ") && answer.ends_with(" hex 2A"), "{text}");
    }

    /// The `FGET P` answer of a wide case that runs a RealTime session, then `motion`, then
    /// reads P; and P's whole range as the answer writes it.
    fn p_read_after_a_session_and(motion: &str) -> (String, String) {
        let b = wide_case(&[
            HostAction::Line("LOOP".into()),
            block(b'C', 0),
            block(b'A', 30),
            HostAction::Abort,
            HostAction::Line(motion.into()),
            HostAction::Line("FGET P".into()),
        ])
        .expect("a case");
        let text = b.transcript.to_text();
        let read = text.lines().skip_while(|l| *l != "send \"FGET P\\r\"").nth(1).unwrap_or_default().to_string();
        let p = Profile::builtin("seed").unwrap();
        let spec = p.param(p.param_id("P").unwrap());
        (read, format!("{{int {}..{}}}", spec.min, spec.max))
    }

    #[test]
    fn a_step_from_an_uncertain_position_leaves_it_uncertain() {
        // IC steps from where the motors are: after a RealTime session that is the hand's
        // clock's position, not the model's (the unmutated sim in fast time, over exec, read
        // 160 where the model's band was 165..215).
        let (read, whole) = p_read_after_a_session_and("IC");
        assert_eq!(read.matches(&whole).count(), 4, "{read}");
    }

    #[test]
    fn a_motion_of_some_motors_leaves_the_others_positions_uncertain() {
        // After a RealTime session the hand's positions are its clock's; a motion of motor 2
        // alone brings back motor 2's, not the others'.
        let (read, whole) = p_read_after_a_session_and("2IC");
        // (motor 1 did not move since the session: a band around the model's position would
        // fail a hand whose clock ran otherwise)
        assert!(read.find('{').is_some_and(|at| read[at..].starts_with(&whole)), "{read}");
    }

    /// The answer line after `send "LINE\r"` in a case's transcript.
    fn answer_to(b: &BuiltCase, line: &str) -> String {
        let text = b.transcript.to_text();
        let sent = format!("send \"{line}\\r\"");
        text.lines().skip_while(|l| *l != sent).nth(1).unwrap_or_default().to_string()
    }

    fn decisions(b: &BuiltCase) -> Vec<String> {
        crate::suite::decisions_of_header(&b.transcript.header)
    }

    #[test]
    fn a_hand_outside_this_process_says_its_own_version_and_reads_its_own_strain_at_rest() {
        // The seed hand of harness/tests/hands said "GCL seed hand 0.1" to VERS and 0 for the
        // spread's strain at rest: neither is fixed by the seed, and the suite's cmd-vers and
        // FGET SG cases accept any. In this process the model is the hand, so both stay exact.
        let actions = [HostAction::Line("VERS".into()), HostAction::Line("FGET SG".into())];
        let wide = wide_case(&actions).expect("a case");
        assert!(answer_to(&wide, "VERS").contains("{text}"), "{}", answer_to(&wide, "VERS"));
        // Its own text, but text: a hand that answers VERS with a status does not have it.
        let vers = wide.transcript.steps.iter().find(|s| s.send.as_ref().is_some_and(|h| h.bytes == b"VERS\r"));
        let vers = &vers.expect("a VERS step").expect;
        assert!(vers.matches(b"VERS\n\rGCL seed hand 0.1\n\r=> "));
        assert!(!vers.matches(b"VERS\n\rERR 64\n\r=> "));
        assert_eq!(answer_to(&wide, "FGET SG").matches("{int 0..255}").count(), 4, "{}", answer_to(&wide, "FGET SG"));
        let here = build_case(&Profile::builtin("seed").unwrap(), &actions, "t", "t", false, true).expect("a case");
        assert!(!answer_to(&here, "VERS").contains('{'), "{}", answer_to(&here, "VERS"));
        assert!(!answer_to(&here, "FGET SG").contains("0..255"), "{}", answer_to(&here, "FGET SG"));
    }

    #[test]
    fn a_case_whose_answers_rest_on_the_joint_stops_names_the_motion_decision() {
        // After C, IC drives the fingers past the model's joint stop (17800): where the stop is
        // is the model's hand constant, so the case rests on seed-motion-model (INFO) and a
        // hand with its stop elsewhere is no MUST finding. C alone stops short of the stop.
        let past = wide_case(&[HostAction::Line("C".into()), HostAction::Line("IC".into())]).expect("a case");
        assert!(decisions(&past).iter().any(|d| d == "seed-motion-model"), "{:?}", decisions(&past));
        // (A finding of it says so: `fuzz::device`'s `a_finding_past_the_joint_stop_is_info`.)
        // IO from the open stop ends short of its goal: the model's 16 is the same decision's.
        let open = wide_case(&[HostAction::Line("2IO".into())]).expect("a case");
        assert!(decisions(&open).iter().any(|d| d == "seed-motion-model"), "{:?}", decisions(&open));
        let short = wide_case(&[HostAction::Line("C".into()), HostAction::Line("FGET P".into())]).expect("a case");
        assert!(!decisions(&short).iter().any(|d| d == "seed-motion-model"), "{:?}", decisions(&short));
    }

    #[test]
    fn a_control_byte_and_an_err_code_out_of_range_rest_on_their_open_decisions() {
        // The seed hand dropped a form feed before IO and printed nothing for ERR 65536: the
        // first is framing-backspace's (no line editing), the second the ERR decision's range.
        let ff = wide_case(&[HostAction::Line("\x0cIO".into())]).expect("a case");
        assert!(decisions(&ff).iter().any(|d| d == "framing-backspace"), "{:?}", decisions(&ff));
        let err = wide_case(&[HostAction::Line("ERR 65536".into())]).expect("a case");
        assert!(decisions(&err).iter().any(|d| d == "seed-err-command"), "{:?}", decisions(&err));
        let io = wide_case(&[HostAction::Line("IO".into())]).expect("a case");
        assert!(!decisions(&io).iter().any(|d| d == "framing-backspace"), "{:?}", decisions(&io));
    }
}
