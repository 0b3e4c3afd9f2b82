//! A `gcl fuzz host` corpus that outlives its campaign (`--corpus DIR`): the schedules guidance
//! kept (for a new wire path or a new edge of the host's code), one JSON file each, named by a
//! hash of the schedule, so that two campaigns or shards writing one folder never clash. Each
//! file holds the schedule and the edges its run reached (when the run read the host's
//! coverage). A campaign given such a folder runs its schedules right after the systematic
//! pass, where each is kept again when it brings something new (AFL's way with a seed corpus),
//! and adds its own.
//!
//! Shards (`--shard K/N`) share a corpus so: each reads the folder's schedules once, at its
//! start (the base, which no shard writes while a campaign runs), and runs those whose run
//! index is its own after its share of the pass; so a shard makes the same runs for a seed and
//! a base whenever it starts, and the shards together run every schedule of the base once.
//! Each shard writes the schedules it kept, with their edges, to the folder's [`INCOMING`]
//! subfolder (atomically, by content-hash name: shards on one machine may share the folder).
//! [`merge`] then folds the incoming schedules, and any other corpus folders, into the base,
//! keeping only schedules that add edges (as `afl-cmin` does): for each edge the smallest
//! schedule that reached it, less those whose edges the others kept reach too. It reads the
//! edges the files hold and runs nothing.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::sim::misbehave::Schedule;

/// The subfolder of a corpus that shards write to, and [`merge`] folds into it.
pub const INCOMING: &str = "incoming";

/// One schedule of a corpus, with the edges of the host's code its run reached (empty when
/// that run read no coverage, and in files written before edges were kept).
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Entry {
    /// The schedule.
    #[serde(flatten)]
    pub schedule: Schedule,
    /// Its run's edges, in order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub edges: Vec<u32>,
}

/// The content-hash name of a schedule's file.
pub fn name(s: &Schedule) -> String {
    let json = serde_json::to_vec(s).unwrap_or_default();
    format!("{}.json", &crate::digest::sha256_hex(&json)[..20])
}

/// A short digest of a list of schedules (their names in order): what a shard's provenance
/// records of the base it ran, so that shards of different bases do not merge.
pub fn digest(schedules: &[Schedule]) -> String {
    let names: Vec<String> = schedules.iter().map(name).collect();
    crate::digest::sha256_hex(names.join("\n").as_bytes())[..16].to_string()
}

pub use crate::fuzz::Malformed;

/// Every `*.json` entry of `dir` (not of its subfolders), with its path, in name order; files
/// that do not read or parse, or plan no misbehaviour, are left out and returned with why.
fn read_entries(dir: &Path) -> std::io::Result<(Vec<(PathBuf, Entry)>, Malformed)> {
    let (all, mut bad) = crate::fuzz::read_json_files::<Entry>(dir)?;
    let (out, empty): (Vec<_>, Vec<_>) = all.into_iter().partition(|(_, e)| !e.schedule.planned.is_empty());
    bad.extend(empty.into_iter().map(|(p, _)| (p, "no misbehaviour planned".to_string())));
    bad.sort();
    Ok((out, bad))
}

/// Every schedule of `dir` (made if missing), in name order: the base, without the
/// [`INCOMING`] ones; files that do not read or parse are left out and returned with why.
pub fn load(dir: &Path) -> std::io::Result<(Vec<Schedule>, Malformed)> {
    std::fs::create_dir_all(dir)?;
    let (entries, bad) = read_entries(dir)?;
    Ok((entries.into_iter().map(|(_, e)| e.schedule).collect(), bad))
}

/// Writes each entry not already in `dir` (made if missing; atomically); how many were new.
pub fn save(dir: &Path, entries: &[Entry]) -> std::io::Result<usize> {
    std::fs::create_dir_all(dir)?;
    let mut new = 0;
    for e in entries {
        let path = dir.join(name(&e.schedule));
        if path.exists() {
            continue;
        }
        crate::report::write_atomic(&path, &serde_json::to_vec_pretty(e).unwrap_or_default())?;
        new += 1;
    }
    Ok(new)
}

/// What [`merge`] did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Merged {
    /// Distinct schedules read (the base, its incoming ones and the other folders').
    pub read: usize,
    /// Schedules in the base after the merge.
    pub kept: usize,
    /// Edges the kept schedules reach (the union of every schedule's read).
    pub edges: usize,
    /// Kept without edges to judge them by (their runs read no coverage).
    pub without_edges: usize,
    /// Files that did not read or parse, left where they were.
    pub malformed: Malformed,
}

/// Folds the schedules of `dir`, of its [`INCOMING`] subfolder and of the corpus folders `from`
/// (each with its own incoming ones) into `dir`, keeping only those that add edges: for each
/// edge, the schedule with the fewest misbehaviours (then the first by name) that reached it.
/// Schedules without edges are kept (nothing to judge them by). The kept ones are
/// written atomically, the others removed from `dir`, and the incoming files read are removed
/// (`from` is only read).
pub fn merge(dir: &Path, from: &[PathBuf]) -> std::io::Result<Merged> {
    std::fs::create_dir_all(dir)?;
    let incoming = dir.join(INCOMING);
    let mut folders = vec![dir.to_path_buf(), incoming.clone()];
    for f in from {
        folders.push(f.clone());
        folders.push(f.join(INCOMING));
    }
    // A folder named twice (DIR among FROM) is read once.
    let mut seen = BTreeSet::new();
    folders.retain(|f| seen.insert(f.canonicalize().unwrap_or_else(|_| f.clone())));
    let mut all: BTreeMap<String, Entry> = BTreeMap::new();
    let mut merged = Merged::default();
    let mut read_incoming = Vec::new();
    for f in &folders {
        if !f.is_dir() {
            continue;
        }
        let (entries, bad) = read_entries(f)?;
        merged.malformed.extend(bad);
        for (p, e) in entries {
            if *f == incoming {
                read_incoming.push(p);
            }
            // The same schedule from two runs: the union of what they reached.
            let slot = all
                .entry(name(&e.schedule))
                .or_insert_with(|| Entry { schedule: e.schedule.clone(), ..Default::default() });
            let union: BTreeSet<u32> = slot.edges.iter().chain(&e.edges).copied().collect();
            slot.edges = union.into_iter().collect();
        }
    }
    merged.read = all.len();
    let keep = minimal(&all);
    merged.edges = all.values().flat_map(|e| e.edges.iter()).collect::<BTreeSet<_>>().len();
    merged.without_edges = keep.iter().filter(|n| all[*n].edges.is_empty()).count();
    merged.kept = keep.len();
    for (n, e) in &all {
        let path = dir.join(n);
        if keep.contains(n) {
            crate::report::write_atomic(&path, &serde_json::to_vec_pretty(e).unwrap_or_default())?;
        } else if path.is_file() {
            std::fs::remove_file(&path)?;
        }
    }
    for p in read_incoming {
        std::fs::remove_file(&p)?;
    }
    // Left only when a shard still writes into it.
    let _ = std::fs::remove_dir(&incoming);
    Ok(merged)
}

/// The names of the schedules [`merge`] keeps of `all`.
fn minimal(all: &BTreeMap<String, Entry>) -> BTreeSet<String> {
    let mut by_size: Vec<(&String, &Entry)> = all.iter().collect();
    by_size.sort_by_key(|(n, e)| (e.schedule.planned.len(), *n));
    let mut owner: BTreeMap<u32, &String> = BTreeMap::new();
    for (n, e) in &by_size {
        for edge in &e.edges {
            owner.entry(*edge).or_insert(n);
        }
    }
    let mut keep: BTreeSet<String> = owner.values().map(|n| (*n).clone()).collect();
    keep.extend(all.iter().filter(|(_, e)| e.edges.is_empty()).map(|(n, _)| n.clone()));
    keep
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::misbehave::{Operator, Planned};

    fn entry(planned: &[(u32, Operator)], edges: &[u32]) -> Entry {
        Entry {
            schedule: Schedule {
                planned: planned.iter().map(|&(answer, op)| Planned { answer, op, arg: 0 }).collect(),
            },
            edges: edges.to_vec(),
        }
    }

    #[test]
    fn a_saved_corpus_loads_back_once_each_and_a_bad_file_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let a = entry(&[(2, Operator::ErrBits)], &[1, 2]);
        let b = entry(&[(3, Operator::Garbage)], &[]);
        assert_eq!(save(dir.path(), &[a.clone(), b.clone(), a.clone()]).unwrap(), 2);
        assert_eq!(save(dir.path(), std::slice::from_ref(&b)).unwrap(), 0, "already there");
        std::fs::write(dir.path().join("zz.json"), "{").unwrap();
        // A file of an older gcl: the schedule alone.
        let old = Schedule { planned: vec![Planned { answer: 4, op: Operator::CrLf, arg: 1 }] };
        std::fs::write(dir.path().join(name(&old)), serde_json::to_vec(&old).unwrap()).unwrap();
        let (got, bad) = load(dir.path()).unwrap();
        let mut want = vec![a.schedule, b.schedule, old];
        want.sort_by_key(name);
        assert_eq!(got, want);
        assert_eq!(bad.len(), 1);
        assert!(bad[0].0.ends_with("zz.json"));
    }

    /// The merge keeps, of the base, its incoming schedules and another folder's, the smallest
    /// schedule for each edge (none of the larger ones that reach only edges it keeps), keeps
    /// those without edges, and empties the incoming folder (the other folder is only read).
    #[test]
    fn a_merge_keeps_only_schedules_that_add_edges() {
        let dir = tempfile::tempdir().unwrap();
        let (base, other) = (dir.path().join("base"), dir.path().join("other"));
        let small = entry(&[(2, Operator::ErrBits)], &[1, 2]);
        let big = entry(&[(2, Operator::ErrBits), (3, Operator::Garbage)], &[1, 2, 3]);
        let same_edges_bigger = entry(&[(2, Operator::ErrBits), (5, Operator::CrLf)], &[1, 2]);
        let covered = entry(&[(4, Operator::Garbage)], &[3]);
        let wire_only = entry(&[(6, Operator::Truncate)], &[]);
        save(&base, std::slice::from_ref(&same_edges_bigger)).unwrap();
        save(&base.join(INCOMING), &[small.clone(), big.clone(), wire_only.clone()]).unwrap();
        save(&other, std::slice::from_ref(&covered)).unwrap();
        let m = merge(&base, std::slice::from_ref(&other)).unwrap();
        assert_eq!((m.read, m.kept, m.edges, m.without_edges), (5, 3, 3, 1), "{m:?}");
        let (got, _) = load(&base).unwrap();
        let mut want = vec![small.schedule, covered.schedule, wire_only.schedule];
        want.sort_by_key(name);
        assert_eq!(got, want, "big's edges are small's and covered's");
        assert!(!base.join(INCOMING).exists(), "the incoming schedules were folded in");
        assert_eq!(load(&other).unwrap().0.len(), 1, "another folder is only read");
        // A merge of a merged base changes nothing, even given itself again.
        assert_eq!(merge(&base, &[]).unwrap().kept, 3);
        save(&base.join(INCOMING), std::slice::from_ref(&big)).unwrap();
        assert_eq!(merge(&base, &[base.clone(), dir.path().join("base/../base")]).unwrap().kept, 3);
        assert!(!base.join(INCOMING).exists());
    }
}
