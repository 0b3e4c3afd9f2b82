//! One motor's mechanics, one millisecond at a time: trapezoidal position moves, velocity
//! moves, joint stops, objects, strain, stall detection and HI.
//!
//! Positions are in encoder counts, velocities in counts per ms. Floating point here is
//! plain IEEE arithmetic, so results are the same on every platform.
//!
//! Most of a motion's ticks repeat the one before: a motor cruising at full speed moves the
//! same distance each, a motor blocked at a stop only counts toward its stall, one at rest does
//! nothing. [`Motor::steady`] finds such a stretch from the present state and
//! [`Motor::pass_steady`] passes it in one step, leaving the motor bit for bit as the ticks one
//! by one would: a cruise is taken only where every sum along it is exact (positions and the
//! step on one binary grid, small enough that no addition rounds, see `exact_run`), so `n`
//! ticks of `d` are `n × d`, and only where no tick of it can end the goal, reach the target's
//! braking distance, touch an object, a stop or a strain limit. Everything else (accelerating,
//! braking, pressing into an object, the tick that ends a goal) runs tick by tick, as does a
//! profile whose speeds are not on such a grid.

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
        strain_at(self.pos, self.powered, object, free, per_count)
    }

    fn bounds(&self, l: &StepLimits) -> (f64, f64) {
        let hi = match l.object {
            Some((o, compliance)) => (o + compliance).min(l.limit),
            None => l.limit,
        };
        (0.0, hi as f64)
    }

    /// The stretch of ticks from the next one on (at most `max`) in which each tick repeats the
    /// one before as [`Motor::step`] would run it; `None` when the next tick may do anything
    /// else (see the module docs). A motor at rest with no goal repeats for ever.
    pub fn steady(&self, l: &StepLimits, max: u64) -> Option<Steady> {
        let Some(goal) = self.goal else {
            let rest = self.rt_velocity == 0.0 && self.velocity == 0.0;
            return rest.then_some(Steady { ticks: max, kind: SteadyKind::Rest });
        };
        let (lo, _) = self.bounds(l);
        let (speed, dir, target) = match goal {
            Goal::Initialize { settled_ms, stall_ms } if self.pos <= lo => {
                // (settling at the open stop: only the count runs, up to the tick that ends it)
                if self.velocity.to_bits() != 0 || stall_ms != 0 {
                    return None;
                }
                let ticks = l.settle_ms.saturating_sub(settled_ms.saturating_add(1)).min(max);
                return Some(Steady { ticks, kind: SteadyKind::Settle });
            }
            Goal::Initialize { .. } => (l.init_speed, -1.0, None),
            Goal::Position { target, .. } => {
                let d = target - self.pos;
                if d.abs() < 0.5 || d.is_nan() {
                    return None;
                }
                let dir = d.signum();
                (if dir > 0.0 { l.close_speed } else { l.open_speed }, dir, Some(target))
            }
            Goal::Velocity { direction, .. } => {
                (if direction > 0.0 { l.close_speed } else { l.open_speed }, direction, None)
            }
        };
        if self.velocity == 0.0 {
            return self.stalling(l, max);
        }
        // Cruising: at full speed in the goal's direction, so the next tick moves as the last.
        let current = self.velocity.abs();
        let wanted = speed.min(current + l.accel).max(0.0);
        if !(wanted == current && self.velocity == dir * current && wanted >= 1e-9) {
            return None;
        }
        let delta = dir * wanted;
        // (more ticks than this would leave the stops)
        let (_, hi) = self.bounds(l);
        let span = hi - lo;
        if !(span >= 0.0 && span.is_finite()) {
            return None;
        }
        let upper = ((span / wanted) as u64).saturating_add(1).min(max);
        // The last tick decides: each condition of a cruise holds all along one if it holds at
        // its last tick, so the longest is found by halving.
        let cruises = |n: u64| exact_run(self.pos, delta, n) && self.cruises_to(l, goal, target, delta, n);
        // (a stretch of one tick is no gain: the tick runs as any other)
        if upper < 2 || !cruises(2) {
            return None;
        }
        let (mut yes, mut no) = (2, upper);
        if cruises(upper) {
            yes = upper;
        } else {
            while no - yes > 1 {
                let mid = yes + (no - yes) / 2;
                if cruises(mid) { yes = mid } else { no = mid }
            }
        }
        Some(Steady { ticks: yes, kind: SteadyKind::Cruise(delta) })
    }

    /// Whether the `n`-th tick (n ≥ 1) of a cruise by `delta` per tick, each tick exact, is
    /// still one: it starts and ends inside the stops and below any object, short of the target
    /// by at least half a count and farther from it than braking needs, with a strain that ends
    /// nothing. Each of these holds all along a cruise if it holds at its first and last ticks.
    fn cruises_to(&self, l: &StepLimits, goal: Goal, target: Option<f64>, delta: f64, n: u64) -> bool {
        let (lo, hi) = self.bounds(l);
        let before = self.pos + (n - 1) as f64 * delta;
        let after = self.pos + n as f64 * delta;
        if !(lo <= self.pos && self.pos <= hi && lo <= after && after <= hi) {
            return false;
        }
        if matches!(goal, Goal::Initialize { .. }) {
            // (HI reads no strain and no object but through the stops)
            return true;
        }
        // (strictly below an object all the way, no strain from pressing it, no breakaway)
        if let Some((o, _)) = l.object
            && self.pos.max(after) >= o as f64
        {
            return false;
        }
        if let Some(t) = target {
            let d = t - before;
            let brake = (2.0 * l.accel * d.abs()).sqrt();
            let vmax = if d > 0.0 { l.close_speed } else { l.open_speed };
            // (still on the side of the target it started from: past it, these hold again)
            let ahead = (t - after) * delta > 0.0;
            if !(ahead && vmax <= brake && (t - after).abs() >= 0.5 && (t - before) * (t - after) > 0.0) {
                return false;
            }
        }
        let sg = strain_at(after, self.powered, l.object.map(|(o, _)| o), l.free_strain, l.strain_per_count);
        let ends = (l.high_strain < 255 && sg > l.high_strain) || (l.low_strain < 255 && sg < l.low_strain);
        !ends
    }

    /// A motor at rest with a goal whose next tick leaves it where it is (blocked at a stop, or
    /// with no speed to move at) and ends nothing: each later tick is the same one, counting
    /// toward the stall, up to the tick that ends it.
    fn stalling(&self, l: &StepLimits, max: u64) -> Option<Steady> {
        if self.velocity.to_bits() != 0 {
            return None;
        }
        let mut next = self.clone();
        if next.step(l).is_some() || next.pos.to_bits() != self.pos.to_bits() || next.velocity.to_bits() != 0 {
            return None;
        }
        // (the step changed nothing but the count)
        let was = stall_count(self.goal)?;
        let mut same = next.goal;
        if stall_count(same) != Some(was.saturating_add(1)) {
            return None;
        }
        set_stall_count(&mut same, was);
        if same != self.goal {
            return None;
        }
        // Tick j leaves the count at was + j and ends the goal once that passes TSTOP.
        Some(Steady { ticks: u64::from(l.tstop_ms.saturating_sub(was)).min(max), kind: SteadyKind::Stall })
    }

    /// Passes `ticks` ticks of a [`Motor::steady`] stretch (at most its own) in one step.
    pub fn pass_steady(&mut self, kind: SteadyKind, ticks: u64) {
        if ticks == 0 {
            return;
        }
        match kind {
            SteadyKind::Rest => {}
            SteadyKind::Settle => {
                if let Some(Goal::Initialize { settled_ms, .. }) = &mut self.goal {
                    *settled_ms += ticks;
                }
            }
            SteadyKind::Stall => {
                let was = stall_count(self.goal).unwrap_or(0);
                let ticks = u32::try_from(ticks).unwrap_or(u32::MAX);
                set_stall_count(&mut self.goal, was.saturating_add(ticks));
            }
            SteadyKind::Cruise(delta) => {
                set_stall_count(&mut self.goal, 0);
                self.pos += ticks as f64 * delta;
                self.velocity = delta;
            }
        }
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

/// A stretch of ticks that repeat themselves (see [`Motor::steady`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Steady {
    /// How many ticks from the next one on are the same tick.
    pub ticks: u64,
    /// What each of them does.
    pub kind: SteadyKind,
}

/// What each tick of a [`Steady`] stretch does.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum SteadyKind {
    /// Nothing: no goal, not moving.
    Rest,
    /// Counts a HI's time at the open stop.
    Settle,
    /// Counts toward a stall, where the motor stands.
    Stall,
    /// Moves the motor by this many counts, at full speed.
    Cruise(f64),
}

/// The stall count of a goal.
fn stall_count(goal: Option<Goal>) -> Option<u32> {
    match goal {
        Some(Goal::Position { stall_ms, .. } | Goal::Velocity { stall_ms, .. } | Goal::Initialize { stall_ms, .. }) => {
            Some(stall_ms)
        }
        None => None,
    }
}

/// Sets the stall count of a goal.
fn set_stall_count(goal: &mut Option<Goal>, to: u32) {
    if let Some(Goal::Position { stall_ms, .. } | Goal::Velocity { stall_ms, .. } | Goal::Initialize { stall_ms, .. }) =
        goal
    {
        *stall_ms = to;
    }
}

/// The raw strain of a motor at `pos` (see [`Motor::strain`]).
fn strain_at(pos: f64, powered: bool, object: Option<i64>, free: i64, per_count: f64) -> i64 {
    // (nothing pressed: the free reading, as the arithmetic below gives it)
    if object.is_none() && per_count.is_finite() && free.unsigned_abs() < 1 << 52 {
        return free;
    }
    let press = object.map_or(0.0, |o| (pos - o as f64).max(0.0));
    let k = if powered { 1.0 } else { 0.5 };
    round(free as f64 + press * per_count * k)
}

/// Whether adding `delta` to `start` one tick at a time, `n` times, gives `start + i × delta`
/// at every tick `i` and `delta` as each difference: true when both lie on a binary grid 2^g
/// (the coarser of their lowest bits) and every value along the way stays below 2^(g+52), so
/// that no sum or product rounds.
fn exact_run(start: f64, delta: f64, n: u64) -> bool {
    /// The exponent of `x`'s lowest set bit; `None` for a value off every usable grid.
    fn lowest_bit(x: f64) -> Option<i32> {
        if x == 0.0 {
            return Some(i32::MAX);
        }
        let bits = x.to_bits();
        let exp = ((bits >> 52) & 0x7ff) as i32;
        if exp == 0 || exp == 0x7ff {
            // (subnormal, infinite or not a number)
            return None;
        }
        let mantissa = (bits & ((1 << 52) - 1)) | (1 << 52);
        Some(exp - 1075 + mantissa.trailing_zeros() as i32)
    }
    let (Some(a), Some(b)) = (lowest_bit(start), lowest_bit(delta)) else { return false };
    let g = a.min(b);
    if g == i32::MAX || n >= 1 << 52 || !(-1000..=900).contains(&g) {
        return g == i32::MAX;
    }
    let reach = start.abs() + n as f64 * delta.abs();
    // (2^(g+52), a normal number for g in the range above)
    reach < f64::from_bits(((g + 52 + 1023) as u64) << 52)
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
