//! `gcl suite`: the committed golden transcripts. `regenerate` rewrites them (and the JSON
//! vectors of `vectors/json/`, whose headers carry the suite hash) from the reference model,
//! `check` fails (exit 1, listing the files) when either is stale, missing or extra, `list`
//! shows the cases.
//!
//! What only reads works from any directory: `list` shows the catalogue built into the binary
//! (or a suite on disk with `--dir`), and `check` finds the committed suite in the current
//! directory or the nearest folder above it that has one, as git finds its repository.

use gcl_model::escape::printable;
use std::io::Write;
use std::path::{Path, PathBuf};

use super::{EXIT_FAIL, EXIT_OK};
use gcl_harness::suite;
use gcl_transcript::Level;

/// Arguments of `gcl suite`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, clap::Subcommand)]
enum Command {
    /// Write the model's goldens (one file per case per profile, and index.json) and the
    /// JSON vectors, whose headers carry the suite hash.
    Regenerate {
        /// The suite directory.
        #[arg(long, default_value = suite::DEFAULT_DIR)]
        dir: PathBuf,
        /// The JSON vectors directory [default: `json` next to the suite directory].
        #[arg(long)]
        vectors_dir: Option<PathBuf>,
    },
    /// Fail (exit 1) when the committed goldens or JSON vectors differ from what the model
    /// generates.
    Check {
        /// The suite directory [default: vectors/suite in this directory or the nearest folder
        /// above it that has one].
        #[arg(long)]
        dir: Option<PathBuf>,
        /// The JSON vectors directory [default: `json` next to the suite directory].
        #[arg(long)]
        vectors_dir: Option<PathBuf>,
    },
    /// List the cases: profile, id, level, requirements, title. From the catalogue built into
    /// gcl (works in any directory), or from a suite on disk with --dir.
    List {
        /// Only this profile.
        #[arg(long)]
        profile: Option<String>,
        /// A suite directory to list instead of the built-in catalogue.
        #[arg(long)]
        dir: Option<PathBuf>,
    },
}

/// The suite directory, or a clear error when there is none: outside the repository the
/// default `vectors/suite` does not exist, and listing 870 "missing" files, or advising a
/// regenerate that would write them into the current directory, helps nobody.
fn existing_suite(dir: &Path) -> anyhow::Result<()> {
    let found = dir.is_dir() && (dir.join(suite::INDEX_FILE).is_file() || has_profile_dir(dir));
    if !found {
        anyhow::bail!(
            "cannot find a suite at {}: run gcl from the repository root (the suite is vectors/suite there) or give \
--dir DIR",
            dir.display()
        );
    }
    Ok(())
}

fn has_profile_dir(dir: &Path) -> bool {
    std::fs::read_dir(dir).map(|d| d.filter_map(|e| e.ok()).any(|e| e.path().is_dir())).unwrap_or(false)
}

/// The JSON vectors that go with a suite directory: `json` next to it (`vectors/json` for
/// `vectors/suite`).
fn json_dir(suite_dir: &Path) -> PathBuf {
    suite_dir.parent().unwrap_or(Path::new(".")).join("json")
}

/// Runs `gcl suite`.
pub fn run(args: Args) -> anyhow::Result<u8> {
    let mut w = super::stdio::out();
    match args.command {
        Command::Regenerate { dir, vectors_dir } => {
            // A new suite directory is made only where its parent exists (`vectors/` in the
            // repository), never as a stray `vectors/suite` under whatever the cwd is.
            let parent = dir.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
            if !dir.is_dir() && !parent.is_dir() {
                anyhow::bail!(
                    "{} does not exist: run gcl from the repository root or give --dir DIR (a new DIR is made only \
inside an existing folder)",
                    dir.display()
                );
            }
            let cases = suite::generate_all()?;
            let before = suite::regenerate(&dir, &cases)?;
            for l in before.lines() {
                writeln!(w, "{}", gcl_model::escape::printable(&l))?;
            }
            writeln!(
                w,
                "{} cases in {}: {} written, {} removed",
                cases.len(),
                dir.display(),
                before.stale.len() + before.missing.len(),
                before.extra.len()
            )?;
            super::vectors::regenerate(&mut w, &vectors_dir.unwrap_or_else(|| json_dir(&dir)), &cases)?;
            Ok(EXIT_OK)
        }
        Command::Check { dir, vectors_dir } => {
            let dir = match dir {
                Some(d) => d,
                None => super::find_upward(suite::DEFAULT_DIR)?,
            };
            existing_suite(&dir)?;
            let cases = suite::generate_all()?;
            let r = suite::check(&dir, &cases)?;
            let vectors_fresh = super::vectors::check(&mut w, &vectors_dir.unwrap_or_else(|| json_dir(&dir)), &cases)?;
            if r.is_fresh() {
                writeln!(w, "{} cases in {} are fresh", r.checked, dir.display())?;
                return Ok(if vectors_fresh { EXIT_OK } else { EXIT_FAIL });
            }
            for l in r.lines() {
                writeln!(w, "{}", gcl_model::escape::printable(&l))?;
            }
            writeln!(w, "the committed suite is stale; run `gcl suite regenerate --dir {}`", dir.display())?;
            Ok(EXIT_FAIL)
        }
        Command::List { profile, dir } => {
            let id = profile.as_deref().map(super::load_profile).transpose()?.map(|p| p.id.clone());
            let cases = match (&dir, &id) {
                (Some(d), Some(id)) => {
                    existing_suite(d)?;
                    suite::load_profile(d, id)?
                }
                (Some(d), None) => {
                    existing_suite(d)?;
                    suite::load_dir(d)?
                }
                (None, _) => {
                    let mut all = suite::generate_all()?;
                    all.retain(|c| id.as_ref().is_none_or(|id| &c.profile == id));
                    all
                }
            };
            // Columns at least as wide as their widest entry (and as wide as ever for the
            // built-in suites), so every title starts in one column.
            let rows: Vec<[String; 5]> = cases
                .iter()
                .map(|c| {
                    let req: Vec<&str> = c.header().requires.iter().map(|r| r.as_str()).collect();
                    [
                        c.profile.to_string(),
                        c.id().to_string(),
                        c.level().to_string(),
                        if req.is_empty() { "-".to_string() } else { req.join(",") },
                        c.header().title.clone(),
                    ]
                })
                .collect();
            let width = |i: usize, least: usize| rows.iter().map(|r| r[i].chars().count()).fold(least, usize::max);
            let (w0, w1, w2, w3) = (width(0, 12), width(1, 44), width(2, 6), width(3, 22));
            for [profile, id, level, req, title] in &rows {
                // A suite folder may come from anywhere: its text is shown, never obeyed.
                writeln!(w, "{}", printable(&format!("{profile:<w0$} {id:<w1$} {level:<w2$} {req:<w3$} {title}")))?;
            }
            let counts = suite::count_by_level(&cases);
            let per: Vec<String> =
                Level::ALL.iter().map(|l| format!("{} {}", counts.get(l).copied().unwrap_or(0), l)).collect();
            writeln!(w, "{} cases: {}", cases.len(), per.join(", "))?;
            Ok(EXIT_OK)
        }
    }
}
