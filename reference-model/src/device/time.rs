//! Time: advancing the hand to a new instant, 1 ms physics ticks while something moves, and
//! the end of a running command. Every `now` is monotonic and saturating (see the module
//! docs of [`super`]).

use super::*;

impl Device {
    pub(super) fn advance(&mut self, now: Duration) {
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
            // Newton's cooling over the idle stretch, in closed form (nothing to do for a cold
            // board or within the same millisecond, the common case between idle commands).
            if self.heat > 0.0 && elapsed_ms > 0 {
                self.heat *= (-(elapsed_ms as f64) / (self.profile.hand.cooling_time_s * 1000.0)).exp();
            }
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

    /// One millisecond of physics. Returns how many motors moved.
    pub(super) fn tick(&mut self) -> u32 {
        let mut moving = 0;
        for m in Motor::ALL {
            let before = self.motors[m].pos;
            let motor = &mut self.motors[m];
            let term = motor.step(self.limits[m]);
            let moved = (motor.pos - before).abs();
            if moved > 0.0 {
                moving += 1;
                let odometer = m.pick_mut(&mut self.nv.odometer_counts);
                *odometer = odometer.saturating_add(moved.round() as u64);
            }
            if let Some(t) = term {
                self.terminate_motor(m, t);
            }
        }
        // One millisecond of heating by the moving motors and of cooling toward ambient: the
        // board settles at moving × heat_per_motor_s × cooling_time_s tenths above ambient.
        let hand = &self.profile.hand;
        self.heat += hand.heat_per_motor_s / 1000.0 * f64::from(moving) - self.heat / (hand.cooling_time_s * 1000.0);
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
