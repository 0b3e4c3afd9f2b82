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
//! Findings are deduplicated by signature: the one first found (the lowest run index of the
//! campaign, for the host fuzzer, whose run indices are the campaign's) stands, with the hits
//! of every shard added up; bundles and transcripts come from the shard whose finding stands.
//! Corpus entries are deduplicated by content hash (an entry whose name is not its hash is
//! stored under its hash). Counts add up; wall times are the longest shard's.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use super::device::report::FuzzReport;
use super::device::{corpus_name, load_corpus};
use super::host::bundle::{BundleInfo, dir_name};
use super::host::{Campaign, Finding};
use crate::report::RunReport;

/// Why shards cannot be merged.
#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    /// A file or folder cannot be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A file is not what a shard writes.
    #[error("{path}: {reason}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// Why.
        reason: String,
    },
    /// The folders are not shards of one campaign.
    #[error("not shards of one campaign: {0}")]
    Mixed(String),
    /// A folder holds neither a host nor a device campaign's report.
    #[error("{0}: no report/fuzz.json (gcl fuzz host) or report/fuzz-device.json (gcl fuzz device) in it")]
    NotAShard(PathBuf),
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> MergeError + '_ {
    move |source| MergeError::Io { path: path.to_path_buf(), source }
}

fn load<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, MergeError> {
    let text = gcl_host::files::read_input_text(path).map_err(io(path))?;
    serde_json::from_str(&text).map_err(|e| MergeError::Invalid { path: path.to_path_buf(), reason: e.to_string() })
}

/// Which fuzzer a shard's folder comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// `gcl fuzz host`.
    Host,
    /// `gcl fuzz device`.
    Device,
}

/// Which fuzzer wrote `dir`.
pub fn kind_of(dir: &Path) -> Result<Kind, MergeError> {
    if dir.join("report/fuzz.json").is_file() {
        Ok(Kind::Host)
    } else if dir.join("report/fuzz-device.json").is_file() {
        Ok(Kind::Device)
    } else {
        Err(MergeError::NotAShard(dir.to_path_buf()))
    }
}

/// The shards of a host campaign, folded.
#[derive(Debug, Clone)]
pub struct HostMerge {
    /// The campaign as one machine would have made it (see the module's notes; `paths` and
    /// `corpus` are sums over the shards: a path two shards took counts twice).
    pub campaign: Campaign,
    /// The first shard's report (its target, profile and seed are every shard's).
    pub report: RunReport,
    /// Each finding's transcript (its bundle's `transcript.gcl`), by signature.
    pub transcripts: BTreeMap<String, String>,
    /// The bundle folder each finding's bundle comes from, by signature.
    pub bundles: BTreeMap<String, PathBuf>,
}

/// Folds the `report/fuzz.json`, `report/report.json` and `bundles/` of host shards.
pub fn merge_host(dirs: &[PathBuf]) -> Result<HostMerge, MergeError> {
    let mut merged = Campaign::default();
    let mut first: Option<RunReport> = None;
    // Signature -> (finding, position in its shard, bundle folder).
    let mut by_sig: BTreeMap<String, (Finding, usize, PathBuf)> = BTreeMap::new();
    for dir in dirs {
        let c: Campaign = load(&dir.join("report/fuzz.json"))?;
        let r: RunReport = load(&dir.join("report/report.json"))?;
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
        merged.runs += c.runs;
        merged.reached += c.reached;
        // A shard that could not test, or was stopped, leaves the whole campaign so.
        if merged.untested.is_none() {
            merged.untested = c.untested.map(|w| format!("{}: {w}", dir.display()));
        }
        if merged.stopped.is_none() {
            merged.stopped = c.stopped.map(|w| format!("{}: {w}", dir.display()));
        }
        merged.minimize_runs += c.minimize_runs;
        merged.elapsed_ms = merged.elapsed_ms.max(c.elapsed_ms);
        merged.corpus += c.corpus;
        merged.paths += c.paths;
        // Every shard learns the same kinds of answer and pass from its own run 0.
        if merged.answer_kinds.is_empty() {
            merged.answer_kinds = c.answer_kinds;
            merged.pass_runs = c.pass_runs;
        }
        for (op, states) in c.fired_at {
            let m = merged.fired_at.entry(op).or_default();
            for (st, n) in states {
                *m.entry(st).or_default() += n;
            }
        }
        for (pos, f) in c.findings.into_iter().enumerate() {
            let bundle = dir.join("bundles").join(dir_name(f.verdict.kind, &f.verdict.signature));
            match by_sig.get_mut(&f.verdict.signature) {
                None => {
                    by_sig.insert(f.verdict.signature.clone(), (f, pos, bundle));
                }
                Some((have, _, _)) if have.run == f.run => {
                    return Err(MergeError::Mixed(format!(
                        "run {} is in two folders ({}, and one before it): the same shard given twice?",
                        f.run,
                        dir.display()
                    )));
                }
                Some((have, have_pos, have_bundle)) => {
                    let hits = have.hits + f.hits;
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
        let t = bundle.join("transcript.gcl");
        transcripts.insert(f.verdict.signature.clone(), gcl_host::files::read_input_text(&t).map_err(io(&t))?);
        let e = bundle.join("stderr.txt");
        f.stderr = gcl_host::files::read_input_text(&e).map_err(io(&e))?;
        bundles.insert(f.verdict.signature.clone(), bundle.clone());
    }
    merged.findings = findings.into_iter().map(|(f, _, _)| f).collect();
    Ok(HostMerge { campaign: merged, report, transcripts, bundles })
}

/// Copies each finding's bundle into `out/<name>`, its `finding.json` with the merged hit
/// count; returns the folders.
pub fn write_host_bundles(m: &HostMerge, out: &Path) -> Result<Vec<PathBuf>, MergeError> {
    let mut written = Vec::new();
    for f in &m.campaign.findings {
        let Some(src) = m.bundles.get(&f.verdict.signature) else { continue };
        let dst = out.join(dir_name(f.verdict.kind, &f.verdict.signature));
        std::fs::create_dir_all(&dst).map_err(io(&dst))?;
        for entry in std::fs::read_dir(src).map_err(io(src))? {
            let p = entry.map_err(io(src))?.path();
            let Some(name) = p.file_name() else { continue };
            if !p.is_file() {
                continue;
            }
            let bytes = if name == "finding.json" {
                let mut info: BundleInfo = load(&p)?;
                info.hits = f.hits;
                let mut b = serde_json::to_vec_pretty(&info).unwrap_or_default();
                b.push(b'\n');
                b
            } else {
                std::fs::read(&p).map_err(io(&p))?
            };
            let to = dst.join(name);
            crate::report::write_atomic(&to, &bytes).map_err(io(&to))?;
        }
        written.push(dst);
    }
    Ok(written)
}

/// Folds the `report/fuzz-device.json` and `findings/` of device shards; writes the merged
/// reports into `out/report` and the findings' transcripts into `out/findings`. `corpus` is
/// the merged corpus's size when the corpora were merged (else the shards' sizes add up).
pub fn merge_device(dirs: &[PathBuf], out: &Path, corpus: Option<usize>) -> Result<FuzzReport, MergeError> {
    let mut merged: Option<FuzzReport> = None;
    let mut seen = BTreeSet::new();
    let findings_out = out.join("findings");
    for dir in dirs {
        let path = dir.join("report/fuzz-device.json");
        let r: FuzzReport = load(&path)?;
        let m = match &mut merged {
            None => merged.insert(FuzzReport { findings: Vec::new(), ..r.clone() }),
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
                m.jobs += r.jobs;
                m.duration_ms = m.duration_ms.max(r.duration_ms);
                m.runs += r.runs;
                m.dropped += r.dropped;
                // A shard that ended early leaves the whole campaign so (the first says why).
                if m.stopped.is_none() {
                    m.stopped = r.stopped.clone();
                }
                m.cases_per_second += r.cases_per_second;
                m.eeprom_writes += r.eeprom_writes;
                m.wire_bytes += r.wire_bytes;
                m.corpus += r.corpus;
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
            if let Some(src) = &f.path {
                let name = src.file_name().map(PathBuf::from).unwrap_or_else(|| PathBuf::from("finding.gcl"));
                let from = dir.join("findings").join(&name);
                let to = findings_out.join(&name);
                std::fs::create_dir_all(&findings_out).map_err(io(&findings_out))?;
                let text = gcl_host::files::read_input_text(&from).map_err(io(&from))?;
                crate::report::write_atomic(&to, text.as_bytes()).map_err(io(&to))?;
                f.path = Some(to);
            }
            m.findings.push(f);
        }
    }
    let mut report = merged.ok_or_else(|| MergeError::Mixed("no folder given".into()))?;
    if let Some(n) = corpus {
        report.corpus = n;
    }
    let dir = out.join("report");
    std::fs::create_dir_all(&dir).map_err(io(&dir))?;
    super::device::report::write_all(&dir, &report)
        .map_err(|e| MergeError::Invalid { path: dir.clone(), reason: e.to_string() })?;
    Ok(report)
}

/// Copies the corpus entries of every `DIR/corpus` into `out`, each under its content hash;
/// returns how many entries the merged corpus has and how many copies were dropped as
/// duplicates.
pub fn merge_corpora(dirs: &[PathBuf], out: &Path) -> Result<(usize, usize), MergeError> {
    let mut names = BTreeSet::new();
    let mut dups = 0;
    for dir in dirs {
        let from = dir.join("corpus");
        if !from.is_dir() {
            continue;
        }
        let (entries, _bad) =
            load_corpus(&from).map_err(|e| MergeError::Invalid { path: from.clone(), reason: e.to_string() })?;
        for actions in entries {
            let name = corpus_name(&actions);
            if !names.insert(name.clone()) {
                dups += 1;
                continue;
            }
            std::fs::create_dir_all(out).map_err(io(out))?;
            let to = out.join(&name);
            let json = serde_json::to_vec_pretty(&actions).unwrap_or_default();
            crate::report::write_atomic(&to, &json).map_err(io(&to))?;
        }
    }
    Ok((names.len(), dups))
}
