//! The `gcl` subcommands. Each module owns one subcommand: its clap arguments and its `run`.
//! `run` returns the process exit code: 0 success, 1 conformance failures, 2 usage or
//! infrastructure errors (errors returned as `Err` become 2 in `main`).

pub mod certify;
pub mod check_host;
pub mod check_host_serve;
pub mod conform;
pub mod explain;
pub mod fuzz;
pub mod fuzz_host;
pub mod fuzz_merge;
pub mod record;
pub mod replay;
pub mod sim;
pub mod spec;
pub mod suite;
pub mod vectors;

use std::sync::Arc;

use gcl_model::Profile;

/// Exit code: everything passed.
pub const EXIT_OK: u8 = 0;
/// Exit code: conformance failures (or a mismatch).
pub const EXIT_FAIL: u8 = 1;
/// Exit code: usage or infrastructure error.
pub const EXIT_ERROR: u8 = 2;

/// Loads a profile by built-in name or alias (`seed`, `bh8-262-4.3`, `bh8-262-4.4`,
/// `bh8-262`) or from a TOML file ([`gcl_host::profiles::load`]).
pub fn load_profile(name: &str) -> anyhow::Result<Arc<Profile>> {
    Ok(gcl_host::profiles::load(name)?)
}
