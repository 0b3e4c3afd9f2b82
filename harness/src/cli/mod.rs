//! The `gcl` subcommands. Each module owns one subcommand: its clap arguments and its `run`.
//! `run` returns the process exit code: 0 success, 1 conformance failures, 2 usage or
//! infrastructure errors (errors returned as `Err` become 2 in `main`).

pub mod certify;
pub mod check_host;
pub mod conform;
pub mod explain;
pub mod fuzz;
pub mod fuzz_host;
pub mod record;
pub mod replay;
pub mod sim;
pub mod spec;
pub mod suite;
pub mod vectors;

use std::path::Path;
use std::sync::Arc;

use anyhow::Context;
use gcl_model::Profile;

/// Exit code: everything passed.
pub const EXIT_OK: u8 = 0;
/// Exit code: conformance failures (or a mismatch).
pub const EXIT_FAIL: u8 = 1;
/// Exit code: usage or infrastructure error.
pub const EXIT_ERROR: u8 = 2;

/// Loads a profile by built-in name or alias (`seed`, `bh8-262-4.3`, `bh8-262-4.4`,
/// `bh8-262`) or from a TOML file; a file's `include`s resolve next to it, then against the
/// embedded `spec/` tree.
pub fn load_profile(name: &str) -> anyhow::Result<Arc<Profile>> {
    if let Ok(p) = Profile::builtin(name) {
        return Ok(p);
    }
    let path = Path::new(name);
    if !path.exists() {
        anyhow::bail!(
            "unknown profile `{name}`: not a built-in profile ({}) nor a readable file",
            Profile::builtin_names().collect::<Vec<_>>().join(", ")
        );
    }
    // The file itself first, so a FIFO, a device or a huge file is one clear error.
    let top_text = crate::files::read_input_text(path).with_context(|| format!("profile file {name}"))?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let top = path.file_name().and_then(|f| f.to_str()).unwrap_or_default().to_string();
    let failed = std::cell::RefCell::new(None::<String>);
    let resolve = |f: &str| -> Option<String> {
        if f == top {
            return Some(top_text.clone());
        }
        let p = dir.join(f);
        match crate::files::read_input_text(&p) {
            Ok(t) => Some(t),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => gcl_model::spec::embedded(f).map(str::to_string),
            Err(e) => {
                failed.borrow_mut().get_or_insert_with(|| format!("{}: {e}", p.display()));
                None
            }
        }
    };
    let loaded = Profile::load_with(&top, &resolve);
    if let Some(e) = failed.into_inner() {
        anyhow::bail!("loading profile file {name}: {e}");
    }
    let p = loaded.with_context(|| format!("loading profile file {name}"))?;
    Ok(Arc::new(p))
}
