//! Tidy: the architecture invariants of `ARCHITECTURE.md` that a compiler cannot see, checked
//! over the sources and the committed files (rust-analyzer's `tidy.rs` is the model). Each
//! test names the invariant it holds and lists every offending place when it fails.

use std::path::{Path, PathBuf};

const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/..");

/// Every `.rs` file under `dir` (relative to the workspace root), sorted.
fn rust_files(dir: &str) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![Path::new(ROOT).join(dir)];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display())) {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push(p);
            }
        }
    }
    out.sort();
    assert!(!out.is_empty(), "no Rust files under {dir}");
    out
}

/// The workspace-relative name of a file, for messages.
fn rel(p: &Path) -> String {
    p.strip_prefix(ROOT).unwrap_or(p).display().to_string()
}

/// The lines of a file that are code outside tests: comments are dropped, and a file stops at
/// its first `#[cfg(test)]` (test modules sit at the end); `tests.rs` files are skipped.
fn code_lines(p: &Path) -> Vec<(usize, String)> {
    if p.file_name().is_some_and(|f| f == "tests.rs") {
        return Vec::new();
    }
    let text = std::fs::read_to_string(p).unwrap();
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let t = line.trim_start();
        if t.starts_with("#[cfg(test)]") {
            break;
        }
        if t.starts_with("//") {
            continue;
        }
        let code = match line.find("//") {
            // A `//` inside a string literal (a URL) is rare in these crates; a line with a
            // quote before the `//` is kept whole.
            Some(i) if !line[..i].contains('"') => &line[..i],
            _ => line,
        };
        out.push((i + 1, code.to_string()));
    }
    out
}

/// Whether `word` occurs in `line` as a whole name: not inside a longer identifier
/// (`SpecFile::` is not `File::`, `crate::client` is not `crate::cli`).
fn has_word(line: &str, word: &str) -> bool {
    let ident = |c: Option<char>| c.is_some_and(|c| c.is_alphanumeric() || c == '_');
    line.match_indices(word).any(|(i, _)| {
        let before = line[..i].chars().next_back();
        let after = line[i + word.len()..].chars().next();
        let word_ends_in_ident = ident(word.chars().next_back());
        !ident(before) && !(word_ends_in_ident && ident(after))
    })
}

/// Every `file:line: text` where `hit` says the code line breaks the rule.
fn offenders(files: &[PathBuf], hit: impl Fn(&Path, &str) -> bool) -> Vec<String> {
    let mut out = Vec::new();
    for f in files {
        for (n, line) in code_lines(f) {
            if hit(f, &line) {
                out.push(format!("{}:{n}: {}", rel(f), line.trim()));
            }
        }
    }
    out
}

/// Architecture invariant: the reference model and the transcript crate do no I/O, read no
/// clock, never sleep and never print. Time and bytes come in as arguments.
#[test]
fn pure_crates_do_no_io() {
    const FORBIDDEN: &[&str] = &[
        "std::fs",
        "std::net",
        "std::process",
        "std::env",
        "std::thread",
        "std::io::stdin",
        "std::io::stdout",
        "std::io::stderr",
        "File::",
        "Instant",
        "SystemTime",
        "sleep(",
        "println!",
        "eprintln!",
        "print!",
        "eprint!",
        "dbg!",
    ];
    let mut files = rust_files("reference-model/src");
    files.extend(rust_files("transcript/src"));
    let bad = offenders(&files, |_, l| FORBIDDEN.iter().any(|w| has_word(l, w)));
    assert!(bad.is_empty(), "I/O, clocks, sleeps or printing in a pure crate:\n{}", bad.join("\n"));
}

/// Architecture invariant: the command line lives in the binary. No library code names it
/// (the compiler refuses `crate::cli` in the library; this also catches a re-export or a
/// `#[path]` trick), and only the binary uses `anyhow`, `clap` and `indicatif`: the
/// library's errors are typed.
#[test]
fn the_cli_and_its_crates_stay_in_the_binary() {
    let lib: Vec<PathBuf> = rust_files("harness/src")
        .into_iter()
        .filter(|p| {
            let r = rel(p);
            !r.starts_with("harness/src/cli/") && r != "harness/src/main.rs"
        })
        .collect();
    let bad = offenders(&lib, |_, l| {
        ["crate::cli", "gcl_harness::cli", "mod cli", "anyhow", "clap", "indicatif"].iter().any(|w| has_word(l, w))
    });
    assert!(bad.is_empty(), "CLI matters in library code:\n{}", bad.join("\n"));
    let mut outside = rust_files("harness/tests");
    outside.extend(rust_files("harness/examples"));
    outside.extend(rust_files("harness/benches"));
    outside.extend(rust_files("fuzz/src"));
    outside.retain(|p| !p.ends_with("tidy.rs"));
    let bad = offenders(&outside, |_, l| has_word(l, "gcl_harness::cli"));
    assert!(bad.is_empty(), "`gcl_harness::cli` outside the binary:\n{}", bad.join("\n"));
}
