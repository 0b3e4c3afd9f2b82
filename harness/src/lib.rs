//! # gcl-harness: the `gcl` binary, and the harness under one name
//!
//! The top layer: the command line (`src/cli/`, a module of the binary, so nothing in a
//! library can reach it; `anyhow`, `clap` and `indicatif` belong to it and `tests/it/tidy.rs`
//! holds that line). The library part of this crate is the layers below under one name, so
//! the binary, the tests and the benches write `gcl_harness::sim`, `gcl_harness::fuzz`, ...:
//!
//! - `gcl-line`: the hand on its transports (`sim`, `outputs`, `digest`, `record`, `replay`);
//! - `gcl-conformance`: the suite and its runner, triage, certificates, reports, vectors;
//! - `gcl-fuzzers`: fuzz device, fuzz host, shards and merges, the host check.
//!
//! Each stands only on those listed before it (and on `gcl-model`, `gcl-transcript` and
//! `gcl-host`), which their `Cargo.toml`s make a compile error to break.

pub use gcl_conformance::{
    actions, align, certify, conform, deadline, motion, preflight, report, suite, triage, vectors,
};
pub use gcl_fuzzers::{fuzz, host_check, host_check_serve};
pub use gcl_line::{digest, outputs, record, replay, sim};

// One limit for input files: the host crate's (profile TOML) is the transcript format's.
const _: () = assert!(gcl_host::files::MAX_INPUT_BYTES == gcl_transcript::MAX_FILE_BYTES as u64);
