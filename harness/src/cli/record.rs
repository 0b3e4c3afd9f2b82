//! `gcl record`: runs a script of host lines and blocks against a hand and writes what it
//! answered as a golden transcript (the script syntax is in
//! [`gcl_transcript::script`] and `vectors/README.md`).

use super::stdio::errln;
use std::io::Write;
use std::path::PathBuf;
use std::time::Duration;

use anyhow::Context;

use super::{EXIT_OK, load_profile};
use gcl_harness::record::{RecordOptions, record};
use gcl_host::target::Target;
use gcl_transcript::script::parse_script_bytes;
use gcl_transcript::{Level, is_slug};

/// Arguments of `gcl record`.
#[derive(Debug, clap::Args)]
#[command(after_help = "Script lines: a host line (sent with a CR), `line: ESCAPED`, `nowait: LINE`, \
`raw: ESCAPED`, `partial: ESCAPED`, `block: 43 14 FB`, `abort`, `wait`, `pause: 200ms`, `timeout: 30s`, `# comment`, \
and transcript header keys (`id:`, `title:`, `clause:`, `level:`, `profile:`, `requires:`, `setup:` (`sim` places its objects), `note:`).\n\n\
Example:\n  gcl record --target sim:seed --script my-case.script --out reports/my-case.gcl")]
pub struct Args {
    /// The hand: `sim`, `sim:PROFILE`, `serial:PATH?baud=N`, `tcp://HOST:PORT` or `exec:COMMAND ARGS`.
    #[arg(long)]
    target: String,
    /// The script to run.
    #[arg(long)]
    script: PathBuf,
    /// Where to write the transcript, atomically (default: standard output).
    #[arg(long)]
    out: Option<PathBuf>,
    /// The case id (default: the script's `id:`, else its file name).
    #[arg(long)]
    id: Option<String>,
    /// The title (default: the script's, else the id).
    #[arg(long)]
    title: Option<String>,
    /// Spec clauses checked (repeatable; added to the script's).
    #[arg(long = "clause")]
    clauses: Vec<String>,
    /// MUST, SHOULD, MAY or INFO (default: the script's, else INFO).
    #[arg(long)]
    level: Option<Level>,
    /// Profiles the case applies to (repeatable). The first is also the profile of the model
    /// that shapes the capture (RealTime block sizes); default: the target's or the script's.
    #[arg(long = "profile")]
    profiles: Vec<String>,
    /// Requirements (repeatable): motion, realtime, eeprom, abort-timing, ...
    #[arg(long = "requires")]
    requires: Vec<String>,
    /// Capture timeout of a step whose script sets none, in milliseconds.
    #[arg(long, value_name = "MS", default_value_t = 30_000, value_parser = super::millis)]
    timeout: u64,
    /// Silence that ends a `nowait:` step, in milliseconds.
    #[arg(long, value_name = "MS", default_value_t = 100, value_parser = super::millis)]
    quiet: u64,
    /// Write RESET banners exactly instead of as `{any}BarrettHand Firmware{any}`.
    #[arg(long)]
    exact_banner: bool,
    /// Keep going when a step times out (write what arrived) instead of failing.
    #[arg(long)]
    allow_timeouts: bool,
}

/// Runs `gcl record`.
pub fn run(args: Args) -> anyhow::Result<u8> {
    let target: Target = args.target.parse()?;
    let bytes =
        gcl_host::files::read_input(&args.script).with_context(|| format!("reading {}", args.script.display()))?;
    let script = parse_script_bytes(&bytes).with_context(|| format!("parsing {}", args.script.display()))?;
    let mut fields = script.fields.clone();
    if let Some(id) = args.id {
        fields.id = Some(id);
    }
    if fields.id.is_none() {
        let stem = args.script.file_stem().and_then(|s| s.to_str()).unwrap_or("recorded").to_ascii_lowercase();
        let slug: String = stem.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '-' }).collect();
        fields.id = Some(if is_slug(&slug) { slug } else { "recorded".into() });
    }
    if let Some(t) = args.title {
        fields.title = Some(t);
    }
    if fields.title.is_none() {
        fields.title = fields.id.clone();
    }
    fields.clauses.extend(args.clauses);
    if fields.clauses.is_empty() {
        fields.clauses.push(format!("recorded: {}", args.script.display()));
    }
    if let Some(l) = args.level {
        fields.level = Some(l);
    }
    fields.level.get_or_insert(Level::Info);
    if !args.profiles.is_empty() {
        fields.profiles = args.profiles;
    }
    let profile = load_profile(target.model_profile(fields.profiles.first().map(String::as_str)))?;
    if fields.profiles.is_empty() {
        fields.profiles.push(profile.id.clone());
    }
    for r in &args.requires {
        fields.apply("requires", r, 0)?;
    }
    let header = fields.finish(0)?;
    // A script's `setup:` lines: `sim` places the objects; any other hand is recorded as it is,
    // with the objects the operator put there.
    if !header.setup.is_empty() && !gcl_harness::conform::places_setup(&target) {
        errln!(
            "gcl record: note: the script needs {} in place; gcl cannot place it on {target}, so it records the hand as it is",
            gcl_model::escape::printable(&gcl_transcript::Setup::list(&header.setup))
        );
    }
    let mut link = super::replay::open_target_with(&target, Some(&profile.id), header.objects())?;
    let mut opts = RecordOptions::new(profile);
    opts.timeout = Duration::from_millis(args.timeout);
    opts.quiet = Duration::from_millis(args.quiet);
    opts.elide_banner = !args.exact_banner;
    let (t, caps) = record(link.as_mut(), header, &script, &opts, args.allow_timeouts)?;
    for (i, c) in caps.iter().enumerate() {
        if c.timed_out {
            errln!("gcl record: step {} (script line {}) timed out; kept what arrived", i + 1, script.steps[i].line);
        }
    }
    let text = t.to_text();
    match args.out {
        // Temporary file, then rename: a kill leaves the old file or the new one, never an
        // empty or torn one.
        Some(path) => {
            gcl_harness::report::write_atomic(&path, text.as_bytes())
                .with_context(|| format!("writing {}", path.display()))?;
            errln!("gcl record: wrote {} ({} steps)", path.display(), t.steps.len());
        }
        None => super::stdio::out().write_all(text.as_bytes())?,
    }
    Ok(EXIT_OK)
}
