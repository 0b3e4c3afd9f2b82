//! `status`: a status number, its bits, and the text `ERR` gives each bit. The oracle is the
//! model's `StatusBits` and the profile's status table.

use gcl_model::StatusBits;
use serde_json::json;

use super::{FileBuilder, Test, VectorsError};

pub(crate) fn build(b: &mut FileBuilder<'_>) -> Result<(), VectorsError> {
    let p = b.profile();
    let bits_of = |code: u32| -> Vec<serde_json::Value> {
        (0..32)
            .map(|i| 1u32 << i)
            .filter(|bit| code & bit != 0)
            .map(|bit| json!({ "bit": bit, "defined": p.status_text(bit).is_some() }))
            .collect()
    };
    let mut codes: Vec<(String, u32, String, Vec<&'static str>)> = Vec::new();
    for s in &p.status {
        let mut flags = Vec::new();
        if s.bit == 512 {
            flags.push("seed-status-512");
        }
        if s.bit == 16 {
            flags.push("bh8-missed-position-code");
        }
        if s.bit == 16384 {
            flags.extend(["bh8-abort-motion", "seed-abort"]);
        }
        let sent = if s.sent { "a hand sends it" } else { "defined, but a hand of this profile never sends it" };
        codes.push((format!("status-{}", s.bit), s.bit, format!("{} is one bit: {}; {sent}", s.bit, s.text), flags));
    }
    let combos: &[(&str, u32, &str)] = &[
        ("unknown-parameter-and-invalid-value", 64 | 128, "FSET NOPE 1 DP 99999 answers 192: both bits"),
        ("prefix-and-too-many-arguments", 4096 | 1024, "1VERS 3 answers 5120: both bits"),
        ("not-initialized-and-missed-position", 4 | 16, "two motion bits together"),
    ];
    for (id, code, comment) in combos {
        codes.push((format!("status-combined-{id}"), *code, (*comment).to_string(), vec!["framing-errors-combine"]));
    }
    let all: u32 = p.status.iter().map(|s| s.bit).sum();
    codes.push(("status-combined-every-bit".into(), all, format!("every bit of the profile: {all}"), vec![]));
    let undefined = (0..32).map(|i| 1u32 << i).find(|bit| p.status_text(*bit).is_none()).unwrap_or(1 << 31);
    codes.push((
        "status-undefined-bit".into(),
        undefined,
        format!("{undefined} is no status bit of this profile: a host reports it as unknown"),
        vec![],
    ));
    for (id, code, comment, flags) in codes {
        let known = StatusBits::from_code(code).is_ok() && bits_of(code).iter().all(|b| b["defined"] == true);
        let body = json!({ "code": code, "bits": bits_of(code) });
        b.push(Test::new(id, comment, known, body).flags(&flags))?;
    }
    for s in &p.status {
        let body = json!({ "bit": s.bit, "text": s.text, "sent": s.sent });
        b.push(
            Test::new(format!("text-{}", s.bit), format!("what `ERR {}` says of bit {}", s.bit, s.bit), true, body)
                .flags(&["bh8-err-format", "seed-err-command"]),
        )?;
    }
    Ok(())
}
