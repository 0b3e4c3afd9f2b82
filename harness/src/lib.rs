//! # gcl-harness: everything around the reference model that touches the world
//!
//! Transports and targets ([`link`], [`target`]), and the tools behind the `gcl` binary
//! ([`cli`]). The reference model (`gcl-model`) stays pure; time, bytes, files and
//! processes live here.

// Lets code that moves between the library and the binary name library items the same
// way (`gcl_harness::...`) from either side.
extern crate self as gcl_harness;

pub mod certify;
pub mod check_host;
pub mod cli;
pub mod client;
pub mod conform;
pub mod deadline;
pub mod files;
pub mod fuzz;
pub mod link;
pub mod links;
pub mod preflight;
pub mod replay;
pub mod report;
pub mod sim;
pub mod suite;
pub mod target;
pub mod transcript;
pub mod triage;
pub mod vectors;

pub use link::{Link, LinkError, SimLink};
pub use target::Target;
