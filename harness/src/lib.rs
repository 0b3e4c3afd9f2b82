//! # gcl-harness: everything around the reference model that touches the world
//!
//! Transports and targets ([`link`], [`target`]), and the tools behind the `gcl` binary
//! ([`cli`]). The reference model (`gcl-model`) stays pure; time, bytes, files and
//! processes live here.

pub mod certify;
pub mod cli;
pub mod link;
pub mod report;
pub mod target;

pub use link::{Link, LinkError, SimLink};
pub use target::Target;
