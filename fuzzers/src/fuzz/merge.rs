//! `gcl fuzz merge DIR...`: folds the outputs of a campaign's shards ([`super::shard`]) into
//! one, as if one machine had made all their runs.
//!
//! A shard's folder holds what the CI recipes (`ci/`) write:
//!
//! ```text
//! DIR/report/   gcl fuzz host: fuzz.json, report.json (+ junit.xml, report.html)
//!               gcl fuzz device: fuzz-device.json (+ junit.xml, fuzz-device.html)
//! DIR/bundles/  gcl fuzz host --out: one reproducer folder per distinct finding
//! DIR/findings/ gcl fuzz device --out: one minimized transcript per distinct finding
//! DIR/corpus/   gcl fuzz device --corpus: one file per entry, named by its content hash
//! ```
//!
//! Only shards of one campaign fold: each report records its slice, seed and options
//! ([`super::shard::Provenance`]), and [`super::shard::plan`] refuses another campaign's
//! folder, another slicing, or the same slice twice. A slice that is missing is no error
//! here: the merged report says which are missing (INCOMPLETE), and the CLI exits 2.
//!
//! Findings are deduplicated by signature: the one first found (the lowest run index of the
//! campaign, for the host fuzzer, whose run indices are the campaign's) stands, with the hits
//! of every shard added up; bundles and transcripts come from the shard whose finding stands.
//! Corpus entries are deduplicated by content hash (an entry whose name is not its hash is
//! stored under its hash). Counts add up, checked: a figure beyond [`MAX_COUNT`] (or a time
//! beyond [`MAX_ELAPSED_MS`]) is refused by name. Wall times are the longest shard's.
//!
//! A shard's folder is data from anywhere (a CI artifact): every file is read through the
//! bounded reader of `gcl_host::files` without following a symbolic link, and only regular
//! files are copied (a link, a FIFO or a device in a bundle is named and left behind). A shard
//! is taken only as gcl wrote it: its report is sealed ([`seal_host`], [`seal_device`]: the
//! campaign's id, the files a merge reads with their digests, the report's own digest), and a
//! report or file that does not match, or an unsealed report, is refused; a file its seal does
//! not hold is never read (named, not copied). The seal is a digest, not a signature: a forger
//! can make one anew, so what a shard's record allows is checked too (its `runs` within its
//! share of `--runs`, a finding of a run of its own slices). What every shard finds in the
//! campaign's run 0 (calibration, the run without misbehaviour, made by each shard) is one
//! finding, its hits counting run 0 once. A merged folder is sealed as a shard is.
//!
//! The merged folder is held ([`take_out`]) for the whole merge and the merge is written
//! beside it ([`Out`]), then put in place whole ([`Out::commit`]) once every input was read:
//! an earlier merge merged again into its own folder loses nothing, and no bundle outlives
//! the report that lists it. (Rather than refusing an input inside `--out`: the docs allow
//! both, and a comparison of paths is fooled by bind mounts and hard links; building aside
//! needs no such comparison.)

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use super::device::action::HostAction;
use super::device::corpus_name;
use super::device::report::FuzzReport;
use super::host::bundle::{BundleInfo, dir_name};
use super::host::{Campaign, Finding, PassAccount};
use super::shard::{Provenance, ShardSetError};
use crate::report::RunReport;
use crate::report::merged::Merged;
use gcl_host::files::{MAX_INPUT_BYTES, read_limited_no_follow};

/// The largest count a shard's report may hold (runs, hits, bytes...): 2^53 - 1, the largest
/// integer every JSON reader keeps exactly. Beyond it a figure is not a campaign's.
pub const MAX_COUNT: u64 = (1 << 53) - 1;

/// The longest wall time a shard's report may hold: 100 years, in milliseconds.
pub const MAX_ELAPSED_MS: u64 = 100 * 366 * 24 * 3600 * 1000;

/// The largest corpus entry merged (as `gcl fuzz device` reads its corpus).
const MAX_CORPUS_ENTRY: u64 = 1 << 20;

/// Why shards cannot be merged.
#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    /// A file or folder cannot be read or written.
    #[error("{path}: {error}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why (in the message, not a `source`, so that a chain prints it once).
        error: std::io::Error,
    },
    /// A file is not what a shard writes.
    #[error("{path}: {reason}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// Why.
        reason: String,
    },
    /// A figure of a shard's report is out of range, or the shards' figures add up beyond it.
    #[error("{path}: `{field}` {value} is out of range (at most {limit}); refused rather than folded")]
    OutOfRange {
        /// The report.
        path: PathBuf,
        /// The field.
        field: String,
        /// Its value (or the sum).
        value: String,
        /// The limit.
        limit: u64,
    },
    /// The folders are not shards of one campaign, each once.
    #[error(transparent)]
    Shards(#[from] ShardSetError),
    /// The folders mix the two fuzzers, or none was given.
    #[error("not shards of one campaign: {0}")]
    Mixed(String),
    /// A folder holds neither a host nor a device campaign's report.
    #[error("{0}: no report/fuzz.json (gcl fuzz host) or report/fuzz-device.json (gcl fuzz device) in it")]
    NotAShard(PathBuf),
    /// The output folder is held by another command (a campaign, another merge), or its lock
    /// file is not one.
    #[error("{0}")]
    Busy(String),
    /// A shard's report carries no seal (written by a gcl before shards were sealed).
    #[error(
        "{0}: its report carries no campaign id or digest (written by an older gcl?), so nothing shows that it is a shard as written; run the shard again with this gcl"
    )]
    Unsealed(PathBuf),
    /// A shard's report or file is not what its seal says.
    #[error("{path}: {reason}; a shard is merged only as gcl wrote it")]
    Tampered {
        /// The file.
        path: PathBuf,
        /// What does not match.
        reason: String,
    },
    /// The output folder holds files no merge wrote.
    #[error(
        "{0} holds files that no `gcl fuzz merge` wrote (a shard's folder, or another command's); give a new or empty --out"
    )]
    NotOurs(PathBuf),
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> MergeError + '_ {
    move |error| MergeError::Io { path: path.to_path_buf(), error }
}

/// A file of a shard, read whole through the bounded reader, refusing a symbolic link.
fn read(path: &Path, limit: u64) -> Result<Vec<u8>, MergeError> {
    read_limited_no_follow(path, limit).map_err(io(path))
}

fn read_text(path: &Path) -> Result<String, MergeError> {
    String::from_utf8(read(path, MAX_INPUT_BYTES)?)
        .map_err(|e| MergeError::Invalid { path: path.to_path_buf(), reason: format!("not UTF-8 text: {e}") })
}

fn load<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, MergeError> {
    serde_json::from_str(&read_text(path)?)
        .map_err(|e| MergeError::Invalid { path: path.to_path_buf(), reason: e.to_string() })
}

/// The fuzzers' names in a campaign id ([`super::shard::campaign_id`]).
const HOST: &str = "fuzz host";
const DEVICE: &str = "fuzz device";

/// The files a merge may read from the shards, each with the SHA-256 its shard's seal gives
/// it, by path.
type Expected = BTreeMap<PathBuf, String>;

/// A shard's report, parsed, its seal checked: the campaign id is its own record's, and the
/// digest is the report's (see [`super::shard::seal`]). The files it holds join `expected`.
/// A report without a provenance is left to [`super::shard::plan`], which refuses it by name.
fn load_sealed<T: serde::de::DeserializeOwned>(
    dir: &Path,
    path: &Path,
    fuzzer: &str,
    provenance: fn(&T) -> Option<&Provenance>,
    expected: &mut Expected,
) -> Result<T, MergeError> {
    let bytes = read(path, MAX_INPUT_BYTES)?;
    let text = std::str::from_utf8(&bytes)
        .map_err(|e| MergeError::Invalid { path: path.to_path_buf(), reason: format!("not UTF-8 text: {e}") })?;
    let report: T = serde_json::from_str(text)
        .map_err(|e| MergeError::Invalid { path: path.to_path_buf(), reason: e.to_string() })?;
    let Some(p) = provenance(&report) else { return Ok(report) };
    let (Some(campaign), Some(digest)) = (&p.campaign, &p.digest) else {
        return Err(MergeError::Unsealed(path.to_path_buf()));
    };
    let tampered = |reason: String| MergeError::Tampered { path: path.to_path_buf(), reason };
    if *campaign != super::shard::campaign_id(fuzzer, p) {
        return Err(tampered(format!(
            "its campaign id {} is not the one its seed, options and shards make",
            &campaign[..campaign.len().min(16)]
        )));
    }
    let actual = super::shard::report_digest(&bytes)
        .map_err(|e| MergeError::Invalid { path: path.to_path_buf(), reason: e.to_string() })?;
    if actual != *digest {
        return Err(tampered(format!(
            "its content does not match the digest it records ({} against {}): changed after gcl wrote it",
            &actual[..16],
            &digest[..digest.len().min(16)]
        )));
    }
    for (name, sha) in &p.holds {
        expected.insert(dir.join(name), sha.clone());
    }
    Ok(report)
}

/// A file of a shard its seal holds, read and checked against the digest the seal gives it.
fn read_held(expected: &Expected, path: &Path, limit: u64) -> Result<Vec<u8>, MergeError> {
    let bytes = read(path, limit)?;
    let tampered = |reason: &str| MergeError::Tampered { path: path.to_path_buf(), reason: reason.into() };
    match expected.get(path) {
        None => Err(tampered("not among the files its shard's seal holds")),
        Some(d) if *d != crate::digest::sha256_hex(&bytes) => {
            Err(tampered("not the file its shard's seal holds (changed after gcl wrote it)"))
        }
        Some(_) => Ok(bytes),
    }
}

/// [`read_held`] as UTF-8 text.
fn read_held_text(expected: &Expected, path: &Path) -> Result<String, MergeError> {
    String::from_utf8(read_held(expected, path, MAX_INPUT_BYTES)?)
        .map_err(|e| MergeError::Invalid { path: path.to_path_buf(), reason: format!("not UTF-8 text: {e}") })
}

/// What a folder's record allows: its `runs` at most the runs of its slices when the
/// campaign's `--runs` is recorded, and each finding of a run (not the campaign's run 0, which
/// every shard may show, see [`merge_host`]) a run of its own slices: a shard relabelled as
/// another, or with its figures raised, is refused whatever its seal says.
fn within_slices(path: &Path, p: &Provenance, runs: u64, finding_runs: &[u64]) -> Result<(), MergeError> {
    p.check_slices(&path.display().to_string())?;
    let (n, ks) = p.covers();
    if let Some(total) = p.options.get("runs").and_then(|r| r.parse::<u64>().ok()) {
        // Each slice's share of the campaign's runs, checked: `runs` is a figure from anywhere.
        let share = ks
            .iter()
            .map(|&k| total.checked_add(n - k).map_or(total / n + 1, |t| t / n))
            .fold(0u64, u64::saturating_add);
        figure(path, "runs", runs, share)?;
    }
    for &run in finding_runs.iter().filter(|&&r| r != 0) {
        let k = run % n.max(1) + 1;
        if !ks.contains(&k) {
            return Err(MergeError::Tampered {
                path: path.to_path_buf(),
                reason: format!(
                    "it reports run {run}, which is shard {k}/{n}'s, and it holds shard(s) {} of {n}",
                    ks.iter().map(u64::to_string).collect::<Vec<_>>().join(", ")
                ),
            });
        }
    }
    Ok(())
}

/// Whether `path` is a folder of its own: `Ok(false)` when absent, an error when it is a
/// symbolic link (never followed) or a file.
fn real_dir(path: &Path) -> Result<bool, MergeError> {
    match std::fs::symlink_metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(false),
        Err(e) => Err(MergeError::Io { path: path.to_path_buf(), error: e }),
        Ok(m) if m.is_dir() => Ok(true),
        Ok(m) => Err(MergeError::Invalid {
            path: path.to_path_buf(),
            reason: format!(
                "{}, not a folder; not followed",
                if m.file_type().is_symlink() { "a symbolic link" } else { "a file" }
            ),
        }),
    }
}

/// A shard's figure, checked against its limit.
fn figure(path: &Path, field: &str, value: u64, limit: u64) -> Result<u64, MergeError> {
    if value > limit {
        return Err(MergeError::OutOfRange {
            path: path.to_path_buf(),
            field: field.into(),
            value: value.to_string(),
            limit,
        });
    }
    Ok(value)
}

/// A count of a shard, added to the merged count: each and the sum at most [`MAX_COUNT`].
fn add(path: &Path, field: &str, sum: u64, value: u64) -> Result<u64, MergeError> {
    figure(path, field, value, MAX_COUNT)?;
    let total = sum.checked_add(value).filter(|t| *t <= MAX_COUNT).ok_or_else(|| MergeError::OutOfRange {
        path: path.to_path_buf(),
        field: format!("{field} (summed over the shards)"),
        value: format!("{sum} + {value}"),
        limit: MAX_COUNT,
    })?;
    Ok(total)
}

/// [`add`] for a `usize` count.
fn add_usize(path: &Path, field: &str, sum: usize, value: usize) -> Result<usize, MergeError> {
    Ok(add(path, field, sum as u64, value as u64)? as usize)
}

/// Which fuzzer a shard's folder comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// `gcl fuzz host`.
    Host,
    /// `gcl fuzz device`.
    Device,
}

/// Which fuzzer wrote `dir` (its `report` folder and report file taken as they are, never
/// through a symbolic link).
pub fn kind_of(dir: &Path) -> Result<Kind, MergeError> {
    let report = dir.join("report");
    let file = |name: &str| std::fs::symlink_metadata(report.join(name)).is_ok_and(|m| m.is_file());
    if !real_dir(&report)? {
        Err(MergeError::NotAShard(dir.to_path_buf()))
    } else if file("fuzz.json") {
        Ok(Kind::Host)
    } else if file("fuzz-device.json") {
        Ok(Kind::Device)
    } else {
        Err(MergeError::NotAShard(dir.to_path_buf()))
    }
}

/// What a merge left behind: files of a shard it did not copy, and why (a symbolic link, a
/// FIFO, a device).
pub type NotCopied = Vec<String>;

/// The shards of a host campaign, folded.
#[derive(Debug, Clone)]
pub struct HostMerge {
    /// The campaign as one machine would have made it (see the module's notes; `paths` and
    /// `corpus` are sums over the shards: a path two shards took counts twice). Its
    /// provenance names the shards folded.
    pub campaign: Campaign,
    /// The slices folded.
    pub merged: Merged,
    /// The first shard's report (its target, profile and seed are every shard's).
    pub report: RunReport,
    /// Each finding's transcript (its bundle's `transcript.gcl`), by signature.
    pub transcripts: BTreeMap<String, String>,
    /// The bundle folder each finding's bundle comes from, by signature.
    pub bundles: BTreeMap<String, PathBuf>,
    /// The shards' files their seals hold, with their digests.
    expected: Expected,
}

/// A host shard's `fuzz.json`, its seal and every figure checked.
fn load_campaign(dir: &Path, path: &Path, expected: &mut Expected) -> Result<Campaign, MergeError> {
    let c: Campaign = load_sealed(dir, path, HOST, |c: &Campaign| c.provenance.as_ref(), expected)?;
    for (field, v) in [("runs", c.runs), ("minimize_runs", c.minimize_runs), ("pass_runs", c.pass_runs)] {
        figure(path, field, v, MAX_COUNT)?;
    }
    figure(path, "elapsed_ms", c.elapsed_ms, MAX_ELAPSED_MS)?;
    if let Some(p) = &c.pass {
        figure(path, "pass.made", p.made, MAX_COUNT)?;
        figure(path, "pass.complete_ms", p.complete_ms.unwrap_or_default(), MAX_ELAPSED_MS)?;
    }
    figure(path, "corpus", c.corpus as u64, MAX_COUNT)?;
    figure(path, "paths", c.paths as u64, MAX_COUNT)?;
    for f in &c.findings {
        figure(path, "findings[].run", f.run, MAX_COUNT)?;
        figure(path, "findings[].hits", f.hits, MAX_COUNT)?;
        figure(path, "findings[].found_after_ms", f.found_after_ms, MAX_ELAPSED_MS)?;
        figure(path, "findings[].timeout_hang_ms", f.timeout_hang_ms, MAX_ELAPSED_MS)?;
    }
    for states in c.fired_at.values() {
        for n in states.values() {
            figure(path, "fired_at", *n, MAX_COUNT)?;
        }
    }
    if let Some(p) = &c.provenance {
        let runs: Vec<u64> = c.findings.iter().filter(|f| !f.by_calibration).map(|f| f.run).collect();
        within_slices(path, p, c.runs, &runs)?;
    }
    Ok(c)
}

/// Folds the `report/fuzz.json`, `report/report.json` and `bundles/` of host shards. Reads
/// only: nothing is written until the shards are known to be one campaign.
pub fn merge_host(dirs: &[PathBuf]) -> Result<HostMerge, MergeError> {
    let mut shards = Vec::new();
    let mut expected = Expected::new();
    for dir in dirs {
        let path = dir.join("report/fuzz.json");
        let c = load_campaign(dir, &path, &mut expected)?;
        let rpath = dir.join("report/report.json");
        let r: RunReport = if c.provenance.is_some() {
            serde_json::from_str(&read_held_text(&expected, &rpath)?)
                .map_err(|e| MergeError::Invalid { path: rpath.clone(), reason: e.to_string() })?
        } else {
            load(&rpath)?
        };
        shards.push((dir, path, c, r));
    }
    let recorded: Vec<(String, Option<Provenance>)> =
        shards.iter().map(|(d, _, c, _)| (d.display().to_string(), c.provenance.clone())).collect();
    let (provenance, merged_from) = super::shard::plan(&recorded)?;
    let mut merged = Campaign { provenance: Some(provenance), ..Campaign::default() };
    let mut first: Option<RunReport> = None;
    // Signature -> (finding, position in its shard, bundle folder).
    let mut by_sig: BTreeMap<String, (Finding, usize, PathBuf)> = BTreeMap::new();
    for (dir, path, c, r) in shards {
        match &first {
            None => first = Some(r),
            Some(f) => {
                if (&f.target, &f.profile, f.options.seed) != (&r.target, &r.profile, r.options.seed) {
                    return Err(MergeError::Mixed(format!(
                        "{} is `{}`, profile {}, seed {:?}; the first is `{}`, profile {}, seed {:?}",
                        dir.display(),
                        r.target,
                        r.profile,
                        r.options.seed,
                        f.target,
                        f.profile,
                        f.options.seed
                    )));
                }
            }
        }
        merged.runs = add(&path, "runs", merged.runs, c.runs)?;
        merged.reached = add(&path, "reached", merged.reached, c.reached)?;
        // A shard that could not test, or was stopped, leaves the whole campaign so.
        if merged.untested.is_none() {
            merged.untested = c.untested.map(|w| format!("{}: {w}", dir.display()));
        }
        if merged.stopped.is_none() {
            merged.stopped = c.stopped.map(|w| format!("{}: {w}", dir.display()));
        }
        merged.minimize_runs = add(&path, "minimize_runs", merged.minimize_runs, c.minimize_runs)?;
        merged.elapsed_ms = merged.elapsed_ms.max(c.elapsed_ms);
        merged.corpus = add_usize(&path, "corpus", merged.corpus, c.corpus)?;
        merged.paths = add_usize(&path, "paths", merged.paths, c.paths)?;
        // Every shard learns the same kinds of answer and pass from its own run 0.
        if merged.answer_kinds.is_empty() {
            merged.answer_kinds = c.answer_kinds;
            merged.pass_runs = c.pass_runs;
        }
        merged.void_runs = add(&path, "void_runs", merged.void_runs, c.void_runs)?;
        merged.void.extend(c.void.into_iter().take(8usize.saturating_sub(merged.void.len())));
        // Each shard made and missed runs of its own indices: the campaign's are their sums.
        if let Some(p) = c.pass {
            let m = merged.pass.get_or_insert_with(|| PassAccount { jobs: p.jobs, ..PassAccount::default() });
            m.made = add(&path, "pass.made", m.made, p.made)?;
            m.not_reached.extend(p.not_reached);
            m.complete_ms = m.complete_ms.max(p.complete_ms);
        }
        for (op, states) in c.fired_at {
            let m = merged.fired_at.entry(op).or_default();
            for (st, n) in states {
                let e = m.entry(st).or_default();
                *e = add(&path, "fired_at", *e, n)?;
            }
        }
        for (pos, f) in c.findings.into_iter().enumerate() {
            let bundle = dir.join("bundles").join(dir_name(f.verdict.kind, &f.verdict.signature));
            match by_sig.get_mut(&f.verdict.signature) {
                None => {
                    by_sig.insert(f.verdict.signature.clone(), (f, pos, bundle));
                }
                // The campaign's run 0 (its run without misbehaviour, its calibration) is made
                // by every shard: one finding, its repeated run 0 counted once.
                Some((have, _, _)) if have.run == 0 && f.run == 0 => {
                    let hits = add(&path, "findings[].hits", have.hits, f.hits.saturating_sub(1))?;
                    have.hits = hits;
                }
                Some((have, _, _)) if have.run == f.run => {
                    return Err(MergeError::Mixed(format!(
                        "run {} is in two folders ({}, and one before it): the same shard given twice?",
                        f.run,
                        dir.display()
                    )));
                }
                Some((have, have_pos, have_bundle)) => {
                    let hits = add(&path, "findings[].hits", have.hits, f.hits)?;
                    if f.run < have.run {
                        *have = f;
                        *have_pos = pos;
                        *have_bundle = bundle;
                    }
                    have.hits = hits;
                }
            }
        }
    }
    let report = first.ok_or_else(|| MergeError::Mixed("no folder given".into()))?;
    let mut findings: Vec<(Finding, usize, PathBuf)> = by_sig.into_values().collect();
    // One machine takes runs in index order, and a run's findings in the order judged.
    findings.sort_by_key(|(f, pos, _)| (f.run, *pos));
    let mut transcripts = BTreeMap::new();
    let mut bundles = BTreeMap::new();
    for (f, _, bundle) in &mut findings {
        if let Some(parent) = bundle.parent() {
            real_dir(parent)?;
        }
        if !real_dir(bundle)? {
            return Err(MergeError::Invalid { path: bundle.clone(), reason: "the finding's bundle is missing".into() });
        }
        transcripts.insert(f.verdict.signature.clone(), read_held_text(&expected, &bundle.join("transcript.gcl"))?);
        f.stderr = read_held_text(&expected, &bundle.join("stderr.txt"))?;
        bundles.insert(f.verdict.signature.clone(), bundle.clone());
    }
    merged.findings = findings.into_iter().map(|(f, _, _)| f).collect();
    Ok(HostMerge { campaign: merged, merged: merged_from, report, transcripts, bundles, expected })
}

/// Copies each finding's bundle into `out/<name>`, its `finding.json` with the merged hit
/// count; returns the folders, and the files not copied (anything but a regular file).
pub fn write_host_bundles(m: &HostMerge, out: &Path) -> Result<(Vec<PathBuf>, NotCopied), MergeError> {
    let mut written = Vec::new();
    let mut skipped = Vec::new();
    for f in &m.campaign.findings {
        let Some(src) = m.bundles.get(&f.verdict.signature) else { continue };
        let dst = out.join(dir_name(f.verdict.kind, &f.verdict.signature));
        std::fs::create_dir_all(&dst).map_err(io(&dst))?;
        let mut entries: Vec<std::fs::DirEntry> =
            std::fs::read_dir(src).map_err(io(src))?.collect::<Result<_, _>>().map_err(io(src))?;
        entries.sort_by_key(std::fs::DirEntry::file_name);
        for entry in entries {
            let p = entry.path();
            // The entry as it is: a link is a link, never what it points to.
            let ty = entry.file_type().map_err(io(&p))?;
            if !ty.is_file() {
                skipped.push(format!("{}: {}", p.display(), kind_name(&ty)));
                continue;
            }
            if !m.expected.contains_key(&p) {
                skipped.push(format!("{}: not among the files its shard's seal holds, not copied", p.display()));
                continue;
            }
            let bytes = if entry.file_name() == "finding.json" {
                let mut info: BundleInfo = serde_json::from_slice(&read_held(&m.expected, &p, MAX_INPUT_BYTES)?)
                    .map_err(|e| MergeError::Invalid { path: p.clone(), reason: e.to_string() })?;
                info.hits = f.hits;
                let mut b = serde_json::to_vec_pretty(&info).unwrap_or_default();
                b.push(b'\n');
                b
            } else {
                read_held(&m.expected, &p, MAX_INPUT_BYTES)?
            };
            let to = dst.join(entry.file_name());
            crate::report::write_atomic(&to, &bytes).map_err(io(&to))?;
        }
        written.push(dst);
    }
    Ok((written, skipped))
}

/// What a folder entry that is not a regular file is, for the list of what was not copied.
fn kind_name(ty: &std::fs::FileType) -> String {
    let what = if ty.is_symlink() { "a symbolic link" } else { gcl_host::files::kind_of(ty) };
    format!("{what}, not copied")
}

/// A device shard's `fuzz-device.json`, its seal and every figure checked.
fn load_device_report(dir: &Path, path: &Path, expected: &mut Expected) -> Result<FuzzReport, MergeError> {
    let r: FuzzReport = load_sealed(dir, path, DEVICE, |r: &FuzzReport| r.provenance.as_ref(), expected)?;
    for (field, v) in [
        ("runs", r.runs),
        ("dropped", r.dropped),
        ("eeprom_writes", r.eeprom_writes),
        ("wire_bytes", r.wire_bytes),
        ("corpus", r.corpus as u64),
        ("jobs", r.jobs as u64),
    ] {
        figure(path, field, v, MAX_COUNT)?;
    }
    figure(path, "duration_ms", r.duration_ms, MAX_ELAPSED_MS)?;
    if !r.cases_per_second.is_finite() || !(0.0..=MAX_COUNT as f64).contains(&r.cases_per_second) {
        return Err(MergeError::OutOfRange {
            path: path.to_path_buf(),
            field: "cases_per_second".into(),
            value: r.cases_per_second.to_string(),
            limit: MAX_COUNT,
        });
    }
    for f in &r.findings {
        figure(path, "findings[].run", f.run, MAX_COUNT)?;
        figure(
            path,
            "findings[].found_after_ms",
            f.found_after.as_millis().min(u128::from(u64::MAX)) as u64,
            MAX_ELAPSED_MS,
        )?;
    }
    for row in &r.coverage {
        figure(path, "coverage[].reached", row.reached as u64, MAX_COUNT)?;
    }
    if let Some(p) = &r.provenance {
        within_slices(path, p, r.runs, &[])?;
    }
    Ok(r)
}

/// The shards of a device campaign, checked and folded in memory: write them with
/// [`write_device`].
#[derive(Debug, Clone)]
pub struct DeviceMerge {
    /// The merged report (its provenance names the shards folded; its findings' paths are
    /// still the shards' files).
    pub report: FuzzReport,
    /// The slices folded.
    pub merged: Merged,
    /// The shards' files their seals hold, with their digests.
    expected: Expected,
}

/// Folds the `report/fuzz-device.json` of device shards. Reads only.
pub fn merge_device(dirs: &[PathBuf]) -> Result<DeviceMerge, MergeError> {
    let mut shards = Vec::new();
    let mut expected = Expected::new();
    for dir in dirs {
        let path = dir.join("report/fuzz-device.json");
        let r = load_device_report(dir, &path, &mut expected)?;
        shards.push((dir, path, r));
    }
    let recorded: Vec<(String, Option<Provenance>)> =
        shards.iter().map(|(d, _, r)| (d.display().to_string(), r.provenance.clone())).collect();
    let (provenance, merged_from) = super::shard::plan(&recorded)?;
    let mut merged: Option<FuzzReport> = None;
    let mut seen = BTreeSet::new();
    for (dir, path, r) in shards {
        let m = match &mut merged {
            None => {
                merged.insert(FuzzReport { findings: Vec::new(), provenance: Some(provenance.clone()), ..r.clone() })
            }
            Some(m) => {
                if (&m.target, &m.profile, &m.faults, m.seed, &m.refused)
                    != (&r.target, &r.profile, &r.faults, r.seed, &r.refused)
                {
                    return Err(MergeError::Mixed(format!(
                        "{} fuzzed `{}` (profile {}, seed {}); the first fuzzed `{}` (profile {}, seed {})",
                        dir.display(),
                        r.target,
                        r.profile,
                        r.seed,
                        m.target,
                        m.profile,
                        m.seed
                    )));
                }
                // `jobs` is each shard's (the same for every shard of a campaign), not a sum:
                // nobody ran the campaign with their total.
                m.duration_ms = m.duration_ms.max(r.duration_ms);
                m.runs = add(&path, "runs", m.runs, r.runs)?;
                m.dropped = add(&path, "dropped", m.dropped, r.dropped)?;
                // A shard that ended early leaves the whole campaign so (the first says why).
                if m.stopped.is_none() {
                    m.stopped = r.stopped.clone();
                }
                m.cases_per_second += r.cases_per_second;
                m.eeprom_writes = add(&path, "eeprom_writes", m.eeprom_writes, r.eeprom_writes)?;
                m.wire_bytes = add(&path, "wire_bytes", m.wire_bytes, r.wire_bytes)?;
                m.corpus = add_usize(&path, "corpus", m.corpus, r.corpus)?;
                for row in &mut m.coverage {
                    let Some(other) = r.coverage.iter().find(|o| o.category == row.category) else { continue };
                    let theirs: BTreeSet<&String> = other.missing.iter().collect();
                    row.missing.retain(|x| theirs.contains(x));
                    row.reached = match row.total {
                        Some(t) => t.saturating_sub(row.missing.len()),
                        // An open category: each shard counts what it reached; the union is at
                        // least the larger count.
                        None => row.reached.max(other.reached),
                    };
                }
                m
            }
        };
        for mut f in r.findings {
            if !seen.insert(f.signature.clone()) {
                continue;
            }
            // The shard's own file (a plain name inside its findings/), whatever the path says.
            if let Some(src) = &f.path {
                let name = src.file_name().map(PathBuf::from).unwrap_or_else(|| PathBuf::from("finding.gcl"));
                f.path = Some(dir.join("findings").join(name));
            }
            m.findings.push(f);
        }
    }
    let report = merged.ok_or_else(|| MergeError::Mixed("no folder given".into()))?;
    Ok(DeviceMerge { report, merged: merged_from, expected })
}

/// Writes a device merge into `out` (aside, until [`Out::commit`]): each finding's transcript
/// into `findings` (its path in the report then names the copy as it will be, in the merged
/// folder), then the reports, sealed, into `report`. `corpus` is the merged corpus's size when
/// the corpora were merged (else the shards' sizes add up). Returns the report as written and
/// the files not copied.
pub fn write_device(m: &DeviceMerge, out: &Out, corpus: Option<usize>) -> Result<(FuzzReport, NotCopied), MergeError> {
    let mut report = m.report.clone();
    let mut skipped = Vec::new();
    let findings_out = out.stage.join("findings");
    for f in &mut report.findings {
        let Some(from) = f.path.clone() else { continue };
        if let Some(parent) = from.parent() {
            real_dir(parent)?;
        }
        match std::fs::symlink_metadata(&from) {
            Ok(meta) if !meta.is_file() => {
                skipped.push(format!("{}: {}", from.display(), kind_name(&meta.file_type())));
                f.path = None;
                continue;
            }
            _ => {}
        }
        let text = read_held_text(&m.expected, &from)?;
        // Two shards name their own findings alike (`fuzz-fget-order.gcl` for two orders):
        // each keeps a file of its own, never written over by the other.
        let stem = from.file_stem().and_then(|s| s.to_str()).unwrap_or("finding");
        let to =
            crate::outputs::write_unique(&findings_out, stem, "gcl", text.as_bytes()).map_err(io(&findings_out))?;
        f.path = to.file_name().map(|n| out.out.join("findings").join(n));
    }
    if let Some(n) = corpus {
        report.corpus = n;
    }
    seal_device(&mut report, &findings_out)?;
    let dir = out.stage.join("report");
    std::fs::create_dir_all(&dir).map_err(io(&dir))?;
    super::device::report::write_all(&dir, &report)
        .map_err(|e| MergeError::Invalid { path: dir.clone(), reason: e.to_string() })?;
    Ok((report, skipped))
}

/// Copies the corpus entries of every `DIR/corpus` into `out`, each under its content hash;
/// returns how many entries the merged corpus has, how many copies were dropped as
/// duplicates, and the files not taken (not a regular file, or not a corpus entry).
pub fn merge_corpora(dirs: &[PathBuf], out: &Path) -> Result<(usize, usize, NotCopied), MergeError> {
    let mut names = BTreeSet::new();
    let mut dups = 0;
    let mut skipped = Vec::new();
    for dir in dirs {
        let from = dir.join("corpus");
        if !real_dir(&from)? {
            continue;
        }
        let mut entries: Vec<std::fs::DirEntry> =
            std::fs::read_dir(&from).map_err(io(&from))?.collect::<Result<_, _>>().map_err(io(&from))?;
        entries.sort_by_key(std::fs::DirEntry::file_name);
        for entry in entries {
            let p = entry.path();
            if p.extension().is_none_or(|x| x != "json") {
                continue;
            }
            let ty = entry.file_type().map_err(io(&p))?;
            if !ty.is_file() {
                skipped.push(format!("{}: {}", p.display(), kind_name(&ty)));
                continue;
            }
            let parsed = read(&p, MAX_CORPUS_ENTRY).and_then(|b| {
                serde_json::from_slice::<Vec<HostAction>>(&b)
                    .map_err(|e| MergeError::Invalid { path: p.clone(), reason: e.to_string() })
            });
            let actions = match parsed {
                Ok(a) => a,
                Err(e) => {
                    skipped.push(format!("{e}: not a corpus entry, not copied"));
                    continue;
                }
            };
            let name = corpus_name(&actions);
            if !names.insert(name.clone()) {
                dups += 1;
                continue;
            }
            let to = out.join(&name);
            let json = serde_json::to_vec_pretty(&actions).unwrap_or_default();
            crate::report::write_atomic(&to, &json).map_err(io(&to))?;
        }
    }
    Ok((names.len(), dups, skipped))
}

/// The files of a host campaign's folders its seal holds: `report/report.json` (in
/// `report_dir`) and every regular file of each finding's bundle (in `bundles`).
fn host_holds(c: &Campaign, report_dir: &Path, bundles: &Path) -> Result<BTreeMap<String, String>, MergeError> {
    let mut files = vec![("report/report.json".to_string(), report_dir.join("report.json"))];
    for f in &c.findings {
        let name = dir_name(f.verdict.kind, &f.verdict.signature);
        let dir = bundles.join(&name);
        let Ok(entries) = std::fs::read_dir(&dir) else { continue };
        for e in entries {
            let e = e.map_err(io(&dir))?;
            if e.file_type().is_ok_and(|t| t.is_file()) {
                files.push((format!("bundles/{name}/{}", e.file_name().to_string_lossy()), e.path()));
            }
        }
    }
    super::shard::holds(files.iter().map(|(n, p)| (n.clone(), p.as_path())))
        .map_err(|e| MergeError::Io { path: report_dir.to_path_buf(), error: e })
}

/// Seals a host campaign before its `fuzz.json` is written (`gcl fuzz host --report`, a
/// merge): its campaign id, the files it holds (its `report.json` in `report_dir`, its
/// bundles in `bundles`) and its digest, so that a merge takes it only as written.
pub fn seal_host(c: &mut Campaign, report_dir: &Path, bundles: &Path) -> Result<(), MergeError> {
    let holds = host_holds(c, report_dir, bundles)?;
    super::shard::seal(c, |c: &mut Campaign| c.provenance.as_mut(), HOST, holds)
        .map_err(|e| MergeError::Invalid { path: report_dir.join("fuzz.json"), reason: e.to_string() })
}

/// Seals a device campaign's report before it is written (`gcl fuzz device`, a merge): its
/// campaign id, the findings' transcripts it holds (each finding's file, by its name, in
/// `findings`) and its digest.
pub fn seal_device(r: &mut FuzzReport, findings: &Path) -> Result<(), MergeError> {
    let files: Vec<(String, PathBuf)> = r
        .findings
        .iter()
        .filter_map(|f| f.path.as_ref()?.file_name())
        .map(|n| (format!("findings/{}", n.to_string_lossy()), findings.join(n)))
        .collect();
    let holds = super::shard::holds(files.iter().map(|(n, p)| (n.clone(), p.as_path())))
        .map_err(|e| MergeError::Io { path: findings.to_path_buf(), error: e })?;
    super::shard::seal(r, |r: &mut FuzzReport| r.provenance.as_mut(), DEVICE, holds)
        .map_err(|e| MergeError::Invalid { path: findings.to_path_buf(), reason: e.to_string() })
}

/// The folder inside `--out` a merge fills before it puts the merge in place ([`Out`]).
pub const STAGE: &str = ".gcl-merge-new";

/// The merged folder of a merge under way: `out`, held for the whole merge, and the folder
/// beside its parts (`out/.gcl-merge-new`) the merge is written into. Nothing of `out` is
/// replaced until [`Out::commit`], after every input was read: an input that is `out` itself
/// (an earlier merge merged again into its own folder), or lies inside it, is read whole
/// before anything of it goes.
#[derive(Debug)]
pub struct Out {
    _lock: crate::outputs::OutLock,
    out: PathBuf,
    stage: PathBuf,
}

impl Out {
    /// Where the merge is written until it is put in place.
    pub fn stage(&self) -> &Path {
        &self.stage
    }

    /// Puts the merge in place: the earlier merge's report goes first (no report ever lists
    /// what is gone), each part is replaced by the new one, the new report comes last.
    pub fn commit(self) -> Result<(), MergeError> {
        remove_part(&self.out.join("report"))?;
        for part in MERGED_PARTS.iter().filter(|p| **p != "report").chain(["report"].iter()) {
            let (old, new) = (self.out.join(part), self.stage.join(part));
            remove_part(&old)?;
            if real_dir(&new)? {
                std::fs::rename(&new, &old).map_err(io(&old))?;
            }
        }
        std::fs::remove_dir(&self.stage).map_err(io(&self.stage))?;
        Ok(())
    }
}

/// Removes a part of a merged folder: a link is removed, never what it points to.
fn remove_part(p: &Path) -> Result<(), MergeError> {
    match std::fs::symlink_metadata(p) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(MergeError::Io { path: p.to_path_buf(), error: e }),
        Ok(m) if !m.is_dir() => std::fs::remove_file(p).map_err(io(p)),
        Ok(_) => std::fs::remove_dir_all(p).map_err(io(p)),
    }
}

/// The folders of a merged `--out` that a merge writes (and a re-merge replaces).
pub const MERGED_PARTS: [&str; 4] = ["report", "bundles", "findings", "corpus"];

/// The file that marks a folder as a merge's output, so a later merge may replace it.
pub const MERGE_MARK: &str = ".gcl-merge";

/// Takes `out` for a merge: holds it for as long as the returned [`Out`] lives (a second
/// merge, or a campaign holding `out` or one of its parts, is refused) and makes the folder
/// the merge is written into, beside what an earlier merge wrote, which [`Out::commit`]
/// replaces whole. A folder with files no merge wrote is refused, not touched.
/// An input inside the folder a merge writes aside (`out/.gcl-merge-new`, which a merge killed
/// before its commit may leave, and the next one empties) is refused, never emptied.
pub fn take_out(out: &Path, inputs: &[PathBuf]) -> Result<Out, MergeError> {
    let lock = crate::outputs::OutLock::acquire(out, "fuzz merge --out").map_err(|e| {
        // (in use, or a lock file that is no lock file: the error names the folder or the file)
        if matches!(e.kind(), std::io::ErrorKind::ResourceBusy | std::io::ErrorKind::InvalidInput) {
            MergeError::Busy(e.to_string())
        } else {
            io(out)(e)
        }
    })?;
    for part in MERGED_PARTS {
        let p = out.join(part);
        if let Some(holder) = crate::outputs::held_by(&p) {
            return Err(MergeError::Busy(format!(
                "{} is in use by {holder}; wait for it to end or choose another --out",
                p.display()
            )));
        }
    }
    let ours = std::fs::symlink_metadata(out.join(MERGE_MARK)).is_ok_and(|m| m.is_file());
    let others = std::fs::read_dir(out)
        .map_err(io(out))?
        .filter_map(Result::ok)
        .any(|e| e.file_name() != crate::outputs::LOCK_FILE && e.file_name() != MERGE_MARK);
    if others && !ours {
        return Err(MergeError::NotOurs(out.to_path_buf()));
    }
    // What a merge killed before its commit left (only in a folder a merge marked), unless a
    // folder given to merge is in it.
    let stage = out.join(STAGE);
    if let Ok(inside) = std::fs::canonicalize(&stage) {
        for dir in inputs {
            if std::fs::canonicalize(dir).is_ok_and(|d| d.starts_with(&inside)) {
                return Err(MergeError::Invalid {
                    path: dir.clone(),
                    reason: format!(
                        "inside {}, where a merge into {} is written before it is put in place; move it elsewhere first",
                        stage.display(),
                        out.display()
                    ),
                });
            }
        }
    }
    remove_part(&stage)?;
    let mark = out.join(MERGE_MARK);
    crate::report::write_atomic(
        &mark,
        b"written by gcl fuzz merge: a merge into this folder replaces report/, bundles/, findings/ and corpus/\n",
    )
    .map_err(io(&mark))?;
    std::fs::create_dir(&stage).map_err(io(&stage))?;
    Ok(Out { _lock: lock, out: out.to_path_buf(), stage })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A shard's record bounds what it may hold: its share of `--runs`, runs of its own slices
    /// (run 0 is the campaign's); a `--runs` of u64::MAX is no overflow.
    #[test]
    fn a_record_bounds_its_runs_and_findings() {
        use super::super::shard::Shard;
        let p = Path::new("s2/report/fuzz.json");
        let options = [("runs".to_string(), "12".to_string())].into();
        let two = Provenance::new(Some(Shard { index: 2, count: 3 }), 1, options);
        assert!(within_slices(p, &two, 4, &[0, 1, 4, 10]).is_ok());
        let e = within_slices(p, &two, 5, &[]).unwrap_err().to_string();
        assert!(e.contains("`runs` 5 is out of range (at most 4)"), "{e}");
        let e = within_slices(p, &two, 4, &[3]).unwrap_err().to_string();
        assert!(e.contains("run 3, which is shard 1/3's, and it holds shard(s) 2 of 3"), "{e}");
        let huge = [("runs".to_string(), u64::MAX.to_string())].into();
        let last = Provenance::new(Some(Shard { index: 1, count: 3 }), 1, huge);
        assert!(within_slices(p, &last, u64::MAX / 3, &[]).is_ok());
    }

    #[test]
    fn counts_add_up_checked_and_refuse_by_name() {
        let p = Path::new("shard-2/report/fuzz.json");
        assert_eq!(add(p, "runs", 15, 15).unwrap(), 30);
        let e = add(p, "runs", MAX_COUNT, 1).unwrap_err().to_string();
        assert!(e.contains("`runs (summed over the shards)`") && e.contains("shard-2/report/fuzz.json"), "{e}");
        let e = add(p, "runs", 0, u64::MAX).unwrap_err().to_string();
        assert!(e.contains("`runs` 18446744073709551615 is out of range"), "{e}");
        let e = figure(p, "elapsed_ms", (1 << 63) - 1, MAX_ELAPSED_MS).unwrap_err().to_string();
        assert!(e.contains("`elapsed_ms` 9223372036854775807"), "{e}");
    }
}
