//! The replay tool behind each target's `main` in ordinary (non-fuzzing) builds: run an entry
//! point on files named on the command line, as libFuzzer would run a reproducer.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The files to replay: each argument, or every file directly inside it if it is a directory,
/// in name order.
pub fn inputs(args: impl IntoIterator<Item = PathBuf>) -> std::io::Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for arg in args {
        if arg.is_dir() {
            let mut entries: Vec<PathBuf> =
                std::fs::read_dir(&arg)?.map(|e| e.map(|e| e.path())).collect::<Result<_, _>>()?;
            entries.retain(|p| p.is_file());
            entries.sort();
            files.extend(entries);
        } else {
            files.push(arg);
        }
    }
    Ok(files)
}

/// Runs the entry point of `target` (a name in [`crate::TARGETS`]) on each input named in the
/// process arguments. Exit status 0 when every input ran, 2 on a usage or I/O error; a finding
/// panics (status 101) with its message.
pub fn main(target: &str) -> ExitCode {
    let Some((_, entry)) = crate::TARGETS.iter().find(|(t, _)| *t == target) else {
        eprintln!("no fuzz target `{target}`");
        return ExitCode::from(2);
    };
    let args: Vec<PathBuf> = std::env::args_os().skip(1).map(PathBuf::from).collect();
    if args.is_empty() || args.iter().any(|a| a == Path::new("-h") || a == Path::new("--help")) {
        eprintln!("usage: {target} FILE_OR_DIR...\nreplays inputs through gcl_fuzz::{target}");
        return ExitCode::from(2);
    }
    let files = match inputs(args) {
        Ok(f) => f,
        Err(e) => {
            eprintln!("{target}: {e}");
            return ExitCode::from(2);
        }
    };
    for file in &files {
        match std::fs::read(file) {
            Ok(data) => {
                entry(&data);
                println!("ok {}", file.display());
            }
            Err(e) => {
                eprintln!("{target}: {}: {e}", file.display());
                return ExitCode::from(2);
            }
        }
    }
    println!("{target}: {} inputs ran", files.len());
    ExitCode::SUCCESS
}
