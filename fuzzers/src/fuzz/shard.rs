//! `--shard K/N`: one of N disjoint, deterministic slices of a campaign, so that a long
//! campaign can be spread over a CI system's own job matrix (and folded back together by
//! [`crate::fuzz::merge`]). No scheduler: each machine works out its slice from K and N.
//!
//! `gcl fuzz host` slices run indices: shard K runs indices K-1, K-1+N, K-1+2N, ...
//! `gcl fuzz device` slices generator streams: its worker w draws from stream K-1+w·N, the
//! stream worker K-1+w·N of a one-machine campaign with N times the workers would draw from.
//!
//! A shard's report is sealed ([`seal`]): its [`Provenance`] carries the campaign's id
//! ([`campaign_id`], from the fuzzer, seed, options and N, so the machines agree on it without
//! talking), the files of its folder a merge reads with their SHA-256 (`holds`), and the digest
//! of the report itself ([`report_digest`]). Old shards without a seal are refused by a merge:
//! a warning would let anyone strip the seal of an edited shard to have it merged.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::report::merged::Merged;

/// Shard `index` (1-based) of `count`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Shard {
    /// K, from 1 to N.
    pub index: u64,
    /// N, at least 1.
    pub count: u64,
}

impl Shard {
    /// The campaign's index of this shard's `t`-th item (0-based).
    pub fn global(self, t: u64) -> u64 {
        t.saturating_mul(self.count).saturating_add(self.index - 1)
    }

    /// Whether campaign index `i` is this shard's.
    pub fn owns(self, i: u64) -> bool {
        i % self.count == self.index - 1
    }

    /// How many of the campaign's indices `0..total` are this shard's.
    pub fn share(self, total: u64) -> u64 {
        // The indices index-1, index-1+count, ... below total; computed without a sum that
        // overflows (`--shard 1/18446744073709551615` is a shard like any other).
        if total < self.index { 0 } else { (total - self.index) / self.count + 1 }
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl FromStr for Shard {
    type Err = String;

    fn from_str(s: &str) -> Result<Shard, String> {
        let bad = || format!("`{s}`: write a shard as K/N, with 1 <= K <= N (1/4 is the first of four)");
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count): (u64, u64) = (k.trim().parse().map_err(|_| bad())?, n.trim().parse().map_err(|_| bad())?);
        if count == 0 || index == 0 || index > count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

/// What makes a shard part of a campaign, as `fuzz.json` (`gcl fuzz host`) and
/// `fuzz-device.json` record it: its slice, the seed and every option that changed what ran.
/// `gcl fuzz merge` folds only shards of one campaign (the same seed and options), each slice
/// once, and says which slices it folded.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Provenance {
    /// `--shard K/N`; absent for the whole campaign (not sharded, or merged).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<Shard>,
    /// The seed.
    pub seed: u64,
    /// Every option that changed what ran or how it was judged, by its flag without the dashes
    /// (`ops`, `runs`, `duration`, `profile`, `skip-decision`, `baseline`...), as its effective
    /// value (a default included), so two shards of one campaign have the same map.
    pub options: BTreeMap<String, String>,
    /// Set on a merged folder: the slices it holds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub merged: Option<Merged>,
    /// The campaign's id ([`campaign_id`]: its fuzzer, seed, options and N), the same in every
    /// shard of it and in their merges.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub campaign: Option<String>,
    /// The files of the folder a merge reads or copies (`report/report.json`,
    /// `bundles/NAME/FILE`, `findings/FILE`), each with its SHA-256.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub holds: BTreeMap<String, String>,
    /// SHA-256 of the report it is written in, this field left out ([`report_digest`]): with
    /// `holds`, a digest of everything the folder holds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub digest: Option<String>,
}

impl Provenance {
    /// N and the slices this folder holds: its shard, a merged folder's shards, or the whole
    /// campaign (1 of 1).
    pub fn covers(&self) -> (u64, Vec<u64>) {
        match (&self.merged, self.shard) {
            (Some(m), _) => (m.count, m.shards.clone()),
            (None, Some(s)) => (s.count, vec![s.index]),
            (None, None) => (1, vec![1]),
        }
    }

    /// A shard's or a merge's record, before it is sealed ([`seal`]).
    pub fn new(shard: Option<Shard>, seed: u64, options: BTreeMap<String, String>) -> Provenance {
        Provenance { shard, seed, options, merged: None, campaign: None, holds: BTreeMap::new(), digest: None }
    }

    /// Refuses a record of a slice no campaign has (K outside 1..=N, N = 0): a report is data
    /// from anywhere, and its slices are checked before anything counts on them. `folder`
    /// names it in the error.
    pub fn check_slices(&self, folder: &str) -> Result<(), ShardSetError> {
        let (n, ks) = self.covers();
        match ks.iter().find(|&&k| k == 0 || k > n) {
            Some(&k) => Err(ShardSetError::NoSuchSlice { folder: folder.to_string(), index: k, count: n }),
            None => Ok(()),
        }
    }

    /// How `other` differs from this one as a campaign (the seed and the options; not the
    /// slice): one entry per difference, the other's value first, `--ops: err-bits=1 against
    /// every operator`.
    pub fn differences(&self, other: &Provenance) -> Vec<String> {
        let mut out = Vec::new();
        if self.seed != other.seed {
            out.push(format!("--seed: {} against {}", other.seed, self.seed));
        }
        let keys: BTreeSet<&String> = self.options.keys().chain(other.options.keys()).collect();
        for k in keys {
            let (mine, theirs) = (self.options.get(k), other.options.get(k));
            if mine != theirs {
                let show = |v: Option<&String>| v.map_or("not recorded".to_string(), String::clone);
                out.push(format!("--{k}: {} against {}", show(theirs), show(mine)));
            }
        }
        out
    }
}

/// Why a set of folders is not the shards of one campaign.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ShardSetError {
    /// A folder records no shard (written before shards were recorded).
    #[error(
        "{0}: its report records no shard, seed or options (written by an older gcl?), so nothing says which campaign it belongs to"
    )]
    Unrecorded(String),
    /// A folder records a slice no campaign has (K outside 1..=N, or N = 0).
    #[error("{folder}: its report records shard {index} of {count}, which no campaign has (K/N runs from 1/N to N/N)")]
    NoSuchSlice {
        /// The folder.
        folder: String,
        /// K as recorded.
        index: u64,
        /// N as recorded.
        count: u64,
    },
    /// Two folders are of different campaigns.
    #[error("not shards of one campaign: {folder} differs from {first} ({folder}'s against {first}'s): {}", differences.join("; "))]
    Mixed {
        /// The folder that differs.
        folder: String,
        /// The first folder.
        first: String,
        /// What differs.
        differences: Vec<String>,
    },
    /// Two folders slice the campaign differently.
    #[error("not shards of one campaign: {folder} is one of {theirs} shards, {first} one of {ours}")]
    Count {
        /// The folder that differs.
        folder: String,
        /// Its N.
        theirs: u64,
        /// The first folder.
        first: String,
        /// The first folder's N.
        ours: u64,
    },
    /// A slice is in two folders.
    #[error(
        "shard {index}/{count} is given twice: in {first} and in {second}; merging it twice would count its runs twice"
    )]
    Duplicate {
        /// K.
        index: u64,
        /// N.
        count: u64,
        /// The first folder that holds it.
        first: String,
        /// The second.
        second: String,
    },
}

/// Checks that `folders` (a name for messages, and what each records) are shards of one
/// campaign, each slice at most once; returns the slices they hold together. Missing slices
/// are no error here: [`Merged::missing`] names them.
pub fn plan(folders: &[(String, Option<Provenance>)]) -> Result<(Provenance, Merged), ShardSetError> {
    let mut first: Option<(&str, &Provenance)> = None;
    let mut seen: BTreeMap<u64, &str> = BTreeMap::new();
    let mut count = 0;
    for (name, p) in folders {
        let p = p.as_ref().ok_or_else(|| ShardSetError::Unrecorded(name.clone()))?;
        p.check_slices(name)?;
        let (n, ks) = p.covers();
        match first {
            None => {
                first = Some((name, p));
                count = n;
            }
            Some((fname, f)) => {
                let differences = f.differences(p);
                if !differences.is_empty() {
                    return Err(ShardSetError::Mixed { folder: name.clone(), first: fname.to_string(), differences });
                }
                if n != count {
                    return Err(ShardSetError::Count {
                        folder: name.clone(),
                        theirs: n,
                        first: fname.to_string(),
                        ours: count,
                    });
                }
            }
        }
        for k in ks {
            if let Some(other) = seen.insert(k, name) {
                return Err(ShardSetError::Duplicate {
                    index: k,
                    count,
                    first: other.to_string(),
                    second: name.clone(),
                });
            }
        }
    }
    let (_, f) = first.ok_or_else(|| ShardSetError::Unrecorded("(no folder given)".into()))?;
    let merged = Merged { count, shards: seen.into_keys().collect() };
    let p =
        Provenance { shard: None, merged: Some(merged.clone()), ..Provenance::new(None, f.seed, f.options.clone()) };
    Ok((p, merged))
}

/// The id of a campaign: SHA-256 of its fuzzer (`fuzz host`, `fuzz device`), seed, options and
/// number of shards, so that the machines of one campaign agree on it without talking to each
/// other, and a shard whose record was edited in part no longer matches its own id.
pub fn campaign_id(fuzzer: &str, p: &Provenance) -> String {
    let what = serde_json::json!({
        "fuzzer": fuzzer,
        "seed": p.seed,
        "options": p.options,
        "shards": p.covers().0,
    });
    crate::digest::sha256_hex(what.to_string().as_bytes())
}

/// The digest of a report's JSON text as its provenance records it: SHA-256 of the JSON
/// parsed and printed compactly again, `provenance.digest` left out (so the digest can be
/// written into the file it covers). Every other field counts, an unknown one included.
pub fn report_digest(json: &[u8]) -> Result<String, serde_json::Error> {
    let mut v: serde_json::Value = serde_json::from_slice(json)?;
    if let Some(p) = v.get_mut("provenance").and_then(serde_json::Value::as_object_mut) {
        p.remove("digest");
    }
    Ok(crate::digest::sha256_hex(&serde_json::to_vec(&v)?))
}

/// Seals `report` (a `fuzz.json` campaign or a `fuzz-device.json` report, its provenance
/// reached through `provenance`) before it is written: its campaign id, the files it holds
/// (path in the folder -> SHA-256, [`holds`]) and the digest of the report as
/// `serde_json::to_string_pretty` prints it. Nothing happens without a provenance.
pub fn seal<T: Serialize>(
    report: &mut T,
    provenance: fn(&mut T) -> Option<&mut Provenance>,
    fuzzer: &str,
    holds: BTreeMap<String, String>,
) -> Result<(), serde_json::Error> {
    let Some(p) = provenance(report) else { return Ok(()) };
    p.campaign = Some(campaign_id(fuzzer, p));
    p.holds = holds;
    p.digest = None;
    let digest = report_digest(serde_json::to_string_pretty(report)?.as_bytes())?;
    if let Some(p) = provenance(report) {
        p.digest = Some(digest);
    }
    Ok(())
}

/// The files of a folder a seal lists: each `(name, path)`, read as a shard's files are read
/// (no link followed, at most [`gcl_host::files::MAX_INPUT_BYTES`]), with its SHA-256.
pub fn holds<'a>(
    files: impl IntoIterator<Item = (String, &'a std::path::Path)>,
) -> std::io::Result<BTreeMap<String, String>> {
    let mut out = BTreeMap::new();
    for (name, path) in files {
        let bytes = gcl_host::files::read_limited_no_follow(path, gcl_host::files::MAX_INPUT_BYTES)
            .map_err(|e| std::io::Error::new(e.kind(), format!("{}: {e}", path.display())))?;
        out.insert(name, crate::digest::sha256_hex(&bytes));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_partition_the_indices() {
        let n = 4;
        let shards: Vec<Shard> = (1..=n).map(|k| format!("{k}/{n}").parse().unwrap()).collect();
        for i in 0..40u64 {
            assert_eq!(shards.iter().filter(|s| s.owns(i)).count(), 1, "index {i}");
        }
        for s in &shards {
            let mine: Vec<u64> = (0..10).map(|t| s.global(t)).collect();
            assert!(mine.iter().all(|&i| s.owns(i)));
            assert_eq!(s.share(10), (0..10).filter(|&i| s.owns(i)).count() as u64);
        }
        assert_eq!(shards.iter().map(|s| s.share(10)).sum::<u64>(), 10);
    }

    /// Issue 39 item 16: the largest shard count and the largest campaign are shards like any
    /// other (`share` overflowed, a panic in debug builds and a wrong share in release).
    #[test]
    fn a_share_never_overflows() {
        let max = u64::MAX;
        let first: Shard = format!("1/{max}").parse().unwrap();
        let last: Shard = format!("{max}/{max}").parse().unwrap();
        assert_eq!(first.share(5), 1);
        assert_eq!(last.share(5), 0);
        assert_eq!(first.share(max), 1);
        assert_eq!(last.share(max), 1);
        let half: Shard = "2/2".parse().unwrap();
        assert_eq!(half.share(max), max / 2);
        assert_eq!("1/2".parse::<Shard>().unwrap().share(max), max / 2 + 1);
        for (k, n, total) in [(1, 3, 0), (3, 3, 2), (3, 3, 3), (2, 3, 7)] {
            let s = Shard { index: k, count: n };
            assert_eq!(s.share(total), (0..total).filter(|&i| s.owns(i)).count() as u64, "{k}/{n} of {total}");
        }
    }

    fn shard(k: u64, n: u64, seed: u64, ops: &str) -> (String, Option<Provenance>) {
        let options = [("ops".to_string(), ops.to_string())].into();
        (format!("shard-{k}"), Some(Provenance::new(Some(Shard { index: k, count: n }), seed, options)))
    }

    #[test]
    fn a_shard_set_is_one_campaign_each_slice_once() {
        let all: Vec<_> = (1..=4).map(|k| shard(k, 4, 5, "every operator")).collect();
        let (p, m) = plan(&all).unwrap();
        assert_eq!(m.describe(), "shards 1–4 of 4");
        assert!(m.complete() && p.shard.is_none() && p.seed == 5);
        // A merged folder holds its slices: merged again with the rest it makes the whole.
        let half = plan(&all[..2]).unwrap().0;
        let (_, again) = plan(&[("half".into(), Some(half)), all[2].clone(), all[3].clone()]).unwrap();
        assert_eq!(again, m);
        // One missing: no error here, but said.
        let (_, m) = plan(&[all[0].clone(), all[2].clone()]).unwrap();
        assert_eq!(m.missing(), vec![2, 4]);
        assert_eq!(m.describe(), "shards 1, 3 of 4 (INCOMPLETE: 2, 4 missing, their runs are not in it)");
        // The same slice twice, another campaign, another slicing, an unrecorded folder.
        let e = plan(&[all[0].clone(), all[0].clone()]).unwrap_err();
        assert!(matches!(e, ShardSetError::Duplicate { index: 1, count: 4, .. }), "{e}");
        let e = plan(&[all[0].clone(), shard(2, 4, 6, "every operator")]).unwrap_err().to_string();
        assert!(e.contains("shard-2 differs from shard-1 (shard-2's against shard-1's): --seed: 6 against 5"), "{e}");
        let e = plan(&[all[0].clone(), shard(2, 4, 5, "truncate=1")]).unwrap_err().to_string();
        assert!(e.contains("--ops: truncate=1 against every operator"), "{e}");
        let e = plan(&[all[0].clone(), shard(2, 3, 5, "every operator")]).unwrap_err().to_string();
        assert!(e.contains("one of 3 shards") && e.contains("one of 4"), "{e}");
        let e = plan(&[all[0].clone(), ("old".into(), None)]).unwrap_err().to_string();
        assert!(e.contains("old: its report records no shard"), "{e}");
        // Slices no campaign has (issue 39, a forged record): K beyond N, N = 0, a merged
        // folder claiming shard 0 or 9 of 3 (it merged as "shards 0–3, 9 of 3", complete).
        for (k, n) in [(7, 3), (1, 0), (0, 3)] {
            let e = plan(&[shard(k, n, 5, "every operator")]).unwrap_err().to_string();
            assert!(e.contains(&format!("records shard {k} of {n}, which no campaign has")), "{e}");
        }
        let mut forged = shard(1, 3, 5, "every operator");
        if let Some(p) = forged.1.as_mut() {
            p.shard = None;
            p.merged = Some(Merged { count: 3, shards: vec![1, 9] });
        }
        let e = plan(&[forged]).unwrap_err().to_string();
        assert!(e.contains("records shard 9 of 3"), "{e}");
    }

    #[test]
    fn bad_shards_are_refused() {
        for s in ["0/4", "5/4", "1/0", "4", "a/b", "1/-2"] {
            assert!(s.parse::<Shard>().is_err(), "{s}");
        }
        assert_eq!("2/3".parse::<Shard>().unwrap().to_string(), "2/3");
    }
}
