//! `gcl explain`: the implementers' pocket reference. Runs lines in order against a freshly
//! powered-up simulated hand and shows, for each, how the model parses it, the exact bytes
//! of the answer, the status, and after LOOP the RealTime block layouts.

use std::io::Write;
use std::time::Duration;

use gcl_model::escape::{escape, unescape};
use gcl_model::grammar::{self, Args as CmdArgs, Line};
use gcl_model::realtime::BlockLayout;
use gcl_model::{Device, Mode, Profile};
use serde_json::{Value, json};

use super::{EXIT_OK, load_profile};

/// Arguments of `gcl explain`.
#[derive(Debug, clap::Args)]
#[command(after_help = "Each LINE may use the escapes \\n \\r \\t \\\\ and \\xHH. In supervisory mode a CR \
is added to each LINE, and a LINE holding CRs ('FGET DP\\rFGET MOV') is the commands the hand reads, each \
explained on its own; in RealTime mode (after LOOP) a LINE is sent as raw bytes, so \
'C\\x14\\xFB' is a control block and '\\x03' leaves the loop.\n\nExample:\n  gcl explain --profile seed HI \\\n    \
'12FSET LCV 1 LCVC 1 LCPG 0 LFV 0 LFS 1 LFAP 0 LFDP 1 LFDPC 1' \\\n    \
'4FSET LCV 0 LCVC 1 LCPG 0 LFV 0 LFS 0 LFAP 0 LFDP 1 LFDPC 1' 124LOOP 'C\\x14\\xFB' '\\x03'")]
pub struct Args {
    /// Profile: seed, bh8-262-4.3, bh8-262-4.4 (alias bh8-262), or a spec TOML file.
    #[arg(long, default_value = "bh8-262")]
    profile: String,
    /// One JSON object per line instead of text.
    #[arg(long)]
    json: bool,
    /// Seed of the simulated hand's noise.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Lines to run, in order.
    #[arg(required = true, value_name = "LINE")]
    lines: Vec<String>,
}

/// One line and what the hand made of it.
pub struct Explained {
    /// The LINE as given, or the one command of it explained (when the LINE held several).
    pub line: String,
    /// Whether it was sent in supervisory mode (else as a RealTime block).
    pub supervisory: bool,
    /// How the model parses it (JSON, as `--json` prints it).
    pub parsed: Value,
    /// The exact answer.
    pub response: Vec<u8>,
    /// The status the line ended with.
    pub status: gcl_model::StatusBits,
    /// The mode after the line.
    pub mode_after: Mode,
    /// The RealTime layouts, while in LOOP.
    pub layout: Option<gcl_model::RtLayout>,
}

impl Explained {
    /// The `--json` object.
    pub fn to_json(&self, profile: &Profile) -> Value {
        let mut obj = json!({
            "line": self.line,
            "mode": if self.supervisory { "supervisory" } else { "realtime" },
            "parsed": self.parsed,
            "response": self.response.iter().map(|&b| char::from(b)).collect::<String>(),
            "response_escaped": escape(&self.response),
            "status": self.status.code(),
            "status_text": self.status.describe(profile),
            "mode_after": self.mode_after,
        });
        if let Some(l) = &self.layout {
            obj["control_block"] = block_json(l.control());
            obj["feedback_block"] = block_json(l.feedback());
        }
        obj
    }
}

/// Runs `lines` in order against a freshly powered-up hand. A supervisory LINE holding the
/// terminator is split into the commands the hand reads, one [`Explained`] each.
pub fn explain_lines(profile: &std::sync::Arc<Profile>, seed: u64, lines: &[String]) -> anyhow::Result<Vec<Explained>> {
    let mut hand = Device::new(profile.clone(), gcl_model::DeviceConfig { seed, ..Default::default() });
    hand.clear_output();
    while hand.poll_event().is_some() {}
    let mut out = Vec::new();
    for text in lines {
        let bytes = unescape(text).map_err(|e| anyhow::anyhow!("LINE `{text}`: {e}"))?;
        if hand.mode() == Mode::Loop {
            hand.handle_input(hand.now(), &bytes);
            out.push(step(&mut hand, text.clone(), false, json!({ "block": escape(&bytes) })));
            continue;
        }
        // A LINE holding the terminator (`FGET DP\rFGET MOV`) is as many commands as the
        // hand reads: each is explained on its own, with its own answer.
        let commands: Vec<&[u8]> = bytes.split(|&b| b == profile.framing.terminator).collect();
        let many = commands.len() > 1;
        for (i, cmd) in commands.iter().enumerate() {
            if hand.mode() == Mode::Loop {
                // An earlier command entered LOOP: the rest are RealTime bytes.
                let rest = commands[i..].join(&[profile.framing.terminator][..]);
                hand.handle_input(hand.now(), &rest);
                out.push(step(&mut hand, escape(&rest), false, json!({ "block": escape(&rest) })));
                break;
            }
            let p = parsed(profile, cmd);
            let mut with_cr = cmd.to_vec();
            with_cr.push(profile.framing.terminator);
            hand.handle_input(hand.now(), &with_cr);
            let line = if many { escape(cmd) } else { text.clone() };
            out.push(step(&mut hand, line, true, p));
        }
    }
    Ok(out)
}

fn step(hand: &mut Device, line: String, supervisory: bool, parsed: Value) -> Explained {
    hand.run_until_idle(Duration::from_secs(600));
    // The status is the one the hand reported for the line; a RealTime block answered with
    // feedback or `*` reports none and ends with no status.
    let mut status = gcl_model::StatusBits::empty();
    while let Some(e) = hand.poll_event() {
        if let gcl_model::Event::LineDone(s) = e {
            status = s;
        }
    }
    Explained {
        line,
        supervisory,
        parsed,
        response: hand.take_output(),
        status,
        mode_after: hand.mode(),
        layout: hand.rt_layout().cloned(),
    }
}

fn parsed(profile: &Profile, bytes: &[u8]) -> Value {
    match grammar::parse_line(profile, bytes) {
        Ok(Line::Empty) => json!({ "empty": true }),
        Ok(Line::Command(c)) => {
            let spec = profile.command(c.command);
            let args = match &c.args {
                CmdArgs::None => json!(null),
                CmdArgs::Integer(v) => json!(v),
                CmdArgs::Names(ns) => json!(ns.iter().map(|n| profile.param(*n).name.clone()).collect::<Vec<_>>()),
                CmdArgs::Pairs(ps) => {
                    json!(ps.iter().map(|(n, v)| json!([profile.param(*n).name, v])).collect::<Vec<_>>())
                }
                CmdArgs::Topic(t) => json!(profile.command(*t).name),
            };
            json!({
                "command": spec.name,
                "kind": spec.kind,
                "prefix": c.prefix.map(|p| p.iter().collect::<Vec<_>>()),
                "args": args,
                "canonical": c.to_line(profile),
            })
        }
        Err(r) => json!({
            "rejected": r.status.code(),
            "problems": r.problems.iter().map(|p| p.to_string()).collect::<Vec<_>>(),
        }),
    }
}

fn block_json(b: &BlockLayout) -> Value {
    json!({
        "size": b.size(),
        "fields": b.fields().iter().map(|f| json!({
            "motor": f.motor(), "name": f.name(), "offset": f.offset(), "size": f.size(), "signed": f.signed(),
        })).collect::<Vec<_>>(),
    })
}

fn block_text(b: &BlockLayout, header: &str) -> String {
    let mut s = format!("{} bytes: [0] {header}", b.size());
    for f in b.fields() {
        let who = f.motor().map_or("hand".to_string(), |m| format!("motor {m}"));
        let ty = format!("{}{}", if f.signed() { "i" } else { "u" }, f.size() * 8);
        let range = if f.size() == 1 {
            format!("[{}]", f.offset())
        } else {
            format!("[{}..{}]", f.offset(), f.offset() + f.size() - 1)
        };
        s.push_str(&format!(", {range} {who} {} {ty}{}", f.name(), if f.size() > 1 { " big-endian" } else { "" }));
    }
    s
}

fn parsed_text(p: &Value) -> String {
    let strs = |v: &Value| {
        v.as_array().map(|a| a.iter().filter_map(|x| x.as_str()).collect::<Vec<_>>().join("; ")).unwrap_or_default()
    };
    if let Some(b) = p.get("block") {
        format!("RealTime block \"{}\"", b.as_str().unwrap_or_default())
    } else if p.get("empty").is_some() {
        "empty line".to_string()
    } else if let Some(code) = p.get("rejected") {
        format!("rejected with {code}: {}", strs(&p["problems"]))
    } else {
        let prefix = match p["prefix"].as_array() {
            Some(ms) => format!("motors {}", ms.iter().map(|m| m.to_string()).collect::<String>()),
            None => "no prefix".to_string(),
        };
        format!(
            "{} ({}), {prefix}, args {}, canonical `{}`",
            p["command"].as_str().unwrap_or_default(),
            p["kind"].as_str().unwrap_or_default(),
            p["args"],
            p["canonical"].as_str().unwrap_or_default()
        )
    }
}

/// Runs `gcl explain`.
pub fn run(args: Args) -> anyhow::Result<u8> {
    let profile = load_profile(&args.profile)?;
    let results = explain_lines(&profile, args.seed, &args.lines)?;
    let mut w = super::stdio::out();
    for r in &results {
        if args.json {
            writeln!(w, "{}", serde_json::to_string(&r.to_json(&profile))?)?;
            continue;
        }
        writeln!(w, "> {}", gcl_model::escape::printable(&r.line))?;
        writeln!(w, "  parsed:   {}", gcl_model::escape::printable(&parsed_text(&r.parsed)))?;
        writeln!(w, "  response: \"{}\"", escape(&r.response))?;
        let texts = r.status.describe(&profile).join("; ");
        writeln!(
            w,
            "  status:   {}{}",
            r.status.code(),
            if texts.is_empty() { String::new() } else { format!(" ({})", gcl_model::escape::printable(&texts)) }
        )?;
        if let Some(l) = &r.layout {
            writeln!(w, "  mode:     RealTime, motors {}", l.motors())?;
            writeln!(w, "  control:  {}", block_text(l.control(), "header C/c (A/a: the header alone)"))?;
            writeln!(w, "  feedback: {}", block_text(l.feedback(), "'*' (reply to c/a: '*' alone)"))?;
        }
    }
    Ok(EXIT_OK)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_holding_a_cr_is_the_two_commands_the_hand_answers() {
        let profile = load_profile("seed").unwrap();
        let r = explain_lines(&profile, 0, &["FGET DP\\rFGET MOV".to_string()]).unwrap();
        assert_eq!(r.len(), 2, "two commands");
        assert_eq!(r[0].line, "FGET DP");
        assert_eq!(r[1].line, "FGET MOV");
        for e in &r {
            assert!(e.parsed.get("rejected").is_none(), "{}: {}", e.line, e.parsed);
            assert_eq!(e.parsed["command"], "FGET");
            assert_eq!(e.status.code(), 0);
        }
        assert!(escape(&r[0].response).starts_with("FGET DP\\n\\r"), "{}", escape(&r[0].response));
        assert!(escape(&r[1].response).starts_with("FGET MOV\\n\\r"), "{}", escape(&r[1].response));
        // A plain LINE is still one entry, shown as given.
        let r = explain_lines(&profile, 0, &["HI".to_string()]).unwrap();
        assert_eq!(r.len(), 1);
        assert_eq!(r[0].line, "HI");
    }
}
