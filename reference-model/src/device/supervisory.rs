//! Supervisory mode: running a parsed command line, the parameters the behaviour reads, and
//! the fault hooks that bend it.

use super::*;

impl Device {
    /// Runs one command line. The faults that bend the grammar are parse options; the rest
    /// are read here, at the hooks named by their `self.has(...)`.
    pub(super) fn run_line(&mut self, line: &[u8]) {
        let opts = ParseOptions {
            case_sensitive_commands: self.has(Fault::LowercaseRejected),
            ignore_forbidden_prefix: self.has(Fault::PrefixNotRefused),
            drop_last_name_without_value: self.has(Fault::MissingValueIgnored),
            accept_one_past_max: self.has(Fault::RangeOffByOne),
            g_includes_spread: self.has(Fault::GIncludesSpread),
        };
        if self.has(Fault::TabNotSeparator) && line.contains(&b'\t') {
            return self.end_line(StatusBits::UNKNOWN_COMMAND);
        }
        match grammar::parse_line_with(&self.profile, line, opts) {
            Ok(Line::Empty) if self.has(Fault::EmptyLineError) => self.end_line(StatusBits::UNKNOWN_COMMAND),
            Ok(Line::Empty) => {
                self.end_line(StatusBits::empty());
                if self.has(Fault::EmptyLineTwoPrompts) {
                    self.prompt();
                }
            }
            Ok(Line::Command(c)) => self.run_command(&c),
            Err(mut r) => {
                if self.has(Fault::UnknownCommand64) && r.status.contains(StatusBits::UNKNOWN_COMMAND) {
                    r.status = (r.status - StatusBits::UNKNOWN_COMMAND) | StatusBits::UNKNOWN_PARAMETER;
                }
                if self.has(Fault::UnknownParam128) && r.status.contains(StatusBits::UNKNOWN_PARAMETER) {
                    r.status = (r.status - StatusBits::UNKNOWN_PARAMETER) | StatusBits::INVALID_VALUE;
                }
                if self.has(Fault::PartialSetApplied)
                    && let Some(Command { prefix, args: Args::Pairs(pairs), .. }) = &r.partial
                {
                    let profile = self.profile.clone();
                    for (id, v) in pairs {
                        self.params.set_unchecked(&profile, *id, prefix.unwrap_or(MotorSet::ALL), *v);
                    }
                }
                if self.has(Fault::TooManyArgsSilent) && r.status == StatusBits::TOO_MANY_ARGUMENTS {
                    return self.end_line(StatusBits::empty());
                }
                if self.has(Fault::ReadOnlyStatus) && r.status.contains(StatusBits::READ_ONLY) {
                    r.status = (r.status - StatusBits::READ_ONLY) | StatusBits::INVALID_VALUE;
                }
                self.end_line(r.status)
            }
        }
    }

    pub(super) fn enabled_motors(&self) -> MotorSet {
        MotorSet::from_motors(Motor::ALL.into_iter().filter(|m| self.role(Role::Enabled, *m) != 0).map(Motor::number))
    }

    /// The value the hand's behaviour (not FGET) reads for `role` on `motor`: its parameter's
    /// (see [`Device::behaviour`]) or, in a profile without one, what the role declares its
    /// absence means ([`Profile::absent_value`]). The loader has checked that a role without
    /// an absent value is present wherever something reads it, so the last arm is only
    /// reached for a value nobody uses (a RealTime coefficient of a flag the profile lacks).
    pub(super) fn role(&self, role: Role, motor: Motor) -> i64 {
        match self.profile.role(role) {
            Some(id) => self.behaviour(id, motor),
            None => self.profile.absent_value(role, motor).unwrap_or_default(),
        }
    }

    /// A behaviour value the profile's `[hand]` table names by source (see
    /// [`Profile::hand_sources`]).
    pub(super) fn source(&self, source: ValueSource, motor: Motor) -> i64 {
        match source {
            ValueSource::Param(id) => self.behaviour(id, motor),
            ValueSource::Fixed(v) => v,
        }
    }

    pub(super) fn behaviour(&self, id: ParamId, motor: Motor) -> i64 {
        if self.ignores(id) {
            self.profile.default_for(id, motor.number())
        } else {
            self.params.get(&self.profile, id, motor.number())
        }
    }

    pub(super) fn ignores(&self, id: ParamId) -> bool {
        if self.without_effect.contains(&id) {
            return true;
        }
        if self.faults.is_empty() {
            return false;
        }
        let name = self.profile.param(id).name.as_str();
        self.faults.iter().any(|f| f.ignored_params().contains(&name))
    }

    /// The parameters as the hand's behaviour sees them (see [`Device::get`]).
    pub(super) fn behaviour_store(&self) -> std::borrow::Cow<'_, ParamStore> {
        if self.without_effect.is_empty() && self.faults.iter().all(|f| f.ignored_params().is_empty()) {
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

    /// Records a value the hand keeps in `role`'s parameter; a profile without one does not
    /// report it ([`Absence::Unreported`](crate::spec::Absence::Unreported)).
    pub(super) fn set_live(&mut self, role: Role, motor: Motor, v: i64) {
        if let Some(id) = self.id(role) {
            let profile = self.profile.clone();
            self.params.set_unchecked(&profile, id, MotorSet::from(motor), v);
        }
    }

    pub(super) fn limit(&self, m: Motor) -> i64 {
        if m == Motor::SPREAD { self.profile.hand.spread_limit } else { self.profile.hand.finger_limit }
    }

    pub(super) fn accel(&self, m: Motor) -> f64 {
        let a = self.role(Role::Acceleration, m).max(1) as f64;
        a * self.profile.hand.velocity_units_per_ms_per_accel * self.profile.hand.counts_per_ms_per_velocity_unit
    }

    pub(super) fn temperature(&mut self) -> i64 {
        let n = self.scenario.temperature_noise;
        let t = self.scenario.temperature + self.heat.round() as i64 + self.noise(n);
        if t > self.nv.peak_temperature {
            self.nv.peak_temperature = t;
        }
        t
    }

    pub(super) fn noise(&mut self, half_width: i64) -> i64 {
        if half_width <= 0 {
            return 0;
        }
        let span = (2 * half_width + 1) as u32;
        i64::from(self.rng.next_u32() % span) - half_width
    }

    pub(super) fn strain(&mut self, m: Motor) -> i64 {
        let hand = &self.profile.hand;
        let raw = self.motors[m].strain(*m.pick(&self.scenario.objects), hand.free_strain, hand.strain_per_count);
        let n = self.scenario.strain_noise;
        let v = (raw + self.noise(n)).clamp(0, 255);
        if self.role(Role::StrainFlip, m) != 0 { 255 - v } else { v }
    }

    /// The value FGET/PGET prints for a parameter and motor.
    pub(super) fn read_param(&mut self, id: ParamId, m: Motor) -> i64 {
        match self.profile.role_of(id) {
            Some(Role::Position) => self.motors[m].position(),
            Some(Role::State) => {
                if self.motors[m].initialized {
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
            Some(Role::Odometer) => (m.pick(&self.nv.odometer_counts) / 1000) as i64,
            _ => self.params.get(&self.profile, id, m.number()),
        }
    }

    pub(super) fn run_command(&mut self, c: &Command) {
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
                for m in motors.motors() {
                    let motor = &mut self.motors[m];
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
                            .map(|id| (id, Motor::ALL.map(|m| self.params.get(&profile, id, m.number()))))
                    })
                    .flatten();
                self.params.transfer(&profile, &mut self.nv, t, Scope::Motor, motors);
                if t == Transfer::Defaults && self.has(Fault::FdefWritesEeprom) {
                    self.params.transfer(&profile, &mut self.nv, Transfer::Save, Scope::Motor, motors);
                }
                if let Some((id, vals)) = keep_mcv {
                    for (m, v) in Motor::ALL.into_iter().zip(vals) {
                        self.params.set_unchecked(&profile, id, MotorSet::from(m), v);
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
                for id in self.listed(kind) {
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
                for id in self.listed(kind) {
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
            CommandKind::Version if self.has(Fault::VersUnknown) => self.end_line(StatusBits::UNKNOWN_COMMAND),
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

    /// The parameters a list command shows: the motor lists show motor parameters, the global
    /// lists global ones, and only the "all" lists show advanced ones. The seed's FLISTA/FLISTAV
    /// list every parameter (motor and hand) in FGET order; bh8-262 splits motor and global lists.
    pub(super) fn listed(&self, kind: CommandKind) -> Vec<ParamId> {
        let scope = if matches!(
            kind,
            CommandKind::MotorList
                | CommandKind::MotorListAll
                | CommandKind::MotorListValues
                | CommandKind::MotorListAllValues
        ) {
            Scope::Motor
        } else {
            Scope::Global
        };
        let all = matches!(
            kind,
            CommandKind::MotorListAll
                | CommandKind::GlobalListAll
                | CommandKind::MotorListAllValues
                | CommandKind::GlobalListAllValues
        );
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
    pub(super) fn value_line(&mut self, id: ParamId, motors: MotorSet, named: bool) -> String {
        let profile = self.profile.clone();
        let p = profile.param(id);
        let mut vals: Vec<(Motor, i64)> = Vec::with_capacity(4);
        match (p.scope, named) {
            (Scope::Global, true) => vals.push((Motor::F1, self.read_param(id, Motor::F1))),
            _ => {
                for m in motors.motors() {
                    vals.push((m, self.read_param(id, m)));
                }
            }
        }
        if Some(id) == self.id(Role::Position) && !named && !self.has(Fault::FgetPKeepsReported) {
            for (m, v) in &vals {
                self.motors[*m].reported = Some(*v);
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

    pub(super) fn overtemperature(&mut self) -> bool {
        let hand_status = self.profile.hand.overtemp_status;
        let otemp = self.role(Role::OverTemperature, Motor::F1);
        hand_status != 0 && otemp != 0 && self.temperature() > otemp
    }

    pub(super) fn start_motion(&mut self, kind: CommandKind, motors: MotorSet, c: &Command) {
        let profile = self.profile.clone();
        let hand = &profile.hand;
        if kind != CommandKind::Initialize
            && !self.has(Fault::UninitializedMoves)
            && motors.motors().any(|m| !self.motors[m].initialized)
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
        for m in motors.motors() {
            let p = self.motors[m].pos;
            let goal = match kind {
                CommandKind::Initialize => Goal::Initialize { settled_ms: 0, stall_ms: 0 },
                CommandKind::Close => Goal::Position { target: self.role(Role::CloseTarget, m) as f64, stall_ms: 0 },
                CommandKind::Open => Goal::Position { target: self.role(Role::OpenTarget, m) as f64, stall_ms: 0 },
                CommandKind::Move => Goal::Position {
                    target: arg.unwrap_or_else(|| self.role(Role::DefaultPosition, m)) as f64,
                    stall_ms: 0,
                },
                CommandKind::Home => Goal::Position { target: 0.0, stall_ms: 0 },
                CommandKind::IncrementalClose => Goal::Position {
                    target: p.round() + arg.unwrap_or_else(|| self.role(Role::DefaultStep, m)) as f64,
                    stall_ms: 0,
                },
                CommandKind::IncrementalOpen => Goal::Position {
                    target: p.round() - arg.unwrap_or_else(|| self.role(Role::DefaultStep, m)) as f64,
                    stall_ms: 0,
                },
                CommandKind::TorqueClose => Goal::Velocity { direction: 1.0, stall_ms: 0 },
                _ => Goal::Velocity { direction: -1.0, stall_ms: 0 },
            };
            if matches!(kind, CommandKind::Open | CommandKind::TorqueOpen) {
                self.set_live(Role::BreakawayDetected, m, 0);
                self.set_live(Role::BreakawayPosition, m, 0);
            }
            let motor = &mut self.motors[m];
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
    pub(super) fn abort_task(&mut self, _task: Task) {
        self.queue.clear();
        for m in Motor::ALL {
            if self.motors[m].goal.take().is_some() {
                self.motors[m].velocity = 0.0;
                self.motors[m].powered = self.role(Role::Hold, m) != 0;
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

    pub(super) fn power_cycle(&mut self) {
        let profile = self.profile.clone();
        let ram = self.params.clone();
        self.params = ParamStore::power_up(&profile, &mut self.nv);
        if self.has(Fault::ResetKeepsRam) {
            self.params = ram;
        }
        for m in self.motors.values_mut() {
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
}
