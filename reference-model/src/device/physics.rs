//! One motor's mechanics, one millisecond at a time: trapezoidal position moves, velocity
//! moves, joint stops, objects, strain, stall detection and HI.
//!
//! Positions are in encoder counts, velocities in counts per ms. Floating point here is
//! plain IEEE arithmetic, so results are the same on every platform.

/// What a motor is doing in supervisory mode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Goal {
    /// Move to a position (M, C, O, IC, IO, HOME).
    Position {
        /// The target position.
        target: f64,
        /// Milliseconds the motor has been blocked.
        stall_ms: u32,
    },
    /// Drive at MCV/MOV until stalled (TC, TO).
    Velocity {
        /// +1 closes, -1 opens.
        direction: f64,
        /// Milliseconds the motor has been blocked.
        stall_ms: u32,
    },
    /// HI: drive open to the stop, settle there, then call it 0.
    Initialize {
        /// Milliseconds spent at the open stop.
        settled_ms: u64,
        /// Milliseconds the motor has been unable to open (an open velocity of 0).
        stall_ms: u32,
    },
}

/// Why a motor stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Termination {
    /// Reached its goal.
    Goal,
    /// Blocked for TSTOP ms.
    Stall,
    /// Strain above HSG/MSG or below LSG.
    Strain,
    /// Breakaway detected (BS = 1).
    Breakaway,
}

/// The per-tick inputs a motor needs from its parameters and the world.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct StepLimits {
    pub limit: i64,
    pub object: Option<(i64, i64)>,
    pub accel: f64,
    pub close_speed: f64,
    pub open_speed: f64,
    pub init_speed: f64,
    pub tstop_ms: u32,
    pub settle_ms: u64,
    pub free_strain: i64,
    pub strain_per_count: f64,
    pub high_strain: i64,
    pub low_strain: i64,
    pub breakaway: bool,
}

/// One motor.
#[derive(Debug, Clone)]
pub(super) struct Motor {
    pub pos: f64,
    pub velocity: f64,
    pub initialized: bool,
    pub powered: bool,
    pub goal: Option<Goal>,
    /// Last reported position for LFDP.
    pub reported: Option<i64>,
    /// RealTime commanded velocity, counts/ms.
    pub rt_velocity: f64,
    /// RealTime proportional gain (last received).
    pub rt_gain: i64,
    /// Whether the loop's control block carries a gain for this motor.
    pub rt_uses_gain: bool,
}

impl Motor {
    pub fn new(pos: f64) -> Motor {
        Motor {
            pos: pos.max(0.0),
            velocity: 0.0,
            initialized: false,
            powered: false,
            goal: None,
            reported: None,
            rt_velocity: 0.0,
            rt_gain: 0,
            rt_uses_gain: false,
        }
    }

    pub fn position(&self) -> i64 {
        round(self.pos)
    }

    pub fn power_down(&mut self) {
        self.initialized = false;
        self.powered = false;
        self.goal = None;
        self.velocity = 0.0;
        self.rt_velocity = 0.0;
        self.reported = None;
    }

    pub fn finish_initialize(&mut self) {
        self.pos = 0.0;
        self.velocity = 0.0;
        self.initialized = true;
        self.reported = None;
    }

    /// The raw strain: the free reading, plus what pressing into an object adds (halved
    /// once the motor is unpowered and the drive relaxes).
    pub fn strain(&self, object: Option<i64>, free: i64, per_count: f64) -> i64 {
        // (nothing pressed: the free reading, as the arithmetic below gives it)
        if object.is_none() && per_count.is_finite() && free.unsigned_abs() < 1 << 52 {
            return free;
        }
        let press = object.map_or(0.0, |o| (self.pos - o as f64).max(0.0));
        let k = if self.powered { 1.0 } else { 0.5 };
        round(free as f64 + press * per_count * k)
    }

    fn bounds(&self, l: &StepLimits) -> (f64, f64) {
        let hi = match l.object {
            Some((o, compliance)) => (o + compliance).min(l.limit),
            None => l.limit,
        };
        (0.0, hi as f64)
    }

    /// Advances one millisecond. Returns a termination when the supervisory goal ends.
    pub fn step(&mut self, l: &StepLimits) -> Option<Termination> {
        let Some(goal) = self.goal else {
            // RealTime velocity control, or idle.
            if self.rt_velocity == 0.0 && self.velocity == 0.0 {
                return None;
            }
            let (lo, hi) = self.bounds(l);
            let target = self.rt_velocity;
            if self.rt_uses_gain {
                let k = (self.rt_gain as f64 / 64.0).clamp(0.0, 1.0);
                self.velocity += (target - self.velocity) * k;
            } else {
                self.velocity = target;
            }
            let next = (self.pos + self.velocity).clamp(lo, hi);
            if next == self.pos {
                self.velocity = 0.0;
            }
            self.pos = next;
            return None;
        };
        let (lo, hi) = self.bounds(l);
        let before_contact = l.object.is_some_and(|(o, _)| self.pos < o as f64);
        let (speed, dir, target) = match goal {
            Goal::Position { target, .. } => {
                let d = target - self.pos;
                if d.abs() < 0.5 {
                    self.pos = target.clamp(lo, hi);
                    self.velocity = 0.0;
                    return Some(Termination::Goal);
                }
                let dir = d.signum();
                let vmax = if dir > 0.0 { l.close_speed } else { l.open_speed };
                let brake = (2.0 * l.accel * d.abs()).sqrt();
                (vmax.min(brake), dir, Some(target))
            }
            Goal::Velocity { direction, .. } => {
                (if direction > 0.0 { l.close_speed } else { l.open_speed }, direction, None)
            }
            Goal::Initialize { settled_ms, .. } => {
                if self.pos <= lo {
                    self.velocity = 0.0;
                    let s = settled_ms + 1;
                    if s >= l.settle_ms {
                        return Some(Termination::Goal);
                    }
                    self.goal = Some(Goal::Initialize { settled_ms: s, stall_ms: 0 });
                    return None;
                }
                (l.init_speed, -1.0, None)
            }
        };
        let current = self.velocity.abs();
        let wanted = speed.min(current + l.accel).max(0.0);
        let mut next = self.pos + dir * wanted;
        if let Some(t) = target
            && (t - self.pos) * (t - next) <= 0.0
        {
            next = t;
        }
        let clamped = next.clamp(lo, hi);
        let blocked = (clamped - self.pos).abs() < 1e-9;
        self.velocity = if blocked { 0.0 } else { clamped - self.pos };
        self.pos = clamped;
        if let Goal::Initialize { settled_ms, stall_ms } = goal {
            // A motor that cannot open stalls like any other, and the HI fails for it.
            let stall_ms = if blocked { stall_ms + 1 } else { 0 };
            self.goal = Some(Goal::Initialize { settled_ms, stall_ms });
            return (stall_ms > l.tstop_ms).then_some(Termination::Stall);
        }
        // Strain checks.
        let sg = self.strain(l.object.map(|(o, _)| o), l.free_strain, l.strain_per_count);
        if l.high_strain < 255 && sg > l.high_strain {
            return Some(Termination::Strain);
        }
        if l.low_strain < 255 && sg < l.low_strain {
            return Some(Termination::Strain);
        }
        if l.breakaway && before_contact && l.object.is_some_and(|(o, _)| self.pos >= o as f64) {
            return Some(Termination::Breakaway);
        }
        if let Some(t) = target
            && (t - self.pos).abs() < 0.5
        {
            self.velocity = 0.0;
            return Some(Termination::Goal);
        }
        let stall = if blocked || wanted == 0.0 { 1 } else { 0 };
        let stalled_for = match &mut self.goal {
            Some(Goal::Position { stall_ms, .. }) | Some(Goal::Velocity { stall_ms, .. }) => {
                *stall_ms = if stall == 1 { *stall_ms + 1 } else { 0 };
                *stall_ms
            }
            _ => 0,
        };
        (stall == 1 && stalled_for > l.tstop_ms).then_some(Termination::Stall)
    }
}

/// `x.round() as i64` (half away from zero, saturating, NaN as 0), without the library call
/// `f64::round` is on targets without a rounding instruction: a millisecond tick rounds every
/// moving motor's position and distance.
pub(super) fn round(x: f64) -> i64 {
    // (below 2^52 the fraction is exact: x minus its truncation)
    if x.abs() < 4_503_599_627_370_496.0 {
        let t = x as i64;
        let f = x - t as f64;
        t + i64::from(f >= 0.5) - i64::from(f <= -0.5)
    } else {
        x.round() as i64
    }
}

#[cfg(test)]
mod tests {
    /// [`super::round`] is `f64::round` to an `i64`, halves, the ends of the exact range and
    /// the values that are not numbers included.
    #[test]
    fn round_is_the_library_round() {
        let mut xs = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.5,
            -1.5,
            2.5,
            0.49999999999999994,
            -0.49999999999999994,
            4_503_599_627_370_495.5,
            4_503_599_627_370_496.0,
            -4_503_599_627_370_497.0,
            1e19,
            -1e19,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            f64::MIN_POSITIVE,
        ];
        // (positions and per-tick distances as the motors make them)
        let mut x = -3.0;
        while x < 20_000.0 {
            xs.push(x);
            x += 0.099_999_999_999_999_98;
        }
        for x in xs {
            assert_eq!(super::round(x), x.round() as i64, "{x:?}");
        }
    }
}
