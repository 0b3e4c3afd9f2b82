//! `grammar`: a command line, then accepted (canonical form, motors, command, arguments) or
//! rejected (status and its bits). The oracle is the model's `parse_line`.

use gcl_model::grammar::{Args, Line, parse_line};
use gcl_model::spec::{ArgRule, PrefixRule};
use serde_json::{Value, json};

use super::{FileBuilder, Test, VectorsError, slug};

/// Decisions a parameter's name or values depend on, by name.
pub(crate) fn param_flags(name: &str) -> &'static [&'static str] {
    match name {
        "BP" => &["bh8-bp-range"],
        "LCVC" | "LFVC" | "LFDPC" => &["bh8-coefficient-range", "bh8-rt-coefficients"],
        "MSG" | "HSG" => &["bh8-msg-alias", "bh8-strain-limits-disable"],
        "LSG" => &["bh8-strain-limits-disable"],
        "TMP" => &["seed-pget-tmp", "bh8-no-tmp"],
        "TEMP" => &["seed-temp-global"],
        "BAUD" => &["seed-baud", "bh8-global-names-on-fset"],
        "MCV" | "MOV" | "IVEL" => &["bh8-velocity-units"],
        "SAMPLE" => &["bh8-sample-fixed", "bh8-velocity-units"],
        "LCT" | "LFBP" | "LFAIN" => &["bh8-new-rt-fields-defaults", "bh8-43-no-44-params"],
        "LFT" => &["bh8-lft-field"],
        "SGFLIP" => &["seed-sgflip-spread", "bh8-sgflip-default"],
        "OTEMP" => &["bh8-otemp-units"],
        "OD" | "UPSECS" | "PTEMP" | "SN" => &["bh8-self-stored"],
        "BS" | "BD" => &["bh8-breakaway"],
        "FDZ" | "FIP" => &["bh8-filter-notes"],
        _ => &[],
    }
}

/// Decisions a command's prefix rule or arguments depend on, by name.
fn command_flags(name: &str) -> &'static [&'static str] {
    match name {
        "FDEF" | "FLOAD" | "FSAVE" | "T" => &["seed-prefix-rules"],
        "VERS" => &["seed-prefix-rules", "bh8-admin-prefixes"],
        "?" => &["seed-prefix-rules", "bh8-admin-prefixes", "seed-help"],
        "A?" | "RESET" => &["bh8-admin-prefixes"],
        "ERR" => &["bh8-admin-prefixes", "seed-err-command"],
        "IC" | "IO" => &["seed-ic-io-args", "bh8-ic-io-range"],
        "M" => &["bh8-ic-io-range"],
        n if n.starts_with("FLIST") || n.starts_with("PLIST") => &["bh8-list-prefixes", "seed-flista"],
        _ => &[],
    }
}

/// What the model makes of a line, as the test's fields; and whether it was accepted.
fn outcome(b: &FileBuilder<'_>, line: &str) -> (bool, Value) {
    let p = b.profile();
    match parse_line(p, line.as_bytes()) {
        Ok(Line::Empty) => (true, json!({ "accepted": { "empty": true } })),
        Ok(Line::Command(c)) => {
            let args = match &c.args {
                Args::None => json!({ "kind": "none" }),
                Args::Integer(v) => json!({ "kind": "integer", "value": v }),
                Args::Names(ns) => {
                    json!({ "kind": "names", "names": ns.iter().map(|n| &p.param(*n).name).collect::<Vec<_>>() })
                }
                Args::Pairs(ps) => json!({
                    "kind": "pairs",
                    "pairs": ps.iter().map(|(n, v)| json!({ "name": p.param(*n).name, "value": v })).collect::<Vec<_>>(),
                }),
                Args::Topic(t) => json!({ "kind": "topic", "command": p.command(*t).name }),
            };
            (
                true,
                json!({ "accepted": {
                    "empty": false,
                    "canonical": c.to_line(p),
                    "motors": c.prefix.map(|m| m.iter().collect::<Vec<u8>>()),
                    "command": p.command(c.command).name,
                    "args": args,
                }}),
            )
        }
        Err(r) => (
            false,
            json!({ "rejected": {
                "status": r.status.code(),
                "bits": r.status.iter().map(|b| b.bits()).collect::<Vec<u32>>(),
            }}),
        ),
    }
}

/// The status a fresh hand answers to `line` (sent with its CR), if it answers `ERR n`.
fn hand_refuses(p: &std::sync::Arc<gcl_model::Profile>, line: &str) -> Option<u32> {
    let mut hand = gcl_model::Device::with_profile(p.clone());
    hand.clear_output();
    hand.handle_input(std::time::Duration::ZERO, format!("{line}\r").as_bytes());
    let out = String::from_utf8_lossy(&hand.take_output()).into_owned();
    let rest = out.split("\n\rERR ").nth(1)?;
    rest.split("\n\r").next()?.trim().parse().ok()
}

fn bits(code: u32) -> Vec<u32> {
    (0..32).map(|i| 1u32 << i).filter(|b| code & b != 0).collect()
}

/// Adds the test of one line, with the framing decisions its text implies.
fn line_test(
    b: &mut FileBuilder<'_>,
    id: String,
    comment: String,
    line: &str,
    flags: &[&'static str],
) -> Result<(), VectorsError> {
    let (ok, mut body) = outcome(b, line);
    let mut t_flags: Vec<&'static str> = flags.to_vec();
    if line.bytes().any(|c| c.is_ascii_lowercase()) {
        t_flags.push("framing-case");
        t_flags.push("bh8-framing-open");
    }
    let trimmed = line.trim_matches(' ');
    if line.contains('\t') || trimmed.contains("  ") || trimmed.len() != line.len() {
        t_flags.push("framing-whitespace");
        t_flags.push("bh8-framing-open");
    }
    if let Some(bits) = body.pointer("/rejected/bits").and_then(Value::as_array)
        && bits.len() > 1
    {
        t_flags.push("framing-errors-combine");
    }
    if let Value::Object(m) = &mut body {
        m.insert("line".into(), json!(line));
    }
    b.push(Test::new(id, comment, ok, body).flags(&t_flags))
}

/// Arguments that make a command line valid, for the prefix tests: a name for a get
/// command, a name and its lowest value for a set command, nothing otherwise.
fn sample_args(p: &gcl_model::Profile, c: &gcl_model::spec::CommandSpec) -> String {
    let pick = |get: bool| {
        p.param_ids().find(|id| {
            let ps = p.param(*id);
            if get { p.getter(*id) == c.name } else { p.setter(*id) == c.name && !ps.read_only }
        })
    };
    match c.args {
        ArgRule::Names => pick(true).map(|id| format!(" {}", p.param(id).name)).unwrap_or_default(),
        ArgRule::Pairs => pick(false)
            .map(|id| {
                let ps = p.param(id);
                format!(" {} {}", ps.name, ps.values.as_ref().and_then(|v| v.first().copied()).unwrap_or(ps.min))
            })
            .unwrap_or_default(),
        ArgRule::None | ArgRule::OptionalInteger => String::new(),
    }
}

pub(crate) fn build(b: &mut FileBuilder<'_>) -> Result<(), VectorsError> {
    let p = b.profile();
    // Framing of the line itself.
    let fixed: &[(&str, &str, &str, &[&'static str])] = &[
        ("empty", "", "an empty line is accepted: the hand prints a fresh prompt", &["framing-empty-line"]),
        ("separators-only", "   ", "a line of separators only is an empty line", &["framing-empty-line"]),
        ("leading-spaces", "  FGET DP", "leading separators are skipped", &[]),
        ("tab-separator", "FGET\tDP", "a tab separates tokens like a space", &[]),
        ("space-after-prefix", "1 FGET DP", "separators between the prefix and the command word are accepted", &[]),
        ("lower-case", "fget dp", "command words and parameter names are case-insensitive", &[]),
        ("mixed-case", "Fget Dp", "mixed case is accepted; the canonical form is upper case", &[]),
        ("unknown-command", "BOGUS", "an unknown command word is 32", &[]),
        ("prefix-only", "12", "a prefix with no command word is an unknown command", &[]),
        ("number-leading-zeros", "FSET DP 007", "leading zeros are decimal digits", &["framing-numbers"]),
        ("number-plus-sign", "FSET DP +5", "a plus sign makes an invalid value", &["framing-numbers"]),
        ("number-hex", "FSET DP 0x10", "hex is an invalid value", &["framing-numbers"]),
        ("number-fraction", "FSET DP 1.5", "a fraction is an invalid value", &["framing-numbers"]),
        ("number-minus-zero", "FSET DP -0", "minus zero is zero", &["framing-numbers"]),
        (
            "number-19-digits",
            "FSET DP 1000000000000000000",
            "more than 18 digits is an invalid value",
            &["framing-numbers"],
        ),
        ("boolean-true", "FSET DP TRUE", "TRUE is not a value", &["seed-booleans", "framing-numbers"]),
        ("combined-unknown-and-range", "FSET NOPE 1 DP 99999", "problems in one line combine their bits", &[]),
        (
            "combined-prefix-and-args",
            "1VERS 3",
            "a forbidden prefix and an extra argument combine",
            &["seed-prefix-rules", "bh8-admin-prefixes"],
        ),
        ("set-missing-value", "FSET DP", "a name without a value is an invalid value", &[]),
        ("set-nothing", "FSET", "FSET with nothing is an invalid value", &[]),
        ("get-nothing", "FGET", "FGET needs a name", &[]),
        ("several-names", "FGET DP DS", "FGET takes several names", &[]),
        ("several-pairs", "FSET DP 100 DS 200", "FSET takes several pairs", &[]),
    ];
    for (id, line, comment, flags) in fixed {
        line_test(b, format!("line-{id}"), (*comment).to_string(), line, flags)?;
    }
    // The line length limit is the hand's framing, not the grammar's: ask a fresh hand.
    let max = p.framing.max_line;
    let at_limit = format!("FGET DP{}", " ".repeat(max.saturating_sub(7)));
    let over = format!("{at_limit} ");
    for (id, line, comment) in [
        ("at-length-limit", &at_limit, format!("{max} bytes before the CR: the longest line a hand keeps")),
        ("over-length-limit", &over, format!("{} bytes before the CR: past the limit", max + 1)),
    ] {
        let (ok, body) = match hand_refuses(p, line) {
            Some(code) => (false, json!({ "rejected": { "status": code, "bits": bits(code) } })),
            None => outcome(b, line),
        };
        let mut body = body;
        if let Value::Object(m) = &mut body {
            m.insert("line".into(), json!(line));
        }
        b.push(Test::new(format!("line-{id}"), comment, ok, body).flags(&[
            "framing-max-line",
            "framing-whitespace",
            "bh8-framing-open",
        ]))?;
    }
    // Every command.
    for c in &p.commands {
        let n = c.name.as_str();
        let s = slug(&n.replace('?', "help"));
        let cf = command_flags(n);
        let bare = match c.args {
            ArgRule::Names => format!("`{n}` alone: it needs a name (128)"),
            ArgRule::Pairs => format!("`{n}` alone: it needs a name and a value (128)"),
            ArgRule::None | ArgRule::OptionalInteger => format!("`{n}` alone"),
        };
        line_test(b, format!("cmd-{s}-bare"), bare, n, cf)?;
        let args = sample_args(p, c);
        let (pre_comment, pre_flags) = match c.prefix {
            PrefixRule::Allowed => ("a motor prefix is allowed on", cf),
            PrefixRule::Forbidden => ("a motor prefix is refused (4096) on", cf),
        };
        line_test(
            b,
            format!("cmd-{s}-prefix-12"),
            format!("{pre_comment} `{n}{args}`"),
            &format!("12{n}{args}"),
            pre_flags,
        )?;
        line_test(
            b,
            format!("cmd-{s}-prefix-g"),
            format!("{pre_comment} `{n}{args}` (G: the fingers)"),
            &format!("G{n}{args}"),
            pre_flags,
        )?;
        if n.bytes().any(|c| c.is_ascii_uppercase()) {
            line_test(
                b,
                format!("cmd-{s}-lower-case"),
                format!("`{n}{args}` in lower case"),
                &format!("{n}{args}").to_ascii_lowercase(),
                cf,
            )?;
        }
        match c.args {
            ArgRule::None => {
                line_test(
                    b,
                    format!("cmd-{s}-extra-argument"),
                    format!("`{n}` takes no argument (1024)"),
                    &format!("{n} 1"),
                    cf,
                )?;
            }
            ArgRule::OptionalInteger => {
                let (lo, hi) = (c.arg_min.unwrap_or(0), c.arg_max.unwrap_or(i64::from(i32::MAX)));
                for (what, v) in [("min", lo), ("max", hi), ("above-max", hi.saturating_add(1))] {
                    line_test(
                        b,
                        format!("cmd-{s}-arg-{what}"),
                        format!("`{n}` with {v} (range {lo}..{hi})"),
                        &format!("{n} {v}"),
                        cf,
                    )?;
                }
                if lo > i64::MIN {
                    line_test(
                        b,
                        format!("cmd-{s}-arg-below-min"),
                        format!("`{n}` with {} (range {lo}..{hi})", lo - 1),
                        &format!("{n} {}", lo - 1),
                        cf,
                    )?;
                }
                line_test(b, format!("cmd-{s}-arg-not-a-number"), format!("`{n}` with a word"), &format!("{n} X"), cf)?;
                line_test(
                    b,
                    format!("cmd-{s}-two-arguments"),
                    format!("`{n}` takes one argument at most (1024)"),
                    &format!("{n} {lo} {lo}"),
                    cf,
                )?;
            }
            ArgRule::Names | ArgRule::Pairs => {}
        }
    }
    // Every parameter through its get and set commands.
    for id in p.param_ids() {
        let ps = p.param(id);
        let n = ps.name.as_str();
        let s = slug(n);
        let pf = param_flags(n);
        let get = p.getter(id).to_string();
        let set = p.setter(id).to_string();
        if p.command_id(&get).is_some() {
            line_test(b, format!("param-{s}-get"), format!("`{get} {n}` reads {n}"), &format!("{get} {n}"), pf)?;
        }
        for other in ["FGET", "PGET"] {
            if other != get && p.command_id(other).is_some() {
                line_test(
                    b,
                    format!("param-{s}-get-{}", slug(other)),
                    format!("{n} is not read by {other} (64)"),
                    &format!("{other} {n}"),
                    pf,
                )?;
            }
        }
        for alias in &ps.input_aliases {
            line_test(
                b,
                format!("param-{s}-alias-{}", slug(alias)),
                format!("{alias} is another name of {n} on input"),
                &format!("{get} {alias}"),
                pf,
            )?;
        }
        if p.command_id(&set).is_none() {
            continue;
        }
        if ps.read_only {
            line_test(
                b,
                format!("param-{s}-set-read-only"),
                format!("{n} is read-only (256)"),
                &format!("{set} {n} {}", ps.min),
                pf,
            )?;
            continue;
        }
        let mut values: Vec<(&str, i64)> = match &ps.values {
            Some(vs) => {
                let first = vs.first().copied().unwrap_or(0);
                let last = vs.last().copied().unwrap_or(0);
                let outside = (first..=last.saturating_add(1)).find(|v| !vs.contains(v)).unwrap_or(last + 1);
                vec![("first", first), ("last", last), ("not-listed", outside)]
            }
            None => vec![("min", ps.min), ("max", ps.max), ("above-max", ps.max.saturating_add(1))],
        };
        if ps.values.is_none() && ps.min > i64::MIN {
            values.push(("below-min", ps.min - 1));
        }
        for (what, v) in values {
            let range = match &ps.values {
                Some(vs) => format!("one of {vs:?}"),
                None => format!("{}..{}", ps.min, ps.max),
            };
            line_test(
                b,
                format!("param-{s}-set-{what}"),
                format!("`{set} {n} {v}`: {n} takes {range}"),
                &format!("{set} {n} {v}"),
                pf,
            )?;
        }
    }
    Ok(())
}
