//! `gcl fuzz merge DIR... --out DIR`: folds the outputs of a campaign's shards into one
//! (library code in `gcl_harness::fuzz::merge`).

use std::path::PathBuf;

use anyhow::Context;
use gcl_harness::fuzz::host::{FuzzOptions, HostRun, Transport, Weights};
use gcl_harness::fuzz::merge::{self, Kind};
use gcl_harness::sim::{Pace, TimeMode};

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

Exit codes: 0 no finding, 1 findings, 2 usage or infrastructure (folders of different
campaigns, unreadable files).

Example:
  gcl fuzz merge shard-1 shard-2 shard-3 shard-4 --out merged")]
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
        Kind::Device => {
            let (entries, dups) = merge::merge_corpora(&a.dirs, &a.out.join("corpus"))?;
            let r = merge::merge_device(&a.dirs, &a.out, Some(entries))?;
            eprintln!(
                "gcl fuzz merge: {} shard(s), {} runs, {} distinct finding(s), corpus {} entries ({} duplicate(s) dropped) -> {}",
                a.dirs.len(),
                r.runs,
                r.findings.len(),
                entries,
                dups,
                a.out.display()
            );
            // Shards that ended early without a new finding make no verdict (as each shard's).
            Ok(match (!r.findings.is_empty(), &r.stopped) {
                (true, _) => EXIT_FAIL,
                (false, Some(_)) => EXIT_ERROR,
                (false, None) => EXIT_OK,
            })
        }
    }
}

fn host(a: &Args) -> anyhow::Result<u8> {
    let m = merge::merge_host(&a.dirs)?;
    let bundles = merge::write_host_bundles(&m, &a.out.join("bundles"))?;
    let profile = load_profile(a.profile.as_deref().unwrap_or(&m.report.profile))
        .context("the shards' profile (give --profile FILE for a profile from a file)")?;
    let command = vec![m.report.target.strip_prefix("host: ").unwrap_or(&m.report.target).to_string()];
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
        },
        seed: m.report.options.seed.unwrap_or(0),
        runs: None,
        duration: None,
        ok_exit_codes: Vec::new(),
        jobs: 1,
        weights: Weights::default(),
        max_planned: 1,
        minimize: false,
        guided: false,
        calibrate: false,
        shard: None,
    };
    let mut report = super::fuzz_host::campaign_report(&opts, &m.campaign, &a.out.join("bundles"), false);
    // Each case's transcript is its finding's bundle transcript, as in a shard's report.
    for (case, f) in report.cases.iter_mut().zip(&m.campaign.findings) {
        if let Some(t) = m.transcripts.get(&f.verdict.signature) {
            case.transcript = Some(gcl_harness::report::truncate_note(t, gcl_harness::report::MAX_SHOWN));
        }
    }
    let dir = a.out.join("report");
    gcl_harness::report::write_all(&dir, &report)?;
    gcl_harness::report::write_atomic(&dir.join("fuzz.json"), &serde_json::to_vec_pretty(&m.campaign)?)?;
    eprintln!(
        "gcl fuzz merge: {} shard(s), {} runs, {} distinct finding(s), {} bundle(s) -> {}",
        a.dirs.len(),
        m.campaign.runs,
        m.campaign.findings.len(),
        bundles.len(),
        a.out.display()
    );
    Ok(match (m.campaign.findings.is_empty(), m.campaign.untested.is_some() || m.campaign.stopped.is_some()) {
        (false, _) => EXIT_FAIL,
        // A shard that could not test or was stopped: no verdict (as each shard's).
        (true, true) => EXIT_ERROR,
        (true, false) => EXIT_OK,
    })
}
