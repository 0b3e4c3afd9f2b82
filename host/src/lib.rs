//! # gcl-host: drive a Barrett BH8 hand in GCL from a host program
//!
//! What a host program needs and nothing more: the [`Link`] trait and its transports
//! ([`link`], [`links`]: a serial port, TCP, a child process, and [`SimLink`], the
//! in-process reference model with simulated time to test against), the `--target` syntax
//! that opens one ([`target`]), profile loading ([`profiles`], bounded file reads in
//! [`files`]), and the client ([`client`]: the sans-IO host core and the blocking `Hand`).
//! The conformance harness (`gcl-harness`) is built on this crate; nothing here knows the
//! suite, the runner, reports, certificates or the simulator server, and the manifest lacks
//! their dependencies, so the compiler keeps it that way.

pub mod client;
pub mod files;
pub mod link;
pub mod links;
pub mod profiles;
pub mod target;

pub use link::{Link, LinkError, SimLink};
pub use target::Target;
