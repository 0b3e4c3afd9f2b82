//! A `gcl fuzz host` corpus that outlives its campaign (`--corpus DIR`): the schedules guidance
//! kept (for a new wire path or a new edge of the host's code), one JSON file each, named by a
//! hash of their content, so that two campaigns or shards writing one folder never clash and
//! `gcl fuzz merge` folds folders by name. A campaign given such a folder runs its schedules
//! right after the systematic pass, where each is kept again when it brings something new
//! (AFL's way with a seed corpus), and adds its own.

use std::path::{Path, PathBuf};

use crate::sim::misbehave::Schedule;

/// The content-hash name of a schedule's file.
pub fn name(s: &Schedule) -> String {
    let json = serde_json::to_vec(s).unwrap_or_default();
    format!("{}.json", &crate::digest::sha256_hex(&json)[..20])
}

/// Files that did not read or parse as a schedule, each with why.
pub type Malformed = Vec<(PathBuf, String)>;

/// Every `*.json` schedule of `dir` (made if missing), in name order; files that do not read or
/// parse are left out and returned with why.
pub fn load(dir: &Path) -> std::io::Result<(Vec<Schedule>, Malformed)> {
    std::fs::create_dir_all(dir)?;
    let mut names: Vec<PathBuf> = std::fs::read_dir(dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    names.sort();
    let (mut out, mut bad) = (Vec::new(), Vec::new());
    for p in names {
        let read = gcl_host::files::read_text_limited(&p, 1 << 20).map_err(|e| e.to_string());
        match read.and_then(|t| serde_json::from_str::<Schedule>(&t).map_err(|e| e.to_string())) {
            Ok(s) if !s.planned.is_empty() => out.push(s),
            Ok(_) => bad.push((p, "no misbehaviour planned".into())),
            Err(why) => bad.push((p, why)),
        }
    }
    Ok((out, bad))
}

/// Writes each schedule not already in `dir` (atomically); how many were new.
pub fn save(dir: &Path, schedules: &[Schedule]) -> std::io::Result<usize> {
    std::fs::create_dir_all(dir)?;
    let mut new = 0;
    for s in schedules {
        let path = dir.join(name(s));
        if path.exists() {
            continue;
        }
        crate::report::write_atomic(&path, &serde_json::to_vec_pretty(s).unwrap_or_default())?;
        new += 1;
    }
    Ok(new)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::misbehave::{Operator, Planned};

    #[test]
    fn a_saved_corpus_loads_back_once_each_and_a_bad_file_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let a = Schedule { planned: vec![Planned { answer: 2, op: Operator::ErrBits, arg: 7 }] };
        let b = Schedule { planned: vec![Planned { answer: 3, op: Operator::Garbage, arg: 1 }] };
        assert_eq!(save(dir.path(), &[a.clone(), b.clone(), a.clone()]).unwrap(), 2);
        assert_eq!(save(dir.path(), std::slice::from_ref(&b)).unwrap(), 0, "already there");
        std::fs::write(dir.path().join("zz.json"), "{").unwrap();
        let (got, bad) = load(dir.path()).unwrap();
        let mut want = vec![a, b];
        want.sort_by_key(name);
        assert_eq!(got, want);
        assert_eq!(bad.len(), 1);
        assert!(bad[0].0.ends_with("zz.json"));
    }
}
