//! Reproducer bundles: one folder per distinct finding.
//!
//! ```text
//! <out>/<kind>-<8 hex digits of the signature>/
//!   finding.json           kind, signature, message, seeds, how the host ended, what fired
//!   schedule.json          the minimized schedule (`--replay` runs this one)
//!   schedule.original.json the schedule as first found
//!   transcript.gcl         the bytes both ways as a `gcl-transcript 1`, misbehaviours marked
//!                          in comments
//!   stderr.txt             the host's stderr
//! ```

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::session::{Dir, Exchange, HostEnd};
use super::{Finding, FindingKind};
use crate::sim::misbehave::{Fired, Schedule};

/// `finding.json`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct BundleInfo {
    /// Crash, hang, exit code or violation.
    pub kind: FindingKind,
    /// The deduplication key.
    pub signature: String,
    /// One line for people.
    pub message: String,
    /// The campaign's seed.
    pub seed: u64,
    /// The run that first showed it.
    pub run: u64,
    /// Milliseconds from the campaign's start to that run's end.
    pub found_after_ms: u64,
    /// Runs that showed it.
    pub hits: u64,
    /// The seed of the hand's noise.
    pub hand_seed: u64,
    /// The profile's id.
    pub profile: String,
    /// `pty` or `tcp`.
    pub transport: super::Transport,
    /// `fast` or `real`.
    pub time: String,
    /// The host command as given.
    pub command: Vec<String>,
    /// How the host ended in the minimized run.
    pub end: HostEnd,
    /// What fired in it, at which protocol states.
    pub fired: Vec<Fired>,
    /// The hang timeout of the campaign that found it, milliseconds (calibrated or given);
    /// `--replay` uses it unless `--timeout-hang` is given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub timeout_hang_ms: Option<u64>,
}

/// Why a bundle cannot be read or written.
#[derive(Debug, thiserror::Error)]
pub enum BundleError {
    /// A file of the bundle cannot be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A file of the bundle is not what it should be.
    #[error("{path}: {reason}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// Why.
        reason: String,
    },
}

/// The folder name of a finding: its kind and a short hash of its signature.
pub fn dir_name(kind: FindingKind, signature: &str) -> String {
    format!("{}-{}", kind.name(), &crate::digest::sha256_hex(signature.as_bytes())[..8])
}

/// Writes a finding's bundle under `out`; returns its folder.
pub fn write(out: &Path, info: &BundleInfo, f: &Finding) -> Result<PathBuf, BundleError> {
    let dir = out.join(dir_name(f.verdict.kind, &f.verdict.signature));
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| BundleError::Io { path, source }
    };
    std::fs::create_dir_all(&dir).map_err(io(&dir))?;
    // Written first and removed last: a bundle cut short (a full disk, a kill) says so, and
    // `read` refuses it instead of replaying half a finding.
    let marker = dir.join(INCOMPLETE);
    crate::report::write_atomic(&marker, b"this bundle was not written whole; do not trust it\n")
        .map_err(io(&marker))?;
    let files: [(&str, Vec<u8>); 5] = [
        ("finding.json", json(info)),
        ("schedule.json", json(&f.schedule)),
        ("schedule.original.json", json(&f.original)),
        ("transcript.gcl", transcript(info, &f.exchanges).into_bytes()),
        ("stderr.txt", f.stderr.clone().into_bytes()),
    ];
    for (name, bytes) in files {
        let p = dir.join(name);
        crate::report::write_atomic(&p, &bytes).map_err(io(&p))?;
    }
    std::fs::remove_file(&marker).map_err(io(&marker))?;
    Ok(dir)
}

/// The file that marks a bundle whose writing did not finish.
pub const INCOMPLETE: &str = "INCOMPLETE";

fn json<T: Serialize>(v: &T) -> Vec<u8> {
    let mut b = serde_json::to_vec_pretty(v).unwrap_or_default();
    b.push(b'\n');
    b
}

/// Reads a bundle's `finding.json` and `schedule.json`.
pub fn read(dir: &Path) -> Result<(BundleInfo, Schedule), BundleError> {
    fn load<T: serde::de::DeserializeOwned>(p: PathBuf) -> Result<T, BundleError> {
        let text =
            gcl_host::files::read_input_text(&p).map_err(|source| BundleError::Io { path: p.clone(), source })?;
        serde_json::from_str(&text).map_err(|e| BundleError::Invalid { path: p, reason: e.to_string() })
    }
    let marker = dir.join(INCOMPLETE);
    if std::fs::symlink_metadata(&marker).is_ok() {
        return Err(BundleError::Invalid {
            path: marker,
            reason: "the bundle is incomplete: writing it did not finish (a full disk?)".into(),
        });
    }
    Ok((load(dir.join("finding.json"))?, load(dir.join("schedule.json"))?))
}

/// Bytes as a transcript string.
fn quote(b: &[u8]) -> String {
    format!("\"{}\"", gcl_transcript::escape_text(b))
}

/// The exchange of a finding as a `gcl-transcript 1` (see [`session_transcript`]).
pub fn transcript(info: &BundleInfo, exchanges: &[Exchange]) -> String {
    let title: String = info.signature.chars().filter(|c| !c.is_control()).collect();
    let header = format!(
        "id: fuzz-host-{}\ntitle: {title}\nclause: host: gcl fuzz host\nlevel: INFO\nprofile: {}\nx-fuzz-seed: {} run {} hand-seed {}\nnote: what a fuzzed hand sent, not what a conforming hand sends\n",
        dir_name(info.kind, &info.signature),
        info.profile,
        info.seed,
        info.run,
        info.hand_seed
    );
    session_transcript(&header, exchanges)
}

/// An exchange as a `gcl-transcript 1` with the given header lines: each host chunk a
/// `send`, the hand's bytes until the next one its `expect`, each misbehaviour a comment
/// before the step it shaped. Its `send` steps make a golden for `gcl check-host --golden`.
pub fn session_transcript(header: &str, exchanges: &[Exchange]) -> String {
    let mut s = String::from("gcl-transcript 1\n");
    s.push_str(header);
    let mut pending_marks: Vec<String> = Vec::new();
    let mut send: Option<Vec<u8>> = None;
    let mut expect: Vec<u8> = Vec::new();
    let flush = |s: &mut String, send: &mut Option<Vec<u8>>, expect: &mut Vec<u8>, marks: &mut Vec<String>| {
        if send.is_none() && expect.is_empty() {
            return;
        }
        s.push('\n');
        for m in marks.drain(..) {
            s.push_str(&format!("# {}\n", m.replace('\n', " ")));
        }
        if let Some(b) = send.take() {
            s.push_str(&format!("send {}\n", quote(&b)));
        }
        s.push_str(&format!("expect {}\n", quote(expect)));
        expect.clear();
    };
    for e in exchanges {
        match e.dir {
            Dir::Host => {
                flush(&mut s, &mut send, &mut expect, &mut pending_marks);
                send = Some(e.bytes.clone());
            }
            Dir::Hand => {
                expect.extend_from_slice(&e.bytes);
                pending_marks.extend(e.marks.iter().cloned());
            }
        }
    }
    flush(&mut s, &mut send, &mut expect, &mut pending_marks);
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_transcript_parses_and_keeps_the_bytes_and_marks() {
        let info = BundleInfo {
            kind: FindingKind::Hang,
            signature: "hang: awaiting the answer after FGET".into(),
            message: "m".into(),
            seed: 1,
            run: 2,
            found_after_ms: 3,
            hits: 1,
            hand_seed: 0,
            profile: "seed".into(),
            transport: super::super::Transport::Pty,
            time: "fast".into(),
            command: vec!["host".into()],
            end: HostEnd::Hung("x".into()),
            timeout_hang_ms: None,
            fired: vec![],
        };
        let ex = vec![
            Exchange { dir: Dir::Host, bytes: b"FGET DP\r".to_vec(), marks: vec![] },
            Exchange { dir: Dir::Hand, bytes: b"FGET DP\n\r{\"".to_vec(), marks: vec!["misbehaviour truncate".into()] },
            Exchange { dir: Dir::Host, bytes: b"\x03".to_vec(), marks: vec![] },
        ];
        let text = transcript(&info, &ex);
        let t = gcl_transcript::parse(&text).unwrap();
        assert_eq!(t.steps.len(), 2);
        assert_eq!(t.steps[0].comments, vec!["misbehaviour truncate".to_string()]);
        assert!(t.steps[0].expect.matches(b"FGET DP\n\r{\""));
    }
}
