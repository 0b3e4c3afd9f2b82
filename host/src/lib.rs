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
//!
//! ## Why a crate of its own
//!
//! A host-library author (a robot program driving a BH8 over a serial port, or its tests against
//! the model) depends on the client (the sans-IO `HostCore` and the blocking `Hand`), the `Link`
//! trait with its transports (serial, TCP, a child process, and `SimLink` to test against the model
//! in simulated time), the `--target` syntax and profile loading. Before the split that meant
//! depending on all of `gcl-harness`, which also brings the suite, the runner, reports (quick-xml,
//! time), certificates (ed25519-dalek, sha2, getrandom), globbing and the simulator server: code
//! and
//! dependencies no host needs, and compile time for every host. `gcl-host` is those modules and
//! four
//! dependencies (`cargo tree -p gcl-host`); the harness's recorder, replayer, runner, simulator and
//! fuzzers use it.
//!
//! What stays out, and why: `deadline.rs` (budgets from the suite's cases), `record.rs` and
//! `replay.rs` (they produce and consume transcripts, a harness format), the key-file limit
//! (`certify.rs`, its only user), and the examples (`harness/examples/`: they parse arguments with
//! clap, which this crate must not depend on, and the harness's tests run them from the harness's
//! target folder). `files` came along because `profiles::load` reads profile TOML through it; its
//! input limit equals the transcript format's `MAX_FILE_BYTES` by a compile-time assertion in the
//! harness, so this crate needs no dependency on `gcl-transcript`.

pub mod client;
pub mod files;
pub mod link;
pub mod links;
pub mod profiles;
pub mod target;

pub use link::{Link, LinkError, SimLink};
pub use target::Target;
