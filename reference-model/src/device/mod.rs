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

pub mod fault;
mod physics;

use std::collections::VecDeque;
use std::sync::Arc;
use std::time::Duration;

use rand_core::{RngCore, SeedableRng};
use serde::{Deserialize, Serialize};

pub use fault::{Fault, UnknownFault};
use physics::{Goal, Motor, Termination};

use crate::grammar::{self, Args, Command, Line, ParseOptions};
use crate::motor::MotorSet;
use crate::params::{NvMemory, ParamStore, Transfer};
use crate::realtime::{self, Control, ControlHeader, Feedback, MotorControl, RtFlag, RtLayout};
use crate::spec::{CommandKind, ParamId, Profile, Role, Scope};
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
}

/// The serial rate of a profile without a BAUD parameter: GCL's factory 9600 bit/s.
const BAUD_WITHOUT_PARAMETER: u32 = 9600;

/// The low-strain stop of a profile without LSG: above any strain byte, so it never trips.
const LOW_STRAIN_OFF: i64 = 256;

/// One physics tick, in nanoseconds.
const TICK_NS: u64 = 1_000_000;

/// A whole simulated grasper.
#[derive(Debug, Clone)]
pub struct Device {
    profile: Arc<Profile>,
    faults: Vec<Fault>,
    scenario: Scenario,
    rng: rand_pcg::Pcg32,
    nv: NvMemory,
    params: ParamStore,
    motors: [Motor; 4],
    state: State,
    line: Vec<u8>,
    overflow: bool,
    queue: VecDeque<u8>,
    events: VecDeque<Event>,
    /// Per-motor physics inputs, refreshed when a command or loop starts.
    limits: [physics::StepLimits; 4],
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
        let has = |f: Fault| config.faults.contains(&f);
        let eol = if has(Fault::CrLf) { b"\r\n".to_vec() } else { profile.framing.line_ending.as_bytes().to_vec() };
        let mut prompt = profile.framing.prompt.as_bytes().to_vec();
        if has(Fault::PromptNoSpace) {
            while prompt.last() == Some(&b' ') {
                prompt.pop();
            }
        }
        let motors = std::array::from_fn(|i| Motor::new(config.scenario.initial_positions[i] as f64));
        let mut d = Device {
            faults: config.faults,
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
            limits: [physics::StepLimits::default(); 4],
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
        self.faults.contains(&f)
    }

    /// The parameter that plays `role` in the hand's profile.
    fn id(&self, role: Role) -> Option<ParamId> {
        self.profile.role(role)
    }

    // ------------------------------------------------------------------ public surface

    /// The profile the hand runs.
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

    /// When the hand next needs [`Device::handle_timeout`] to make progress on its own (a
    /// running command), or `None` when it only waits for input.
    pub fn poll_timeout(&self) -> Option<Duration> {
        self.is_busy().then(|| Duration::from_nanos(self.next_tick_ns.max(self.now_ns)))
    }

    /// Runs a supervisory command in progress to completion, as fast as possible, and returns
    /// the time it completed. `limit` bounds the simulated time spent.
    pub fn run_until_idle(&mut self, limit: Duration) -> Duration {
        let end = self.now_ns.saturating_add(limit.as_nanos().min(u128::from(u64::MAX)) as u64);
        while let Some(t) = self.poll_timeout() {
            if t.as_nanos() as u64 > end {
                break;
            }
            self.advance(t);
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
        self.id(Role::Baud).map_or(BAUD_WITHOUT_PARAMETER, |id| (self.params.get(&self.profile, id, 1) * 100) as u32)
    }

    /// Present position of a motor (1..=4), rounded.
    pub fn position(&self, motor: u8) -> i64 {
        self.motors[(motor.clamp(1, 4) - 1) as usize].position()
    }

    /// Whether a motor has been initialised by HI.
    pub fn initialized(&self, motor: u8) -> bool {
        self.motors[(motor.clamp(1, 4) - 1) as usize].initialized
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

    // ------------------------------------------------------------------ time

    fn advance(&mut self, now: Duration) {
        let now_ns = now.as_nanos().min(u128::from(u64::MAX)) as u64;
        if now_ns <= self.now_ns {
            return;
        }
        let elapsed_ms = (now_ns - self.now_ns) / 1_000_000;
        self.nv.powered_ms = self.powered_at_boot_ms.saturating_add(now_ns / 1_000_000);
        let active = match self.state {
            State::Busy(_) => true,
            State::Loop(_) => self.loop_moving(),
            State::Idle => false,
        };
        if !active {
            self.heat = (self.heat - 0.0002 * elapsed_ms as f64).max(0.0);
            self.now_ns = now_ns;
            self.next_tick_ns = now_ns.saturating_add(TICK_NS);
            return;
        }
        while self.next_tick_ns <= now_ns {
            self.now_ns = self.next_tick_ns;
            self.next_tick_ns = self.next_tick_ns.saturating_add(TICK_NS);
            let moved = self.tick();
            if matches!(self.state, State::Loop(_)) && moved == 0 {
                // Every loop motor is still (pinned at a stop, or commanded to 0): nothing
                // changes until the next control block, so jump ahead.
                break;
            }
            if matches!(self.state, State::Idle) {
                // The command finished: queued input runs at this instant.
                self.drain_queue();
                if matches!(self.state, State::Idle) {
                    break;
                }
            }
        }
        if self.now_ns < now_ns {
            self.now_ns = now_ns;
            if self.next_tick_ns <= now_ns {
                self.next_tick_ns = now_ns.saturating_add(TICK_NS);
            }
        }
    }

    fn loop_moving(&self) -> bool {
        self.motors.iter().any(|m| m.rt_velocity != 0.0 || m.velocity != 0.0)
    }

    /// What one motor's physics needs from the parameters and the world. Parameters cannot
    /// change while a command runs or a loop is open, so this is computed when one starts.
    fn step_limits(&self, m: u8) -> physics::StepLimits {
        let profile = &self.profile;
        let hand = &profile.hand;
        let i = (m - 1) as usize;
        let vel_unit = hand.counts_per_ms_per_velocity_unit;
        let (mcv, mov) = (
            self.get(self.id(Role::CloseVelocity), m) as f64 * vel_unit,
            self.get(self.id(Role::OpenVelocity), m) as f64 * vel_unit,
        );
        physics::StepLimits {
            limit: self.limit(m),
            object: self.scenario.objects[i].map(|o| (o, hand.object_compliance)),
            accel: self.accel(m),
            close_speed: mcv,
            open_speed: mov,
            init_speed: self.id(Role::InitVelocity).map_or(mov, |id| self.behaviour(id, m) as f64 * vel_unit),
            tstop_ms: self.get(self.id(Role::StopTime), m).clamp(0, i64::from(u32::MAX)) as u32,
            settle_ms: hand.hi_settle_ms
                * self.id(Role::InitHoldTime).map_or(1, |id| self.behaviour(id, m).max(1) as u64),
            free_strain: hand.free_strain,
            strain_per_count: hand.strain_per_count,
            high_strain: self.get(self.id(Role::HighStrain), m),
            low_strain: self.id(Role::LowStrain).map_or(LOW_STRAIN_OFF, |id| self.behaviour(id, m)),
            breakaway: self.get(self.id(Role::Breakaway), m) != 0,
        }
    }

    fn refresh_limits(&mut self) {
        self.limits = std::array::from_fn(|i| self.step_limits((i + 1) as u8));
    }

    /// One millisecond of physics. Returns how many motors moved.
    fn tick(&mut self) -> u32 {
        let mut moving = 0;
        for i in 0..4 {
            let m = (i + 1) as u8;
            let before = self.motors[i].pos;
            let motor = &mut self.motors[i];
            let term = motor.step(self.limits[i]);
            let moved = (motor.pos - before).abs();
            if moved > 0.0 {
                moving += 1;
                self.nv.odometer_counts[i] = self.nv.odometer_counts[i].saturating_add(moved.round() as u64);
            }
            if let Some(t) = term {
                self.terminate_motor(m, t);
            }
        }
        self.heat += 0.0005 * f64::from(moving);
        if let State::Busy(task) = &self.state
            && task.motors.iter().all(|m| self.motors[(m - 1) as usize].goal.is_none())
        {
            self.finish_task();
        }
        moving
    }

    fn terminate_motor(&mut self, m: u8, t: Termination) {
        let i = (m - 1) as usize;
        let hold = self.get(self.id(Role::Hold), m) != 0;
        let goal = self.motors[i].goal.take();
        self.motors[i].velocity = 0.0;
        self.motors[i].powered = hold;
        if let Some(Goal::Initialize { .. }) = goal {
            if t == Termination::Goal {
                self.motors[i].finish_initialize();
            } else {
                // A HI that stalled before the open stop leaves the motor uninitialised.
                self.motors[i].initialized = false;
            }
            self.motors[i].powered = hold;
            return;
        }
        if t == Termination::Breakaway {
            let at = self.motors[i].position();
            self.set_live(self.id(Role::BreakawayDetected), m, 1);
            self.set_live(self.id(Role::BreakawayPosition), m, at);
        }
        let mpe = self.get(self.id(Role::PositionError), m);
        let missed = StatusBits::from_bits_truncate(self.profile.hand.missed_position_status);
        let position = self.motors[i].position();
        let ignore_mpe = self.faults.contains(&Fault::MpeIgnored);
        if let (State::Busy(task), Some(Goal::Position { target, .. })) = (&mut self.state, goal)
            && task.check_mpe
            && !ignore_mpe
            && (position - target.round() as i64).abs() > mpe
        {
            task.status |= missed;
        }
    }

    fn finish_task(&mut self) {
        let State::Busy(task) = std::mem::replace(&mut self.state, State::Idle) else { return };
        if task.kind == CommandKind::Initialize {
            for m in task.motors.iter() {
                self.motors[(m - 1) as usize].reported = None;
                self.set_live(self.id(Role::BreakawayDetected), m, 0);
                self.set_live(self.id(Role::BreakawayPosition), m, 0);
            }
        }
        self.end_line(task.status);
    }

    // ------------------------------------------------------------------ bytes

    fn input_byte(&mut self, b: u8) {
        match std::mem::replace(&mut self.state, State::Idle) {
            State::Busy(task) => {
                if b == self.profile.framing.abort {
                    self.abort_task(task);
                } else {
                    self.state = State::Busy(task);
                    if self.queue.len() < 2 * self.profile.framing.max_line + 4 {
                        self.queue.push_back(b);
                    }
                }
            }
            State::Loop(rt) => self.loop_byte(rt, b),
            State::Idle => self.line_byte(b),
        }
    }

    /// Runs the input that arrived while a command ran, until the queue is empty or a queued
    /// command starts running in turn.
    fn drain_queue(&mut self) {
        while !self.is_busy() {
            let Some(b) = self.queue.pop_front() else { break };
            self.input_byte(b);
        }
    }

    fn line_byte(&mut self, b: u8) {
        let framing = &self.profile.framing;
        if b == framing.abort {
            self.line.clear();
            self.overflow = false;
            self.last_status = StatusBits::empty();
            self.push_event(Event::LineDone(StatusBits::empty()));
            self.prompt();
        } else if b == framing.terminator {
            let line = std::mem::take(&mut self.line);
            let overflow = std::mem::replace(&mut self.overflow, false);
            if overflow && !self.has(Fault::OverlongLineRuns) {
                self.end_line(StatusBits::from_bits_truncate(framing.overlong_status));
            } else {
                self.run_line(&line);
            }
            self.line = line;
            self.line.clear();
        } else {
            if framing.echo && !self.has(Fault::NoEcho) {
                self.out.push(b);
            }
            if self.line.len() < framing.max_line {
                self.line.push(b);
            } else {
                self.overflow = true;
            }
        }
    }

    fn prompt(&mut self) {
        self.out.extend_from_slice(&self.eol);
        self.out.extend_from_slice(&self.prompt);
    }

    fn print_line(&mut self, text: &str) {
        self.out.extend_from_slice(&self.eol);
        self.out.extend_from_slice(text.as_bytes());
    }

    /// Ends a command: the status line if any, then the prompt.
    fn end_line(&mut self, status: StatusBits) {
        self.last_status = status;
        self.push_event(Event::LineDone(status));
        if !status.is_empty() {
            let text = format!("ERR {}", status.code());
            self.print_line(&text);
        }
        self.prompt();
    }

    fn push_event(&mut self, e: Event) {
        if self.events.len() >= MAX_EVENTS {
            self.events.pop_front();
        }
        self.events.push_back(e);
    }

    fn print_banner(&mut self) {
        self.push_event(Event::PoweredUp);
        for i in 0..self.profile.banner.len() {
            let l = self.profile.banner[i].clone();
            self.print_line(&l);
        }
        self.prompt();
    }

    // ------------------------------------------------------------------ supervisory

    fn run_line(&mut self, line: &[u8]) {
        let opts = ParseOptions { case_sensitive_commands: self.has(Fault::LowercaseRejected) };
        if self.has(Fault::TabNotSeparator) && line.contains(&b'\t') {
            return self.end_line(StatusBits::UNKNOWN_COMMAND);
        }
        match grammar::parse_line_with(&self.profile, line, opts) {
            Ok(Line::Empty) if self.has(Fault::EmptyLineError) => self.end_line(StatusBits::UNKNOWN_COMMAND),
            Ok(Line::Empty) => {
                self.last_status = StatusBits::empty();
                self.push_event(Event::LineDone(StatusBits::empty()));
                self.prompt();
            }
            Ok(Line::Command(mut c)) => {
                if self.has(Fault::GIncludesSpread) && prefix_text(&self.profile, line).contains(['G', 'g']) {
                    c.prefix = c.prefix.map(|p| p | MotorSet::single(4).unwrap_or_default());
                }
                self.run_command(&c)
            }
            Err(mut r) => {
                if self.has(Fault::UnknownCommand64) && r.status.contains(StatusBits::UNKNOWN_COMMAND) {
                    r.status = (r.status - StatusBits::UNKNOWN_COMMAND) | StatusBits::UNKNOWN_PARAMETER;
                }
                if self.has(Fault::UnknownParam128) && r.status.contains(StatusBits::UNKNOWN_PARAMETER) {
                    r.status = (r.status - StatusBits::UNKNOWN_PARAMETER) | StatusBits::INVALID_VALUE;
                }
                if self.has(Fault::PartialSetApplied) {
                    self.apply_valid_pairs(line);
                }
                if self.has(Fault::MissingValueIgnored)
                    && r.status == StatusBits::INVALID_VALUE
                    && let Some(cut) = self.without_last_name(line)
                {
                    return self.run_command(&cut);
                }
                if self.has(Fault::TooManyArgsSilent) && r.status == StatusBits::TOO_MANY_ARGUMENTS {
                    return self.end_line(StatusBits::empty());
                }
                if self.has(Fault::PrefixNotRefused) && r.status == StatusBits::PREFIX_NOT_ALLOWED {
                    let skip = line.len() - line.trim_ascii_start().len() + prefix_text(&self.profile, line).len();
                    if let Ok(Line::Command(c)) = grammar::parse_line(&self.profile, &line[skip..]) {
                        return self.run_command(&c);
                    }
                }
                if self.has(Fault::ReadOnlyStatus) && r.status.contains(StatusBits::READ_ONLY) {
                    r.status = (r.status - StatusBits::READ_ONLY) | StatusBits::INVALID_VALUE;
                }
                if self.has(Fault::RangeOffByOne)
                    && r.status == StatusBits::INVALID_VALUE
                    && let Some(c) = self.off_by_one_accepts(line)
                {
                    return self.run_command(&c);
                }
                self.end_line(r.status)
            }
        }
    }

    /// The missing-value-ignored fault: a set line with an odd token count, run without its
    /// last token.
    fn without_last_name(&self, line: &[u8]) -> Option<Command> {
        let text = std::str::from_utf8(line).ok()?;
        let toks: Vec<&str> = text.split_ascii_whitespace().collect();
        if toks.len() < 2 || !toks.len().is_multiple_of(2) {
            return None;
        }
        // A lone name: the set of nothing (parsed with a dummy pair, then emptied).
        let probe = format!("{} {} 0", toks[..toks.len() - 1].join(" "), toks[toks.len() - 1]);
        let text = if toks.len() == 2 { probe } else { toks[..toks.len() - 1].join(" ") };
        match grammar::parse_line(&self.profile, text.as_bytes()) {
            Ok(Line::Command(mut c)) if matches!(c.args, Args::Pairs(_)) => {
                if toks.len() == 2 {
                    c.args = Args::Pairs(Vec::new());
                }
                Some(c)
            }
            _ => None,
        }
    }

    /// The partial-set-applied fault: the pairs of a refused set line that parse alone.
    fn apply_valid_pairs(&mut self, line: &[u8]) {
        let Ok(text) = std::str::from_utf8(line) else { return };
        let mut toks = text.split_ascii_whitespace();
        let Some(head) = toks.next() else { return };
        let rest: Vec<&str> = toks.collect();
        let profile = self.profile.clone();
        for pair in rest.chunks(2) {
            let one = format!("{head} {}", pair.join(" "));
            if let Ok(Line::Command(c)) = grammar::parse_line(&profile, one.as_bytes())
                && let Args::Pairs(ps) = &c.args
            {
                for (id, v) in ps {
                    self.params.set_unchecked(&profile, *id, c.prefix.unwrap_or(MotorSet::ALL), *v);
                }
            }
        }
    }

    /// The range-off-by-one fault: a set whose only problem is a value one past a maximum.
    fn off_by_one_accepts(&self, line: &[u8]) -> Option<Command> {
        let text = std::str::from_utf8(line).ok()?;
        let mut toks: Vec<String> = text.split_ascii_whitespace().map(str::to_string).collect();
        let mut changed = false;
        for i in 1..toks.len() {
            if let (Some(id), Ok(v)) = (self.profile.param_id(&toks[i - 1]), toks[i].parse::<i64>()) {
                let p = self.profile.param(id);
                if p.values.is_none() && v == p.max + 1 {
                    toks[i] = p.max.to_string();
                    changed = true;
                }
            }
        }
        if !changed {
            return None;
        }
        let Ok(Line::Command(mut c)) = grammar::parse_line(&self.profile, toks.join(" ").as_bytes()) else {
            return None;
        };
        if let Args::Pairs(ps) = &mut c.args {
            for (id, v) in ps.iter_mut() {
                if *v == self.profile.param(*id).max && self.profile.param(*id).values.is_none() {
                    *v += 1;
                }
            }
        }
        Some(c)
    }

    fn enabled_motors(&self) -> MotorSet {
        match self.id(Role::Enabled) {
            Some(en) => MotorSet::from_motors((1..=4).filter(|m| self.behaviour(en, *m) != 0)),
            None => MotorSet::ALL,
        }
    }

    /// The value a parameter has for the hand's behaviour (not for FGET): what was set, or
    /// its factory value when a `*-ignored` fault makes the hand ignore it.
    fn get(&self, id: Option<ParamId>, motor: u8) -> i64 {
        id.map_or(0, |id| self.behaviour(id, motor))
    }

    fn behaviour(&self, id: ParamId, motor: u8) -> i64 {
        if self.ignores(id) { self.profile.default_for(id, motor) } else { self.params.get(&self.profile, id, motor) }
    }

    fn ignores(&self, id: ParamId) -> bool {
        let name = self.profile.param(id).name.as_str();
        self.faults.iter().any(|f| f.ignored_params().contains(&name))
    }

    /// The parameters as the hand's behaviour sees them (see [`Device::get`]).
    fn behaviour_store(&self) -> std::borrow::Cow<'_, ParamStore> {
        if self.faults.iter().all(|f| f.ignored_params().is_empty()) {
            return std::borrow::Cow::Borrowed(&self.params);
        }
        let mut store = self.params.clone();
        for id in self.profile.param_ids().filter(|id| self.ignores(*id)) {
            for m in 1..=4u8 {
                let v = self.profile.default_for(id, m);
                store.set_unchecked(&self.profile, id, MotorSet::single(m).unwrap_or_default(), v);
            }
        }
        std::borrow::Cow::Owned(store)
    }

    fn set_live(&mut self, id: Option<ParamId>, motor: u8, v: i64) {
        if let Some(id) = id {
            let profile = self.profile.clone();
            self.params.set_unchecked(&profile, id, MotorSet::single(motor).unwrap_or_default(), v);
        }
    }

    fn limit(&self, m: u8) -> i64 {
        if m == 4 { self.profile.hand.spread_limit } else { self.profile.hand.finger_limit }
    }

    fn accel(&self, m: u8) -> f64 {
        let a = self.get(self.id(Role::Acceleration), m).max(1) as f64;
        a * self.profile.hand.velocity_units_per_ms_per_accel * self.profile.hand.counts_per_ms_per_velocity_unit
    }

    fn temperature(&mut self) -> i64 {
        let n = self.scenario.temperature_noise;
        let t = self.scenario.temperature + self.heat.round() as i64 + self.noise(n);
        if t > self.nv.peak_temperature {
            self.nv.peak_temperature = t;
        }
        t
    }

    fn noise(&mut self, half_width: i64) -> i64 {
        if half_width <= 0 {
            return 0;
        }
        let span = (2 * half_width + 1) as u32;
        i64::from(self.rng.next_u32() % span) - half_width
    }

    fn strain(&mut self, m: u8) -> i64 {
        let i = (m - 1) as usize;
        let hand = &self.profile.hand;
        let raw = self.motors[i].strain(self.scenario.objects[i], hand.free_strain, hand.strain_per_count);
        let n = self.scenario.strain_noise;
        let v = (raw + self.noise(n)).clamp(0, 255);
        if self.get(self.id(Role::StrainFlip), m) != 0 { 255 - v } else { v }
    }

    /// The value FGET/PGET prints for a parameter and motor.
    fn read_param(&mut self, id: ParamId, m: u8) -> i64 {
        let i = (m.clamp(1, 4) - 1) as usize;
        match self.profile.role_of(id) {
            Some(Role::Position) => self.motors[i].position(),
            Some(Role::State) => {
                if self.motors[i].initialized {
                    0
                } else {
                    self.profile.hand.uninitialized_state_value
                }
            }
            Some(Role::Strain) => self.strain(m),
            Some(Role::Temperature) => self.temperature(),
            Some(Role::PeakTemperature) => self.nv.peak_temperature,
            Some(Role::UpSeconds) => (self.nv.powered_ms / 1000) as i64,
            Some(Role::SerialNumber) => self.nv.serial_number,
            Some(Role::Odometer) => (self.nv.odometer_counts[i] / 1000) as i64,
            _ => self.params.get(&self.profile, id, m),
        }
    }

    fn run_command(&mut self, c: &Command) {
        let profile = self.profile.clone();
        let spec = profile.command(c.command);
        let kind = spec.kind;
        let is_motion_like =
            kind.is_motion() || matches!(kind, CommandKind::Initialize | CommandKind::Terminate | CommandKind::Loop);
        let motors = match c.prefix {
            Some(p) => p,
            None if is_motion_like => self.enabled_motors(),
            None => MotorSet::ALL,
        };
        match kind {
            k if k.is_motion() || k == CommandKind::Initialize => self.start_motion(k, motors, c),
            CommandKind::Terminate => {
                let mut status = StatusBits::empty();
                for m in motors.iter() {
                    let motor = &mut self.motors[(m - 1) as usize];
                    if motor.initialized {
                        motor.powered = false;
                        motor.goal = None;
                        motor.velocity = 0.0;
                    } else {
                        status |= StatusBits::from_bits_truncate(profile.hand.terminate_uninitialized_status);
                    }
                }
                self.end_line(status);
            }
            CommandKind::Loop => self.start_loop(motors),
            CommandKind::MotorSet | CommandKind::GlobalSet => {
                if let Args::Pairs(pairs) = &c.args {
                    for (id, v) in pairs {
                        self.params.set_unchecked(&profile, *id, motors, *v);
                    }
                }
                self.end_line(StatusBits::empty());
            }
            CommandKind::MotorGet | CommandKind::GlobalGet => {
                // PGET prints one value per name; FGET one per selected motor (the seed's
                // BAUD, a hand value read through FGET, repeats).
                let motors =
                    if kind == CommandKind::GlobalGet { MotorSet::single(1).unwrap_or_default() } else { motors };
                if let Args::Names(names) = &c.args {
                    for id in names {
                        let line = self.value_line(*id, motors, false);
                        self.print_line(&line);
                    }
                }
                self.end_line(StatusBits::empty());
            }
            CommandKind::MotorDefaults | CommandKind::MotorLoad | CommandKind::MotorSave => {
                let t = match kind {
                    CommandKind::MotorDefaults => Transfer::Defaults,
                    CommandKind::MotorLoad => Transfer::Load,
                    _ => Transfer::Save,
                };
                let keep_mcv = (t == Transfer::Defaults && self.has(Fault::FdefSkipsMcv))
                    .then(|| {
                        self.id(Role::CloseVelocity)
                            .map(|id| (id, [1, 2, 3, 4].map(|m| self.params.get(&profile, id, m))))
                    })
                    .flatten();
                self.params.transfer(&profile, &mut self.nv, t, Scope::Motor, motors);
                if t == Transfer::Defaults && self.has(Fault::FdefWritesEeprom) {
                    self.params.transfer(&profile, &mut self.nv, Transfer::Save, Scope::Motor, motors);
                }
                if let Some((id, vals)) = keep_mcv {
                    for m in 1..=4u8 {
                        self.params.set_unchecked(
                            &profile,
                            id,
                            MotorSet::single(m).unwrap_or_default(),
                            vals[m as usize - 1],
                        );
                    }
                }
                self.end_line(StatusBits::empty());
            }
            CommandKind::GlobalDefaults | CommandKind::GlobalLoad | CommandKind::GlobalSave => {
                let t = match kind {
                    CommandKind::GlobalDefaults => Transfer::Defaults,
                    CommandKind::GlobalLoad => Transfer::Load,
                    _ => Transfer::Save,
                };
                self.params.transfer(&profile, &mut self.nv, t, Scope::Global, MotorSet::ALL);
                self.end_line(StatusBits::empty());
            }
            CommandKind::MotorList
            | CommandKind::MotorListAll
            | CommandKind::GlobalList
            | CommandKind::GlobalListAll => {
                let scope = if matches!(kind, CommandKind::MotorList | CommandKind::MotorListAll) {
                    Scope::Motor
                } else {
                    Scope::Global
                };
                let all = matches!(kind, CommandKind::MotorListAll | CommandKind::GlobalListAll);
                for id in self.listed(kind, scope, all) {
                    let p = profile.param(id);
                    let line = format!("{} {}  {}", p.name, if p.read_only { "RO" } else { "RW" }, p.description);
                    self.print_line(&line);
                }
                self.end_line(StatusBits::empty());
            }
            CommandKind::MotorListValues
            | CommandKind::MotorListAllValues
            | CommandKind::GlobalListValues
            | CommandKind::GlobalListAllValues => {
                let scope = if matches!(kind, CommandKind::MotorListValues | CommandKind::MotorListAllValues) {
                    Scope::Motor
                } else {
                    Scope::Global
                };
                let all = matches!(kind, CommandKind::MotorListAllValues | CommandKind::GlobalListAllValues);
                for id in self.listed(kind, scope, all) {
                    let line = self.value_line(id, motors, true);
                    self.print_line(&line);
                }
                self.end_line(StatusBits::empty());
            }
            CommandKind::Reset => {
                self.power_cycle();
            }
            CommandKind::ErrorText => {
                let bits = match c.args {
                    Args::Integer(n) => StatusBits::from_bits_truncate(n as u32),
                    _ => StatusBits::all(),
                };
                for l in bits.describe(&profile) {
                    self.print_line(&l);
                }
                self.end_line(StatusBits::empty());
            }
            CommandKind::Version => {
                for l in &profile.version {
                    self.print_line(l);
                }
                self.end_line(StatusBits::empty());
            }
            CommandKind::Help | CommandKind::HelpAll => {
                let topic = match c.args {
                    Args::Topic(t) => Some(t),
                    _ => None,
                };
                for (i, cmd) in profile.commands.iter().enumerate() {
                    let wanted = match topic {
                        Some(t) => t.0 as usize == i,
                        None => {
                            kind == CommandKind::HelpAll || !(profile.hand.help_lists_standard_only && cmd.advanced)
                        }
                    };
                    if wanted {
                        self.print_line(&format!("{}  {}", cmd.name, cmd.help));
                    }
                }
                self.end_line(StatusBits::empty());
            }
            _ => self.end_line(StatusBits::UNKNOWN_COMMAND),
        }
    }

    /// The parameters a list command shows. The seed's FLISTA/FLISTAV list every parameter
    /// (motor and hand) in FGET order; bh8-262 splits motor and global lists.
    fn listed(&self, kind: CommandKind, scope: Scope, all: bool) -> Vec<ParamId> {
        let profile = &self.profile;
        let seed_style = matches!(kind, CommandKind::MotorListAll | CommandKind::MotorListAllValues)
            && profile.command_of_kind(CommandKind::GlobalList).is_none();
        profile
            .param_ids()
            .filter(|id| {
                let p = profile.param(*id);
                (seed_style || p.scope == scope) && (all || !p.advanced)
            })
            .collect()
    }

    /// One FGET-style line: values for the motors in order (globals once). With `named`, the
    /// parameter's name first (the list commands).
    fn value_line(&mut self, id: ParamId, motors: MotorSet, named: bool) -> String {
        let profile = self.profile.clone();
        let p = profile.param(id);
        let mut vals: Vec<(u8, i64)> = Vec::with_capacity(4);
        match (p.scope, named) {
            (Scope::Global, true) => vals.push((1, self.read_param(id, 1))),
            _ => {
                for m in motors.iter() {
                    vals.push((m, self.read_param(id, m)));
                }
            }
        }
        if Some(id) == self.id(Role::Position) && !named && !self.has(Fault::FgetPKeepsReported) {
            for (m, v) in &vals {
                self.motors[(*m - 1) as usize].reported = Some(*v);
            }
        }
        if self.has(Fault::FgetReversed) && !named {
            vals.reverse();
        }
        let mut s = String::new();
        if named {
            s.push_str(&p.name);
        }
        for (i, (_, v)) in vals.iter().enumerate() {
            if i > 0 || named {
                s.push(' ');
            }
            s.push_str(&v.to_string());
        }
        s
    }

    fn overtemperature(&mut self) -> bool {
        let hand_status = self.profile.hand.overtemp_status;
        let otemp = self.get(self.id(Role::OverTemperature), 1);
        hand_status != 0 && otemp != 0 && self.temperature() > otemp
    }

    fn start_motion(&mut self, kind: CommandKind, motors: MotorSet, c: &Command) {
        let profile = self.profile.clone();
        let hand = &profile.hand;
        if kind != CommandKind::Initialize
            && !self.has(Fault::UninitializedMoves)
            && motors.iter().any(|m| !self.motors[(m - 1) as usize].initialized)
        {
            return self.end_line(StatusBits::from_bits_truncate(hand.uninitialized_status));
        }
        if kind.is_motion() && self.overtemperature() {
            return self.end_line(StatusBits::from_bits_truncate(hand.overtemp_status));
        }
        if motors.is_empty() {
            return self.end_line(StatusBits::empty());
        }
        let arg = match c.args {
            Args::Integer(v) => Some(v),
            _ => None,
        };
        for m in motors.iter() {
            let i = (m - 1) as usize;
            let p = self.motors[i].pos;
            // The loader requires both targets of a profile without CT.
            let finger_ct = hand.finger_close_target.unwrap_or_default();
            let spread_ct = hand.spread_close_target.unwrap_or_default();
            let goal = match kind {
                CommandKind::Initialize => Goal::Initialize { settled_ms: 0, stall_ms: 0 },
                CommandKind::Close => Goal::Position {
                    target: self
                        .id(Role::CloseTarget)
                        .map_or(if m == 4 { spread_ct } else { finger_ct }, |id| self.behaviour(id, m))
                        as f64,
                    stall_ms: 0,
                },
                CommandKind::Open => {
                    Goal::Position { target: self.get(self.id(Role::OpenTarget), m) as f64, stall_ms: 0 }
                }
                CommandKind::Move => Goal::Position {
                    target: arg.unwrap_or_else(|| self.get(self.id(Role::DefaultPosition), m)) as f64,
                    stall_ms: 0,
                },
                CommandKind::Home => Goal::Position { target: 0.0, stall_ms: 0 },
                CommandKind::IncrementalClose => Goal::Position {
                    target: p.round() + arg.unwrap_or_else(|| self.get(self.id(Role::DefaultStep), m)) as f64,
                    stall_ms: 0,
                },
                CommandKind::IncrementalOpen => Goal::Position {
                    target: p.round() - arg.unwrap_or_else(|| self.get(self.id(Role::DefaultStep), m)) as f64,
                    stall_ms: 0,
                },
                CommandKind::TorqueClose => Goal::Velocity { direction: 1.0, stall_ms: 0 },
                _ => Goal::Velocity { direction: -1.0, stall_ms: 0 },
            };
            if matches!(kind, CommandKind::Open | CommandKind::TorqueOpen) {
                self.set_live(self.id(Role::BreakawayDetected), m, 0);
                self.set_live(self.id(Role::BreakawayPosition), m, 0);
            }
            let motor = &mut self.motors[i];
            motor.goal = Some(goal);
            motor.powered = true;
            motor.rt_velocity = 0.0;
        }
        self.state = State::Busy(Task {
            kind,
            motors,
            status: StatusBits::empty(),
            check_mpe: matches!(
                kind,
                CommandKind::Move | CommandKind::Home | CommandKind::IncrementalClose | CommandKind::IncrementalOpen
            ),
        });
        self.refresh_limits();
        self.next_tick_ns = self.now_ns.saturating_add(TICK_NS);
    }

    /// ^C while a command runs: the task is dropped, its moving motors stop.
    fn abort_task(&mut self, _task: Task) {
        self.queue.clear();
        for m in 1..=4u8 {
            let i = (m - 1) as usize;
            if self.motors[i].goal.take().is_some() {
                self.motors[i].velocity = 0.0;
                self.motors[i].powered = self.get(self.id(Role::Hold), m) != 0;
            }
        }
        self.state = State::Idle;
        let status = if self.has(Fault::AbortSilent) {
            StatusBits::empty()
        } else {
            StatusBits::from_bits_truncate(self.profile.hand.abort_status)
        };
        self.end_line(status);
    }

    fn power_cycle(&mut self) {
        let profile = self.profile.clone();
        let ram = self.params.clone();
        self.params = ParamStore::power_up(&profile, &mut self.nv);
        if self.has(Fault::ResetKeepsRam) {
            self.params = ram;
        }
        for m in &mut self.motors {
            m.power_down();
        }
        if matches!(self.state, State::Loop(_)) {
            self.push_event(Event::LoopLeft);
        }
        self.state = State::Idle;
        self.queue.clear();
        self.last_status = StatusBits::empty();
        if self.has(Fault::ResetNoBanner) {
            self.push_event(Event::PoweredUp);
            self.prompt();
        } else {
            self.print_banner();
        }
    }

    // ------------------------------------------------------------------ RealTime

    fn start_loop(&mut self, motors: MotorSet) {
        let profile = self.profile.clone();
        if motors.iter().any(|m| !self.motors[(m - 1) as usize].initialized) {
            return self.end_line(StatusBits::from_bits_truncate(profile.hand.uninitialized_status));
        }
        let layout = RtLayout::compute(&profile, &self.behaviour_store(), motors);
        for m in motors.iter() {
            let motor = &mut self.motors[(m - 1) as usize];
            if motor.reported.is_none() {
                motor.reported = Some(motor.position());
            }
            motor.rt_velocity = 0.0;
            motor.rt_gain = 0;
            motor.powered = true;
        }
        if self.has(Fault::LoopAckNewline) {
            self.out.extend_from_slice(&self.eol.clone());
        }
        self.out.push(realtime::FEEDBACK_HEADER);
        self.last_status = StatusBits::empty();
        self.state = State::Loop(Box::new(LoopState { layout, pending: None, data: Vec::with_capacity(16) }));
        self.push_event(Event::LoopEntered);
        self.refresh_limits();
    }

    /// One byte in RealTime mode. The loop's state is handed in (the hand is `Idle` meanwhile)
    /// and put back unless the byte ends the loop.
    fn loop_byte(&mut self, mut rt: Box<LoopState>, b: u8) {
        if rt.pending.is_some() {
            // `data` holds the header byte, then the control data so far.
            rt.data.push(b);
            if rt.data.len() >= rt.layout.control().size() {
                if let Ok(control) = Control::parse(rt.layout.control(), &rt.data) {
                    self.apply_control(&rt.layout, &control);
                }
                // The answer follows the whole block, as a hand reads a block before it
                // answers: no exchange beats the line's wire time in both directions.
                if rt.pending.is_some_and(|h| h.wants_feedback()) {
                    self.emit_feedback(&rt.layout);
                } else {
                    self.out.push(realtime::FEEDBACK_HEADER);
                }
                rt.pending = None;
                rt.data.clear();
            }
            self.state = State::Loop(rt);
            return;
        }
        match ControlHeader::from_byte(b) {
            Some(ControlHeader::Abort) => {
                self.leave_loop();
                self.prompt();
            }
            Some(h) => {
                self.last_status = StatusBits::empty();
                if h.has_data() && rt.layout.control().size() > 1 {
                    // Answered once the data is in (above).
                    rt.pending = Some(h);
                    rt.data.clear();
                    rt.data.push(h.byte());
                } else if h.wants_feedback() {
                    self.emit_feedback(&rt.layout);
                } else {
                    self.out.push(realtime::FEEDBACK_HEADER);
                }
                self.state = State::Loop(rt);
            }
            None => {
                let status = StatusBits::from_bits_truncate(self.profile.hand.bad_header_status);
                if self.has(Fault::StayInLoop) {
                    self.state = State::Loop(rt);
                    self.print_line(&format!("ERR {}", status.code()));
                    self.prompt();
                    self.last_status = status;
                } else {
                    self.leave_loop();
                    self.end_line(status);
                }
            }
        }
    }

    /// Ends the loop (its state already taken by [`Device::loop_byte`]).
    fn leave_loop(&mut self) {
        self.state = State::Idle;
        self.push_event(Event::LoopLeft);
        for m in &mut self.motors {
            m.rt_velocity = 0.0;
            m.velocity = 0.0;
        }
    }

    fn apply_control(&mut self, layout: &RtLayout, control: &Control) {
        let profile = self.profile.clone();
        let hand = &profile.hand;
        for m in layout.motors().iter() {
            let MotorControl { velocity, gain, torque } = control.motor(m);
            let i = (m - 1) as usize;
            if let Some(v) = velocity {
                let v = if self.has(Fault::LcvUnsigned) { i64::from(v as u8) } else { v };
                let lcvc = self.get(self.id(Role::VelocityCoefficient), m);
                self.motors[i].rt_velocity =
                    realtime::control_velocity(v, lcvc, hand.lcv_fraction_bits) * hand.rt_velocity_counts_per_ms;
            }
            if let Some(g) = gain {
                self.motors[i].rt_gain = g;
            }
            if let Some(t) = torque {
                self.motors[i].rt_velocity =
                    realtime::control_velocity(t, 1, hand.lcv_fraction_bits + 4) * hand.rt_velocity_counts_per_ms;
            }
            let has_gain = self.id(Role::ControlGain).is_some_and(|id| self.behaviour(id, m) != 0);
            self.motors[i].rt_uses_gain = has_gain;
        }
    }

    /// Sends a feedback block: one value per field of the layout, computed in wire order (the
    /// noise of strain and temperature is drawn in that order).
    fn emit_feedback(&mut self, layout: &RtLayout) {
        let profile = self.profile.clone();
        let hand = &profile.hand;
        let discard = self.get(self.id(Role::DeltaDiscard), 1) != 0;
        let mut feedback = Feedback::default();
        for f in layout.feedback().fields() {
            let i = f.motor().map_or(0, |m| usize::from(m.clamp(1, 4) - 1));
            let m = (i + 1) as u8;
            let v = match f.flag() {
                RtFlag::Lfv => {
                    let c = self.get(self.id(Role::FeedbackVelocityCoefficient), m).max(1) as f64;
                    (self.motors[i].velocity / hand.lfv_counts_per_ms / c).trunc() as i64
                }
                RtFlag::Lfs => self.strain(m),
                RtFlag::Lfap => {
                    let p = self.motors[i].position().clamp(0, 65535);
                    if self.faults.contains(&Fault::LittleEndianLfap) { ((p & 0xFF) << 8) | (p >> 8) } else { p }
                }
                RtFlag::Lfdp => {
                    let present = self.motors[i].position();
                    let c = self.get(self.id(Role::DeltaCoefficient), m);
                    let mut r = self.motors[i].reported.unwrap_or(present);
                    let q = if self.faults.contains(&Fault::LfdpNotClipped) {
                        let d = (present - r) / c.max(1);
                        r += d * c.max(1);
                        i64::from(d as i8)
                    } else {
                        i64::from(realtime::lfdp_step(&mut r, present, c, discard))
                    };
                    self.motors[i].reported = Some(r);
                    q
                }
                RtFlag::Lfbp => self.get(self.id(Role::BreakawayPosition), m),
                RtFlag::Lfain => self.scenario.analog_input[i],
                RtFlag::Lft => {
                    let t = self.temperature();
                    if f.size() == 1 && hand.lft_whole_degrees { t / 10 } else { t }
                }
                // Control flags never make a feedback field.
                RtFlag::Lcv | RtFlag::Lcpg | RtFlag::Lct => 0,
            };
            feedback.set(f, v);
        }
        feedback.emit_clamped(layout.feedback(), &mut self.out);
    }
}

/// The run of prefix characters a line starts with (after leading separators).
fn prefix_text(profile: &Profile, line: &[u8]) -> String {
    line.trim_ascii_start()
        .iter()
        .take_while(|b| b.is_ascii() && profile.prefix_motors(**b as char).is_some())
        .map(|b| *b as char)
        .collect()
}

#[cfg(test)]
mod tests;
