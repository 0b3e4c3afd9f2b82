//! RealTime: the loop, block layouts from the flags, the codec, LFDP. Here are the generators
//! over the profile's RealTime flags (`rt-field-*`, `rt-all-fields`) and the cases whose bounds
//! need the model's arithmetic (LFDP stepping, velocity data fitted to LFV's byte, strain
//! clamps); the fixed-line cases are scripts (`conformance/suite-cases/realtime/`), which set
//! their flags with `rt-flags:` through [`Gen::rt_flags`].

use super::*;

impl Gen {
    /// FSET (and PSET) lines setting every RealTime flag: 1 for `on`, 0 for the rest.
    pub(super) fn rt_flags(&self, prefix: &str, on: &[&str]) -> Vec<String> {
        let flags: Vec<&ParamSpec> = self.p.params.iter().filter(|x| x.rt.is_some()).collect();
        let motor: Vec<String> = flags
            .iter()
            .filter(|x| x.scope == Scope::Motor)
            .map(|x| format!("{} {}", x.name, i32::from(on.contains(&x.name.as_str()))))
            .collect();
        let mut lines = chunk_lines(&format!("{prefix}FSET"), &motor, safe_line(&self.p));
        for g in flags.iter().filter(|x| x.scope == Scope::Global) {
            if let Some(id) = self.p.param_id(&g.name) {
                lines.push(format!("{} {} {}", self.p.setter(id), g.name, i32::from(on.contains(&g.name.as_str()))));
            }
        }
        lines
    }

    pub(super) fn rt_case(&self, id: &str, title: &str, prefix: &str, on: &[&str]) -> CaseB {
        let mut k = self.case(id, title).src("RealTime Control").requires(Requirement::Realtime).preamble(true);
        for l in self.rt_flags(prefix, on) {
            k = k.line(&l);
        }
        k
    }

    pub(super) fn at_rest(&self) -> Vec<FieldRule> {
        (1..=4u8).map(|m| FieldRule { motor: Some(m), name: "LFAP", range: Some((0, self.mpe(m))) }).collect()
    }

    pub(super) fn realtime(&mut self) {
        self.scripts(&["rt-header-upper-c", "rt-header-lower-c", "rt-header-upper-a", "rt-header-lower-a"]);

        let flags: Vec<ParamSpec> = self.p.params.iter().filter(|x| x.rt.is_some()).cloned().collect();
        for f in &flags {
            let Some(rt) = f.rt else { continue };
            let block = if rt.block == gcl_model::spec::BlockKind::Control { "control" } else { "feedback" };
            let bytes = if rt.size == 1 { "1 byte" } else { "2 bytes" };
            let mut k = self.rt_case(
                &format!("rt-field-{}", slug(&f.name)),
                &format!("{} alone adds {bytes} to the {block} block", f.name),
                if f.scope == Scope::Motor { "1" } else { "" },
                &[&f.name],
            );
            let cited: &[&str] = match f.name.as_str() {
                "LFT" => &["bh8-lft-field"],
                "LCT" | "LFBP" | "LFAIN" => &["bh8-44-rt-field-order", "bh8-new-rt-fields-defaults"],
                _ => &[],
            };
            k = self.cite_or_must(k, cited);
            k = k.src(&format!("Parameter {}", f.name)).line("1LOOP");
            if rt.block == gcl_model::spec::BlockKind::Control {
                let mut b = vec![b'C'];
                b.extend(std::iter::repeat_n(0u8, rt.size));
                let mut c = vec![b'c'];
                c.extend(std::iter::repeat_n(0u8, rt.size));
                k = k.block(&b, Shape::Block(self.at_rest())).block(&c, Shape::Block(self.at_rest()));
            } else {
                k = k.block(b"A", Shape::Block(self.at_rest()));
            }
            // And back: with the flag 0 the field is gone (a C block is its header alone).
            let off = match self.p.param_id(&f.name) {
                Some(id) if f.scope == Scope::Global => format!("{} {} 0", self.p.setter(id), f.name),
                _ => format!("1FSET {} 0", f.name),
            };
            k = k
                .abort()
                .comment(format!("{} 0: no field", f.name))
                .line(&off)
                .line("1LOOP")
                .block(if rt.block == gcl_model::spec::BlockKind::Control { b"C" } else { b"A" }, Shape::Exact)
                .abort();
            self.add(k);
        }

        let all: Vec<&str> = flags.iter().map(|x| x.name.as_str()).collect();
        let control_size: usize = flags
            .iter()
            .filter(|x| x.scope == Scope::Motor && x.rt.is_some_and(|r| r.block == gcl_model::spec::BlockKind::Control))
            .map(|x| x.rt.map_or(0, |r| r.size))
            .sum::<usize>()
            * 4;
        let mut block = vec![b'C'];
        block.extend(std::iter::repeat_n(0u8, control_size));
        let k = self
            .rt_case(
                "rt-all-fields",
                "Every flag on every motor: fields per motor in order, motors ascending, hand fields last",
                "",
                &all,
            )
            .decision("seed-rt-field-order")
            .decision("bh8-44-rt-field-order")
            .line("1234LOOP")
            .block(&block, Shape::Block(self.at_rest()))
            .block(b"A", Shape::Block(self.at_rest()))
            .abort();
        self.add(k);

        self.scripts(&["rt-lfap-byte-order"]);

        self.lfdp_case(
            "rt-lfdp-worked-example",
            "The LFDP worked example: LFDPC 2, reported 1500, moved to 2000: 127, 123, 0",
            2,
            1500,
            2000,
            false,
            3,
        );
        if self.has_param("LFDPD") {
            self.lfdp_case(
                "rt-lfdpd-discard",
                "With LFDPD 1 the clipped rest of LFDP is dropped: 127, 0, 0",
                2,
                1500,
                2000,
                true,
                3,
            );
        }
        self.lfdpc_scaling();

        // LFVC divides the feedback velocity: two motors at one velocity, LFVC 2 on motor 1.
        let (datum, lcvc) = self.fit_lfv(40, self.brisk_lcvc(), 2, 1);
        let (v1, v2) = (self.lfv_at(datum, lcvc, 2), self.lfv_at(datum, lcvc, 1));
        let k = self
            .rt_case(
                "rt-lfvc-scaling",
                "LFV is the velocity divided by LFVC: at one velocity, LFVC 1 reads twice what LFVC 2 reads",
                "12",
                &["LCV", "LFV"],
            )
            .src("Parameter LFVC")
            .line(&format!("12FSET LCVC {lcvc}"))
            .line("1FSET LFVC 2")
            .line("2FSET LFVC 1");
        self.add(two_motor_ratio(k, datum, (v1, v2), (2, 1), "motor 1 divides by LFVC 2, motor 2 by 1"));

        // The units of the control and feedback velocities: one datum, one LCVC, an absolute
        // band. The only case that rests on them; the scaling cases above hold ratios.
        let lcvc = ((1i64 << self.p.hand.lcv_fraction_bits) / 4).clamp(1, 255);
        let (datum, lcvc) = self.fit_lfv(40, lcvc, 1, 1);
        let lfv = self.lfv_at(datum, lcvc, 1);
        let k = self
            .rt_case(
                "rt-velocity-units",
                &format!(
                    "The velocity units: LCV {datum} x LCVC {lcvc} runs a motor at a velocity LFV reads as about {lfv}"
                ),
                "1",
                &["LCV", "LFV"],
            )
            .src("Parameter LCVC")
            .src("Parameter LFV")
            .decision("seed-rt-velocity")
            .decision("bh8-velocity-units")
            .note("Velocities during motion are compared with 25% tolerance.")
            .line(&format!("1FSET LCVC {lcvc}"))
            .line("1LOOP")
            .block(&[b'C', datum as u8], Shape::Block(Vec::new()))
            .pause_ms(50)
            .block(b"A", Shape::Block(vec![FieldRule { motor: Some(1), name: "LFV", range: Some(tol(lfv)) }]))
            .abort();
        self.add(k);

        self.scripts(&["rt-bad-header-returns-to-supervisory"]);

        self.realtime_decisions();
    }

    /// The LFV a motor reads while it runs at the control velocity of an LCV `datum` with
    /// `lcvc` (no gain field), reported with `lfvc` (0 acts as 1).
    pub(super) fn lfv_at(&self, datum: i64, lcvc: i64, lfvc: i64) -> i64 {
        super::super::build::lfv_exact(&self.p, datum, lcvc, lfvc).trunc() as i64
    }

    /// `datum` and `lcvc`, halved (LCVC first) until the LFV of `factor` × `lcvc` with `lfvc`,
    /// with its tolerance band, fits LFV's signed byte: feedback units differ by profile.
    fn fit_lfv(&self, mut datum: i64, mut lcvc: i64, factor: i64, lfvc: i64) -> (i64, i64) {
        while tol(self.lfv_at(datum, factor * lcvc, lfvc)).1 > 127 && datum > 1 {
            if lcvc > 1 {
                lcvc /= 2;
            } else {
                datum /= 2;
            }
        }
        (datum, lcvc)
    }

    /// An LCVC for a brisk RealTime move that stays inside the joint range over a case's short
    /// pauses: half of one whole LCV unit (LCV has `lcv_fraction_bits` fraction bits).
    pub(super) fn brisk_lcvc(&self) -> i64 {
        ((1i64 << self.p.hand.lcv_fraction_bits) / 2).clamp(1, 255)
    }

    /// RealTime cases for decisions about the loop's motors, gains and coefficients.
    pub(super) fn realtime_decisions(&mut self) {
        // LFV x LFVC is the velocity: two motors at one velocity, LFVC 1 and 2.
        let (datum, lcvc) = self.fit_lfv(40, self.brisk_lcvc(), 2, 1);
        let (v1, v2) = (self.lfv_at(datum, lcvc, 1), self.lfv_at(datum, lcvc, 2));
        let k = self
            .rt_case(
                "rt-lfv-formula",
                "LFV x LFVC is the velocity: at one velocity, LFVC 2 reads half what LFVC 1 reads",
                "12",
                &["LCV", "LFV"],
            )
            .src("Parameter LFV")
            .src("Parameter LFVC")
            .decision("seed-lfv-formula")
            .line(&format!("12FSET LCVC {lcvc}"))
            .line("1FSET LFVC 1")
            .line("2FSET LFVC 2");
        self.add(two_motor_ratio(
            k,
            datum,
            (v1, v2),
            (1, 2),
            "LFV x LFVC is one velocity: motor 1 has LFVC 1, motor 2 LFVC 2",
        ));

        // LCVC multiplies the datum: two motors at one datum, LCVC twice as large on motor 1.
        let (v1, v2) = (self.lfv_at(datum, 2 * lcvc, 1), self.lfv_at(datum, lcvc, 1));
        let k = self
            .rt_case(
                "rt-lcvc-scaling",
                "The control velocity is LCV x LCVC: one datum with twice the LCVC runs twice as fast",
                "12",
                &["LCV", "LFV"],
            )
            .src("Parameter LCVC")
            .src("Parameter LCV")
            .line(&format!("1FSET LCVC {}", 2 * lcvc))
            .line(&format!("2FSET LCVC {lcvc}"));
        self.add(two_motor_ratio(
            k,
            datum,
            (v1, v2),
            (1, 2),
            "the control velocity is LCV x LCVC: motor 1 has LCVC twice motor 2's",
        ));

        self.lcvc_positions(datum, lcvc);

        // With LCPG 1 the gain starts at 0: a velocity alone does not move the motor. A motor
        // without LCV keeps its control velocity of 0 whatever its gain.
        let finger = self.limit(1);
        let v = self.lfv_at(datum, lcvc, 1);
        let still = |g: &Gen| -> Vec<FieldRule> {
            (1..=2u8).map(|m| FieldRule { motor: Some(m), name: "LFAP", range: Some((0, g.mpe(m))) }).collect()
        };
        // Moving is the clause, not how fast: the sign of the datum, in whatever units.
        let moving = vec![
            FieldRule { motor: Some(1), name: "LFV", range: Some((1, 127)) },
            FieldRule { motor: Some(1), name: "LFAP", range: Some((0, finger)) },
            FieldRule { motor: Some(2), name: "LFAP", range: Some((0, self.mpe(2))) },
        ];
        let mut k = self
            .rt_case(
                "rt-lcpg-zero-gain",
                "With LCPG 1 the gain starts at 0 on LOOP entry: a control velocity moves nothing until a gain arrives; a motor without LCV stays",
                "12",
                &["LCPG", "LFV", "LFAP"],
            )
            .src("Parameter LCPG");
        k = k.decision("seed-lcpg-gain").decision("bh8-rt-zero-gain");
        let k = k
            .note(format!(
                "Control blocks: motor 1 LCV then LCPG, motor 2 LCPG. The answer to a C block shows the state before \
                 its data. Once a gain arrives motor 1 runs: its LFV reads the datum's sign (1..127; the model reads about {v})."
            ))
            .line(&format!("1FSET LCV 1 LCVC {lcvc}"))
            .line("12LOOP")
            .comment(format!("velocity {datum}, gain 0 on motor 1; gain 64 on motor 2, which has no velocity field"))
            .block(&[b'C', datum as u8, 0, 64], Shape::Block(still(self)))
            .pause_ms(100)
            .block(b"A", Shape::Block(still(self)))
            .comment("the same velocity with gain 64: motor 1 runs, motor 2 still has no velocity")
            .block(&[b'C', datum as u8, 64, 64], Shape::Block(still(self)))
            .pause_ms(100)
            .block(b"A", Shape::Block(moving))
            .abort();
        self.add(k);

        self.lcpg_positions(datum, lcvc);

        self.scripts(&["rt-loop-en-motors"]);

        // SGFLIP turns the LFS byte over as it turns FGET SG over.
        if self.p.decisions.iter().any(|d| d.id == "bh8-lfs-sgflip") {
            let f = self.p.hand.free_strain;
            let (plain, flipped) = ((0, (2 * f).min(255)), ((255 - 2 * f).max(0), 255));
            let k = self
                .rt_case(
                    "rt-lfs-sgflip",
                    "With SGFLIP 1 the LFS byte is 255 minus the strain, as FGET SG reads",
                    "12",
                    &["LFS"],
                )
                .src("Parameter LFS")
                .src("Parameter SGFLIP")
                .decision("bh8-lfs-sgflip")
                .decision("bh8-sgflip-default")
                .note(format!(
                    "A free finger's strain is near {f}: with SGFLIP 0 it reads {}..{}, with SGFLIP 1 {}..{}.",
                    plain.0, plain.1, flipped.0, flipped.1
                ))
                .line("2FSET SGFLIP 1")
                .line_shaped("12FGET SG", Shape::Values(vec![vec![Some(plain), Some(flipped)]]))
                .line("12LOOP")
                .block(
                    b"A",
                    Shape::Block(vec![
                        FieldRule { motor: Some(1), name: "LFS", range: Some(plain) },
                        FieldRule { motor: Some(2), name: "LFS", range: Some(flipped) },
                    ]),
                )
                .abort();
            self.add(k);
        }

        self.scripts(&["rt-coefficients-no-field"]);

        // A coefficient of 0 is accepted and divides as 1.
        if self.p.decisions.iter().any(|d| d.id == "bh8-coefficient-range") {
            let mpe = 10;
            let (from, to) = (0i64, 100i64);
            let mut lfdp = vec![(i64::MAX, i64::MIN); 2];
            for p1 in (from - mpe).max(0)..=from + mpe {
                for p2 in (to - mpe).max(0)..=to + mpe {
                    let mut r = p1;
                    for slot in lfdp.iter_mut() {
                        let v = i64::from(lfdp_step(&mut r, p2, 1, false));
                        *slot = (slot.0.min(v), slot.1.max(v));
                    }
                }
            }
            let both = |name: &'static str, r: Option<Range>| -> Vec<FieldRule> {
                (1..=2u8).map(|m| FieldRule { motor: Some(m), name, range: r }).collect()
            };
            let v = self.lfv_at(datum, lcvc, 1);
            let near: [Range; 4] = [(0, mpe); 4];
            let mut k = self
                .rt_case(
                    "rt-coefficients-zero",
                    "LFVC 0 and LFDPC 0 are accepted and act as 1: motor 1 (0) reads as motor 2 (1)",
                    "12",
                    &["LCV", "LFV", "LFDP"],
                )
                .src("Parameter LFVC")
                .src("Parameter LFDPC")
                .decision("bh8-coefficient-range")
                .note(format!("MPE is {mpe} so that LFDP after the move is narrow."))
                .line("1FSET LFVC 0 LFDPC 0")
                .line("2FSET LFVC 1 LFDPC 1")
                .line(&format!("12FSET LCVC {lcvc} MPE {mpe}"))
                .get("12", &["LFVC", "LFDPC"], None)
                .get("12", &["P"], Some(near))
                .line(&format!("12M {to}"))
                .line("12LOOP");
            for r in &lfdp {
                k = k.block(b"A", Shape::Block(both("LFDP", Some(*r))));
            }
            let mut moving = vec![FieldRule { motor: Some(1), name: "LFV", range: Some((LEAST_ANCHOR, 127)) }];
            moving.extend(both("LFDP", Some((0, 127))));
            let lfv = |m: u8| Target::Field { motor: Some(m), name: "LFV" };
            let evidence = format!(
                "LFVC 0 acts as 1, so motor 1 (LFVC 0) reads motor 2's (LFVC 1) velocity, whatever the velocity units \
                 (the model reads {v} on both); velocities during motion are compared with 25 % tolerance"
            );
            let k = k
                .block(&[b'C', datum as u8, datum as u8], Shape::Block(Vec::new()))
                .pause_ms(50)
                .block(b"A", Shape::Block(moving))
                .capture(lfv(1), "v1")
                .relate(lfv(2), Relation::new("v1", 1, 1, 25), evidence, vec![(v, v)])
                .abort();
            self.add(k);
        }
    }

    /// The counts per ms a motor runs at in the loop with velocity datum `datum` and `lcvc`, by
    /// the model's arithmetic (no gain field: it runs at the control velocity at once).
    fn rt_counts_per_ms(&self, datum: i64, lcvc: i64) -> f64 {
        let h = &self.p.hand;
        gcl_model::realtime::control_velocity(datum, lcvc, h.lcv_fraction_bits) * h.rt_velocity_counts_per_ms
    }

    /// A pause in the loop, and the landing window of the ^C after it, in which a motor at `v`
    /// counts per ms moves far enough for a ratio to show (about 600 counts) and a hand twice as
    /// fast still stays short of motor `m`'s joint stop; `None` where no such pause is.
    fn rt_pause(&self, v: f64, m: u8) -> Option<(u64, u64)> {
        let slack = 150u64;
        let pause = ((600.0 / v.abs().max(1e-9)).round() as u64).clamp(30, 300);
        let far = v.abs() * (pause + slack) as f64;
        (v.abs() * pause as f64 >= 100.0 && 2.0 * far < (self.limit(m) - self.mpe(m)) as f64).then_some((pause, slack))
    }

    /// rt-lcvc-scaling reads LCVC's effect through LFV, which another clause defines: a hand
    /// whose feedback velocity is broken fails it whatever its LCVC does, and an LCVC ignored
    /// on top of that adds no failure. Its behavioural twin reads where the motors went: two
    /// motors from home at one datum, motor 1 with twice motor 2's LCVC, the loop ended by ^C
    /// after a pause, then FGET P: motor 1 went twice as far, whatever the velocity units or
    /// how long the pause really was (both ran over the same interval; and a hand that kept the
    /// motors going after the ^C until the read would keep the ratio too).
    fn lcvc_positions(&mut self, datum: i64, lcvc: i64) {
        let (v1, v2) = (self.rt_counts_per_ms(datum, 2 * lcvc), self.rt_counts_per_ms(datum, lcvc));
        let Some((pause, slack)) = self.rt_pause(v1, 1) else { return };
        let at = |v: f64, t: u64| (v * t as f64).round() as i64;
        let window = pause..=pause + slack;
        let pairs: Vec<(i64, i64)> = window.clone().map(|t| (at(v1, t), at(v2, t))).collect();
        // (a hand that ignores LCVC runs both at the factory LCVC: the same distance)
        let factory = self.default("LCVC", 1);
        let same = self.rt_counts_per_ms(datum, factory);
        let ignored: Vec<(i64, i64)> = window.map(|t| (at(same, t), at(same, t))).collect();
        let Some(fit) = super::super::build::fit_tolerance("p1", 1, 2, &pairs, 2) else { return };
        let rel = Relation::new("p1", 1, 2, fit.tolerance.max(25));
        if ignored.iter().any(|(a, b)| {
            let (lo, hi) = rel.band(*a);
            (lo..=hi).contains(b)
        }) {
            return;
        }
        let (lo, hi) = (pairs.iter().map(|x| x.0).min().unwrap_or(0), pairs.iter().map(|x| x.0).max().unwrap_or(0));
        // Off home by enough counts for the ratio to show through truncation (motor 2 then
        // reads at least LEAST_ANCHOR), not by what the pause gives on the model's clock: the
        // ratio holds however long the motors ran, so a hand whose motions take no wall time
        // (a firmware build over a pipe, which still moves over the RealTime cycles it runs) is
        // judged too.
        let anchor = (2 * LEAST_ANCHOR, (self.limit(1) - self.mpe(1)).min(4 * hi));
        let evidence = format!(
            "the control velocity is LCV x LCVC: motors 1 and 2 run from home at one datum ({datum}), motor \
             1 with LCVC {} and motor 2 with LCVC {lcvc}, over the same interval (the ^C lands {pause}..{} \
             ms after the block), so motor 2 goes half as far as motor 1 whatever the velocity units; the \
             model reads {}..{} and {}..{}; a position read in motion is compared with 25 % tolerance, which \
             refuses a hand that runs both alike (LCVC without effect); motor 1 must be {} counts or more \
             from home (the least for the ratio to show) and short of its stop; no clock is read: the case \
             holds on a hand whose motions take no wall time",
            2 * lcvc,
            pause + slack,
            lo,
            hi,
            pairs.iter().map(|x| x.1).min().unwrap_or(0),
            pairs.iter().map(|x| x.1).max().unwrap_or(0),
            anchor.0,
        );
        let k = self
            .rt_case(
                "rt-lcvc-positions",
                "The control velocity is LCV x LCVC, seen in where the motors go: one datum with twice the LCVC goes twice as far",
                "12",
                &["LCV"],
            )
            .src("Parameter LCVC")
            .src("Parameter LCV")
            // (no `requires: abort-timing`: the ^C ends the loop wherever the motors are, and the
            // ratio is read, not a time)
            .line(&format!("1FSET LCVC {}", 2 * lcvc))
            .line(&format!("2FSET LCVC {lcvc}"))
            .line("12LOOP")
            // (`c`: no feedback asked, so no feedback flag's clause is read)
            .block(&[b'c', datum as u8, datum as u8], Shape::Exact)
            .pause_ms(pause)
            .abort()
            .get("12", &["P"], Some([anchor, (0, 0), (0, 0), (0, 0)]))
            .capture(Target::Value { line: 0, token: 0 }, "p1")
            .relate(Target::Value { line: 0, token: 1 }, rel, evidence, pairs);
        self.add(k);
    }

    /// rt-lcpg-zero-gain reads LCPG's effect through LFAP and LFV, which other clauses define.
    /// Its behavioural twin reads where the motor went: with LCPG 1 a velocity with gain 0 (the
    /// gain at LOOP entry) leaves motor 1 at home; the same velocity with a gain in a second
    /// loop moves it.
    fn lcpg_positions(&mut self, datum: i64, lcvc: i64) {
        if !self.p.decisions.iter().any(|d| d.id == "seed-lcpg-gain" || d.id == "bh8-rt-zero-gain") {
            return;
        }
        let v = self.rt_counts_per_ms(datum, lcvc);
        let Some((pause, _)) = self.rt_pause(v, 1) else { return };
        let home = [(0, self.mpe(1)); 4];
        let moved = [(2 * self.mpe(1), self.limit(1)), (0, 0), (0, 0), (0, 0)];
        let mut k = self
            .rt_case(
                "rt-lcpg-zero-gain-positions",
                "With LCPG 1 the gain starts at 0 on LOOP entry, seen in where the motor goes: a velocity alone leaves it at home; with a gain it moves",
                "1",
                &["LCPG"],
            )
            .src("Parameter LCPG")
            // (the motor moves over the host's pause: a hand whose motions take no time does not)
            .requires(Requirement::AbortTiming);
        k = k.decision("seed-lcpg-gain").decision("bh8-rt-zero-gain");
        let k = k
            .note(format!(
                "Control blocks (`c`, no feedback asked): motor 1 LCV then LCPG. After a velocity with gain 0 \
                 and {pause} ms, motor 1 is still at home (within MPE); after the same velocity with gain 64 \
                 in a new loop it has moved (the model runs it about {} counts)",
                (v * pause as f64).round() as i64
            ))
            .line(&format!("1FSET LCV 1 LCVC {lcvc}"))
            .line("1LOOP")
            .comment(format!("velocity {datum}, gain 0"))
            .block(&[b'c', datum as u8, 0], Shape::Exact)
            .pause_ms(pause)
            .abort()
            .get("1", &["P"], Some(home))
            .line("1LOOP")
            .comment(format!("velocity {datum}, gain 64"))
            .block(&[b'c', datum as u8, 64], Shape::Exact)
            .pause_ms(pause)
            .abort()
            .get("1", &["P"], Some(moved));
        self.add(k);
    }

    /// LFDPC divides the movement LFDP reports: motors 1 and 2 run at one control velocity
    /// in the loop, motor 2 with twice motor 1's LFDPC, so between two feedback blocks motor 2's
    /// LFDP is half motor 1's. The ratio is the clause. The relation is read on the second of
    /// two blocks, whose LFDP counts from the first: where LFDP counts from before any block
    /// (the last reported position, an open point) does not matter, nor do the velocity units
    /// or how long the host's pause really is.
    fn lfdpc_scaling(&mut self) {
        let (datum, lcvc) = self.fit_lfv(40, self.brisk_lcvc(), 2, 1);
        let h = &self.p.hand;
        let counts_per_ms =
            gcl_model::realtime::control_velocity(datum, lcvc, h.lcv_fraction_bits) * h.rt_velocity_counts_per_ms;
        let pause = 50u64;
        // The movement between the blocks in the model's units, and an LFDPC that reads it as
        // about 40.
        let m0 = (counts_per_ms * pause as f64).round() as i64;
        let coeff = (m0 / 40).clamp(1, 127);
        let least = LEAST_ANCHOR * coeff;
        let (lo_m, hi_m) = ((m0 / 2).max(least), (2 * m0).min(127 * coeff));
        // Every movement from half to twice the model's, and every rest a truncation leaves
        // behind (LFDP carries it: the reported position advances by LFDP x LFDPC).
        let mut pairs: Vec<(i64, i64)> = Vec::new();
        for m in lo_m..=hi_m {
            for r1 in 0..coeff {
                for r2 in 0..2 * coeff {
                    let pair = ((m + r1) / coeff, (m + r2) / (2 * coeff));
                    if !pairs.contains(&pair) {
                        pairs.push(pair);
                    }
                }
            }
        }
        let Some(rel) = super::super::build::fit_tolerance("d1", 1, 2, &pairs, 2) else { return };
        let evidence = format!(
            "both motors run at one control velocity (LCV {datum} x LCVC {lcvc}, about {m0} counts in the model \
             between the two blocks); motor 1 divides the movement by LFDPC {coeff}, motor 2 by {}, so motor 2's \
             LFDP is half motor 1's; the tolerance is the least that holds the model's LFDP arithmetic (truncation, \
             with the rest carried) over every movement of {lo_m}..{hi_m} counts ({} pairs), plus 2 points; motor 1 \
             must read {LEAST_ANCHOR}..127, a movement large enough for the ratio to show",
            2 * coeff,
            pairs.len()
        );
        let lfdp = |m: u8| Target::Field { motor: Some(m), name: "LFDP" };
        let any = |name: &'static str| -> Vec<FieldRule> {
            (1..=2u8).map(|m| FieldRule { motor: Some(m), name, range: Some((-128, 127)) }).collect()
        };
        let k = self
            .rt_case(
                "rt-lfdpc-scaling",
                &format!(
                    "LFDP is the movement divided by LFDPC: at one velocity, LFDPC {} reads half what LFDPC {coeff} reads",
                    2 * coeff
                ),
                "12",
                &["LCV", "LFDP"],
            )
            .src("Parameter LFDPC")
            // The movement between the blocks is made over the host's pause: a hand whose
            // motions take no time moves too little for the ratio to show.
            .requires(Requirement::AbortTiming)
            .line(&format!("12FSET LCVC {lcvc}"))
            .line(&format!("1FSET LFDPC {coeff}"))
            .line(&format!("2FSET LFDPC {}", 2 * coeff))
            .line("12LOOP")
            .comment("both motors at one velocity; the first feedback counts from wherever LFDP starts")
            .block(&[b'C', datum as u8, datum as u8], Shape::Block(any("LFDP")))
            .pause_ms(pause)
            .block(b"A", Shape::Block(any("LFDP")))
            .comment("the movement since the block before")
            .pause_ms(pause)
            .block(b"A", Shape::Block(vec![FieldRule { motor: Some(1), name: "LFDP", range: Some((LEAST_ANCHOR, 127)) }]))
            .capture(lfdp(1), "d1")
            .relate(lfdp(2), rel, evidence, pairs)
            .abort();
        self.add(k);
    }

    #[allow(clippy::too_many_arguments)]
    pub(super) fn lfdp_case(
        &mut self,
        id: &str,
        title: &str,
        coeff: i64,
        from: i64,
        to: i64,
        discard: bool,
        blocks: usize,
    ) {
        let mpe = self.mpe(1);
        // Every position the two moves may end at within MPE, and the LFDP values that follow.
        let mut ranges = vec![(i64::MAX, i64::MIN); blocks];
        for p1 in (from - mpe).max(0)..=from + mpe {
            for p2 in (to - mpe).max(0)..=to + mpe {
                let mut r = p1;
                for slot in ranges.iter_mut() {
                    let v = i64::from(lfdp_step(&mut r, p2, coeff, discard));
                    *slot = (slot.0.min(v), slot.1.max(v));
                }
            }
        }
        let mut k = self.rt_case(id, title, "1", &["LFDP"]).src("Parameter LFDPC");
        if discard {
            k = k.src("Parameter LFDPD");
        }
        k = k.decision("seed-lfdp-state").decision("bh8-lfdp-state").decision("bh8-rt-clipping");
        if discard {
            k = k.line("PSET LFDPD 1");
        }
        k = k
            .note(format!("LFDP ranges cover both moves ending anywhere within MPE ({mpe}) of their goals."))
            .line(&format!("1FSET LFDPC {coeff}"));
        if from > 0 {
            k = k.line(&format!("1M {from}"));
        }
        k = k.get("1", &["P"], Some(self.near([from; 4]))).line(&format!("1M {to}")).line("1LOOP");
        for r in ranges {
            k = k.block(b"A", Shape::Block(vec![FieldRule { motor: Some(1), name: "LFDP", range: Some(r) }]));
        }
        k = k.abort();
        self.add(k);
    }
}
