//! Fuzzers that check someone else's implementation of GCL against the reference model.
//!
//! [`device`] drives a hand (any `--target`) with generated host actions and judges every
//! answer by the model. [`host`] puts a misbehaving simulated hand in front of a host program
//! and catches its crashes, hangs and protocol violations. [`shard`] slices a campaign of
//! either over machines and [`merge`] folds the slices' outputs back into one. The fuzzers
//! print nothing and own no CLI.

pub mod device;
pub mod host;
pub mod merge;
pub mod shard;

use std::path::{Path, PathBuf};

/// Corpus files that did not read or parse, each with why.
pub type Malformed = Vec<(PathBuf, String)>;

/// Every `*.json` file of `dir` (not of its subfolders) parsed as a `T`, with its path, in name
/// order: both fuzzers' corpora are folders of such files. Files that do not read (at most a
/// MiB) or parse are left out and returned with why, so the caller can warn about them.
pub fn read_json_files<T: serde::de::DeserializeOwned>(dir: &Path) -> std::io::Result<(Vec<(PathBuf, T)>, Malformed)> {
    let mut names: Vec<PathBuf> = std::fs::read_dir(dir)?
        .filter_map(|e| e.ok())
        .filter(|e| e.file_type().is_ok_and(|t| t.is_file()))
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    names.sort();
    let (mut out, mut bad) = (Vec::new(), Vec::new());
    for p in names {
        let read = gcl_host::files::read_text_limited(&p, 1 << 20).map_err(|e| e.to_string());
        match read.and_then(|t| serde_json::from_str::<T>(&t).map_err(|e| e.to_string())) {
            Ok(v) => out.push((p, v)),
            Err(why) => bad.push((p, why)),
        }
    }
    Ok((out, bad))
}
