//! Parameter effects: a case per parameter that changes what a motion does. Those with fixed
//! lines are scripts (`conformance/suite-cases/params/param-*-effect.gcls`); the ones here compute
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
        self.hold_effect();
        self.breakaway_stop_effect();
    }

    /// BS: with BS 1 a finger stops where its breakaway is detected, and BD and BP say so.
    /// The case places an object half-way along motor 1's close (`setup: object`): with the
    /// factory BS 0 the finger closes on past the object, with BS 1 it stops there, BD reads 1
    /// and BP where it stopped.
    fn breakaway_stop_effect(&mut self) {
        if !self.has_param("BS") || !self.has_param("BD") || !self.has_param("BP") || self.default("BS", 1) != 0 {
            return;
        }
        let at = self.close_target(1) / 2;
        let mpe = self.mpe(1);
        let limit = self.limit(1);
        let pos = |r: Range| Some([r, (0, 0), (0, 0), (0, 0)]);
        let k = self
            .case(
                "param-bs-effect",
                "BS 1 stops a finger where its breakaway is detected: it stops at the object, BD reads 1 and BP where it stopped; with BS 0 it closes on past the object",
            )
            .src("Parameter BS")
            .src("Parameter BD")
            .src("Parameter BP")
            .decision("bh8-breakaway")
            .object(1, at)
            .note(format!(
                "The object is where motor 1 meets it when closing, {at}: with BS 0 the finger goes on past it (the \
                 TorqueSwitch lets the fingertip close while the inner link rests on the object: more than MPE {mpe} \
                 beyond), with BS 1 it stops within MPE of it, and BP is its position there"
            ))
            .preamble(true)
            .line("1C")
            .get("1", &["P"], pos((at + mpe + 1, limit)))
            .line("1O")
            .line("1FSET BS 1")
            .line("1C")
            .get("1", &["P"], pos((at - mpe, at + mpe)))
            .get("1", &["BD", "BP"], None);
        // BP is a determined value (written exactly); the hand's is where it stopped, near the
        // object: a band, as P's.
        let k = k.shape_last(Shape::Values(vec![vec![None], vec![Some((at - mpe, at + mpe))]]));
        self.add(k);
    }

    /// HOLD: what a motor does once its move ends. Seen only where something pushes back: a
    /// finger closed onto an object keeps pressing while it is held, and is let go with HOLD 0.
    /// The case places an object half-way along motor 1's close (`setup: object`), closes onto
    /// it with the factory HOLD 0 and captures the strain, then opens, sets HOLD 1 and closes
    /// again: the held finger reads more strain than the released one.
    fn hold_effect(&mut self) {
        if !self.has_param("HOLD") || self.default("HOLD", 1) != 0 {
            return;
        }
        let at = self.close_target(1) / 2;
        let k = self
            .case(
                "param-hold-effect",
                "HOLD 1 keeps a finger pressing on an object after its close ends: it reads more strain than with HOLD 0, which lets the motor go",
            )
            .src("Parameter HOLD")
            .src("Command C")
            .decision("seed-hold")
            .decision("bh8-hold")
            .object(1, at)
            .preamble(true)
            .line("1C")
            .get("1", &["SG"], None)
            .capture(Target::Value { line: 0, token: 0 }, "s0")
            .line("1O")
            .line("1FSET HOLD 1")
            .line("1C")
            .get("1", &["SG"], None);
        // The model's two readings, from the plan as it stands (the relation is the last bind).
        let caps = match super::super::build::capture_plan_with(&self.p, &k.def.plans, &k.def.setup) {
            Ok(c) => c,
            Err(_) => return,
        };
        let eol = self.p.framing.line_ending.clone();
        let strain = |i: usize| -> Option<i64> {
            let out = String::from_utf8_lossy(&caps.get(i)?.output).into_owned();
            out.split(eol.as_str()).nth(1)?.trim().parse().ok()
        };
        let n = caps.len();
        let (Some(released), Some(held)) = (strain(n - 5), strain(n - 1)) else { return };
        // The clause is an order, not the model's factor: held above released. The relation is
        // twice the released strain with the widest tolerance whose band still starts above
        // 1.1 times it (so a hand that holds both alike, or lets both go, is refused), and it
        // must hold the model's pair.
        let rel = Relation::new("s0", 2, 1, 45);
        let (lo, hi) = rel.band(released);
        if !(lo..=hi).contains(&held) || lo <= released {
            return;
        }
        let evidence = format!(
            "D3000 (termination cases): when a motion ends, with HOLD 0 the motor is turned off, with HOLD 1 it is \
             servoed to keep the position where it ended; a finger closed onto an object (motor 1 meets it at {at}) \
             keeps pressing while held, so its strain reads above the released one. The model reads {released} with \
             HOLD 0 and {held} with HOLD 1 (it halves what pressing adds once the motor is off); the case checks the \
             order only: 2 x the released strain +-45 %, a band from 1.1 to 2.9 times it, which refuses a hand whose \
             HOLD changes nothing (both alike)"
        );
        let k = k.relate(Target::Value { line: 0, token: 0 }, rel, evidence, vec![(released, held)]);
        self.add(k);
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
    /// where one motor is against another when a ^C lands (a relation between the two, so
    /// the velocity units do not matter), or how soon a command ends. These need a hand whose
    /// motion takes time (`abort-timing`).
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
            let at =
                |v: i64| -> Vec<i64> { (pause..=pause + slack).map(|t| self.reach(from, to, accel, v, t)).collect() };
            let pairs: Vec<(i64, i64)> = at(slow).into_iter().zip(at(def)).collect();
            let ignored: Vec<(i64, i64)> = at(def).into_iter().map(|p| (p, p)).collect();
            let word = if kind == CommandKind::Close { "C" } else { "O" };
            let why = format!(
                "motor 1 moves at {name} {slow}, motor 2 at {name} {def}; where each is when the ^C lands {pause}..{} ms \
                 after {word}, by the model's motion trapezoid",
                pause + slack
            );
            let Some((k, rel)) = self.position_ratio(name, word, from, to, pairs, &ignored, why) else { continue };
            let k = k.line(&format!("1FSET {name} {slow}")).nowait(&format!("12{word}")).pause_ms(pause).abort();
            self.add(rel.read(k));
        }

        // ACCEL: where the ramp up takes long enough to see (the seed's units).
        if let Some(x) = self.param("ACCEL").cloned() {
            let fast = (accel * 100).min(x.max);
            let speed = self.param("MCV").map_or(0, |m| m.max);
            let pause = 150u64;
            let slack = 100u64;
            let at = |a: i64| -> Vec<i64> { (pause..=pause + slack).map(|t| self.reach(0, ct, a, speed, t)).collect() };
            let pairs: Vec<(i64, i64)> = at(fast).into_iter().zip(at(accel)).collect();
            let ignored: Vec<(i64, i64)> = at(accel).into_iter().map(|p| (p, p)).collect();
            let still_moving = pairs.iter().all(|(a, _)| *a < ct - self.mpe(1));
            let why = format!(
                "both motors close at MCV {speed}, motor 1 with ACCEL {fast}, motor 2 with ACCEL {accel}; where each is \
                 when the ^C lands {pause}..{} ms after C, by the model's motion trapezoid",
                pause + slack
            );
            if still_moving && let Some((k, rel)) = self.position_ratio("ACCEL", "C", 0, ct, pairs, &ignored, why) {
                let k = k
                    .line(&format!("12FSET MCV {speed}"))
                    .line(&format!("1FSET ACCEL {fast}"))
                    .nowait("12C")
                    .pause_ms(pause)
                    .abort();
                self.add(rel.read(k));
            }
        }

        // TSTOP: a motor stalled at its joint stop keeps driving for TSTOP ms. With TSTOP 5000
        // a move that stalls at the joint stop cannot end sooner than 5 s after it starts,
        // however fast the motor got there; with the factory TSTOP it ends long before.
        let l4 = self.limit(4);
        let goal = l4 + 850;
        let tstop = 5000u64;
        let (a4, v4) = (self.default("ACCEL", 4), self.default("MCV", 4));
        let mut t_stop = 0u64;
        while t_stop < 60_000 && self.reach(0, goal, a4, v4, t_stop) < l4 {
            t_stop += 10;
        }
        let factory = u64::try_from(self.default("TSTOP", 4)).unwrap_or(0);
        if factory >= tstop {
            return;
        }
        let k = self
            .case(
                "param-tstop-effect",
                format!("TSTOP sets how long a stalled motor keeps driving: with TSTOP {tstop} a move stalled at the joint stop ends no sooner than {tstop} ms after it starts"),
            )
            .src("Parameter TSTOP")
            .src("Command M")
            .decision("seed-motion-model").decision("bh8-position-bounds")
            .requires(Requirement::AbortTiming)
            .preamble(true)
            .line(&format!("SFSET TSTOP {tstop}"))
            .line(&format!("SM {goal}"))
            .no_sooner_than(
                Duration::from_millis(tstop),
                format!(
                    "SM {goal} stalls at the joint stop ({l4}) and keeps driving TSTOP {tstop} ms before it ends, so its \
                     answer comes no sooner than {tstop} ms after the line, whatever the motor's speed (the model reaches \
                     the stop after about {t_stop} ms; with the factory TSTOP {factory} the move would end after about {} ms)",
                    t_stop + factory
                ),
            );
        self.add(k);
    }

    /// A case that sets `name` on motor 1 only and shows where motor 1 is against motor 2 when
    /// a ^C lands: `pairs` are the model's (motor 1, motor 2) positions over the landing
    /// window; `ignored` the pairs of a hand that ignores the parameter, which the relation
    /// must refuse (else no case: the effect would not show).
    #[allow(clippy::too_many_arguments)]
    fn position_ratio(
        &self,
        name: &str,
        word: &str,
        from: i64,
        to: i64,
        pairs: Vec<(i64, i64)>,
        ignored: &[(i64, i64)],
        why: String,
    ) -> Option<(CaseB, PositionRatio)> {
        // The widest margin, up to 5 points, that still refuses a hand ignoring the parameter.
        let refuses = |rel: &Relation| {
            ignored.iter().all(|(a, b)| {
                let (lo, hi) = rel.band(*a);
                !(lo..=hi).contains(b)
            })
        };
        let (margin, rel) = (0..=5u32)
            .rev()
            .filter_map(|m| super::super::build::derive_relation("p1", &pairs, m).map(|r| (m, r)))
            .find(|(_, r)| refuses(r))?;
        let (lo, hi) = (from.min(to) + self.mpe(1), from.max(to) - self.mpe(1));
        if pairs.iter().any(|(a, _)| !(lo < *a && *a < hi)) {
            return None;
        }
        let (r_lo, r_hi) = pairs.iter().fold((f64::INFINITY, 0.0f64), |(l, h), (a, b)| {
            let r = *b as f64 / *a as f64;
            (l.min(r), h.max(r))
        });
        let evidence = format!(
            "{why}, motor 2's position is {r_lo:.2}..{r_hi:.2} times motor 1's ({} model pairs); the relation is \
             the midpoint of those ratios with the least tolerance that holds them all, plus {margin} points (the most, \
             up to 5, that still refuses a hand that ignores {name}: both motors alike); motor 1 must be off its start and short of its goal \
             (more than MPE from each)",
            pairs.len()
        );
        let k = self
            .case(
                format!("param-{}-effect", slug(name)),
                format!("{name} sets how fast {word} moves: with {name} set on motor 1 alone, motor 2 is where the model's ratio puts it against motor 1 when a ^C lands"),
            )
            .src(&format!("Parameter {name}"))
            .src(&format!("Command {word}"))
            .decision("seed-abort")
            .decision("bh8-abort-motion")
            .decision("seed-motion-model")
            .requires(Requirement::AbortTiming)
            .preamble(true);
        let k = if from > 0 { k.line(&format!("12M {from}")) } else { k };
        Some((k, PositionRatio { rel, evidence, pairs, anchor: (lo + 1, hi - 1) }))
    }
}

/// Where motor 2 is against motor 1, as [`Gen::position_ratio`] derived it from the model.
struct PositionRatio {
    rel: Relation,
    evidence: String,
    pairs: Vec<(i64, i64)>,
    /// Where motor 1 may be: off its start and short of its goal.
    anchor: Range,
}

impl PositionRatio {
    /// Reads both positions: motor 1's captured as `p1`, motor 2's held to the relation.
    fn read(self, k: CaseB) -> CaseB {
        k.get("12", &["P"], Some([self.anchor, (0, 0), (0, 0), (0, 0)]))
            .capture(Target::Value { line: 0, token: 0 }, "p1")
            .relate(Target::Value { line: 0, token: 1 }, self.rel, self.evidence, self.pairs)
    }
}
