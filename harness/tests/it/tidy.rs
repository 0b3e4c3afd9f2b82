//! Tidy: the architecture invariants of `ARCHITECTURE.md` that a compiler cannot see, checked
//! over the sources and the committed files (rust-analyzer's `tidy.rs` is the model). Each
//! test names the invariant it holds and lists every offending place when it fails.

use std::path::{Path, PathBuf};

const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/..");

/// Every file with extension `ext` under `dir` (relative to the workspace root), sorted;
/// `target` directories are skipped.
fn files_with_ext(dir: &str, ext: &str) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![Path::new(ROOT).join(dir)];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display())) {
            let p = e.unwrap().path();
            if p.is_dir() {
                if !p.ends_with("target") {
                    stack.push(p);
                }
            } else if p.extension().is_some_and(|x| x == ext) {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// Every `.rs` file under `dir` (relative to the workspace root), sorted.
fn rust_files(dir: &str) -> Vec<PathBuf> {
    let out = files_with_ext(dir, "rs");
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
        !(ident(before) || (word_ends_in_ident && ident(after)))
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
/// Snapshots have one home, the model's tests: `.ci/run` fails on a committed snapshot that
/// no test used in its `cargo test` run, and one place keeps that list short to read.
#[test]
fn insta_snapshots_live_only_in_the_model() {
    let home = Path::new(ROOT).join("reference-model/tests/it/snapshots");
    let mut outside = Vec::new();
    for dir in ["harness", "line", "conformance", "fuzzers", "host", "transcript", "fuzz", "reference-model"] {
        outside.extend(files_with_ext(dir, "snap").iter().filter(|p| !p.starts_with(&home)).map(|p| rel(p)));
    }
    for dir in ["harness", "line", "conformance", "fuzzers", "host", "transcript", "fuzz"] {
        outside.extend(offenders(&rust_files(dir), |_, l| l.contains(concat!("insta", "::"))));
    }
    assert!(
        outside.is_empty(),
        "insta snapshots outside gcl-model, which .ci/run does not check:\n{}",
        outside.join("\n")
    );
}

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
    let mut lib: Vec<PathBuf> = rust_files("harness/src")
        .into_iter()
        .filter(|p| {
            let r = rel(p);
            !r.starts_with("harness/src/cli/") && r != "harness/src/main.rs"
        })
        .collect();
    lib.extend(LIBRARY_SRC.iter().flat_map(|d| rust_files(d)));
    lib.extend(rust_files("host/src"));
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

/// Issue 39 item 1: what a command prints never decides its fate. The binary writes to stdout
/// and stderr only through `harness/src/cli/stdio.rs` (a closed pipe or a full disk is
/// dropped there, and `main` judges it once), and no library prints with a macro that panics
/// when its stream is closed (`println!` and `eprintln!` do).
#[test]
fn the_binary_prints_through_one_door() {
    const PRINTING: &[&str] = &["println!", "eprintln!", "print!", "eprint!", "dbg!"];
    let mut binary: Vec<PathBuf> = rust_files("harness/src/cli");
    binary.push(Path::new(ROOT).join("harness/src/main.rs"));
    binary.retain(|p| !p.ends_with("cli/stdio.rs"));
    let bad = offenders(&binary, |_, l| PRINTING.iter().chain(&["io::stdout", "io::stderr"]).any(|w| has_word(l, w)));
    assert!(bad.is_empty(), "printing around harness/src/cli/stdio.rs:\n{}", bad.join("\n"));
    let mut lib: Vec<PathBuf> = LIBRARY_SRC.iter().flat_map(|d| rust_files(d)).collect();
    lib.extend(rust_files("host/src"));
    let bad = offenders(&lib, |_, l| PRINTING.iter().any(|w| has_word(l, w)));
    assert!(bad.is_empty(), "a library prints with a macro that panics on a closed stream:\n{}", bad.join("\n"));
}

/// Architecture invariant: the host library (`gcl-host`) carries nothing of the harness. Its
/// manifest is what the compiler enforces (a module that reaches for the suite, a report or
/// the CLI does not build); this keeps the manifest from growing the harness's crates back, and
/// its sources from naming the harness.
#[test]
fn the_host_library_needs_nothing_of_the_harness() {
    const HARNESS_ONLY: &[&str] = &[
        "gcl-harness",
        "gcl-transcript",
        "clap",
        "anyhow",
        "indicatif",
        "quick-xml",
        "time",
        "sha2",
        "ed25519-dalek",
        "getrandom",
        "globset",
    ];
    let manifest: toml::Table =
        std::fs::read_to_string(Path::new(ROOT).join("host/Cargo.toml")).unwrap().parse().unwrap();
    let mut bad = Vec::new();
    for table in ["dependencies", "build-dependencies"] {
        let deps = manifest.get(table).and_then(|t| t.as_table()).cloned().unwrap_or_default();
        bad.extend(deps.keys().filter(|k| HARNESS_ONLY.contains(&k.as_str())).map(|k| format!("[{table}] {k}")));
    }
    assert!(manifest.get("target").is_none(), "host/Cargo.toml: platform-specific dependencies escape this test");
    assert!(bad.is_empty(), "host/Cargo.toml depends on the harness's crates:\n{}", bad.join("\n"));
    let bad = offenders(&rust_files("host/src"), |_, l| has_word(l, "gcl_harness"));
    assert!(bad.is_empty(), "the host library names the harness:\n{}", bad.join("\n"));
}

/// Architecture invariant: profiles are data. No code compares a profile's id with a name
/// (`p.id == "seed"`, a match arm on `"seed"`): what differs between profiles lives in the spec
/// TOML, in the case data under `conformance/suite-cases/`, or in which decisions a profile has.
#[test]
fn no_code_branches_on_a_profile_id() {
    let ids: Vec<String> = gcl_model::Profile::builtin_names().map(str::to_string).collect();
    assert!(ids.iter().any(|i| i == "seed"), "{ids:?}");
    let mut files = rust_files("harness/src");
    files.extend(LIBRARY_SRC.iter().flat_map(|d| rust_files(d)));
    files.extend(rust_files("host/src"));
    files.extend(rust_files("reference-model/src"));
    files.extend(rust_files("transcript/src"));
    files.extend(rust_files("fuzz/src"));
    let bad = offenders(&files, |_, l| {
        ids.iter().any(|id| {
            let lit = format!("\"{id}\"");
            l.match_indices(&lit).any(|(i, _)| {
                let before = l[..i].trim_end();
                let after = l[i + lit.len()..].trim_start();
                before.ends_with("==")
                    || before.ends_with("!=")
                    || after.starts_with("==")
                    || after.starts_with("!=")
                    || after.starts_with("=>")
                    || after.starts_with('|')
                    || (before.ends_with('(') && after.starts_with(',') && l.contains("=>"))
            })
        })
    });
    assert!(bad.is_empty(), "code that compares a profile id (put the difference in data):\n{}", bad.join("\n"));
}

/// The decision ids of every built-in profile.
fn decisions_of(profile: &str) -> Vec<String> {
    gcl_model::Profile::builtin(profile).unwrap().decisions.iter().map(|d| d.id.clone()).collect()
}

/// Architecture invariant: a case cites only decisions the spec has. Every decision id the
/// suite's generators name (`.decision("...")`) or its case scripts cite (`clause:
/// decision:...`) is a decision of some built-in profile (a typo
/// would otherwise be dropped silently, since a case cites only the decisions its profile
/// has), and every decision a committed golden rests on (`index.json`) is one of its own
/// profile's.
#[test]
fn cited_decisions_exist_in_the_spec() {
    let all: Vec<String> = gcl_model::Profile::builtin_names().flat_map(decisions_of).collect();
    let mut files = rust_files("conformance/src/suite");
    files.retain(|p| !p.ends_with("tests.rs"));
    let mut bad = Vec::new();
    let mut named = 0;
    for f in &files {
        for (n, line) in code_lines(f) {
            for (i, _) in line.match_indices(".decision(\"") {
                let rest = &line[i + ".decision(\"".len()..];
                let id = &rest[..rest.find('"').unwrap_or(rest.len())];
                named += 1;
                if !all.iter().any(|d| d == id) {
                    bad.push(format!("{}:{n}: `{id}`", rel(f)));
                }
            }
        }
    }
    // Case scripts cite decisions as `clause: decision:ID`.
    for p in files_with_ext("conformance/suite-cases", "gcls") {
        for (n, line) in std::fs::read_to_string(&p).unwrap().lines().enumerate() {
            if let Some(id) = line.trim().strip_prefix("clause:").and_then(|c| c.trim().strip_prefix("decision:")) {
                named += 1;
                if !all.iter().any(|d| d == id.trim()) {
                    bad.push(format!("{}:{}: `{}`", rel(&p), n + 1, id.trim()));
                }
            }
        }
    }
    assert!(named > 50, "found only {named} cited decisions: has the builder's method been renamed?");
    assert!(bad.is_empty(), "decisions cited by cases that no profile has:\n{}", bad.join("\n"));

    let index: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(Path::new(ROOT).join("vectors/suite/index.json")).unwrap())
            .unwrap();
    let mut bad = Vec::new();
    for c in index["cases"].as_array().unwrap() {
        let profile = c["profile"].as_str().unwrap();
        let own = decisions_of(profile);
        let cited = c["decisions"].as_array().unwrap().iter().chain(c["clauses"].as_array().unwrap());
        for d in cited.filter_map(|d| d.as_str()) {
            let id = d.strip_prefix("decision:").unwrap_or(d);
            if (d.starts_with("decision:") || !d.contains(':')) && !own.iter().any(|o| o == id) {
                bad.push(format!("{profile}/{}: `{id}`", c["id"].as_str().unwrap()));
            }
        }
    }
    assert!(bad.is_empty(), "goldens resting on decisions their profile lacks:\n{}", bad.join("\n"));
}

/// A checker of `vectors/schema/transcript.abnf`, rule by rule (the rule each function
/// follows is named in its comment). It checks the shape the grammar gives, not the rules the
/// grammar leaves to prose (the parser in `gcl-transcript` checks those).
mod abnf {
    fn wsp(c: u8) -> bool {
        c == b' ' || c == b'\t'
    }

    fn vchar_or_wsp(c: char) -> bool {
        c == ' ' || c == '\t' || ('\x21'..='\x7e').contains(&c)
    }

    fn digits(s: &str, max: usize) -> bool {
        !s.is_empty() && s.len() <= max && s.bytes().all(|b| b.is_ascii_digit())
    }

    /// `duration = 1*12DIGIT ("ms" / "s")`
    fn duration(s: &str) -> bool {
        s.strip_suffix("ms").or_else(|| s.strip_suffix('s')).is_some_and(|d| digits(d, 12))
    }

    /// `integer = ["-"] 1*18DIGIT`
    fn integer(s: &str) -> bool {
        digits(s.strip_prefix('-').unwrap_or(s), 18)
    }

    /// `range = integer ".." integer`
    fn range(s: &str) -> bool {
        s.split_once("..").is_some_and(|(a, b)| integer(a) && integer(b))
    }

    /// `name = LC-ALPHA *31(LC-ALPHA / DIGIT / "_")`
    fn name(s: &str) -> bool {
        s.len() <= 32
            && s.starts_with(|c: char| c.is_ascii_lowercase())
            && s.bytes().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == b'_')
    }

    /// `setup-value = "object" 1*WSP motor 1*WSP position`, `motor = %x31-34`,
    /// `position = "0" / (%x31-39 *6DIGIT)`
    fn setup_value(s: &str) -> bool {
        let w: Vec<&str> = s.split([' ', '\t']).filter(|w| !w.is_empty()).collect();
        matches!(w.as_slice(), ["object", m, p]
            if matches!(*m, "1" | "2" | "3" | "4") && (*p == "0" || factor(p)))
    }

    /// `factor = %x31-39 *6DIGIT`
    fn factor(s: &str) -> bool {
        digits(s, 7) && !s.starts_with('0')
    }

    /// `relation = name ["*" factor] ["/" factor] SP "+-" percent "%"`, as its two words.
    fn relation(term: &str, tol: &str) -> bool {
        let (head, den) = term.split_once('/').unwrap_or((term, "1"));
        let (n, num) = head.split_once('*').unwrap_or((head, "1"));
        // percent = "0" / %x31-39 *2DIGIT
        let pct = tol.strip_prefix("+-").and_then(|t| t.strip_suffix('%'));
        name(n) && factor(num) && factor(den) && pct.is_some_and(|p| p == "0" || (digits(p, 3) && !p.starts_with('0')))
    }

    /// `elision = "{" ("int" [SP range] / "line" / "any" / "text" / "byte" / type SP range / value) "}"`
    /// and `value = type [SP (range / relation)] [SP "as" SP name]`, given what is between the
    /// braces.
    fn elision(inner: &str) -> bool {
        let mut words: Vec<&str> = inner.split(' ').collect();
        if words.len() >= 3 && words[words.len() - 2] == "as" && name(words[words.len() - 1]) {
            words.truncate(words.len() - 2);
            return matches!(words[0], "int" | "u8" | "i8" | "u16" | "i16")
                && match &words[1..] {
                    [] => true,
                    [r] => range(r),
                    [t, p] => relation(t, p),
                    _ => false,
                };
        }
        match words.as_slice() {
            [w] => matches!(*w, "int" | "line" | "any" | "text" | "byte"),
            [t, r] => matches!(*t, "int" | "u8" | "i8" | "u16" | "i16") && range(r),
            [t, a, b] => matches!(*t, "int" | "u8" | "i8" | "u16" | "i16") && relation(a, b),
            _ => false,
        }
    }

    /// `send-string` / `expect-string`: `DQUOTE *(plain / escape [/ elision]) DQUOTE`. Returns
    /// the rest of the line after the closing quote.
    fn string(s: &str, elisions: bool) -> Result<&str, String> {
        let b = s.as_bytes();
        if b.first() != Some(&b'"') {
            return Err(format!("expected a string at `{s}`"));
        }
        let mut i = 1;
        loop {
            match b.get(i) {
                None => return Err("string without its closing quote".into()),
                Some(b'"') => return Ok(&s[i + 1..]),
                Some(b'\\') => match b.get(i + 1) {
                    Some(b'n' | b'r' | b't' | b'\\') => i += 2,
                    Some(b'x') if b.get(i + 2..i + 4).is_some_and(|h| h.iter().all(u8::is_ascii_hexdigit)) => i += 4,
                    _ => return Err(format!("bad escape at `{}`", &s[i..])),
                },
                Some(b'{') if elisions => {
                    let end = s[i..].find('}').ok_or("`{` without `}`")?;
                    if !elision(&s[i + 1..i + end]) {
                        return Err(format!("bad elision `{}`", &s[i..=i + end]));
                    }
                    i += end + 1;
                }
                // plain = %x20-21 / %x23-5B / %x5D-7A / %x7C-7E
                Some(&c) if (0x20..=0x7e).contains(&c) && c != b'{' => i += 1,
                Some(&c) => return Err(format!("byte {c:#04x} is not `plain`")),
            }
        }
    }

    /// A body line without its leading and trailing WSP: `pause / send / expect`.
    fn body(t: &str) -> Result<(), String> {
        let (word, rest) = t.split_once(|c: char| wsp(c as u8)).unwrap_or((t, ""));
        let rest = rest.trim_start_matches([' ', '\t']);
        match word {
            "pause" if duration(rest) => Ok(()),
            "send" if rest.starts_with('"') => string(rest, false)
                .and_then(|r| if r.is_empty() { Ok(()) } else { Err(format!("after the string: `{r}`")) }),
            "send" => hex(rest, false),
            "expect" => {
                let mut rest = rest;
                if let Some(r) = rest.strip_prefix("within") {
                    let r = r.trim_start_matches([' ', '\t']);
                    let (d, r) = r.split_once([' ', '\t']).unwrap_or((r, ""));
                    // [duration ".."] duration
                    let (lower, d) = d.split_once("..").map_or(("1ms", d), |(a, b)| (a, b));
                    if !duration(d) || !duration(lower) {
                        return Err(format!("bad duration `{d}`"));
                    }
                    rest = r.trim_start_matches([' ', '\t']);
                }
                // *(1*WSP segment); segment = expect-string / "hex" *(1*WSP hextoken)
                while !rest.is_empty() {
                    if rest.starts_with('"') {
                        rest = string(rest, true)?.trim_start_matches([' ', '\t']);
                    } else {
                        let end = rest.find('"').unwrap_or(rest.len());
                        hex(rest[..end].trim_end(), true)?;
                        rest = &rest[end..];
                    }
                }
                Ok(())
            }
            _ => Err(format!("not a pause, send or expect: `{t}`")),
        }
    }

    /// `"hex" *(1*WSP hexbyte)`, or with `hextoken = hexbyte / "??" / elision`.
    fn hex(s: &str, tokens: bool) -> Result<(), String> {
        let mut words = s.split([' ', '\t']).filter(|w| !w.is_empty());
        if words.next() != Some("hex") {
            return Err(format!("expected `hex` at `{s}`"));
        }
        // An elision holds a space (`{u16 0..9}`): join the words back inside braces.
        let mut pending = String::new();
        for w in words {
            if !pending.is_empty() || (tokens && w.starts_with('{') && !w.ends_with('}')) {
                pending.push_str(if pending.is_empty() { "" } else { " " });
                pending.push_str(w);
                if !w.ends_with('}') {
                    continue;
                }
            }
            let w = if pending.is_empty() { w.to_string() } else { std::mem::take(&mut pending) };
            let byte = w.len() == 2 && w.bytes().all(|c| c.is_ascii_hexdigit());
            let token =
                tokens && (w == "??" || w.strip_prefix('{').and_then(|x| x.strip_suffix('}')).is_some_and(elision));
            if !byte && !token {
                return Err(format!("bad hex token `{w}`"));
            }
        }
        if pending.is_empty() { Ok(()) } else { Err(format!("`{pending}` without `}}`")) }
    }

    /// `transcript = *ignored magic eol *(header-line / ignored) *(body-line / ignored)`.
    pub fn check(text: &str) -> Result<(), String> {
        // eol = [CR] LF: every line, the last included, ends with LF.
        let Some(text) = text.strip_suffix('\n') else { return Err("the last line has no LF".into()) };
        let mut seen_magic = false;
        let mut in_body = false;
        for (n, raw) in text.split('\n').enumerate() {
            let line = raw.strip_suffix('\r').unwrap_or(raw);
            let at = |e: String| format!("line {}: {e}", n + 1);
            let t = line.trim_matches([' ', '\t']);
            // ignored = *WSP [comment] eol; comment = "#" *VCHAR-OR-WSP
            if t.is_empty() || t.starts_with('#') {
                if !t.chars().all(vchar_or_wsp) {
                    return Err(at("a comment with a control or non-ASCII character".into()));
                }
                continue;
            }
            if !seen_magic {
                // magic = *WSP "gcl-transcript 1" *WSP
                if t != "gcl-transcript 1" {
                    return Err(at(format!("expected the magic line, got `{t}`")));
                }
                seen_magic = true;
                continue;
            }
            let header = t.split_once(':').filter(|(k, _)| {
                matches!(*k, "id" | "title" | "clause" | "level" | "profile" | "requires" | "setup" | "note")
                    || k.strip_prefix("x-").is_some_and(|x| {
                        !x.is_empty() && x.bytes().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == b'-')
                    })
            });
            match header {
                // header-line = *WSP key ":" *WSP value *WSP eol, before any body line
                Some((k, v)) if !in_body => {
                    let v = v.trim_matches([' ', '\t']);
                    if v.is_empty() || v.chars().any(|c| c.is_control() && c != '\t') {
                        return Err(at(format!("bad header value `{v}`")));
                    }
                    if k == "setup" && !setup_value(v) {
                        return Err(at(format!("bad setup `{v}`")));
                    }
                }
                _ => {
                    in_body = true;
                    body(t).map_err(at)?;
                }
            }
        }
        if seen_magic { Ok(()) } else { Err("no magic line".into()) }
    }
}

/// Architecture invariant: every committed golden is a sentence of the published grammar,
/// `vectors/schema/transcript.abnf`, so an implementer who writes a parser from the grammar
/// alone reads every file.
#[test]
fn goldens_match_the_abnf_grammar() {
    let grammar = std::fs::read_to_string(Path::new(ROOT).join("vectors/schema/transcript.abnf")).unwrap();
    // The checker follows these rules; one renamed or removed in the grammar must be followed here.
    for rule in [
        "transcript",
        "header-line",
        "body-line",
        "expect-string",
        "elision",
        "hextoken",
        "duration",
        "value",
        "relation",
        "setup-value",
    ] {
        assert!(grammar.lines().any(|l| l.starts_with(&format!("{rule} "))), "rule `{rule}` left the grammar");
    }
    let goldens = files_with_ext("vectors/suite", "gcl");
    let mut bad = Vec::new();
    for p in &goldens {
        if let Err(e) = abnf::check(&std::fs::read_to_string(p).unwrap()) {
            bad.push(format!("{}: {e}", rel(p)));
        }
    }
    assert!(goldens.len() > 100, "only {} goldens found", goldens.len());
    assert!(bad.is_empty(), "goldens the grammar rejects:\n{}", bad.join("\n"));
    // The checker is not a yes-machine.
    for wrong in [
        "gcl-transcript 1\nsend \"x\"\nid: late\n",
        "gcl-transcript 1\nsend \"a\\qb\"\n",
        "gcl-transcript 1\nexpect \"{int 5}\"\n",
        "gcl-transcript 1\nexpect hex 0G\n",
        "gcl-transcript 1\npause soon\n",
        "gcl-transcript 2\n",
        "gcl-transcript 1\nsend \"x\"",
        "gcl-transcript 1\nexpect \"{int 2*p +-5%}\"\n",
        "gcl-transcript 1\nexpect \"{int p*2 5%}\"\n",
        "gcl-transcript 1\nexpect \"{line as p}\"\n",
        "gcl-transcript 1\nexpect \"{text as p}\"\n",
        "gcl-transcript 1\nexpect \"{texts}\"\n",
        "gcl-transcript 1\nexpect within 1s.. \"x\"\n",
        "gcl-transcript 1\nsetup: object 5 100\n",
        "gcl-transcript 1\nsetup: object 1 0100\n",
    ] {
        assert!(abnf::check(wrong).is_err(), "the checker took {wrong:?}");
    }
    abnf::check(
        "gcl-transcript 1\nid: a\n\nsend hex 43 00\nexpect within 2s \"C\" hex {u16 0..9} ?? 2A \"{int}\\n\\r\"\n",
    )
    .unwrap();
    abnf::check("gcl-transcript 1\nexpect \"VERS\\n\\r{text}\\n\\r=> \"\n").unwrap();
    abnf::check("gcl-transcript 1\nexpect within 1s..2s \"{int 1..9 as p} {int p*2/3 +-25%}\" hex {i8 p +-0% as q}\n")
        .unwrap();
}

/// What `cargo test --workspace` leaves out, CI still runs (issue 33 item 4): every ignored
/// test is in the slow group, `#[ignore = "slow: ..."]`, which `.ci/run` runs with
/// `--include-ignored`, or is a report that is no gate and that `.ci/run` skips by name. The
/// test step also skips one slow test whose commands another step of `.ci/run` runs as they are.
#[test]
fn every_test_left_out_of_the_default_run_is_run_by_ci() {
    const SLOW: &str = "#[ignore = \"slow: .ci/run runs it (cargo test --workspace -- --include-ignored)\"]";
    const REPORTS: &[&str] = &["necessity_report"];
    // (test, what `.ci/run` runs instead: the same commands)
    const ELSEWHERE: &[(&str, &[&str])] = &[(
        "the_python_package_tests_pass",
        &["python3 -m unittest discover -s tests -t .", "python3 -m gcl_vectors check -q"],
    )];
    let ci = std::fs::read_to_string(Path::new(ROOT).join(".ci/run")).unwrap();
    for (test, commands) in ELSEWHERE {
        for c in *commands {
            assert!(ci.contains(c), ".ci/run skips {test} but does not run `{c}`");
        }
    }
    let skips: String =
        REPORTS.iter().chain(ELSEWHERE.iter().map(|(t, _)| t)).map(|r| format!(" --skip {r}")).collect();
    // The test step runs `cargo test --workspace TARGETS -- --include-ignored ... FILTERS` over
    // lanes of tests that together are all of them (`.ci/run` says how).
    let line = format!("-- --include-ignored{skips} \"$@\"");
    assert!(
        ci.lines().any(|l| l.contains("cargo test --workspace ") && l.trim_end().ends_with(&line)),
        ".ci/run does not run `cargo test --workspace ... {line}`"
    );
    let mut files = Vec::new();
    for dir in ["harness", "line", "conformance", "fuzzers", "reference-model", "host", "transcript", "fuzz/src"] {
        files.extend(files_with_ext(dir, "rs"));
    }
    let (mut slow, mut bad) = (0, Vec::new());
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        for (i, l) in lines.iter().enumerate() {
            let l = l.trim();
            if !l.starts_with("#[ignore") {
                continue;
            }
            let name = lines[i + 1..].iter().find_map(|n| n.trim().strip_prefix("fn ")).unwrap_or("");
            let name = name.split('(').next().unwrap_or("");
            if l == SLOW {
                slow += 1;
            } else if !REPORTS.contains(&name) {
                bad.push(format!("{}:{}: {l} (fn {name})", rel(f), i + 1));
            }
        }
    }
    assert!(bad.is_empty(), "ignored tests that CI would not run (use `{SLOW}`):\n{}", bad.join("\n"));
    assert!(slow > 0);
}

/// The library crates of the harness, lowest layer first (what the `gcl` binary's crate,
/// `gcl-harness`, re-exports under one name).
const LIBRARY_SRC: &[&str] = &["line/src", "conformance/src", "fuzzers/src"];

/// The workspace's crates by layer, lowest first: a crate may depend on the crates of the
/// layers below it, never on one of its own layer or above (the compiler then refuses a wrong
/// import: the crate it would name is not a dependency).
const LAYERS: &[&[&str]] = &[
    // the reference model: pure, no I/O, no clock
    &["gcl-model"],
    // the transcript format, and the host library (links, targets, the client)
    &["gcl-transcript", "gcl-host"],
    // the hand on its transports: the simulator, output files and digests, recording and replay
    &["gcl-line"],
    // conformance: the suite, its cases built from host actions, alignment, triage, pre-flight, deadlines, the motion probe, the runner, certificates, reports, vectors
    &["gcl-conformance"],
    // the fuzzers (device, host, merge, shard) and the host check built on the host fuzzer's sessions
    &["gcl-fuzzers"],
    // the command line (the `gcl` binary), which re-exports the layers below as `gcl_harness`
    &["gcl-harness"],
    // the cargo-fuzz targets
    &["gcl-fuzz"],
];

/// Code of a file with string and char literals emptied (their text is not a path).
fn without_literals(code: &str) -> String {
    let b = code.as_bytes();
    let mut out = String::with_capacity(code.len());
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        let ident_before = i > 0 && (b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_');
        if (c == b'r' || c == b'b') && !ident_before {
            // r"..", r#".."#, br"..", b".."
            let mut j = i + 1;
            if c == b'b' && j < b.len() && b[j] == b'r' {
                j += 1;
            }
            let hashes = b[j..].iter().take_while(|&&x| x == b'#').count();
            if j + hashes < b.len() && b[j + hashes] == b'"' && (hashes > 0 || b[j - 1] == b'r') {
                let close = format!("\"{}", "#".repeat(hashes));
                let start = j + hashes + 1;
                let end = code[start..].find(&close).map_or(b.len(), |k| start + k + close.len());
                out.push_str("\"\"");
                i = end;
                continue;
            }
        }
        if c == b'"' {
            let mut j = i + 1;
            while j < b.len() && b[j] != b'"' {
                j += if b[j] == b'\\' { 2 } else { 1 };
            }
            out.push_str("\"\"");
            i = j + 1;
            continue;
        }
        if c == b'\'' {
            // a char literal ('x', '\n', '\''), not a lifetime
            let rest = &code[i + 1..];
            let len = if rest.starts_with('\\') {
                rest.get(2..).and_then(|r| r.find('\'')).map(|k| k + 2)
            } else {
                rest.chars().next().map(char::len_utf8)
            };
            if let Some(l) = len
                && rest[l..].starts_with('\'')
            {
                out.push_str("' '");
                i += l + 2;
                continue;
            }
        }
        let ch = code[i..].chars().next().unwrap();
        out.push(ch);
        i += ch.len_utf8();
    }
    out
}

/// The paths of a `use` tree or an inline path starting at `s` (after its root keyword):
/// `a::b::{c, d::e}` gives `a::b::c` and `a::b::d::e`; `self` in a group names the prefix.
fn path_tree(s: &str) -> Vec<Vec<String>> {
    fn tree(s: &[u8], i: &mut usize) -> Vec<Vec<String>> {
        let skip = |i: &mut usize| {
            while *i < s.len() && s[*i].is_ascii_whitespace() {
                *i += 1;
            }
        };
        skip(i);
        if *i < s.len() && s[*i] == b'{' {
            *i += 1;
            let mut all = Vec::new();
            loop {
                skip(i);
                if *i >= s.len() || s[*i] == b'}' {
                    *i += 1;
                    break;
                }
                all.extend(tree(s, i));
                skip(i);
                if *i < s.len() && s[*i] == b',' {
                    *i += 1;
                }
            }
            return all;
        }
        let start = *i;
        while *i < s.len() && (s[*i].is_ascii_alphanumeric() || s[*i] == b'_') {
            *i += 1;
        }
        let seg = String::from_utf8_lossy(&s[start..*i]).into_owned();
        if seg.is_empty() {
            // `*` or the end of the path
            if *i < s.len() && s[*i] == b'*' {
                *i += 1;
            }
            return vec![Vec::new()];
        }
        let mut j = *i;
        skip(&mut j);
        if s[j..].starts_with(b"::") {
            *i = j + 2;
            let rest = tree(s, i);
            return rest
                .into_iter()
                .map(|mut r| {
                    if seg != "self" {
                        r.insert(0, seg.clone());
                    }
                    r
                })
                .collect();
        }
        // `x as y` keeps `x`
        if s[j..].starts_with(b"as ") {
            *i = j + 3;
            skip(i);
            while *i < s.len() && (s[*i].is_ascii_alphanumeric() || s[*i] == b'_') {
                *i += 1;
            }
        }
        if seg == "self" { vec![Vec::new()] } else { vec![vec![seg]] }
    }
    let mut i = 0;
    tree(s.as_bytes(), &mut i)
}

/// One crate's file-level module graph: each module (a file, named by its path in the crate)
/// and the other modules its code names through `crate::`, `super::`, `self::` (and, in the
/// harness, `gcl_harness::`). A module naming one of its own descendants is not an arrow (a
/// module holds its children); a child naming its parent is.
fn module_graph(src: &str) -> std::collections::BTreeMap<String, std::collections::BTreeSet<String>> {
    use std::collections::{BTreeMap, BTreeSet};
    let files = rust_files(src);
    let module_of = |p: &Path| -> String {
        let r = p.strip_prefix(Path::new(ROOT).join(src)).unwrap().with_extension("");
        let parts: Vec<String> = r.iter().map(|s| s.to_string_lossy().into_owned()).collect();
        let parts: Vec<&str> = parts.iter().map(String::as_str).filter(|s| *s != "mod").collect();
        if parts == ["lib"] || parts == ["main"] { String::new() } else { parts.join("::") }
    };
    let modules: BTreeSet<String> = files.iter().map(|p| module_of(p)).collect();
    let mut graph = BTreeMap::new();
    for f in &files {
        let me = module_of(f);
        let code: Vec<String> = code_lines(f).into_iter().map(|(_, l)| l).collect();
        let code = without_literals(&code.join("\n"));
        let mut targets = BTreeSet::new();
        let b = code.as_bytes();
        for root in ["crate::", "super::", "self::", "gcl_harness::"] {
            for (at, _) in code.match_indices(root) {
                if at > 0 && (b[at - 1].is_ascii_alphanumeric() || b[at - 1] == b'_' || b[at - 1] == b':') {
                    continue;
                }
                let mut base: Vec<&str> = if root == "crate::" || root == "gcl_harness::" || me.is_empty() {
                    Vec::new()
                } else {
                    me.split("::").collect()
                };
                let mut rest = &code[at + root.len()..];
                if root == "super::" {
                    base.pop();
                    while let Some(r) = rest.strip_prefix("super::") {
                        base.pop();
                        rest = r;
                    }
                }
                for path in path_tree(rest) {
                    let full: Vec<&str> = base.iter().copied().chain(path.iter().map(String::as_str)).collect();
                    let target = (1..=full.len()).rev().map(|k| full[..k].join("::")).find(|m| modules.contains(m));
                    if let Some(t) = target
                        && t != me
                        && !(me.is_empty() || t.starts_with(&format!("{me}::")))
                    {
                        targets.insert(t);
                    }
                }
            }
        }
        graph.insert(me, targets);
    }
    graph
}

/// The groups of modules that reach each other (strongly connected, more than one module).
fn cycles(graph: &std::collections::BTreeMap<String, std::collections::BTreeSet<String>>) -> Vec<Vec<String>> {
    use std::collections::BTreeSet;
    let reach = |from: &String| -> BTreeSet<String> {
        let mut seen = BTreeSet::new();
        let mut stack = vec![from.clone()];
        while let Some(m) = stack.pop() {
            for t in graph.get(&m).into_iter().flatten() {
                if seen.insert(t.clone()) {
                    stack.push(t.clone());
                }
            }
        }
        seen
    };
    let reaches: std::collections::BTreeMap<&String, BTreeSet<String>> = graph.keys().map(|m| (m, reach(m))).collect();
    let mut done = BTreeSet::new();
    let mut out = Vec::new();
    for m in graph.keys() {
        if done.contains(m) || !reaches[m].contains(m) {
            continue;
        }
        let group: Vec<String> = reaches[m].iter().filter(|o| reaches[*o].contains(m)).cloned().collect();
        done.extend(group.iter().cloned());
        out.push(group);
    }
    out
}

/// Architecture invariant: no circles between files. In every crate, no two modules (files)
/// depend on each other, directly or round a circle: what two files share lives in the one
/// that owns it, or in a module both stand on.
#[test]
fn no_circles_between_files() {
    let mut bad = Vec::new();
    for src in [
        "reference-model/src",
        "transcript/src",
        "host/src",
        "line/src",
        "conformance/src",
        "fuzzers/src",
        "harness/src",
        "fuzz/src",
    ] {
        let graph = module_graph(src);
        for group in cycles(&graph) {
            let arrows: Vec<String> = group
                .iter()
                .flat_map(|m| graph[m].iter().filter(|t| group.contains(t)).map(move |t| format!("{m} -> {t}")))
                .collect();
            bad.push(format!("{src}: {}\n    {}", group.join(" <-> "), arrows.join("\n    ")));
        }
    }
    assert!(bad.is_empty(), "modules in a circle:\n{}", bad.join("\n"));
}

/// Architecture invariant: the workspace's layers (`LAYERS`) hold. Every crate has its layer,
/// and its manifest names as dependencies only crates of the layers below it (the compiler does
/// the rest); the `gcl` binary's crate holds no library module of its own (only `cli/`,
/// `main.rs` and the re-exports of `lib.rs`).
#[test]
fn no_crate_depends_on_its_layer_or_one_above() {
    let layer_of = |c: &str| LAYERS.iter().position(|l| l.contains(&c));
    let root: toml::Table = std::fs::read_to_string(Path::new(ROOT).join("Cargo.toml")).unwrap().parse().unwrap();
    let members: Vec<String> =
        root["workspace"]["members"].as_array().unwrap().iter().map(|m| m.as_str().unwrap().to_string()).collect();
    let mut bad = Vec::new();
    for dir in &members {
        let manifest: toml::Table =
            std::fs::read_to_string(Path::new(ROOT).join(dir).join("Cargo.toml")).unwrap().parse().unwrap();
        let name = manifest["package"]["name"].as_str().unwrap().to_string();
        let Some(mine) = layer_of(&name) else {
            bad.push(format!("{dir}: crate {name} has no layer in LAYERS"));
            continue;
        };
        for table in ["dependencies", "build-dependencies"] {
            let deps = manifest.get(table).and_then(|t| t.as_table()).cloned().unwrap_or_default();
            for dep in deps.keys() {
                if let Some(theirs) = layer_of(dep)
                    && theirs >= mine
                {
                    bad.push(format!("{name} (layer {mine}) -> {dep} (layer {theirs})"));
                }
            }
        }
    }
    assert_eq!(members.len(), LAYERS.iter().map(|l| l.len()).sum::<usize>(), "LAYERS lists every member");
    let own: Vec<String> = std::fs::read_dir(Path::new(ROOT).join("harness/src"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !["cli", "main.rs", "lib.rs"].contains(&n.as_str()))
        .collect();
    assert!(own.is_empty(), "library modules in the binary's crate (they belong in a layer's crate): {own:?}");
    assert!(bad.is_empty(), "arrows up the layers:\n{}", bad.join("\n"));
}
