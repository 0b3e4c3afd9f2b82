//! RealTime mode: entering and leaving the loop, control blocks in, feedback blocks out.

use super::*;

impl Device {
    pub(super) fn start_loop(&mut self, motors: MotorSet) {
        let profile = self.profile.clone();
        if motors.motors().any(|m| !self.motors[m].initialized) {
            return self.end_line(StatusBits::from_bits_truncate(profile.hand.uninitialized_status));
        }
        let layout = RtLayout::compute(&profile, &self.behaviour_store(), motors);
        for m in motors.motors() {
            let motor = &mut self.motors[m];
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
        self.out.push(crate::realtime::FEEDBACK_HEADER);
        self.last_status = StatusBits::empty();
        let params = PerMotor(Motor::ALL.map(|m| LoopParams {
            lcvc: self.role(Role::VelocityCoefficient, m),
            lfvc: self.role(Role::FeedbackVelocityCoefficient, m),
            lfdpc: self.role(Role::DeltaCoefficient, m),
            uses_gain: self.role(Role::ControlGain, m) != 0,
        }));
        let discard = self.role(Role::DeltaDiscard, Motor::F1) != 0;
        let data = Vec::with_capacity(16);
        self.state = State::Loop(Box::new(LoopState { layout, pending: None, data, params, discard }));
        self.push_event(Event::LoopEntered);
        self.refresh_limits();
    }

    /// One byte in RealTime mode. The loop's state is handed in (the hand is `Idle` meanwhile)
    /// and put back unless the byte ends the loop.
    pub(super) fn loop_byte(&mut self, mut rt: Box<LoopState>, b: u8) {
        if rt.pending.is_some() {
            // `data` holds the header byte, then the control data so far.
            rt.data.push(b);
            if rt.data.len() >= rt.layout.control().size() {
                if let Ok(control) = Control::parse(rt.layout.control(), &rt.data) {
                    self.apply_control(&rt, &control);
                }
                // The answer follows the whole block, as a hand reads a block before it
                // answers: no exchange beats the line's wire time in both directions.
                if rt.pending.is_some_and(|h| h.wants_feedback()) {
                    self.emit_feedback(&rt);
                } else {
                    self.out.push(crate::realtime::FEEDBACK_HEADER);
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
                    self.emit_feedback(&rt);
                } else {
                    self.out.push(crate::realtime::FEEDBACK_HEADER);
                }
                self.state = State::Loop(rt);
            }
            None => {
                let status = StatusBits::from_bits_truncate(self.profile.hand.bad_header_status);
                if self.has(Fault::StayInLoop) {
                    self.state = State::Loop(rt);
                } else {
                    self.leave_loop();
                }
                self.end_line(status);
            }
        }
    }

    /// Ends the loop (its state already taken by [`Device::loop_byte`]).
    pub(super) fn leave_loop(&mut self) {
        self.state = State::Idle;
        self.push_event(Event::LoopLeft);
        for m in self.motors.values_mut() {
            m.rt_velocity = 0.0;
            m.velocity = 0.0;
        }
    }

    pub(super) fn apply_control(&mut self, rt: &LoopState, control: &Control) {
        let profile = self.profile.clone();
        let hand = &profile.hand;
        for m in rt.layout.motors().motors() {
            let MotorControl { velocity, gain, torque } = control.motor(m.number());
            if let Some(v) = velocity {
                let v = if self.has(Fault::LcvUnsigned) { i64::from(v as u8) } else { v };
                let lcvc = rt.params[m].lcvc;
                self.motors[m].rt_velocity =
                    crate::realtime::control_velocity(v, lcvc, hand.lcv_fraction_bits) * hand.rt_velocity_counts_per_ms;
            }
            if let Some(g) = gain {
                self.motors[m].rt_gain = g;
            }
            if let Some(t) = torque {
                self.motors[m].rt_velocity = crate::realtime::control_velocity(t, 1, hand.lcv_fraction_bits + 4)
                    * hand.rt_velocity_counts_per_ms;
            }
            self.motors[m].rt_uses_gain = rt.params[m].uses_gain;
        }
    }

    /// Sends a feedback block: one value per field of the layout, computed in wire order (the
    /// noise of strain and temperature is drawn in that order).
    pub(super) fn emit_feedback(&mut self, rt: &LoopState) {
        let layout = &rt.layout;
        let profile = self.profile.clone();
        let hand = &profile.hand;
        let discard = rt.discard;
        let mut feedback = Feedback::default();
        for f in layout.feedback().fields() {
            // A hand-wide field (LFT) reads no motor; F1 stands in for the arithmetic below.
            let m = f.motor().and_then(Motor::new).unwrap_or(Motor::F1);
            let v = match f.flag() {
                RtFlag::Lfv => {
                    let c = rt.params[m].lfvc.max(1) as f64;
                    (self.motors[m].velocity / hand.lfv_counts_per_ms / c).trunc() as i64
                }
                RtFlag::Lfs => self.strain(m),
                RtFlag::Lfap => {
                    let p = self.motors[m].position().clamp(0, 65535);
                    if self.has(Fault::LittleEndianLfap) { ((p & 0xFF) << 8) | (p >> 8) } else { p }
                }
                RtFlag::Lfdp => {
                    let present = self.motors[m].position();
                    let c = rt.params[m].lfdpc;
                    let mut r = self.motors[m].reported.unwrap_or(present);
                    let q = if self.has(Fault::LfdpNotClipped) {
                        let d = (present - r) / c.max(1);
                        r += d * c.max(1);
                        i64::from(d as i8)
                    } else {
                        i64::from(crate::realtime::lfdp_step(&mut r, present, c, discard))
                    };
                    self.motors[m].reported = Some(r);
                    q
                }
                RtFlag::Lfbp => self.role(Role::BreakawayPosition, m),
                RtFlag::Lfain => *m.pick(&self.scenario.analog_input),
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
