//! `gcl replay`: sends a golden transcript's host side to a hand and compares its answers.
//! Exit 0 when every answer matches, 1 on a mismatch or a timeout (expected against actual,
//! escaped, at the byte where they part), 2 on errors (a file that does not parse, a target
//! that does not open, a link that fails).

use super::stdio::errln;
use std::io::Write;
use std::path::PathBuf;
use std::time::Duration;

use anyhow::Context;

use super::{EXIT_ERROR, EXIT_FAIL, EXIT_OK};
use gcl_harness::replay::{ReplayOptions, ReplayOutcome, replay};
use gcl_host::target::Target;
use gcl_model::escape::printable;
use gcl_transcript::parse_bytes;

/// Arguments of `gcl replay`.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "A transcript with `setup:` lines (an object in the fingers' way) runs on `sim`, which places the \
objects; on any other target it is SKIP unless --fixture object says they are in place.\n\n\
Example:\n  gcl replay vectors/suite/seed/framing-echo.gcl --target sim:seed"
)]
pub struct Args {
    /// Transcript files to replay, in order.
    #[arg(required = true, value_name = "FILE")]
    files: Vec<PathBuf>,
    /// The hand: `sim`, `sim:PROFILE`, `serial:PATH?baud=N`, `tcp://HOST:PORT` or `exec:COMMAND ARGS`.
    /// A bare `sim` runs the transcript's first profile.
    #[arg(long, default_value = "sim")]
    target: String,
    /// Wait of a step without `within`, in milliseconds.
    #[arg(long, value_name = "MS", default_value_t = gcl_transcript::DEFAULT_STEP_TIMEOUT.as_millis() as u64, value_parser = super::millis)]
    timeout: u64,
    /// Send ^C and drain the answer before the first step.
    #[arg(long)]
    resync: bool,
    /// Print only failures.
    #[arg(long, short)]
    quiet: bool,
    /// Declare a transcript's set-up in place (only `object`: the objects its `setup:` lines
    /// name). `sim` places them itself; elsewhere such transcripts are SKIP without this.
    #[arg(long = "fixture", value_name = "FIXTURE", value_parser = ["object"])]
    fixture: Vec<String>,
}

/// Opens a target for a transcript of `profile` (used when the target is a bare `sim`).
pub(crate) fn open_target(target: &Target, profile: Option<&str>) -> anyhow::Result<Box<dyn gcl_host::Link>> {
    open_target_with(target, profile, [None; 4])
}

/// [`open_target`] with objects where each motor meets one when closing (`sim` only).
pub(crate) fn open_target_with(
    target: &Target,
    profile: Option<&str>,
    objects: [Option<i64>; 4],
) -> anyhow::Result<Box<dyn gcl_host::Link>> {
    let scenario = objects.iter().any(Option::is_some).then(|| gcl_model::Scenario { objects, ..Default::default() });
    let opts = gcl_host::target::OpenOptions { profile: profile.map(str::to_string), scenario, ..Default::default() };
    let mut link = gcl_host::target::open(target, &opts).with_context(|| format!("opening {target}"))?;
    if matches!(target, Target::Exec { .. }) {
        // A freshly started process prints its power-up banner when it is ready, which may be
        // well after the first quiet period a transcript's drain allows: wait for it here.
        let mut junk = Vec::new();
        link.recv(&mut junk, Duration::from_secs(5))?;
        gcl_host::link::drain(link.as_mut(), Duration::from_millis(100), Duration::from_secs(5))?;
    }
    Ok(link)
}

/// Runs `gcl replay`.
pub fn run(args: Args) -> anyhow::Result<u8> {
    let target: Target = args.target.parse()?;
    let opts = ReplayOptions {
        default_timeout: Duration::from_millis(args.timeout),
        resync: args.resync,
        ..ReplayOptions::default()
    };
    let mut transcripts = Vec::new();
    for f in &args.files {
        let bytes = gcl_host::files::read_input(f).with_context(|| format!("reading {}", f.display()))?;
        let t = parse_bytes(&bytes).with_context(|| format!("parsing {}", f.display()))?;
        transcripts.push((f, t));
    }
    // A simulated hand of one profile answering a transcript written for another differs by
    // the profile, not by a bug: say so before the verdicts.
    if let Target::Sim { profile: Some(p) } = &target {
        let simulated = super::load_profile(p)?.id.clone();
        for (f, t) in &transcripts {
            if !t.header.profiles.is_empty() && !t.header.profiles.contains(&simulated) {
                errln!(
                    "gcl replay: warning: {} is written for profile {}, but the target simulates {simulated}; \
differences may come from the profile, not a bug (use --target sim:{} or sim to match)",
                    printable(&f.display().to_string()),
                    printable(&t.header.profiles.join(", ")),
                    printable(&t.header.profiles[0])
                );
            }
        }
    }
    let mut code = EXIT_OK;
    let mut shared: Option<Box<dyn gcl_host::Link>> = None;
    let mut w = super::stdio::out();
    for (f, t) in &transcripts {
        let sim = gcl_harness::conform::places_setup(&target);
        if !t.header.setup.is_empty() && !sim && args.fixture.is_empty() {
            writeln!(
                w,
                "SKIP {}: needs {} in place, which gcl cannot place on {target}; put it there and pass --fixture object",
                printable(&f.display().to_string()),
                printable(&gcl_transcript::Setup::list(&t.header.setup))
            )?;
            continue;
        }
        // Each transcript gets a fresh simulated hand (with its objects); a real hand is
        // opened once.
        let mut fresh;
        let link: &mut dyn gcl_host::Link = if sim {
            fresh = open_target_with(&target, t.header.profiles.first().map(String::as_str), t.header.objects())?;
            fresh.as_mut()
        } else {
            if shared.is_none() {
                shared = Some(open_target(&target, None)?);
            }
            match shared.as_mut() {
                Some(l) => l.as_mut(),
                None => anyhow::bail!("no link"),
            }
        };
        let out = replay(t, link, &opts);
        match &out {
            ReplayOutcome::Pass(p) => {
                if !args.quiet {
                    writeln!(w, "PASS {} ({} steps)", printable(&f.display().to_string()), p.exchange.len())?;
                }
            }
            ReplayOutcome::Mismatch(_) | ReplayOutcome::Timeout(_) | ReplayOutcome::Flooded(_) => {
                let verdict = if matches!(out, ReplayOutcome::Timeout(_)) { "TIMEOUT" } else { "FAIL" };
                writeln!(
                    w,
                    "{verdict} {}: {}",
                    printable(&f.display().to_string()),
                    printable(out.render().trim_end())
                )?;
                code = code.max(EXIT_FAIL);
            }
            ReplayOutcome::Disconnected(_) => {
                writeln!(w, "ERROR {}: {}", printable(&f.display().to_string()), printable(&out.summary()))?;
                code = EXIT_ERROR;
            }
        }
    }
    Ok(code)
}
