//! `lfdp`: sequences of positions with LFDPC (and LFDPD where the profile has it), giving
//! the LFDP value sent in each feedback block, its byte, and the reported position after
//! each. The oracle is the model's `lfdp_step`.

use gcl_model::realtime::lfdp_step;
use serde_json::json;

use super::{FileBuilder, Test, VectorsError};
use gcl_transcript::hex_bytes;

pub(crate) fn build(b: &mut FileBuilder<'_>) -> Result<(), VectorsError> {
    let p = b.profile();
    if p.param_id("LFDP").is_none() {
        return Ok(());
    }
    let has_discard = p.param_id("LFDPD").is_some();
    let ramp: Vec<i64> = (1..=6).map(|i| 1000 + i * 300).collect();
    let seqs: Vec<(&str, &str, i64, i64, Vec<i64>)> = vec![
        (
            "worked-example",
            "the seed's example: LFDPC 2, last reported 1500, the motor at 2000",
            2,
            1500,
            vec![2000, 2000, 2000],
        ),
        ("small-steps", "steps that fit one byte at LFDPC 1", 1, 0, vec![10, 30, 25, 25, -100]),
        (
            "clipped-up",
            "a jump of 1000 at LFDPC 1 is sent over several blocks",
            1,
            0,
            vec![1000, 1000, 1000, 1000, 1000, 1000, 1000, 1000, 1000],
        ),
        ("clipped-down", "a drop of 1000 at LFDPC 1", 1, 1000, vec![0, 0, 0, 0, 0, 0, 0, 0, 0]),
        (
            "truncates-toward-zero",
            "division truncates toward zero, both signs (LFDPC 4)",
            4,
            100,
            vec![107, 107, 93, 93, 90],
        ),
        ("ramp", "a motor moving 300 counts a block at LFDPC 3", 3, 1000, ramp),
        ("largest-coefficient", "LFDPC 255", 255, 0, vec![17000, 17000, 17000]),
        ("zero-coefficient", "LFDPC 0 counts as 1", 0, 0, vec![5, 200, 200]),
    ];
    for (id, comment, coeff, start, positions) in seqs {
        let discards: &[bool] = if has_discard { &[false, true] } else { &[false] };
        for &discard in discards {
            let mut reported = start;
            let mut sent = Vec::new();
            let mut after = Vec::new();
            let mut clipped = false;
            for &pos in &positions {
                let c = coeff.max(1);
                clipped |= !(-128..=127).contains(&((pos - reported) / c));
                let v = lfdp_step(&mut reported, pos, coeff, discard);
                sent.push(i64::from(v));
                after.push(reported);
            }
            let bytes: Vec<u8> = sent.iter().map(|v| *v as i8 as u8).collect();
            let mut flags = vec!["seed-lfdp-state", "bh8-lfdp-state"];
            if clipped {
                flags.push("bh8-rt-clipping");
            }
            if coeff == 0 || coeff == 255 {
                flags.extend(["bh8-coefficient-range", "bh8-rt-coefficients"]);
            }
            let (suffix, mode) = match (has_discard, discard) {
                (false, _) => ("", ""),
                (true, false) => ("-lfdpd-0", ", LFDPD 0 (carry the clipped rest)"),
                (true, true) => ("-lfdpd-1", ", LFDPD 1 (discard the clipped rest)"),
            };
            let body = json!({
                "lfdpc": coeff,
                "lfdpd": has_discard.then_some(i64::from(discard)),
                "last_reported": start,
                "positions": positions,
                "sent": sent,
                "bytes": hex_bytes(&bytes),
                "reported": after,
            });
            b.push(Test::new(format!("lfdp-{id}{suffix}"), format!("{comment}{mode}"), true, body).flags(&flags))?;
        }
    }
    Ok(())
}
