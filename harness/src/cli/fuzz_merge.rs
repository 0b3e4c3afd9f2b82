//! `gcl fuzz merge DIR... --out DIR`: folds the outputs of a campaign's shards into one
//! (library code in `gcl_harness::fuzz::merge`).

use super::stdio::errln;
use std::path::PathBuf;

use anyhow::Context;
use gcl_harness::fuzz::host::{FuzzOptions, HostRun, Transport, Weights};
use gcl_harness::fuzz::merge::{self, Kind, NotCopied};
use gcl_harness::report::merged::Merged;
use gcl_harness::report::{CaseResult, Verdict};
use gcl_harness::sim::{Pace, TimeMode};
use gcl_model::escape::printable;

use super::{EXIT_ERROR, EXIT_FAIL, EXIT_OK, load_profile};

/// Arguments of `gcl fuzz merge`.
#[derive(Debug, clap::Args)]
#[command(after_help = "\
Each DIR is one shard's folder, as the CI recipes in ci/ write it:
  DIR/report    --report of gcl fuzz host (fuzz.json, report.json) or gcl fuzz device
  DIR/bundles   --out of gcl fuzz host
  DIR/findings  --out of gcl fuzz device
  DIR/corpus    --corpus of gcl fuzz device
The merged folder has the same layout. Findings are deduplicated by signature (the first
found stands, hits add up), corpus entries by content hash.

Only shards of one campaign merge: each report records its --shard K/N, its seed and every
option that changed what ran, and a folder of another campaign (another seed, --ops, --runs,
profile...), of another N, or the same shard twice is refused. A merged folder may be merged
again with the remaining shards. Missing shards are merged and said: the reports say
\"merged from shards 1, 3 of 4 (INCOMPLETE: 2, 4 missing)\" and the exit code is 2.

A shard is merged only as gcl wrote it: its report carries the campaign's id and a digest of
the report and of every file a merge reads from the folder (a file edited, swapped or planted
is refused or left behind, by name), and a shard written by an older gcl, without them, is
refused. What every shard finds in the campaign's run 0 (calibration, the run without
misbehaviour) is one finding.

Files are read as they are: a symbolic link, a FIFO or a device in a shard's folder is never
followed or copied (each is named), and a file over 4 MiB is refused. --out is held for the
merge (a campaign or another merge using it is refused); it must be new, empty or an earlier
merge's output, which the merge replaces whole: the merge is written beside it and put in
place once every input is read, so an earlier merge may be merged again into its own folder.

Exit codes: 0 every shard merged, no new finding; 1 every shard merged, findings; 2 usage or
infrastructure (shards missing, folders of different campaigns or the same shard twice,
a shard edited or unsealed, unreadable or out-of-range files, --out in use).

Example:
  gcl fuzz merge reports/shard-1 reports/shard-2 reports/shard-3 reports/shard-4 \\
      --out reports/merged")]
pub struct Args {
    /// The shards' folders.
    #[arg(required = true, value_name = "DIR")]
    dirs: Vec<PathBuf>,
    /// Where the merged folder goes.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// The profile of a host campaign whose hand ran a profile from a TOML file (built-in
    /// profiles are found by their id).
    #[arg(long)]
    profile: Option<String>,
}

/// Runs `gcl fuzz merge`.
pub fn run(a: Args) -> anyhow::Result<u8> {
    let kinds: Vec<Kind> = a.dirs.iter().map(|d| merge::kind_of(d)).collect::<Result<_, _>>()?;
    if kinds.windows(2).any(|w| w[0] != w[1]) {
        anyhow::bail!("the folders mix gcl fuzz host and gcl fuzz device campaigns");
    }
    match kinds[0] {
        Kind::Host => host(&a),
        Kind::Device => device(&a),
    }
}

/// Names what was left behind, and says whether every shard was merged.
fn finish(merged: &Merged, not_copied: &NotCopied) -> bool {
    // The names are a shard's (a CI artifact's): shown, never obeyed.
    for n in not_copied {
        errln!("gcl fuzz merge: warning: {}", printable(n));
    }
    if !merged.complete() {
        errln!(
            "gcl fuzz merge: shard(s) {} of {} missing: the merged reports say INCOMPLETE, and the exit code is 2",
            merged.missing().iter().map(u64::to_string).collect::<Vec<_>>().join(", "),
            merged.count
        );
    }
    merged.complete()
}

fn device(a: &Args) -> anyhow::Result<u8> {
    // Everything is read and checked before --out is touched.
    let m = merge::merge_device(&a.dirs)?;
    let out = merge::take_out(&a.out, &a.dirs)?;
    let (entries, dups, mut not_copied) = merge::merge_corpora(&a.dirs, &out.stage().join("corpus"))?;
    let (r, more) = merge::write_device(&m, &out, Some(entries))?;
    not_copied.extend(more);
    out.commit()?;
    errln!(
        "gcl fuzz merge: merged from {}: {} runs, {} distinct finding(s) ({} new), corpus {} entries ({} duplicate(s) dropped) -> {}",
        m.merged.describe(),
        r.runs,
        r.findings.len(),
        r.new_findings(),
        entries,
        dups,
        a.out.display()
    );
    if !finish(&m.merged, &not_copied) {
        return Ok(EXIT_ERROR);
    }
    // Shards that ended early without a new finding make no verdict (as each shard's).
    Ok(match (r.new_findings() != 0, &r.stopped) {
        (true, _) => EXIT_FAIL,
        (false, Some(_)) => EXIT_ERROR,
        (false, None) => EXIT_OK,
    })
}

fn host(a: &Args) -> anyhow::Result<u8> {
    let m = merge::merge_host(&a.dirs)?;
    let profile = load_profile(a.profile.as_deref().unwrap_or(&m.report.profile))
        .context("the shards' profile (give --profile FILE for a profile from a file)")?;
    let out = merge::take_out(&a.out, &a.dirs)?;
    let (bundles, not_copied) = merge::write_host_bundles(&m, &out.stage().join("bundles"))?;
    let recorded = m.campaign.provenance.as_ref().map(|p| &p.options);
    // The misbehaviours the shards drew from, as they recorded them.
    let weights = recorded.and_then(|o| o.get("ops")).and_then(|ops| Weights::parse(ops).ok());
    // The shards' host command, word for word (its replay lines quote each word), else the
    // target line as one word.
    let target = m.report.target.strip_prefix("host: ").unwrap_or(&m.report.target);
    let command = m.report.host.as_ref().map(|h| h.command.clone()).filter(|c| !c.is_empty());
    let command = command.unwrap_or_else(|| vec![target.to_string()]);
    // The campaign's options as far as its report shows them; the rest does not reach it.
    let opts = FuzzOptions {
        run: HostRun {
            command,
            transport: Transport::Pty,
            profile,
            time: TimeMode::Fast,
            pace: Pace::Unpaced,
            hand_seed: m.report.options.seed.unwrap_or(0),
            timeout_hang: std::time::Duration::ZERO,
            budget: std::time::Duration::ZERO,
            link: None,
            coverage: Default::default(),
            env: Vec::new(),
        },
        seed: m.report.options.seed.unwrap_or(0),
        runs: None,
        duration: None,
        ok_exit_codes: Vec::new(),
        jobs: 1,
        weights: weights.clone().unwrap_or_default(),
        max_planned: 1,
        minimize: false,
        guided: false,
        calibrate: false,
        shard: None,
    };
    let mut report = super::fuzz_host::campaign_report(&opts, &m.campaign, &a.out.join("bundles"), weights.is_some());
    // Each case's transcript is its finding's bundle transcript, as in a shard's report.
    for (case, f) in report.cases.iter_mut().zip(&m.campaign.findings) {
        if let Some(t) = m.transcripts.get(&f.verdict.signature) {
            case.transcript = Some(gcl_harness::report::truncate_note(t, gcl_harness::report::MAX_SHOWN));
        }
    }
    if !m.merged.complete() {
        // The runs of the missing shards were never judged here: no green for them.
        report.cases.push(CaseResult {
            id: "fuzz-merge-incomplete".into(),
            title: format!("merged from {}", m.merged.describe()),
            clauses: vec!["host: fuzz".into()],
            decisions: Vec::new(),
            level: "MUST".into(),
            verdict: Verdict::Error,
            duration_ms: 0.0,
            message: Some(format!(
                "shard(s) {} of {} missing: their runs are not in this report",
                m.merged.missing().iter().map(u64::to_string).collect::<Vec<_>>().join(", "),
                m.merged.count
            )),
            diff: None,
            failure: None,
            transcript: None,
        });
        report.tally();
    }
    // Written aside, sealed as a shard is (so that it merges again), then put in place.
    let dir = out.stage().join("report");
    gcl_harness::report::write_all(&dir, &report)?;
    let mut campaign = m.campaign.clone();
    merge::seal_host(&mut campaign, &dir, &out.stage().join("bundles"))?;
    gcl_harness::report::write_atomic(&dir.join("fuzz.json"), &serde_json::to_vec_pretty(&campaign)?)?;
    out.commit()?;
    errln!(
        "gcl fuzz merge: merged from {}: {} runs, {} distinct finding(s), {} bundle(s) -> {}",
        m.merged.describe(),
        m.campaign.runs,
        m.campaign.findings.len(),
        bundles.len(),
        a.out.display()
    );
    if !finish(&m.merged, &not_copied) {
        return Ok(EXIT_ERROR);
    }
    Ok(match (m.campaign.findings.is_empty(), m.campaign.untested.is_some() || m.campaign.stopped.is_some()) {
        (false, _) => EXIT_FAIL,
        // A shard that could not test or was stopped: no verdict (as each shard's).
        (true, true) => EXIT_ERROR,
        (true, false) => EXIT_OK,
    })
}
