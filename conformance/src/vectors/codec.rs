//! `codec`: field values to bytes and bytes to values, at the edges of each field type and
//! past them (what a hand clips), and whole blocks. Two-byte fields are big-endian. The
//! oracle is the model's `FieldType::write` and `read` for single fields, and
//! `BlockLayout::encode` and `decode` for whole blocks.

use gcl_model::MotorSet;
use gcl_model::realtime::{FEEDBACK_HEADER, Field};
use serde_json::json;

use super::layout::{block_json, layout_flags, layout_with, rt_flags};
use super::{FileBuilder, Test, VectorsError, slug};
use gcl_transcript::hex_bytes;

/// Encodes one value into a field of `f`'s type (clamped, as a hand does) and returns its bytes.
fn field_bytes(f: &Field, v: i64) -> Vec<u8> {
    let mut out = vec![0; f.size()];
    f.ty().write(v, &mut out);
    out
}

fn field_value(f: &Field, bytes: &[u8]) -> Option<i64> {
    if bytes.len() != f.size() {
        return None;
    }
    f.ty().read(bytes)
}

pub(crate) fn build(b: &mut FileBuilder<'_>) -> Result<(), VectorsError> {
    let p = b.profile();
    let names = rt_flags(p);
    let all: Vec<&str> = names.iter().map(String::as_str).collect();
    let full = layout_with(p, MotorSet::ALL, &all);
    let mut seen = std::collections::BTreeSet::new();
    for f in full.control().fields().iter().chain(full.feedback().fields()) {
        if !seen.insert(f.name()) {
            continue;
        }
        let kind = format!("{}{}", if f.signed() { "i" } else { "u" }, f.size() * 8);
        let field = json!({ "name": f.name(), "size": f.size(), "signed": f.signed() });
        let mut values = vec![("min", f.min()), ("max", f.max()), ("zero", 0), ("one", 1)];
        if f.signed() {
            values.push(("minus-one", -1));
        }
        if f.size() == 2 {
            values.push(("5000", 5000.min(f.max())));
        }
        for (what, v) in values {
            let bytes = field_bytes(f, v);
            if field_value(f, &bytes) != Some(v) {
                return Err(VectorsError::Generate(format!("{}: {v} does not survive a round trip", f.name())));
            }
            b.push(
                Test::new(
                    format!("{}-{what}", slug(f.name())),
                    format!("{} is {kind}: {v} is {}", f.name(), hex_bytes(&bytes)),
                    true,
                    json!({ "field": field, "value": v, "bytes": hex_bytes(&bytes), "direction": "both", "clipped_from": null }),
                )
                .flags(&["seed-rt-field-order"]),
            )?;
        }
        for (what, v) in [("below-min", f.min() - 1), ("above-max", f.max() + 1), ("far-above-max", f.max() * 4 + 3)] {
            let bytes = field_bytes(f, v);
            let clipped = v.clamp(f.min(), f.max());
            b.push(
                Test::new(
                    format!("{}-clip-{what}", slug(f.name())),
                    format!("{v} does not fit {} ({kind}): a hand sends {clipped}, {}", f.name(), hex_bytes(&bytes)),
                    true,
                    json!({ "field": field, "value": clipped, "bytes": hex_bytes(&bytes), "direction": "encode", "clipped_from": v }),
                )
                .flags(&["bh8-rt-clipping"]),
            )?;
        }
        // The byte patterns at the sign edge, read back.
        let patterns: Vec<Vec<u8>> = if f.size() == 1 {
            vec![vec![0x7F], vec![0x80], vec![0xFF]]
        } else {
            vec![vec![0x7F, 0xFF], vec![0x80, 0x00], vec![0xFF, 0xFF], vec![0x13, 0x88], vec![0x00, 0xFF]]
        };
        for bytes in patterns {
            let Some(v) = field_value(f, &bytes) else {
                return Err(VectorsError::Generate(format!("{}: {} does not decode", f.name(), hex_bytes(&bytes))));
            };
            b.push(
                Test::new(
                    format!("{}-read-{}", slug(f.name()), hex_bytes(&bytes).replace(' ', "").to_ascii_lowercase()),
                    format!("{} ({kind}) reads {} as {v}", f.name(), hex_bytes(&bytes)),
                    true,
                    json!({ "field": field, "value": v, "bytes": hex_bytes(&bytes), "direction": "decode", "clipped_from": null }),
                )
                .flags(&["seed-rt-field-order"]),
            )?;
        }
    }
    // Whole blocks: the fingers with LCV and LFAP (the seed's RealTime example), and every flag.
    let blocks: Vec<(&str, Vec<&str>, MotorSet)> = vec![
        ("lcv-lfap-fingers", vec!["LCV", "LFAP"], MotorSet::FINGERS),
        ("every-flag-all-motors", all.clone(), MotorSet::ALL),
    ];
    for (id, on, motors) in blocks {
        if !on.iter().all(|n| all.contains(n)) {
            continue;
        }
        let l = layout_with(p, motors, &on);
        for (which, layout, header) in [("control", l.control(), b'C'), ("feedback", l.feedback(), FEEDBACK_HEADER)] {
            let values: Vec<i64> =
                layout.fields().iter().enumerate().map(|(i, f)| if i % 2 == 0 { f.max() } else { f.min() }).collect();
            let mut bytes = Vec::new();
            layout.encode(header, &values, &mut bytes).map_err(|e| VectorsError::Generate(e.to_string()))?;
            let body = json!({
                "block": which,
                "motors": motors.iter().collect::<Vec<u8>>(),
                "flags_on": on,
                "layout": block_json(layout),
                "values": values,
                "bytes": hex_bytes(&bytes),
            });
            b.push(
                Test::new(
                    format!("block-{which}-{id}"),
                    format!("a {which} block with {} fields, each at an edge of its type", layout.fields().len()),
                    true,
                    body,
                )
                .flags(&layout_flags(&on)),
            )?;
            let short = &bytes[..bytes.len() - 1];
            let err = layout.decode(short).err().map(|e| e.to_string()).unwrap_or_default();
            b.push(
                Test::new(
                    format!("block-{which}-{id}-short"),
                    format!("one byte short is not a {which} block ({err})"),
                    false,
                    json!({
                        "block": which,
                        "motors": motors.iter().collect::<Vec<u8>>(),
                        "flags_on": on,
                        "layout": block_json(layout),
                        "values": null,
                        "bytes": hex_bytes(short),
                    }),
                )
                .flags(&layout_flags(&on)),
            )?;
        }
    }
    Ok(())
}
