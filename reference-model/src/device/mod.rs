//! The simulated grasper: a sans-IO state machine of a whole hand.
//!
//! Bytes and time go in ([`Device::handle_input`], [`Device::handle_timeout`]); bytes come out
//! ([`Device::take_output`]). The device never reads a clock, never sleeps and never does I/O:
//! a transport (pty, TCP, stdio, the in-process target, a fuzzer, a test) owns those. The
//! same inputs at the same times give the same bytes; noise comes from a seeded generator.
//!
//! Time is monotonic: every `now` is the time since power-up, and a `now` earlier than the
//! time the hand has reached ([`Device::now`]) means "no time passed" (never an error, never
//! a step back). Time arithmetic saturates, so any `Duration` up to `Duration::MAX` is safe.
//!
//! Physics runs in 1 ms ticks, only while something moves.
//!
//! This file holds the hand's state and its public surface; the behaviour is split by
//! concern: `framing` (bytes in, lines out, events), `supervisory` (command lines and the
//! parameters behaviour reads), `realtime` (the loop's blocks), `time` (ticks and the end
//! of a command), `physics` (one motor's motion) and [`fault`] (the deliberate bugs).
//!
//! Besides the bytes, `poll_event()` tells what happened (power-up, line done with its status, loop
//! entered, loop left). Internally one `State` enum (`Idle`, `Busy(Task)`, `Loop(LoopState)`)
//! carries each activity's data; `mode()` is a query derived from it.
//!
//! In `realtime`, a `Control` comes in and a `Feedback` goes out, filled by an exhaustive match on
//! `RtFlag`. In `time`, ticks that only count (HI settling at the open stop) pass at once, as
//! do ticks that repeat the one before while a command runs (a motor cruising at full speed on
//! an exact grid, one blocked toward its stall: `physics`), bit for bit as the tick loop (the
//! board's heat over them in closed form, the same to far below TEMP's tenth of a degree), and
//! `handle_timeout_until_output`, which `SimLink` uses, runs a command's ticks up to its output in
//! one call, each as tick-by-tick calls would (`tests/it/time_jumps.rs`). The deliberate `Fault`s of
//! `fault` are framing, status, persistence and RealTime bugs, plus one `*-ignored` fault per
//! parameter with an effect, under which the hand behaves as if the parameter had its factory
//! value.

pub mod fault;
mod framing;
mod physics;
mod realtime;
mod supervisory;
mod time;

use std::collections::VecDeque;
use std::sync::Arc;
use std::time::Duration;

use rand_core::{RngCore, SeedableRng};
use serde::{Deserialize, Serialize};

pub use fault::{Fault, FaultSet, UnknownFault};
use physics::{Goal, Motor as Joint, Termination};

use crate::grammar::{self, Args, Command, Line, ParseOptions};
use crate::motor::{Motor, MotorSet, PerMotor};
use crate::params::{NvMemory, ParamStore, Transfer};
use crate::realtime::{Control, ControlHeader, Feedback, MotorControl, RtFlag, RtLayout};
use crate::spec::{CommandKind, ParamId, Profile, Role, Scope, ValueSource};
use crate::status::StatusBits;

/// Conditions in and around the hand that the protocol cannot set: objects, temperature,
/// where the joints are at power-up.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Scenario {
    /// For each motor 1..=4, the position where it meets an object when closing, if any.
    pub objects: [Option<i64>; 4],
    /// Ambient board temperature, tenths of °C.
    pub temperature: i64,
    /// Peak-to-peak half-width of temperature noise, tenths of °C.
    pub temperature_noise: i64,
    /// Half-width of strain noise, in strain counts.
    pub strain_noise: i64,
    /// Joint positions at power-up, counts.
    pub initial_positions: [i64; 4],
    /// RealTime analog input (LFAIN) per motor.
    pub analog_input: [i64; 4],
}

impl Default for Scenario {
    fn default() -> Scenario {
        Scenario {
            objects: [None; 4],
            temperature: 315,
            temperature_noise: 3,
            strain_noise: 2,
            initial_positions: [0; 4],
            analog_input: [0; 4],
        }
    }
}

/// Everything a device is built from besides its profile.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DeviceConfig {
    /// Seed of the noise generator.
    pub seed: u64,
    /// The world around the hand.
    pub scenario: Scenario,
    /// The EEPROM contents at power-up.
    pub nv: NvMemory,
    /// Deliberate bugs.
    pub faults: Vec<Fault>,
    /// Parameters stored as set but without effect on the hand's behaviour, which reads their
    /// factory values instead: not a bug of this model but a hypothesis about another hand (the
    /// device fuzzer replays a failing case on a model built so, to name the parameter whose
    /// setting the hand ignored). Empty for the hand the profile describes.
    pub without_effect: Vec<ParamId>,
}

/// What the hand is doing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Mode {
    /// Supervisory mode, waiting for a command line.
    Idle,
    /// Supervisory mode, a command running.
    Busy,
    /// RealTime mode.
    Loop,
}

/// Something that happened in the hand, reported by [`Device::poll_event`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Event {
    /// The hand powered up (or RESET): its banner and a prompt were written.
    PoweredUp,
    /// A command line finished with this status (empty: success); its prompt was written.
    LineDone(StatusBits),
    /// `LOOP` was accepted: the hand is in RealTime mode.
    LoopEntered,
    /// The hand left RealTime mode (^C, a bad header, RESET).
    LoopLeft,
}

/// How many events the hand keeps for [`Device::poll_event`] before it drops the oldest.
pub const MAX_EVENTS: usize = 64;

/// What the hand is doing, with the data each activity needs.
#[derive(Debug, Clone)]
enum State {
    /// Supervisory mode, waiting for a command line.
    Idle,
    /// Supervisory mode, a command running.
    Busy(Task),
    /// RealTime mode.
    Loop(Box<LoopState>),
}

#[derive(Debug, Clone)]
struct Task {
    kind: CommandKind,
    motors: MotorSet,
    status: StatusBits,
    check_mpe: bool,
}

#[derive(Debug, Clone)]
struct LoopState {
    layout: RtLayout,
    /// The header whose data is being received, and the data so far.
    pending: Option<ControlHeader>,
    data: Vec<u8>,
    /// What the blocks' arithmetic reads from the parameters, read once at LOOP: no parameter
    /// can change while the loop is open.
    params: PerMotor<LoopParams>,
    /// LFDPD: LFDP discards the clipped rest.
    discard: bool,
}

/// One motor's parameters as the loop's arithmetic reads them (see [`LoopState::params`]).
#[derive(Debug, Clone, Copy, Default)]
struct LoopParams {
    lcvc: i64,
    lfvc: i64,
    lfdpc: i64,
    uses_gain: bool,
}

/// One physics tick, in nanoseconds.
const TICK_NS: u64 = 1_000_000;

/// A whole simulated grasper.
#[derive(Debug, Clone)]
pub struct Device {
    profile: Arc<Profile>,
    faults: FaultSet,
    /// See [`DeviceConfig::without_effect`].
    without_effect: Vec<ParamId>,
    scenario: Scenario,
    rng: rand_pcg::Pcg32,
    nv: NvMemory,
    params: ParamStore,
    motors: PerMotor<Joint>,
    state: State,
    line: Vec<u8>,
    overflow: bool,
    queue: VecDeque<u8>,
    events: VecDeque<Event>,
    /// Per-motor physics inputs, refreshed when a command or loop starts.
    limits: PerMotor<physics::StepLimits>,
    out: Vec<u8>,
    /// Simulated time since power-up, ns.
    now_ns: u64,
    next_tick_ns: u64,
    /// Powered milliseconds in the EEPROM at power-up (UPSECS counts on from there).
    powered_at_boot_ms: u64,
    heat: f64,
    last_status: StatusBits,
    eol: Vec<u8>,
    prompt: Vec<u8>,
}

impl Device {
    /// Powers up a hand: it prints its banner and a prompt.
    pub fn new(profile: Arc<Profile>, config: DeviceConfig) -> Device {
        let mut nv = config.nv;
        let powered_at_boot_ms = nv.powered_ms;
        let params = ParamStore::power_up(&profile, &mut nv);
        // Faults of framing alone are patches of the profile the hand runs.
        let mut framing = profile.framing.clone();
        let faults: FaultSet = config.faults.into_iter().filter(|f| !f.patch_framing(&mut framing)).collect();
        let profile = if framing == profile.framing {
            profile
        } else {
            let mut patched = (*profile).clone();
            patched.framing = framing;
            Arc::new(patched)
        };
        let eol = profile.framing.line_ending.as_bytes().to_vec();
        let prompt = profile.framing.prompt.as_bytes().to_vec();
        let motors = PerMotor(config.scenario.initial_positions.map(|p| Joint::new(p as f64)));
        let mut d = Device {
            faults,
            without_effect: config.without_effect,
            rng: rand_pcg::Pcg32::seed_from_u64(config.seed),
            scenario: config.scenario,
            nv,
            params,
            motors,
            state: State::Idle,
            line: Vec::with_capacity(profile.framing.max_line),
            overflow: false,
            queue: VecDeque::new(),
            events: VecDeque::new(),
            limits: PerMotor([physics::StepLimits::default(); 4]),
            out: Vec::with_capacity(256),
            now_ns: 0,
            next_tick_ns: TICK_NS,
            powered_at_boot_ms,
            heat: 0.0,
            last_status: StatusBits::empty(),
            eol,
            prompt,
            profile,
        };
        d.print_banner();
        d
    }

    /// A powered-up hand of a built-in profile with default conditions.
    pub fn with_profile(profile: Arc<Profile>) -> Device {
        Device::new(profile, DeviceConfig::default())
    }

    fn has(&self, f: Fault) -> bool {
        self.faults.contains(f)
    }

    /// The parameter that plays `role` in the hand's profile.
    fn id(&self, role: Role) -> Option<ParamId> {
        self.profile.role(role)
    }

    // ------------------------------------------------------------------ public surface

    /// The profile the hand runs: the one it was built with, with the framing faults among
    /// its [`DeviceConfig::faults`] applied.
    pub fn profile(&self) -> &Arc<Profile> {
        &self.profile
    }

    /// Feeds bytes from the host, received at `now` (time since power-up).
    pub fn handle_input(&mut self, now: Duration, bytes: &[u8]) {
        self.advance(now);
        for &b in bytes {
            self.input_byte(b);
        }
    }

    /// Lets time pass to `now` with no input.
    pub fn handle_timeout(&mut self, now: Duration) {
        self.advance(now);
    }

    /// [`Device::handle_timeout`], stopping early at the first millisecond tick after which the
    /// hand has output waiting (its clock then stands at that tick): what a caller gets that
    /// calls `handle_timeout` at each [`Device::poll_timeout`] up to `now` and looks for output
    /// after each, in one call. Returns whether it stopped early.
    pub fn handle_timeout_until_output(&mut self, now: Duration) -> bool {
        self.advance_until(now, time::Stop::Output)
    }

    /// When the hand next needs [`Device::handle_timeout`] to make progress on its own (a
    /// running command), or `None` when it only waits for input.
    pub fn poll_timeout(&self) -> Option<Duration> {
        // (ticks that only count, such as HI settling at the open stop, need no call)
        let quiet = self.quiet_ticks().saturating_mul(TICK_NS);
        self.is_busy().then(|| Duration::from_nanos(self.next_tick_ns.saturating_add(quiet).max(self.now_ns)))
    }

    /// Runs a supervisory command in progress to completion, as fast as possible, and returns
    /// the time it completed. `limit` bounds the simulated time spent.
    pub fn run_until_idle(&mut self, limit: Duration) -> Duration {
        let end = self.now_ns.saturating_add(limit.as_nanos().min(u128::from(u64::MAX)) as u64);
        // (the ticks up to the command's end in one call, as one call per tick would run them)
        if self.poll_timeout().is_some_and(|t| t.as_nanos() as u64 <= end) {
            self.advance_until(Duration::from_nanos(end), time::Stop::NotBusy);
        }
        self.now()
    }

    /// Bytes written since the last call.
    pub fn take_output(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.out)
    }

    /// Appends the bytes written since the last call to `into`, keeping the hand's own buffer
    /// (no allocation in a steady exchange).
    pub fn drain_output(&mut self, into: &mut Vec<u8>) {
        into.extend_from_slice(&self.out);
        self.out.clear();
    }

    /// Bytes written and not yet taken.
    pub fn output(&self) -> &[u8] {
        &self.out
    }

    /// Forgets the bytes written so far.
    pub fn clear_output(&mut self) {
        self.out.clear();
    }

    /// The value the hand's behaviour reads for parameter `id` of `motor` (1..=4; any for a
    /// global): what is stored, or the factory value of a parameter stored but without effect
    /// (a fault, or [`DeviceConfig::without_effect`]). [`Device::params`] is what reads give.
    pub fn effective(&self, id: ParamId, motor: u8) -> i64 {
        match Motor::new(motor.clamp(1, 4)) {
            Some(m) => self.behaviour(id, m),
            None => self.params.get(&self.profile, id, motor),
        }
    }

    /// The simulated time the hand has reached.
    pub fn now(&self) -> Duration {
        Duration::from_nanos(self.now_ns)
    }

    /// What the hand is doing.
    pub fn mode(&self) -> Mode {
        match self.state {
            State::Idle => Mode::Idle,
            State::Busy(_) => Mode::Busy,
            State::Loop(_) => Mode::Loop,
        }
    }

    /// Whether a supervisory command is running.
    pub fn is_busy(&self) -> bool {
        matches!(self.state, State::Busy(_))
    }

    /// The next thing that happened in the hand since the last call, oldest first: a line
    /// done (with its status), the loop entered or left, a power-up. The hand keeps the last
    /// [`MAX_EVENTS`] events; older ones are dropped when nobody polls.
    pub fn poll_event(&mut self) -> Option<Event> {
        self.events.pop_front()
    }

    /// The status of the last finished command line (empty for success).
    pub fn last_status(&self) -> StatusBits {
        self.last_status
    }

    /// The RealTime layouts while in LOOP.
    pub fn rt_layout(&self) -> Option<&RtLayout> {
        match &self.state {
            State::Loop(rt) => Some(&rt.layout),
            State::Idle | State::Busy(_) => None,
        }
    }

    /// The working parameter values.
    pub fn params(&self) -> &ParamStore {
        &self.params
    }

    /// The EEPROM contents.
    pub fn nv(&self) -> &NvMemory {
        &self.nv
    }

    /// The serial rate the hand is set to, in bit/s.
    pub fn baud(&self) -> u32 {
        match self.profile.hand_sources().baud {
            ValueSource::Param(id) => (self.params.get(&self.profile, id, 1) * 100) as u32,
            ValueSource::Fixed(bits_per_s) => bits_per_s as u32,
        }
    }

    /// Present position of a motor (1..=4), rounded.
    pub fn position(&self, motor: Motor) -> i64 {
        self.motors[motor].position()
    }

    /// Whether a motor has been initialised by HI.
    pub fn initialized(&self, motor: Motor) -> bool {
        self.motors[motor].initialized
    }

    /// The world around the hand.
    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    /// Changes the world around the hand (objects, temperature) from now on.
    pub fn set_scenario(&mut self, scenario: Scenario) {
        self.scenario = scenario;
        self.refresh_limits();
    }
}
