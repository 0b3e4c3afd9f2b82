//! Time: advancing the hand to a new instant, 1 ms physics ticks while something moves, and
//! the end of a running command. Every `now` is monotonic and saturating (see the module
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
        for _ in 0..ticks {
            self.cool_tick(0);
        }
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

    /// HI on a warm board (after motions) and from a closed hand: the settling ticks passed at
    /// once leave the hand as ticking through them does, the board's heat to the last bit, and
    /// HI ends at the same tick.
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
                assert_eq!(format!("{a:?}"), format!("{b:?}"), "{name}: the hand after {line}");
                // (the later HIs settle on a board the motions warmed: it cools as it settles)
                assert!(i == 0 || a.heat > 0.0, "{name}: a warm board after {line}");
            }
        }
    }
}
