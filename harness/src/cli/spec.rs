//! `gcl spec`: prints a loaded profile, as text for people or JSON for programs.

use std::io::Write;

use gcl_model::spec::Scope;

use super::{EXIT_OK, load_profile};

/// Arguments of `gcl spec`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Profile: seed, bh8-262-4.3, bh8-262-4.4 (alias bh8-262), or a spec TOML file.
    #[arg(long, default_value = "bh8-262")]
    profile: String,
    /// Print the resolved profile as JSON.
    #[arg(long)]
    json: bool,
}

/// Runs `gcl spec`.
pub fn run(args: Args) -> anyhow::Result<u8> {
    let p = load_profile(&args.profile)?;
    let mut w = super::stdio::out();
    if args.json {
        serde_json::to_writer_pretty(&mut w, &*p)?;
        writeln!(w)?;
        return Ok(EXIT_OK);
    }
    // A profile may be a file from anywhere: its text is shown escaped, never obeyed.
    let mut text = Vec::new();
    let w = &mut text;
    let esc = gcl_model::escape::escape;
    writeln!(w, "profile {}: {}", p.id, p.title)?;
    if !p.aliases.is_empty() {
        writeln!(w, "aliases: {}", p.aliases.join(", "))?;
    }
    let f = &p.framing;
    writeln!(w, "\nframing")?;
    writeln!(
        w,
        "  terminator \"{}\", echo {}, line ending \"{}\", prompt \"{}\", max line {} bytes (longer: ERR {}), abort \"{}\"",
        esc(&[f.terminator]),
        f.echo,
        esc(f.line_ending.as_bytes()),
        esc(f.prompt.as_bytes()),
        f.max_line,
        f.overlong_status,
        esc(&[f.abort])
    )?;
    writeln!(w, "  banner: {}", p.banner.join(" / "))?;
    writeln!(w, "\nmotor prefixes")?;
    for pr in &p.prefixes {
        writeln!(w, "  {}  motors {}", pr.char, pr.motors.iter().map(|m| m.to_string()).collect::<Vec<_>>().join(","))?;
    }
    writeln!(w, "\ncommands")?;
    writeln!(w, "  {:<8} {:<13} {:<10} {:<17} help", "name", "category", "prefix", "args")?;
    for c in &p.commands {
        let args = match c.args {
            gcl_model::spec::ArgRule::OptionalInteger => {
                format!("[{}..{}]", c.arg_min.unwrap_or_default(), c.arg_max.unwrap_or_default())
            }
            a => format!("{a:?}").to_lowercase(),
        };
        writeln!(
            w,
            "  {:<8} {:<13} {:<10} {:<17} {}",
            c.name,
            c.category,
            format!("{:?}", c.prefix).to_lowercase(),
            args,
            c.help
        )?;
    }
    writeln!(w, "\nparameters")?;
    writeln!(
        w,
        "  {:<7} {:<7} {:<14} {:>8} {:>8} {:<6} {:<4} {:<4} {:<17} realtime",
        "name", "scope", "range", "finger", "spread", "access", "adv", "live", "persist"
    )?;
    for prm in &p.params {
        let range = match &prm.values {
            Some(v) => format!("{{{}}}", v.iter().map(|x| x.to_string()).collect::<Vec<_>>().join(",")),
            None => format!("{}..{}", prm.min, prm.max),
        };
        let d = |v: Option<i64>| v.map_or("-".to_string(), |x| x.to_string());
        let rt = prm.rt.map_or(String::new(), |r| {
            format!("{:?} {}B {}", r.block, r.size, if r.signed { "signed" } else { "unsigned" }).to_lowercase()
        });
        writeln!(
            w,
            "  {:<7} {:<7} {:<14} {:>8} {:>8} {:<6} {:<4} {:<4} {:<17} {}{}",
            prm.name,
            if prm.scope == Scope::Motor { "motor" } else { "hand" },
            range,
            d(prm.default),
            if prm.scope == Scope::Motor { d(prm.default_spread.or(prm.default)) } else { "".into() },
            if prm.read_only { "RO" } else { "RW" },
            if prm.advanced { "yes" } else { "" },
            if prm.live { "yes" } else { "" },
            prm.persist.join(","),
            rt,
            prm.alias_of.as_ref().map_or(String::new(), |a| format!(" (alias of {a})")),
        )?;
    }
    writeln!(w, "\nstatus codes")?;
    for s in &p.status {
        writeln!(w, "  {:>5}  {}{}", s.bit, s.text, if s.sent { "" } else { "  (never sent)" })?;
    }
    writeln!(w, "\ndecisions ({})", p.decisions.len())?;
    for d in &p.decisions {
        writeln!(w, "  [{}] {} {} ({})\n      {}", d.level, d.id, d.evidence, d.clause, d.resolution)?;
    }
    super::stdio::out().write_all(gcl_model::escape::printable(&String::from_utf8_lossy(&text)).as_bytes())?;
    Ok(EXIT_OK)
}
