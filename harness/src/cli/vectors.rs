//! `gcl vectors`: the flat JSON test vectors under `vectors/json/`. `regenerate` rewrites
//! them from the reference model (their headers carry each profile's suite hash, so the suite
//! is generated too), `check` fails (exit 1, listing the files) when they are stale. `gcl
//! suite regenerate` and `gcl suite check` do the same for the vectors as for the goldens.

use std::io::Write;
use std::path::{Path, PathBuf};

use super::{EXIT_FAIL, EXIT_OK};
use gcl_harness::{suite, vectors};

/// Arguments of `gcl vectors`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, clap::Subcommand)]
enum Command {
    /// Write the model's vectors: one file per kind per profile.
    Regenerate {
        /// The vectors directory.
        #[arg(long, default_value = vectors::DEFAULT_DIR)]
        dir: PathBuf,
    },
    /// Fail (exit 1) when the committed vectors differ from what the model generates.
    Check {
        /// The vectors directory [default: vectors/json in this directory or the nearest
        /// folder above it that has one].
        #[arg(long)]
        dir: Option<PathBuf>,
    },
}

/// Writes the vectors for `cases` (the generated suite) under `dir`, and says what changed.
pub(crate) fn regenerate(w: &mut dyn Write, dir: &Path, cases: &[suite::Case]) -> anyhow::Result<()> {
    let want = vectors::expected_files(cases)?;
    let before = vectors::regenerate(dir, &want)?;
    for l in before.lines() {
        writeln!(w, "{}", gcl_model::escape::printable(&l))?;
    }
    writeln!(
        w,
        "{} vector files in {}: {} written, {} removed",
        want.len(),
        dir.display(),
        before.stale.len() + before.missing.len(),
        before.extra.len()
    )?;
    Ok(())
}

/// Checks the vectors under `dir` against `cases` (the generated suite); false when stale.
pub(crate) fn check(w: &mut dyn Write, dir: &Path, cases: &[suite::Case]) -> anyhow::Result<bool> {
    let want = vectors::expected_files(cases)?;
    let r = vectors::check(dir, &want)?;
    if r.is_fresh() {
        writeln!(w, "{} vector files in {} are fresh", r.checked, dir.display())?;
        return Ok(true);
    }
    for l in r.lines() {
        writeln!(w, "{}", gcl_model::escape::printable(&l))?;
    }
    writeln!(w, "the committed vectors are stale; run `gcl suite regenerate` (goldens and vectors)")?;
    Ok(false)
}

/// Runs `gcl vectors`.
pub fn run(args: Args) -> anyhow::Result<u8> {
    let mut w = super::stdio::out();
    let cases = suite::generate_all()?;
    match args.command {
        Command::Regenerate { dir } => {
            regenerate(&mut w, &dir, &cases)?;
            Ok(EXIT_OK)
        }
        Command::Check { dir } => {
            let dir = match dir {
                Some(d) => d,
                None => super::find_upward(vectors::DEFAULT_DIR)?,
            };
            Ok(if check(&mut w, &dir, &cases)? { EXIT_OK } else { EXIT_FAIL })
        }
    }
}
