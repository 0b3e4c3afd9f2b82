//! Relations between feedback fields, for hands outside this process.
//!
//! Once a RealTime block has moved a hand outside this process, its positions are the hand's
//! clock's, not the model's, and [`super::case`] accepts any LFAP, LFV, LFDP or LFBP. What the
//! clauses of LCVC, LFVC and LFDPC say survives that: they are ratios. A motor's feedback
//! velocity is its control velocity (LCV × LCVC) over LFVC, whatever the hand's velocity
//! units; two motors' LFDP over one interval are their movements over their LFDPC, however
//! long the interval really was. So the fuzzer writes them as the suite's relations
//! ([`crate::suite::build::Bind`]): the first steady feedback velocity of a case is captured,
//! and every later one is held to it times the ratio the model gives; within one block, each
//! motor's LFDP is held to the LFDP of the motor that moves most, times theirs. The matcher
//! judges them as it judges a golden's.
//!
//! A reading is related only where the model's arithmetic fixes it whatever the timing:
//! - the motor has an LCV field and neither a gain nor a torque field (a gain ramps the
//!   velocity at the model's pace), and a velocity datum other than 0;
//! - LFV: the block leaves the motor's datum as it was, so the feedback reads the same velocity
//!   whether a hand reports before or after it takes the block's data; the model reads its
//!   own arithmetic exactly (the motor runs, in the model, at no limit) and 4..=100 (truncation
//!   inside the tolerance, and room under the signed byte's end);
//! - LFDP: neither motor's datum changed since the block before the previous feedback, so both
//!   ran at one velocity over the whole interval; the anchor (the first such motor on the wire)
//!   reads 8..=24 in the model (room for a faster hand or a longer interval under the signed
//!   byte's end), and only
//!   motors after it that move no more than it are held to it; every earlier reading of both
//!   in the loop was at most 24 in the model too (a clipped reading carries its rest into the
//!   next).
//!
//! The factor is the model's ratio (a fraction over 1000); the tolerance is the 25 % the suite
//! allows velocities in motion, and a reading is related only where that holds every truncation
//! of the model's arithmetic, plus 2 points, over readings from half to twice the model's (LFDP:
//! with every rest the last reading may have carried).

use gcl_model::realtime::{Control, ControlHeader, RtLayout, control_velocity};
use gcl_model::spec::Role;
use gcl_model::{Device, Motor, Profile};

use crate::record::Captured;
use crate::suite::build::{fit_tolerance, gcd, lfv_exact};
use crate::suite::plan::{Bind, Target};
use gcl_transcript::Relation;

/// The least a velocity in motion is allowed to differ from the ratio, in percent (the suite's
/// relations between velocities use it too).
const MOTION_TOLERANCE: u32 = 25;
/// LFV readings beyond this are too near the signed byte's end for a ratio (a hand whose units
/// are a little larger clips).
const MOST_LFV: i64 = 100;
/// LFDP readings of the anchor beyond this are not related: LFDP counts the movement over the
/// hand's real interval at the hand's own speed (the seed leaves motion speed open; the
/// independent seed hand moves 2.5 times the model's), and a host stalled under load
/// stretches the interval, so a reading must leave room for five times the model's before the
/// signed byte clips it (a clipped anchor breaks the ratio: seen at 40 on a loaded machine).
const MOST_LFDP: i64 = 24;
/// [`MOST_LFDP`] for a case built on a hypothesis about the hand (a coefficient without
/// effect reads larger): room for twice the model's reading under the signed byte's end. A
/// hypothesis's case is only a hypothesis until the hand answers it (see `variant`): one whose
/// relation a faster hand breaks names nothing, it never names the wrong bug.
const MOST_LFDP_HYPOTHESIS: i64 = 63;
/// The least LFV reading related: from 4 on, truncation stays inside the tolerance.
const LEAST_LFV: i64 = 4;
/// The least LFDP reading of the moving motor: half of it is still [`LEAST_LFV`].
const LEAST_LFDP: i64 = 2 * LEAST_LFV;

/// The coefficients a motor's loop runs with (read when the loop starts, as the model does).
#[derive(Debug, Clone, Copy, Default)]
struct Coefficients {
    lcvc: Option<i64>,
    lfvc: Option<i64>,
    lfdpc: Option<i64>,
}

/// The loop the shadow model is in, as the host drove it: each motor's velocity datum and when
/// it last changed.
pub(super) struct LoopTrack {
    coeff: [Coefficients; 4],
    datum: [i64; 4],
    changed: [Option<u32>; 4],
    blocks: u32,
    last_feedback: Option<u32>,
    /// Which loop of the case (the step it was entered at).
    id: usize,
}

/// What a feedback block may be related on: per motor (index 0 is motor 1).
#[derive(Debug, Clone)]
pub(super) struct BlockNote {
    /// The loop's id.
    loop_id: usize,
    coeff: [Coefficients; 4],
    datum: [i64; 4],
    /// The block leaves the motor's velocity as it was.
    lfv: [bool; 4],
    /// The motor ran at one velocity since the previous feedback.
    lfdp: [bool; 4],
}

impl LoopTrack {
    /// The loop the shadow has just entered, at step `id`.
    pub(super) fn enter(p: &Profile, shadow: &Device, id: usize) -> LoopTrack {
        let read = |role: Role, m: u8| -> Option<i64> {
            match p.role(role) {
                Some(id) => Some(shadow.effective(id, m)),
                None => Motor::new(m).and_then(|motor| p.absent_value(role, motor)),
            }
        };
        let coeff = [1u8, 2, 3, 4].map(|m| Coefficients {
            lcvc: read(Role::VelocityCoefficient, m),
            lfvc: read(Role::FeedbackVelocityCoefficient, m),
            lfdpc: read(Role::DeltaCoefficient, m),
        });
        LoopTrack { coeff, datum: [0; 4], changed: [None; 4], blocks: 0, last_feedback: None, id }
    }

    /// A whole block the host sent in the loop (`bytes`: header and data as encoded); its note
    /// when it asks for feedback.
    pub(super) fn block(&mut self, layout: &RtLayout, bytes: &[u8]) -> Option<BlockNote> {
        let h = ControlHeader::from_byte(*bytes.first()?)?;
        let before = self.datum;
        if h.has_data()
            && let Ok(c) = Control::parse(layout.control(), bytes)
        {
            for m in 1..=4u8 {
                if let Some(v) = c.motor(m).velocity {
                    self.datum[usize::from(m - 1)] = v;
                }
            }
        }
        let has = |m: u8, name: &str| layout.control().position(Some(m), name).is_some();
        let mut note =
            BlockNote { loop_id: self.id, coeff: self.coeff, datum: self.datum, lfv: [false; 4], lfdp: [false; 4] };
        for m in 1..=4u8 {
            let i = usize::from(m - 1);
            if before[i] != self.datum[i] {
                self.changed[i] = Some(self.blocks);
            }
            let steady = has(m, "LCV") && !has(m, "LCPG") && !has(m, "LCT") && self.datum[i] != 0;
            note.lfv[i] = steady && before[i] == self.datum[i];
            note.lfdp[i] = steady && self.last_feedback.is_some_and(|f| self.changed[i].is_some_and(|c| c < f));
        }
        let wants = h.wants_feedback();
        if wants {
            self.last_feedback = Some(self.blocks);
        }
        self.blocks += 1;
        wants.then_some(note)
    }
}

/// The feedback velocity captured first in a case, which later ones are related to.
struct Anchor {
    name: String,
    exact: f64,
    model: i64,
    /// LCVC and LFVC.
    coeff: (i64, i64),
    what: String,
}

/// Relations across a case's feedback blocks (one per case).
pub(super) struct Relations {
    /// The largest LFDP reading of the model related ([`MOST_LFDP`], or
    /// [`MOST_LFDP_HYPOTHESIS`]).
    most_lfdp: i64,
    anchor: Option<Anchor>,
    /// The loop whose LFDP readings `lfdp_bounded` follows.
    lfdp_loop: Option<usize>,
    /// Per motor: every LFDP reading of the loop so far was at most [`MOST_LFDP`] in the
    /// model, so no hand clipped one and carried the rest into the next (a reading carries
    /// what the byte could not hold: seen as 125 where the relation wanted about 45).
    lfdp_bounded: [bool; 4],
    /// Coverage features of the relations made (a relation between different coefficients
    /// checks their clause).
    pub features: Vec<String>,
}

impl Relations {
    /// Relations for a case; `hypothesis`: one built on a model that holds a hypothesis about
    /// the hand (see [`MOST_LFDP_HYPOTHESIS`]).
    pub(super) fn new(hypothesis: bool) -> Relations {
        Relations {
            most_lfdp: if hypothesis { MOST_LFDP_HYPOTHESIS } else { MOST_LFDP },
            anchor: None,
            lfdp_loop: None,
            lfdp_bounded: [false; 4],
            features: Vec::new(),
        }
    }

    /// The captures and relations for the answer `c` of step `step`, a feedback block with
    /// `note`, each holding the model's own answer.
    /// Every feedback block of a tracked loop comes here in order; `bind` is false where the
    /// block's fields are judged exactly (its readings still count for what follows).
    pub(super) fn binds(&mut self, p: &Profile, step: usize, note: &BlockNote, c: &Captured, bind: bool) -> Vec<Bind> {
        let Some(layout) = &c.layout else { return Vec::new() };
        let fb = layout.feedback();
        let Ok((_, values)) = fb.decode(&c.output) else { return Vec::new() };
        let model = |m: u8, name: &str| fb.value_of(&values, Some(m), name);
        if self.lfdp_loop != Some(note.loop_id) {
            self.lfdp_loop = Some(note.loop_id);
            self.lfdp_bounded = [true; 4];
        }
        let bounded = self.lfdp_bounded;
        for (m, b) in (1..=4u8).zip(self.lfdp_bounded.iter_mut()) {
            if model(m, "LFDP").is_some_and(|v| v.abs() > self.most_lfdp) {
                *b = false;
            }
        }
        if !bind {
            return Vec::new();
        }
        let mut binds = self.lfv(p, step, note, &model);
        binds.extend(self.lfdp(p, step, note, bounded, &model));
        binds
    }

    fn lfv(
        &mut self,
        p: &Profile,
        step: usize,
        note: &BlockNote,
        model: &dyn Fn(u8, &str) -> Option<i64>,
    ) -> Vec<Bind> {
        let mut binds = Vec::new();
        for m in 1..=4u8 {
            let i = usize::from(m - 1);
            let (Some(lcvc), Some(lfvc), true) = (note.coeff[i].lcvc, note.coeff[i].lfvc, note.lfv[i]) else {
                continue;
            };
            let Some(got) = model(m, "LFV") else { continue };
            let datum = note.datum[i];
            let exact = lfv_exact(p, datum, lcvc, lfvc);
            if got != exact.trunc() as i64 || !(LEAST_LFV..=MOST_LFV).contains(&got.abs()) {
                continue;
            }
            let target = Target::Field { motor: Some(m), name: "LFV" };
            let what = format!("motor {m} (LCV {datum}, LCVC {lcvc}, LFVC {lfvc}; the model reads {got})");
            let Some(a) = &self.anchor else {
                let name = format!("v{step}_{m}");
                binds.push(Bind {
                    target,
                    capture: Some(name.clone()),
                    relation: None,
                    evidence: String::new(),
                    samples: Vec::new(),
                });
                self.anchor = Some(Anchor { name, exact, model: got, coeff: (lcvc, lfvc), what });
                continue;
            };
            let ratio = exact / a.exact;
            // (scales of the hand's units from half to twice the model's, each truncated)
            let pairs: Vec<(i64, i64)> = (10..=40)
                .map(|k| f64::from(k) / 20.0)
                .map(|s| ((a.exact * s).trunc() as i64, (exact * s).trunc() as i64))
                .filter(|(x, _)| *x != 0)
                .chain([(a.model, got)])
                .collect();
            let Some(rel) = relation(&a.name, ratio, &pairs) else { continue };
            let coefficients = if (lcvc, lfvc) != a.coeff { ":coefficients" } else { "" };
            self.features.push(format!("relation:LFV{coefficients}"));
            let evidence = format!(
                "the control velocity is LCV x LCVC and LFV reads it divided by LFVC, whatever the hand's velocity \
                 units: {what} reads {} of {} times {:.3}; the tolerance holds the truncation of both readings \
                 from half to twice the model's units, and at least {MOTION_TOLERANCE} % for velocities in motion",
                a.name, a.what, ratio
            );
            binds.push(Bind { target, capture: None, relation: Some(rel), evidence, samples: pairs });
        }
        binds
    }

    fn lfdp(
        &mut self,
        p: &Profile,
        step: usize,
        note: &BlockNote,
        bounded: [bool; 4],
        model: &dyn Fn(u8, &str) -> Option<i64>,
    ) -> Vec<Bind> {
        let h = &p.hand;
        // (motor, LFDPC, the LFDP per unit of time, the model's reading)
        let mut moving: Vec<(u8, i64, f64, i64)> = Vec::new();
        for m in 1..=4u8 {
            let i = usize::from(m - 1);
            let (Some(lcvc), Some(lfdpc), true) = (note.coeff[i].lcvc, note.coeff[i].lfdpc, note.lfdp[i] && bounded[i])
            else {
                continue;
            };
            let Some(got) = model(m, "LFDP") else { continue };
            let c = lfdpc.max(1);
            moving.push((m, c, control_velocity(note.datum[i], lcvc, h.lcv_fraction_bits) / c as f64, got));
        }
        // The anchor: the first motor on the wire (a capture is read before what relates to
        // it) the model reads 8..=24; the motors after it that move no more are held to it
        // (a hand whose interval is short reads small values, where truncation is a whole
        // unit: held to a larger anchor, a smaller reading stays within the band's rounding).
        let most = self.most_lfdp;
        let Some(&(am, ac, arate, agot)) = moving.iter().find(|x| (LEAST_LFDP..=most).contains(&x.3.abs())) else {
            return Vec::new();
        };
        // (a hypothesis's case holds the faster ones too where the tolerance allows: a motor
        // whose coefficient the hypothesis takes away often moves more than the anchor)
        let faster = self.most_lfdp > MOST_LFDP;
        moving.retain(|x| x.0 > am && (faster || x.2.abs() <= arate.abs()));
        let name = format!("d{step}_{am}");
        let mut binds = Vec::new();
        for &(m, c, rate, got) in &moving {
            let ratio = rate / arate;
            if ratio <= 0.0 {
                continue;
            }
            // Every movement of the moving motor from half to twice the model's, the other's in
            // the ratio of their velocities, and every rest each last reading may have carried.
            let (lo, hi) = ((agot.abs() * ac) / 2, 2 * agot.abs() * ac);
            let sign = agot.signum();
            let rests = |c: i64| [0, c / 2, c - 1];
            let mut pairs: Vec<(i64, i64)> = vec![(agot, got)];
            for k in 0..=40 {
                let moved = lo + (hi - lo) * k / 40;
                let other = (moved as f64 * ratio * c as f64 / ac as f64).round() as i64;
                for r1 in rests(ac) {
                    for r2 in rests(c) {
                        let pair = (sign * ((moved + r1) / ac), sign * ((other + r2) / c));
                        if pair.0.abs() <= 127 && pair.1.abs() <= 127 && !pairs.contains(&pair) {
                            pairs.push(pair);
                        }
                    }
                }
            }
            let Some(rel) = relation(&name, ratio, &pairs) else { continue };
            if binds.is_empty() {
                binds.push(Bind {
                    target: Target::Field { motor: Some(am), name: "LFDP" },
                    capture: Some(name.clone()),
                    relation: None,
                    evidence: String::new(),
                    samples: Vec::new(),
                });
            }
            let coefficients = if c != ac { ":coefficients" } else { "" };
            self.features.push(format!("relation:LFDP{coefficients}"));
            let evidence = format!(
                "LFDP is the movement since the last feedback divided by LFDPC: motors {am} (LFDPC {ac}) and {m} \
                 (LFDPC {c}) ran at one control velocity each since the block before the previous feedback, so \
                 motor {m} reads motor {am}'s LFDP times {ratio:.3}, however long the interval (the model reads \
                 {agot} and {got}); the tolerance holds the truncation and carried rest of both readings over \
                 movements from half to twice the model's, and at least {MOTION_TOLERANCE} % for motors in motion"
            );
            binds.push(Bind {
                target: Target::Field { motor: Some(m), name: "LFDP" },
                capture: None,
                relation: Some(rel),
                evidence,
                samples: pairs,
            });
        }
        binds
    }
}

/// `name × ratio` (a fraction over 1000) with the least tolerance that holds every pair plus 2
/// points, at least [`MOTION_TOLERANCE`]; `None` when truncation alone needs more than that.
fn relation(name: &str, ratio: f64, pairs: &[(i64, i64)]) -> Option<Relation> {
    if !(ratio.is_finite() && ratio > 0.0) {
        return None;
    }
    let (mut num, mut den) = ((ratio * 1000.0).round() as i64, 1000i64);
    let g = gcd(num, den);
    if g > 1 {
        (num, den) = (num / g, den / g);
    }
    let fitted = fit_tolerance(name, num, den, pairs, 2)?;
    (fitted.tolerance <= MOTION_TOLERANCE).then_some(Relation { tolerance: MOTION_TOLERANCE, ..fitted })
}

#[cfg(test)]
mod tests {
    use super::super::HostAction;
    use super::super::case::build_case;
    use gcl_model::Profile;
    use gcl_transcript::{Piece, Transcript};

    fn block(header: u8, values: &[i64], pause_ms: u64) -> HostAction {
        HostAction::Block { header, values: values.to_vec(), extra: 0, pause_ms }
    }

    /// The relations of a transcript's values, as written: `v8_1*333/1000 +-25%`.
    fn relations(t: &Transcript) -> Vec<String> {
        t.steps
            .iter()
            .flat_map(|s| s.expect.pieces())
            .filter_map(|(_, p)| match p {
                Piece::Value(v) => v.relation.as_ref().map(|r| r.text()),
                _ => None,
            })
            .collect()
    }

    fn session(lines: &[&str], blocks: Vec<HostAction>) -> Transcript {
        let p = Profile::builtin("seed").unwrap();
        let mut actions: Vec<HostAction> = lines.iter().map(|l| HostAction::Line(l.to_string())).collect();
        actions.extend(blocks);
        actions.push(HostAction::Abort);
        build_case(&p, &actions, "t", "t", true, true).unwrap().transcript
    }

    #[test]
    fn a_held_velocity_relates_each_motors_feedback_by_its_coefficients() {
        let t = session(
            &["12FSET LCV 1 LCPG 0 LFV 1 LFDP 1", "1FSET LCVC 3 LFDPC 2", "12LOOP"],
            vec![block(b'C', &[5, 5], 0), block(b'C', &[5, 5], 0), block(b'A', &[], 10), block(b'A', &[], 10)],
        );
        let rel = relations(&t);
        // LFV: motor 2 (LCVC 1) reads a third of motor 1 (LCVC 3), on every block after the
        // first whose velocity held; LFDP: motor 2 (LFDPC 1) two thirds of motor 1 (LFDPC 2),
        // once a whole interval ran at one velocity.
        assert!(rel.iter().any(|r| r.ends_with("*333/1000 +-25%") && r.starts_with('v')), "{rel:?}");
        assert!(rel.iter().any(|r| r.ends_with("*667/1000 +-25%") && r.starts_with('d')), "{rel:?}");
        let text = t.to_text();
        assert!(text.contains("note: relation `v"), "the evidence is stated:\n{text}");
    }

    #[test]
    fn lfdp_after_a_reading_a_hand_may_have_clipped_is_not_related() {
        // The first feedback counts the movement since LOOP, 100 ms of it: on a faster hand the
        // byte clips and the rest is carried into the next reading (the clean seed hand read
        // 125 where the relation wanted about 45).
        let t = session(
            &["12FSET LCV 1 LCPG 0 LFV 1 LFDP 1", "1FSET LCVC 3 LFDPC 2", "12LOOP"],
            vec![block(b'c', &[5, 5], 0), block(b'A', &[], 100), block(b'C', &[5, 5], 10), block(b'A', &[], 10)],
        );
        let rel = relations(&t);
        assert!(!rel.iter().any(|r| r.starts_with('d')), "{rel:?}");
    }

    #[test]
    fn a_velocity_that_changes_at_every_block_is_not_related() {
        // Whether a hand reports a block's velocity before or after it takes the block's data
        // is its own: a block that changes the datum reads either.
        let t = session(
            &["12FSET LCV 1 LCPG 0 LFV 1", "1FSET LCVC 3", "12LOOP"],
            vec![block(b'C', &[10, 10], 0), block(b'C', &[20, 20], 0), block(b'C', &[30, 30], 0)],
        );
        assert!(relations(&t).is_empty(), "{:?}", relations(&t));
    }

    #[test]
    fn a_gain_or_a_motor_without_velocity_is_not_related() {
        // With LCPG the model ramps towards the velocity at its own pace.
        let t = session(
            &["12FSET LCV 1 LCPG 1 LFV 1", "1FSET LCVC 3", "12LOOP"],
            vec![block(b'C', &[10, 64, 10, 64], 0), block(b'A', &[], 0), block(b'A', &[], 0)],
        );
        assert!(relations(&t).is_empty(), "{:?}", relations(&t));
    }
}
