//! Time: advancing the hand to a new instant, 1 ms physics ticks while something moves, and
//! the end of a running command. Stretches of ticks that only count, or that repeat the one
//! before for every motor (see `physics`), pass in one step; the tests below hold them to the
//! tick loop. Every `now` is monotonic and saturating (see the module
//! docs of [`super`]).

use super::*;

/// Where [`Device::advance_until`] stops early.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Stop {
    /// Never: it runs to the instant asked for.
    Never,
    /// At the first tick after which output is waiting.
    Output,
    /// At the first tick after which no command runs.
    NotBusy,
}

impl Device {
    pub(super) fn advance(&mut self, now: Duration) {
        self.advance_until(now, Stop::Never);
    }

    /// [`Device::advance`], stopping after the first tick that meets `stop` with the hand's
    /// clock at that tick: what a caller gets that advances tick by tick (to each
    /// [`Device::poll_timeout`]) and looks after each. Returns whether it stopped so.
    pub(super) fn advance_until(&mut self, now: Duration, stop: Stop) -> bool {
        let now_ns = now.as_nanos().min(u128::from(u64::MAX)) as u64;
        if now_ns <= self.now_ns {
            return false;
        }
        let elapsed_ms = (now_ns - self.now_ns) / 1_000_000;
        self.nv.powered_ms = self.powered_at_boot_ms.saturating_add(now_ns / 1_000_000);
        let active = match self.state {
            State::Busy(_) => true,
            State::Loop(_) => self.loop_moving(),
            State::Idle => false,
        };
        if !active {
            // Newton's cooling over the idle stretch, in closed form (nothing to do for a cold
            // board or within the same millisecond, the common case between idle commands).
            if self.heat > 0.0 && elapsed_ms > 0 {
                self.heat *= (-(elapsed_ms as f64) / (self.profile.hand.cooling_time_s * 1000.0)).exp();
            }
            self.now_ns = now_ns;
            self.next_tick_ns = now_ns.saturating_add(TICK_NS);
            return false;
        }
        while self.next_tick_ns <= now_ns {
            // Ticks in which only counters run (HI settling at the open stop) pass at once.
            let quiet = self.quiet_ticks();
            if quiet > 0 {
                let ticks = quiet.min((now_ns - self.next_tick_ns) / TICK_NS + 1);
                self.pass_quiet_ticks(ticks);
                self.now_ns = self.next_tick_ns.saturating_add((ticks - 1).saturating_mul(TICK_NS));
                self.next_tick_ns = self.now_ns.saturating_add(TICK_NS);
                continue;
            }
            // Ticks that repeat the one before (motors cruising at full speed, blocked, at rest)
            // pass at once too, up to the instant asked for.
            let left = (now_ns - self.next_tick_ns) / TICK_NS + 1;
            let steady = if left > 1 { self.steady_ticks(left) } else { None };
            if let Some((ticks, kinds)) = steady {
                self.pass_steady_ticks(ticks, kinds);
                self.now_ns = self.next_tick_ns.saturating_add((ticks - 1).saturating_mul(TICK_NS));
                self.next_tick_ns = self.now_ns.saturating_add(TICK_NS);
                continue;
            }
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
            }
            let stopped = match stop {
                Stop::Never => false,
                Stop::Output => !self.out.is_empty(),
                Stop::NotBusy => !matches!(self.state, State::Busy(_)),
            };
            if stopped {
                self.nv.powered_ms = self.powered_at_boot_ms.saturating_add(self.now_ns / 1_000_000);
                return true;
            }
            if matches!(self.state, State::Idle) {
                break;
            }
        }
        if stop == Stop::NotBusy {
            // (run tick by tick, the clock stays at the last tick that ran)
            self.nv.powered_ms = self.powered_at_boot_ms.saturating_add(self.now_ns / 1_000_000);
            return false;
        }
        if self.now_ns < now_ns {
            self.now_ns = now_ns;
            if self.next_tick_ns <= now_ns {
                self.next_tick_ns = now_ns.saturating_add(TICK_NS);
            }
        }
        false
    }

    pub(super) fn loop_moving(&self) -> bool {
        self.motors.iter().any(|(_, m)| m.rt_velocity != 0.0 || m.velocity != 0.0)
    }

    /// What one motor's physics needs from the parameters and the world. Parameters cannot
    /// change while a command runs or a loop is open, so this is computed when one starts.
    pub(super) fn step_limits(&self, m: Motor) -> physics::StepLimits {
        let profile = &self.profile;
        let hand = &profile.hand;
        let sources = profile.hand_sources();
        let vel_unit = hand.counts_per_ms_per_velocity_unit;
        physics::StepLimits {
            limit: self.limit(m),
            object: m.pick(&self.scenario.objects).map(|o| (o, hand.object_compliance)),
            accel: self.accel(m),
            close_speed: self.role(Role::CloseVelocity, m) as f64 * vel_unit,
            open_speed: self.role(Role::OpenVelocity, m) as f64 * vel_unit,
            init_speed: self.source(sources.hi_velocity, m) as f64 * vel_unit,
            tstop_ms: self.role(Role::StopTime, m).clamp(0, i64::from(u32::MAX)) as u32,
            settle_ms: hand.hi_settle_ms * self.source(sources.hi_hold_repetitions, m).max(1) as u64,
            free_strain: hand.free_strain,
            strain_per_count: hand.strain_per_count,
            high_strain: self.role(Role::HighStrain, m),
            low_strain: self.source(sources.low_strain_stop, m),
            breakaway: self.role(Role::Breakaway, m) != 0,
        }
    }

    pub(super) fn refresh_limits(&mut self) {
        self.limits = PerMotor(Motor::ALL.map(|m| self.step_limits(m)));
    }

    /// How many ticks from the next one on change nothing but counters, while a command runs:
    /// every motor of the hand still, or settling at the open stop during HI (a tick only counts
    /// its time there), up to the tick in which the first settling motor is done. The board
    /// only cools in them. 0 when the next tick may do more.
    pub(super) fn quiet_ticks(&self) -> u64 {
        if !matches!(self.state, State::Busy(_)) {
            return 0;
        }
        let mut quiet = u64::MAX;
        for m in Motor::ALL {
            let motor = &self.motors[m];
            match motor.goal {
                None if motor.rt_velocity == 0.0 && motor.velocity == 0.0 => {}
                // (the open stop is position 0: see `physics::Motor::step`)
                Some(physics::Goal::Initialize { settled_ms, .. }) if motor.pos <= 0.0 && motor.velocity == 0.0 => {
                    quiet = quiet.min(self.limits[m].settle_ms.saturating_sub(settled_ms.saturating_add(1)));
                }
                _ => return 0,
            }
        }
        if quiet == u64::MAX { 0 } else { quiet }
    }

    /// Passes `ticks` of [`Device::quiet_ticks`] as [`Device::tick`] would, one by one: each
    /// settling motor counts them, and the board cools by the same arithmetic.
    fn pass_quiet_ticks(&mut self, ticks: u64) {
        for m in Motor::ALL {
            let motor = &mut self.motors[m];
            if let Some(physics::Goal::Initialize { settled_ms, .. }) = motor.goal {
                motor.goal = Some(physics::Goal::Initialize { settled_ms: settled_ms + ticks, stall_ms: 0 });
            }
        }
        self.cool_ticks(ticks, 0);
    }

    /// [`Device::cool_tick`] `ticks` times over.
    fn cool_ticks(&mut self, ticks: u64, moving: u32) {
        let hand = &self.profile.hand;
        let cooling = hand.cooling_time_s * 1000.0;
        if self.heat.to_bits() == 0
            && moving == 0
            && hand.heat_per_motor_s.is_finite()
            && cooling != 0.0
            && !cooling.is_nan()
        {
            // (a cold board at rest stays cold: 0 + (0 - 0 / c) is 0 again, bit for bit)
            return;
        }
        let gain = hand.heat_per_motor_s / 1000.0 * f64::from(moving);
        if ticks > 1 && gain.is_finite() && cooling.is_finite() && cooling >= 1.0 {
            // In closed form: each tick is h + g - h / c, so after n ticks the board is at
            // g·c + (h - g·c)·(1 - 1/c)^n. It differs from the ticks' arithmetic in the last
            // bits only (TEMP reads it rounded to a tenth of a degree), and spares a division
            // per millisecond of every motion.
            let settle = gain * cooling;
            let keep = (ticks as f64 * (-1.0 / cooling).ln_1p()).exp();
            self.heat = settle + (self.heat - settle) * keep;
            return;
        }
        for _ in 0..ticks {
            self.cool_tick(moving);
        }
    }

    /// How many ticks from the next one on (at most `max`, and more than one) repeat the one
    /// before for every motor while a command runs, with what each motor's ticks do (see
    /// `physics::Motor::steady`); `None` when the next tick may do more, or when no motor has a
    /// goal left (that tick ends the command).
    fn steady_ticks(&self, max: u64) -> Option<(u64, PerMotor<physics::SteadyKind>)> {
        if !matches!(self.state, State::Busy(_)) {
            return None;
        }
        let mut ticks = max;
        let mut kinds = PerMotor([physics::SteadyKind::Rest; 4]);
        for m in Motor::ALL {
            let s = self.motors[m].steady(&self.limits[m], ticks)?;
            ticks = ticks.min(s.ticks);
            if ticks <= 1 {
                return None;
            }
            kinds[m] = s.kind;
        }
        let busy = kinds.iter().any(|(_, k)| *k != physics::SteadyKind::Rest);
        busy.then_some((ticks, kinds))
    }

    /// Passes `ticks` of [`Device::steady_ticks`] as [`Device::tick`] would, one by one: each
    /// motor moves, counts and wears its odometer as its ticks would, and the board heats and
    /// cools by the same arithmetic, tick by tick.
    fn pass_steady_ticks(&mut self, ticks: u64, kinds: PerMotor<physics::SteadyKind>) {
        let mut moving = 0;
        for m in Motor::ALL {
            let kind = kinds[m];
            if let physics::SteadyKind::Cruise(delta) = kind {
                moving += 1;
                let odometer = m.pick_mut(&mut self.nv.odometer_counts);
                *odometer = odometer.saturating_add((physics::round(delta.abs()) as u64).saturating_mul(ticks));
            }
            self.motors[m].pass_steady(kind, ticks);
        }
        self.cool_ticks(ticks, moving);
    }

    /// One millisecond of heating by `moving` motors and of cooling toward ambient: the board
    /// settles at moving × heat_per_motor_s × cooling_time_s tenths above ambient.
    fn cool_tick(&mut self, moving: u32) {
        let hand = &self.profile.hand;
        self.heat += hand.heat_per_motor_s / 1000.0 * f64::from(moving) - self.heat / (hand.cooling_time_s * 1000.0);
    }

    /// One millisecond of physics. Returns how many motors moved.
    pub(super) fn tick(&mut self) -> u32 {
        let mut moving = 0;
        for m in Motor::ALL {
            let before = self.motors[m].pos;
            let motor = &mut self.motors[m];
            let term = motor.step(&self.limits[m]);
            let moved = (motor.pos - before).abs();
            if moved > 0.0 {
                moving += 1;
                let odometer = m.pick_mut(&mut self.nv.odometer_counts);
                *odometer = odometer.saturating_add(physics::round(moved) as u64);
            }
            if let Some(t) = term {
                self.terminate_motor(m, t);
            }
        }
        self.cool_tick(moving);
        if let State::Busy(task) = &self.state
            && task.motors.motors().all(|m| self.motors[m].goal.is_none())
        {
            self.finish_task();
        }
        moving
    }

    pub(super) fn terminate_motor(&mut self, m: Motor, t: Termination) {
        let hold = self.role(Role::Hold, m) != 0;
        let goal = self.motors[m].goal.take();
        self.motors[m].velocity = 0.0;
        self.motors[m].powered = hold;
        if let Some(Goal::Initialize { .. }) = goal {
            if t == Termination::Goal {
                self.motors[m].finish_initialize();
            } else {
                // A HI that stalled before the open stop leaves the motor uninitialised.
                self.motors[m].initialized = false;
            }
            return;
        }
        if t == Termination::Breakaway {
            let at = self.motors[m].position();
            self.set_live(Role::BreakawayDetected, m, 1);
            self.set_live(Role::BreakawayPosition, m, at);
        }
        let mpe = self.role(Role::PositionError, m);
        let missed = StatusBits::from_bits_truncate(self.profile.hand.missed_position_status);
        let position = self.motors[m].position();
        let ignore_mpe = self.has(Fault::MpeIgnored);
        if let (State::Busy(task), Some(Goal::Position { target, .. })) = (&mut self.state, goal)
            && task.check_mpe
            && !ignore_mpe
            && (position - target.round() as i64).abs() > mpe
        {
            task.status |= missed;
        }
    }

    pub(super) fn finish_task(&mut self) {
        let State::Busy(task) = std::mem::replace(&mut self.state, State::Idle) else { return };
        if task.kind == CommandKind::Initialize {
            for m in task.motors.motors() {
                self.motors[m].reported = None;
                self.set_live(Role::BreakawayDetected, m, 0);
                self.set_live(Role::BreakawayPosition, m, 0);
            }
        }
        self.end_line(task.status);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs a command to its end one tick per iteration with none passed at once: the model's
    /// time as it was before quiet ticks passed at once.
    fn tick_by_tick(d: &mut Device) {
        while matches!(d.state, State::Busy(_)) {
            d.now_ns = d.next_tick_ns;
            d.next_tick_ns = d.next_tick_ns.saturating_add(TICK_NS);
            d.nv.powered_ms = d.powered_at_boot_ms.saturating_add(d.now_ns / 1_000_000);
            d.tick();
            if matches!(d.state, State::Idle) {
                d.drain_queue();
            }
        }
    }

    /// [`Device::advance_until`] as it was before any tick passed at once: one tick per
    /// iteration, every one of them run. The oracle of the ticks passed at once.
    fn advance_ticking(d: &mut Device, now: Duration, stop: Stop) -> bool {
        let now_ns = now.as_nanos().min(u128::from(u64::MAX)) as u64;
        if now_ns <= d.now_ns {
            return false;
        }
        let elapsed_ms = (now_ns - d.now_ns) / 1_000_000;
        d.nv.powered_ms = d.powered_at_boot_ms.saturating_add(now_ns / 1_000_000);
        let active = match d.state {
            State::Busy(_) => true,
            State::Loop(_) => d.loop_moving(),
            State::Idle => false,
        };
        if !active {
            if d.heat > 0.0 && elapsed_ms > 0 {
                d.heat *= (-(elapsed_ms as f64) / (d.profile.hand.cooling_time_s * 1000.0)).exp();
            }
            d.now_ns = now_ns;
            d.next_tick_ns = now_ns.saturating_add(TICK_NS);
            return false;
        }
        while d.next_tick_ns <= now_ns {
            d.now_ns = d.next_tick_ns;
            d.next_tick_ns = d.next_tick_ns.saturating_add(TICK_NS);
            let moved = d.tick();
            if matches!(d.state, State::Loop(_)) && moved == 0 {
                break;
            }
            if matches!(d.state, State::Idle) {
                d.drain_queue();
            }
            let stopped = match stop {
                Stop::Never => false,
                Stop::Output => !d.out.is_empty(),
                Stop::NotBusy => !matches!(d.state, State::Busy(_)),
            };
            if stopped {
                d.nv.powered_ms = d.powered_at_boot_ms.saturating_add(d.now_ns / 1_000_000);
                return true;
            }
            if matches!(d.state, State::Idle) {
                break;
            }
        }
        if stop == Stop::NotBusy {
            d.nv.powered_ms = d.powered_at_boot_ms.saturating_add(d.now_ns / 1_000_000);
            return false;
        }
        if d.now_ns < now_ns {
            d.now_ns = now_ns;
            if d.next_tick_ns <= now_ns {
                d.next_tick_ns = now_ns.saturating_add(TICK_NS);
            }
        }
        false
    }

    /// Everything of a hand that time changes, bit for bit (floats print exactly), less its
    /// profile and the board's heat (see [`same_heat`]).
    fn moving_state(d: &Device) -> String {
        format!(
            "{:?} {:?} {:?} now {} next {} out {:?} queue {:?} events {:?} {:?} {:?} {:?}",
            d.motors, d.state, d.nv, d.now_ns, d.next_tick_ns, d.out, d.queue, d.events, d.params, d.rng, d.limits
        )
    }

    /// Whether two boards are equally warm to far below TEMP's resolution (a tenth of a
    /// degree): the ticks passed at once heat and cool the board in closed form, which differs
    /// from the tick loop's arithmetic in the last bits.
    fn same_heat(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-9 * b.abs().max(1.0)
    }

    /// [`Device`]'s whole state, with the board's heat left out once [`same_heat`] holds.
    fn same_hand_but_heat(a: &Device, b: &Device) -> (String, String) {
        assert!(same_heat(a.heat, b.heat), "heat {} against {}", a.heat, b.heat);
        let (mut a, mut b) = (a.clone(), b.clone());
        (a.heat, b.heat) = (0.0, 0.0);
        (format!("{a:?}"), format!("{b:?}"))
    }

    /// What the host does next in [`motions_in_one_step_are_the_tick_loop`].
    #[derive(Debug, Clone)]
    enum Act {
        /// Sends bytes after this many ms.
        Send(u64, Vec<u8>),
        /// Lets this many ms pass.
        Wait(u64),
        /// Lets time pass up to the first output, at most this many ms.
        UntilOutput(u64),
        /// Runs the command to its end.
        Idle,
    }

    fn act() -> impl proptest::strategy::Strategy<Value = Act> {
        use proptest::prelude::*;
        let motors = prop::sample::select(vec!["", "1", "2", "3", "4", "S", "G", "12", "123"]);
        let command = prop_oneof![
            Just("HI".to_string()),
            Just("C".to_string()),
            Just("O".to_string()),
            Just("TC".to_string()),
            Just("TO".to_string()),
            Just("HOME".to_string()),
            (0i64..20_000).prop_map(|n| format!("M {n}")),
            (0i64..6000).prop_map(|n| format!("IC {n}")),
            (0i64..6000).prop_map(|n| format!("IO {n}")),
        ];
        let line = (motors, command).prop_map(|(m, c)| format!("{m}{c}\r").into_bytes());
        let set = (
            prop::sample::select(vec![
                "ACCEL", "MCV", "MOV", "TSTOP", "HSG", "LSG", "BS", "HOLD", "IVEL", "IHIT", "MPE",
            ]),
            prop_oneof![0i64..4, 1i64..300, Just(255), Just(256)],
        )
            .prop_map(|(p, v)| format!("FSET {p} {v}\r").into_bytes());
        let read = prop::sample::select(vec!["FGET P\r", "FGET TEMP\r", "FGET SG\r", "\x03"])
            .prop_map(|s| s.as_bytes().to_vec());
        prop_oneof![
            4 => (0u64..5, line).prop_map(|(t, l)| Act::Send(t, l)),
            2 => (0u64..5, set).prop_map(|(t, l)| Act::Send(t, l)),
            2 => (0u64..3000, read).prop_map(|(t, l)| Act::Send(t, l)),
            2 => (1u64..3000).prop_map(Act::Wait),
            2 => (1u64..3000).prop_map(Act::UntilOutput),
            3 => Just(Act::Idle),
        ]
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig { cases: 256, ..Default::default() })]

        /// The ticks passed at once (cruising, stalling, at rest, settling) leave the hand bit
        /// for bit as running every tick does, through random motions: any motor set, speed,
        /// acceleration, stall time, strain limits, objects in the way and starting positions,
        /// with reads, aborts and waits that stop anywhere in a motion.
        #[test]
        fn motions_in_one_step_are_the_tick_loop(
            profile in proptest::sample::select(vec!["seed", "bh8-262-4.4", "bh8-262-4.3"]),
            objects in proptest::array::uniform4(proptest::option::of(0i64..18_000)),
            initial in proptest::array::uniform4(0i64..18_000),
            acts in proptest::collection::vec(act(), 1..24),
        ) {
            let p = Profile::builtin(profile).unwrap();
            let scenario = Scenario { objects, initial_positions: initial, ..Scenario::default() };
            let mut a = Device::new(p, DeviceConfig { seed: 7, scenario, ..DeviceConfig::default() });
            let mut b = a.clone();
            for (i, act) in acts.iter().enumerate() {
                let (sa, sb) = match act {
                    Act::Send(ms, bytes) => {
                        let t = a.now() + Duration::from_millis(*ms);
                        a.handle_input(t, bytes);
                        advance_ticking(&mut b, t, Stop::Never);
                        for &x in bytes {
                            b.input_byte(x);
                        }
                        (false, false)
                    }
                    Act::Wait(ms) => {
                        let t = a.now() + Duration::from_millis(*ms);
                        a.handle_timeout(t);
                        advance_ticking(&mut b, t, Stop::Never);
                        (false, false)
                    }
                    Act::UntilOutput(ms) => {
                        let t = a.now() + Duration::from_millis(*ms);
                        (a.handle_timeout_until_output(t), advance_ticking(&mut b, t, Stop::Output))
                    }
                    Act::Idle => {
                        let limit = Duration::from_secs(60);
                        let end = a.now() + limit;
                        a.run_until_idle(limit);
                        if b.poll_timeout().is_some_and(|t| t <= end) {
                            advance_ticking(&mut b, end, Stop::NotBusy);
                        }
                        (false, false)
                    }
                };
                if !matches!(act, Act::Idle) {
                    proptest::prop_assert_eq!(sa, sb, "stopped early after act {} {:?}", i, act);
                }
                proptest::prop_assert_eq!(moving_state(&a), moving_state(&b), "after act {} {:?}", i, act);
                proptest::prop_assert!(same_heat(a.heat, b.heat), "heat {} against {} after act {} {:?}", a.heat, b.heat, i, act);
                // (a link takes what the hand wrote after every call)
                a.clear_output();
                b.clear_output();
            }
        }
    }

    proptest::proptest! {
        /// The board's heat after ticks passed at once (closed form) is what as many ticks one
        /// by one give, to far below TEMP's resolution, and TEMP reads the same tenth unless the
        /// heat is within a hair of a half tenth: warming with 0 to 4 motors moving and cooling,
        /// from cold or warm, for 2 ticks to more than 3 minutes.
        #[test]
        fn heat_passed_at_once_is_the_heat_of_the_ticks(
            profile in proptest::sample::select(vec!["seed", "bh8-262-4.4", "bh8-262-4.3"]),
            start in proptest::prop_oneof![proptest::strategy::Just(0.0), 0.0f64..500.0],
            moving in 0u32..=4,
            ticks in proptest::prop_oneof![2u64..50, 2u64..200_000],
        ) {
            let p = Profile::builtin(profile).unwrap();
            let mut a = Device::new(p, DeviceConfig::default());
            a.heat = start;
            let mut b = a.clone();
            a.cool_ticks(ticks, moving);
            for _ in 0..ticks {
                b.cool_tick(moving);
            }
            proptest::prop_assert!(same_heat(a.heat, b.heat), "{} against {}", a.heat, b.heat);
            let near_half = (b.heat.fract() - 0.5).abs() < 1e-6;
            proptest::prop_assert!(near_half || a.heat.round() == b.heat.round());
        }
    }

    /// HI on a warm board (after motions) and from a closed hand: the settling ticks passed at
    /// once leave the hand as ticking through them does (the board's heat to far below TEMP's
    /// resolution), and HI ends at the same tick.
    #[test]
    fn quiet_ticks_passed_at_once_leave_the_hand_as_ticking_does() {
        for name in ["seed", "bh8-262"] {
            let p = Profile::builtin(name).unwrap();
            let mut a = Device::new(p, DeviceConfig { seed: 3, ..DeviceConfig::default() });
            for (i, line) in ["HI", "C", "O", "C", "HI", "1M 2000", "HI"].into_iter().enumerate() {
                let mut b = a.clone();
                let bytes = format!("{line}\r").into_bytes();
                let t = a.now();
                a.handle_input(t, &bytes);
                b.handle_input(t, &bytes);
                a.run_until_idle(Duration::from_secs(600));
                tick_by_tick(&mut b);
                let (sa, sb) = same_hand_but_heat(&a, &b);
                assert_eq!(sa, sb, "{name}: the hand after {line}");
                // (the later HIs settle on a board the motions warmed: it cools as it settles)
                assert!(i == 0 || a.heat > 0.0, "{name}: a warm board after {line}");
            }
        }
    }
}
