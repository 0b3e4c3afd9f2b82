//! Parameter effects: a case per parameter that changes what a motion does. Those with fixed
//! lines are scripts (`harness/suite-cases/params/param-*-effect.gcls`); the ones here compute
//! their bounds: SGFLIP's from the free strain, and the timed ones (MCV, MOV, ACCEL, TSTOP)
//! from the model's motion trapezoid.

use super::*;

impl Gen {
    /// For parameters whose value changes what the hand does: a case that sets one to a value
    /// other than its default and shows the difference on the wire.
    pub(super) fn effects(&mut self) {
        self.scripts(&[
            "param-dp-effect",
            "param-ds-effect",
            "param-ct-effect",
            "param-ot-effect",
            "param-mpe-effect",
            "param-lsg-effect",
        ]);

        // SGFLIP turns FGET SG over.
        let f = self.p.hand.free_strain;
        let (plain, flipped) = ((0, (2 * f).min(255)), ((255 - 2 * f).max(0), 255));
        let k = self
            .case("param-sgflip-effect", "With SGFLIP 1 FGET SG reads 255 minus the strain")
            .src("Parameter SGFLIP")
            .src("Parameter SG")
            .decision("seed-strain-at-rest")
            .decision("bh8-strain-at-rest")
            .note(format!(
                "A free finger's strain is near {f}: with SGFLIP 0 it reads {}..{}, with SGFLIP 1 {}..{}.",
                plain.0, plain.1, flipped.0, flipped.1
            ))
            .preamble(false)
            .line("2FSET SGFLIP 1")
            .line_shaped("12FGET SG", Shape::Values(vec![vec![Some(plain), Some(flipped)]]));
        self.add(k);

        self.timed_effects();
    }

    /// Where a motor is `ticks` ms after a position move from `from` to `target` starts, with
    /// ACCEL `accel` and maximum velocity `speed` (MCV or MOV), by the model's trapezoid.
    pub(super) fn reach(&self, from: i64, target: i64, accel: i64, speed: i64, ticks: u64) -> i64 {
        let h = &self.p.hand;
        let a = accel.max(1) as f64 * h.velocity_units_per_ms_per_accel * h.counts_per_ms_per_velocity_unit;
        let vmax = speed as f64 * h.counts_per_ms_per_velocity_unit;
        let (mut pos, mut v) = (from as f64, 0.0f64);
        let t = target as f64;
        for _ in 0..ticks {
            let d = t - pos;
            if d.abs() < 0.5 {
                break;
            }
            let want = vmax.min((2.0 * a * d.abs()).sqrt()).min(v + a).max(0.0);
            let next = pos + d.signum() * want;
            pos = if (t - pos) * (t - next) <= 0.0 { t } else { next };
            v = want;
        }
        pos.round() as i64
    }

    /// Parameters whose effect is how fast a motor moves or how long it waits: seen through
    /// where a motor is when a ^C lands, or whether its command is still running then. These
    /// need a hand whose motion takes time (`abort-timing`).
    pub(super) fn timed_effects(&mut self) {
        // The ^C lands between `pause` and `pause + slack` ms after the command: the host's
        // pause, plus the echo and the recorder's quiet time.
        let slack = 150u64;
        let (ct, accel) = (self.close_target(1), self.default("ACCEL", 1));
        for (name, kind) in [("MCV", CommandKind::Close), ("MOV", CommandKind::Open)] {
            let Some(x) = self.param(name).cloned() else { continue };
            let def = self.default(name, 1);
            let slow = (def / 6).max(x.min).max(1);
            let from = if kind == CommandKind::Close { 0 } else { 12000 };
            let to = if kind == CommandKind::Close { ct } else { 0 };
            let pause = 150u64;
            let range = |v: i64| {
                let (a, b) = (self.reach(from, to, accel, v, pause), self.reach(from, to, accel, v, pause + slack));
                (a.min(b) - 2, a.max(b) + 2)
            };
            let (r1, r2) = (range(slow), range(def));
            if r1.1 >= r2.0 && r2.1 >= r1.0 {
                continue;
            }
            let word = if kind == CommandKind::Close { "C" } else { "O" };
            let mut k = self
                .case(
                    format!("param-{}-effect", slug(name)),
                    format!("{name} sets how fast {word} moves: with {name} {slow} motor 1 is behind motor 2 ({name} {def}) when a ^C lands"),
                )
                .src(&format!("Parameter {name}"))
                .src(&format!("Command {word}"))
                .decision("seed-abort").decision("bh8-abort-motion")
                .decision("seed-motion-model").decision("bh8-velocity-units")
                .requires(Requirement::AbortTiming)
                .note(format!(
                    "The ^C lands {pause}..{} ms after the command: motor 1 is then within {}..{}, motor 2 within {}..{}.",
                    pause + slack,
                    r1.0,
                    r1.1,
                    r2.0,
                    r2.1
                ))
                .preamble(true);
            if from > 0 {
                k = k.line(&format!("12M {from}"));
            }
            let k = k.line(&format!("1FSET {name} {slow}")).nowait(&format!("12{word}")).pause_ms(pause).abort().get(
                "12",
                &["P"],
                Some([r1, r2, (0, 0), (0, 0)]),
            );
            self.add(k);
        }

        // ACCEL: where the ramp up takes long enough to see (the seed's units).
        if let Some(x) = self.param("ACCEL").cloned() {
            let fast = (accel * 100).min(x.max);
            let speed = self.param("MCV").map_or(0, |m| m.max);
            let pause = 150u64;
            let slack = 100u64;
            let range = |a: i64| {
                let (lo, hi) = (self.reach(0, ct, a, speed, pause), self.reach(0, ct, a, speed, pause + slack));
                (lo - 2, hi + 2)
            };
            let (r1, r2) = (range(fast), range(accel));
            if r1.0 > r2.1 && r1.1 < ct - self.mpe(1) {
                let k = self
                    .case(
                        "param-accel-effect",
                        format!("ACCEL sets how fast a move speeds up: with ACCEL {fast} motor 1 is ahead of motor 2 (ACCEL {accel}) when a ^C lands"),
                    )
                    .src("Parameter ACCEL")
                    .src("Command C")
                    .decision("seed-abort").decision("bh8-abort-motion")
                    .decision("seed-motion-model").decision("bh8-velocity-units")
                    .requires(Requirement::AbortTiming)
                    .note(format!(
                        "Both motors close at MCV {speed}; the ^C lands {pause}..{} ms after the command: motor 1 is then within {}..{}, motor 2 within {}..{}.",
                        pause + slack,
                        r1.0,
                        r1.1,
                        r2.0,
                        r2.1
                    ))
                    .preamble(true)
                    .line(&format!("12FSET MCV {speed}"))
                    .line(&format!("1FSET ACCEL {fast}"))
                    .nowait("12C")
                    .pause_ms(pause)
                    .abort()
                    .get("12", &["P"], Some([r1, r2, (0, 0), (0, 0)]));
                self.add(k);
            }
        }

        // TSTOP: a motor stalled at its joint stop keeps driving for TSTOP ms. With TSTOP 5000
        // the move is still running a second after the stall began, so the ^C stops it;
        // with the factory TSTOP it would long have ended with 16.
        let l4 = self.limit(4);
        let goal = l4 + 850;
        let (a4, v4) = (self.default("ACCEL", 4), self.default("MCV", 4));
        let mut t_stop = 0u64;
        while t_stop < 60_000 && self.reach(0, goal, a4, v4, t_stop) < l4 {
            t_stop += 10;
        }
        let tstop = 5000;
        let pause = t_stop + 1000;
        let k = self
            .case(
                "param-tstop-effect",
                format!("TSTOP sets how long a stalled motor keeps driving: with TSTOP {tstop} a move stalled at the joint stop is still running when a ^C lands 1 s later"),
            )
            .src("Parameter TSTOP")
            .src("Command M")
            .decision("seed-abort").decision("bh8-abort-motion")
            .decision("seed-motion-model").decision("bh8-position-bounds")
            .requires(Requirement::AbortTiming)
            .note(format!("The spread reaches its joint stop ({l4}) about {t_stop} ms after SM {goal} starts."))
            .preamble(true)
            .line(&format!("SFSET TSTOP {tstop}"))
            .nowait(&format!("SM {goal}"))
            .pause_ms(pause)
            .abort()
            .get("S", &["P"], Some([(l4 - self.mpe(4), l4); 4]));
        self.add(k);
    }
}
