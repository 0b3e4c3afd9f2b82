//! # gcl-harness: everything around the reference model that touches the world
//!
//! Transports and targets ([`link`], [`target`]), the host library ([`client`]), and the
//! tools behind the `gcl` binary: replay, recording, the conformance suite and its runner,
//! reports and certificates. The reference model (`gcl-model`) stays pure and the transcript
//! format is its own crate (`gcl-transcript`); time, bytes, files and processes live here.
//! The command line is not here: it is a module of the binary (`src/cli/`), so nothing in
//! this library can reach it, and the library's errors are typed (`anyhow`, `clap` and
//! `indicatif` belong to the binary; `tests/tidy.rs` holds that line).

// Lets code that moves between the library and the binary name library items the same
// way (`gcl_harness::...`) from either side.
extern crate self as gcl_harness;

pub mod certify;
pub mod check_host;
pub mod client;
pub mod conform;
pub mod deadline;
pub mod files;
pub mod fuzz;
pub mod link;
pub mod links;
pub mod preflight;
pub mod profiles;
pub mod record;
pub mod replay;
pub mod report;
pub mod sim;
pub mod suite;
pub mod target;
pub mod triage;
pub mod vectors;

pub use link::{Link, LinkError, SimLink};
pub use target::Target;
