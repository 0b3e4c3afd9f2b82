//! # gcl-harness: everything around the reference model that touches the world
//!
//! The tools behind the `gcl` binary: replay, recording, the conformance suite and its
//! runner, reports, certificates, the simulator server and the fuzzers. The reference model
//! (`gcl-model`) stays pure, the transcript format is its own crate (`gcl-transcript`), and
//! links, targets and the client are the host library (`gcl-host`), which this crate builds
//! on; time, bytes, files and processes live here and there.
//! The command line is not here: it is a module of the binary (`src/cli/`), so nothing in
//! this library can reach it, and the library's errors are typed (`anyhow`, `clap` and
//! `indicatif` belong to the binary; `tests/tidy.rs` holds that line).

// Lets code that moves between the library and the binary name library items the same
// way (`gcl_harness::...`) from either side.
extern crate self as gcl_harness;

pub mod actions;
pub mod align;
pub mod certify;
pub mod conform;
pub mod deadline;
pub mod digest;
pub mod fuzz;
pub mod host_check;
pub mod host_check_serve;
pub mod motion;
pub mod outputs;
pub mod preflight;
pub mod record;
pub mod replay;
pub mod report;
pub mod sim;
pub mod suite;
pub mod triage;
pub mod vectors;

// One limit for input files: the host crate's (profile TOML) is the transcript format's.
const _: () = assert!(gcl_host::files::MAX_INPUT_BYTES == gcl_transcript::MAX_FILE_BYTES as u64);
