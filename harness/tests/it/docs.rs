//! The docs checker (issue 33): every command README.md, the guides of `docs/src/` and every
//! `gcl ... --help` give is run, and what it prints is compared with what the document shows.
//!
//! - A `console` block of a document is run as written, in trycmd's format: each `$ ` line
//!   (`> ` lines continue it; a `? N` line after it is its exit code, 0 when none is given) is
//!   run in a folder of the file's own, in the file's order, and what it prints (stdout and
//!   stderr together) is compared by snapbox with the lines below it: `...` stands for any
//!   lines, `[..]` for any text in a line. (snapbox, not trycmd's own runner: trycmd turns
//!   every `\` of a command's output into `/`, for Windows paths, and GCL's answers are
//!   written with escapes, `"FGET DP\n\r1000"`.)
//! - A command in an `sh` block, or in a `--help`'s examples, is either run as written by a
//!   `console` block somewhere (a document's or a stand-in's), or quoted by a stand-in: a
//!   `## ` heading of a file in `harness/tests/stand-ins/` followed by the `console` block that
//!   runs in its place (the in-process model for a hand on `/dev/ttyUSB0`, the example host for
//!   a host author's own program, seconds for minutes), or by `Run by FILE: `TEXT`` (a file
//!   of the repository that CI runs, `.ci/run` or a test, holds each TEXT: checked), or by
//!   `Not run: WHY`.
//!
//! [`every_documented_command_is_run`] fails on a command nobody runs, a stand-in for a command
//! no document has any more, a `console` block marked `ignore` (trycmd's way to skip one), a
//! program the checker does not run. Fenced blocks whose info string has `file=NAME` are the
//! files the examples read: they are written into every folder the commands run in, with
//! `stand-ins/lib.sh`, the stand-ins' shell helpers.

use crate::deps;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

const GCL: &str = env!("CARGO_BIN_EXE_gcl");

/// The programs a document's `console` block may run: the `gcl` under test (what a reader
/// types must be what runs).
const DOC_BINS: &[&str] = &["gcl"];

/// The programs a stand-in may run besides: a shell (for a background `gcl sim`, a pipe, a
/// folder of the checkout, Python) and the host library's examples.
const STAND_IN_BINS: &[&str] = &["gcl", "sh", "host_scenario", "realtime", "supervisory"];

/// The example programs of this package the stand-ins run.
const EXAMPLES: &[&str] = &["host_scenario", "realtime", "supervisory"];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..").canonicalize().unwrap()
}

/// A Markdown file: where it is and what it says.
struct Doc {
    path: PathBuf,
    text: String,
}

fn read_docs(files: Vec<PathBuf>) -> Vec<Doc> {
    files.into_iter().map(|path| Doc { text: std::fs::read_to_string(&path).unwrap(), path }).collect()
}

fn md_files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    files.sort();
    files
}

/// README.md and the chapters of the book, with `vectors/README.md`, which the book's vectors
/// chapter includes whole.
fn documents() -> Vec<Doc> {
    let mut files = vec![root().join("README.md")];
    files.extend(md_files(&root().join("docs/src")));
    files.push(root().join("vectors/README.md"));
    read_docs(files)
}

fn stand_ins() -> Vec<Doc> {
    read_docs(md_files(&root().join("harness/tests/stand-ins")))
}

/// A fenced block: its info string, its lines, and the line of the document it opens on.
struct Block {
    info: String,
    lines: Vec<String>,
    line: usize,
}

impl Block {
    fn lang(&self) -> &str {
        self.info.split([',', ' ']).next().unwrap_or("")
    }
    fn is_console(&self) -> bool {
        matches!(self.lang(), "console" | "trycmd")
    }
    /// The file this block is, when its info string says `file=NAME`.
    fn file(&self) -> Option<&str> {
        self.info.split([',', ' ']).find_map(|w| w.strip_prefix("file="))
    }
}

/// The fenced blocks of `text`, each closed by a line that starts with its opening fence, with
/// the `## ` heading each one comes under.
fn blocks(text: &str) -> Vec<(Option<String>, Block)> {
    let mut out = Vec::new();
    let mut heading = None;
    let mut lines = text.lines().enumerate();
    while let Some((i, line)) = lines.next() {
        if let Some(h) = line.strip_prefix("## ") {
            heading = Some(h.to_string());
            continue;
        }
        let ticks = line.chars().take_while(|&c| c == '`').count();
        if ticks < 3 {
            continue;
        }
        let fence = &line[..ticks];
        let mut block = Block { info: line[ticks..].trim().to_string(), lines: Vec::new(), line: i + 1 };
        for (_, l) in lines.by_ref() {
            if l.starts_with(fence) {
                break;
            }
            block.lines.push(l.to_string());
        }
        out.push((heading.clone(), block));
    }
    out
}

/// One `$ ` command of a `console` block, in trycmd's format: the command (`> ` lines continue
/// it) as its words, leading `NAME=VALUE` words included; the exit code a `? N` line after it
/// gives (0 without one); and the lines it prints, up to the next command or the block's end.
struct Step {
    line: usize,
    words: Vec<String>,
    status: i32,
    expected: String,
    /// Whether the command goes on in trycmd's `> ` lines, which a shell cannot take: a
    /// document continues a command as a shell does, with `\` at the end of the line.
    continued_by_gt: bool,
}

/// A command line's words, and whether it ends in `\` (the next line goes on with it).
fn command_words(text: &str) -> (Vec<String>, bool) {
    let text = text.trim();
    match text.strip_suffix('\\') {
        Some(head) => (shlex::Shlex::new(head).collect(), true),
        None => (shlex::Shlex::new(text).collect(), false),
    }
}

fn steps(block: &Block) -> Vec<Step> {
    let mut out: Vec<Step> = Vec::new();
    let mut in_command = false;
    // The command's last line ended in `\`: the next line goes on with it, as in a shell.
    let mut goes_on = false;
    for (i, l) in block.lines.iter().enumerate() {
        if goes_on && let Some(step) = out.last_mut() {
            let (more, on) = command_words(l);
            step.words.extend(more);
            goes_on = on;
            continue;
        }
        if let Some(cmd) = l.strip_prefix("$ ") {
            let line = block.line + 1 + i;
            let (words, on) = command_words(cmd);
            goes_on = on;
            out.push(Step { line, words, status: 0, expected: String::new(), continued_by_gt: false });
            in_command = true;
            continue;
        }
        let Some(step) = out.last_mut() else { continue };
        if in_command && let Some(more) = l.strip_prefix("> ") {
            step.words.extend(shlex::Shlex::new(more.trim()));
            step.continued_by_gt = true;
            continue;
        }
        if in_command && let Some(status) = l.strip_prefix("? ") {
            step.status = match status.trim() {
                "success" => 0,
                "failed" => 1,
                n => n.parse().unwrap_or(-1),
            };
            in_command = false;
            continue;
        }
        in_command = false;
        step.expected.push_str(l);
        step.expected.push('\n');
    }
    for step in &mut out {
        let trimmed = step.expected.trim_end_matches('\n');
        step.expected = if trimmed.is_empty() { String::new() } else { format!("{trimmed}\n") };
    }
    out
}

fn console_commands(block: &Block) -> Vec<Vec<String>> {
    steps(block).into_iter().map(|s| s.words).collect()
}

/// The program a command runs: its first word that is not an environment assignment.
fn program(words: &[String]) -> &str {
    words.iter().find(|w| !w.contains('=')).map_or("", String::as_str)
}

/// The command lines of an `sh` block: continuations joined, comments dropped.
fn sh_commands(block: &Block) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    for line in &block.lines {
        let line = line.trim();
        let joined = if cur.is_empty() { line.to_string() } else { format!("{cur} {line}") };
        if let Some(head) = joined.strip_suffix('\\') {
            cur = head.trim_end().to_string();
            continue;
        }
        cur.clear();
        if joined.is_empty() || joined.starts_with('#') {
            continue;
        }
        // A comment after the command: two or more spaces, then `# `.
        out.push(match joined.find("  #") {
            Some(i) => joined[..i].trim_end().to_string(),
            None => joined,
        });
    }
    out
}

fn words(command: &str) -> Vec<String> {
    shlex::Shlex::new(command).collect()
}

fn help(path: &[&str]) -> String {
    let o = Command::new(GCL).args(path).arg("--help").output().unwrap();
    assert!(o.status.success(), "gcl {path:?} --help");
    String::from_utf8(o.stdout).unwrap()
}

/// Every subcommand path, from the `Commands:` lists of the help texts.
fn command_paths() -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let mut todo: Vec<Vec<String>> = vec![vec![]];
    while let Some(p) = todo.pop() {
        let args: Vec<&str> = p.iter().map(String::as_str).collect();
        let text = help(&args);
        if let Some(i) = text.find("\nCommands:\n") {
            for l in text[i + 11..].lines().take_while(|l| !l.trim().is_empty()) {
                // A name starts two spaces in; a wrapped description sits deeper.
                if let Some(name) =
                    l.strip_prefix("  ").filter(|r| !r.starts_with(' ')).and_then(|r| r.split_whitespace().next())
                    && name != "help"
                {
                    let mut q = p.clone();
                    q.push(name.to_string());
                    todo.push(q);
                }
            }
        }
        out.push(p);
    }
    out
}

/// The example lines of every `--help`: the lines of its `Example(s):` section, and any other
/// line that starts with `cargo run`; and the lines of an examples section that do not start a
/// command (one that wrapped cannot be pasted).
fn help_examples() -> (Vec<String>, Vec<String>) {
    let (mut out, mut wrapped) = (Vec::new(), Vec::new());
    for p in command_paths() {
        let args: Vec<&str> = p.iter().map(String::as_str).collect();
        let mut in_examples = false;
        let mut cur = String::new();
        for l in help(&args).lines() {
            // A line ending in `\` goes on, as in a shell.
            let joined = if cur.is_empty() { l.trim().to_string() } else { format!("{cur} {}", l.trim()) };
            if in_examples && let Some(head) = joined.strip_suffix('\\') {
                cur = head.trim_end().to_string();
                continue;
            }
            cur.clear();
            let t = joined.as_str();
            if t == "Example:" || t == "Examples:" {
                in_examples = true;
                continue;
            }
            if t.is_empty() {
                in_examples = false;
                continue;
            }
            let starts = t.starts_with("gcl ") || t.starts_with("cargo run");
            if in_examples && !starts {
                wrapped.push(format!("gcl {}: {t}", p.join(" ")));
            } else if in_examples || t.starts_with("cargo run") {
                // A comment after the command, as in the documents' `sh` blocks.
                out.push(t.find("  #").map_or(t, |i| t[..i].trim_end()).to_string());
            }
        }
    }
    (out, wrapped)
}

/// Everything that would let a documented command go unrun. `help` is the `--help` examples.
fn check(docs: &[Doc], stand_ins: &[Doc], help: &[String]) -> Vec<String> {
    check_and_count(docs, stand_ins, help).0
}

/// [`check`], and how many documented commands are held each way.
fn check_and_count(docs: &[Doc], stand_ins: &[Doc], help: &[String]) -> (Vec<String>, BTreeMap<&'static str, usize>) {
    let mut wrong = Vec::new();
    let mut count: BTreeMap<&'static str, usize> = BTreeMap::new();
    // How each stand-in holds its command: runs a console block, or `Run by`, or `Not run`.
    let mut held_by: BTreeMap<Vec<String>, &'static str> = BTreeMap::new();
    let mut run: BTreeSet<Vec<String>> = BTreeSet::new();
    // Each documented command, by its words, with where it is written.
    let mut documented: BTreeMap<Vec<String>, String> = BTreeMap::new();
    for h in help {
        documented.insert(words(h), format!("`{h}` (a --help example)"));
    }
    // Each stand-in: its heading's command, where, and whether it runs or says why not.
    let mut quoted: BTreeMap<Vec<String>, String> = BTreeMap::new();
    for (set, is_stand_in) in [(docs, false), (stand_ins, true)] {
        let bins = if is_stand_in { STAND_IN_BINS } else { DOC_BINS };
        for doc in set {
            let name = doc.path.strip_prefix(root()).unwrap_or(&doc.path).display().to_string();
            let mut sections: BTreeMap<String, (usize, Option<&'static str>)> = BTreeMap::new();
            for (heading, block) in blocks(&doc.text) {
                let at = format!("{name}:{}", block.line);
                if block.is_console() {
                    if block.info.split(',').any(|a| a.trim() == "ignore") {
                        wrong.push(format!("{at}: a console block marked `ignore` is not run"));
                    }
                    let commands = console_commands(&block);
                    if commands.is_empty() {
                        wrong.push(format!("{at}: a console block with no `$ ` command"));
                    }
                    // What a reader pastes must be what a shell takes.
                    for s in steps(&block).iter().filter(|s| s.continued_by_gt && !is_stand_in) {
                        wrong.push(format!(
                            "{name}:{}: `{}` goes on in `> ` lines, which a shell cannot take: end its lines in `\\`",
                            s.line,
                            s.words.join(" ")
                        ));
                    }
                    for c in commands {
                        if !bins.contains(&program(&c)) {
                            wrong.push(format!(
                                "{at}: `{}` runs `{}`, which the checker does not run here (it runs {bins:?})",
                                c.join(" "),
                                program(&c)
                            ));
                        }
                        if !is_stand_in {
                            *count.entry("console commands of the documents, run as written").or_default() += 1;
                        }
                        run.insert(c);
                    }
                    if is_stand_in {
                        match &heading {
                            Some(h) => sections.entry(h.clone()).or_default().0 += 1,
                            None => wrong.push(format!(
                                "{at}: a stand-in's commands go under the `## ` heading that quotes what they stand for"
                            )),
                        }
                    }
                }
                if block.lang() == "sh" && !is_stand_in {
                    for c in sh_commands(&block) {
                        documented.entry(words(&c)).or_insert(format!("`{c}` ({at})"));
                    }
                }
            }
            if !is_stand_in {
                continue;
            }
            // The headings, and the sections that say why they are not run.
            let mut heading: Option<&str> = None;
            for (i, line) in doc.text.lines().enumerate() {
                if let Some(h) = line.strip_prefix("## ") {
                    heading = Some(h);
                    let Some(cmd) = h.strip_prefix('`').and_then(|h| h.strip_suffix('`')) else {
                        wrong.push(format!(
                            "{name}:{}: a stand-in's heading is the command it stands for, in backticks",
                            i + 1
                        ));
                        continue;
                    };
                    if quoted.insert(words(cmd), format!("{name}:{}", i + 1)).is_some() {
                        wrong.push(format!("{name}:{}: `{cmd}` has two stand-ins", i + 1));
                    }
                    sections.entry(h.to_string()).or_default();
                } else if line.starts_with("Not run: ")
                    && let Some(h) = heading
                {
                    sections.entry(h.to_string()).or_default().1 = Some("not run (a reason given)");
                } else if let Some(rest) = line.strip_prefix("Run by ")
                    && let Some(h) = heading
                {
                    // `Run by FILE: `TEXT`...`: FILE (of the repository, which CI runs) holds
                    // each TEXT, so the claim is checked, not taken on trust.
                    sections.entry(h.to_string()).or_default().1 =
                        Some("run by another part of CI (checked in its file)");
                    let at = format!("{name}:{}", i + 1);
                    let Some((file, texts)) = rest.split_once(": ") else {
                        wrong.push(format!("{at}: `Run by FILE: `TEXT``, FILE holding each TEXT"));
                        continue;
                    };
                    let Ok(held) = std::fs::read_to_string(root().join(file)) else {
                        wrong.push(format!("{at}: run by {file}, which is not a file of the repository"));
                        continue;
                    };
                    let texts: Vec<&str> = texts.split('`').skip(1).step_by(2).collect();
                    if texts.is_empty() {
                        wrong.push(format!("{at}: run by {file}, but no `TEXT` says what it runs"));
                    }
                    for text in texts {
                        if !held.contains(text) {
                            wrong.push(format!("{at}: run by {file}, which does not hold `{text}`"));
                        }
                    }
                }
            }
            for (h, (blocks, not_run)) in sections {
                if let Some(cmd) = h.strip_prefix('`').and_then(|h| h.strip_suffix('`')) {
                    held_by.insert(words(cmd), not_run.unwrap_or("run by a stand-in in its place"));
                }
                match (blocks > 0, not_run.is_some()) {
                    (false, false) => wrong.push(format!(
                        "{name}: {h} neither runs a console block nor says `Not run: WHY` or `Run by FILE: `TEXT``"
                    )),
                    (true, true) => wrong.push(format!("{name}: {h} runs a console block and says it is not run")),
                    _ => {}
                }
            }
        }
    }
    for (w, at) in &documented {
        let how = if run.contains(w) { Some("run as written by a console block") } else { held_by.get(w).copied() };
        *count.entry(how.unwrap_or("not run by anything")).or_default() += 1;
        *count.entry("documented commands (sh blocks, --help examples)").or_default() += 1;
        if !run.contains(w) && !quoted.contains_key(w) {
            wrong.push(format!("{at}: not run as written by any console block, and no stand-in quotes it"));
        }
    }
    for (w, at) in &quoted {
        if !documented.contains_key(w) {
            wrong.push(format!("{at}: a stand-in for `{}`, which no document or --help gives any more", w.join(" ")));
        }
    }
    (wrong, count)
}

#[test]
fn every_documented_command_is_run() {
    let (help, wrapped) = help_examples();
    assert!(wrapped.is_empty(), "--help examples that wrap (cannot be pasted):\n{}", wrapped.join("\n"));
    let (wrong, count) = check_and_count(&documents(), &stand_ins(), &help);
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
    for (what, n) in &count {
        eprintln!("{n:4} {what}");
    }
    // Say what is not run, and why.
    for doc in stand_ins() {
        let mut heading = "";
        for line in doc.text.lines() {
            if let Some(h) = line.strip_prefix("## ") {
                heading = h;
            } else if let Some(why) = line.strip_prefix("Not run: ") {
                eprintln!("not run: {heading}: {why}");
            } else if let Some(by) = line.strip_prefix("Run by ") {
                eprintln!("run by {by}: {heading}");
            }
        }
    }
}

/// The check fails on each thing it is there to catch.
#[test]
fn the_check_catches_a_command_nobody_runs() {
    let doc = |text: &str| Doc { path: PathBuf::from("doc.md"), text: text.to_string() };
    let fine_doc = doc(
        "```sh\ngcl conform --target 'serial:/dev/ttyUSB0'   # a hand\n```\n\n```console\n$ gcl explain HI\n...\n```\n",
    );
    let fine_stand_in = doc(
        "## `gcl conform --target serial:/dev/ttyUSB0`\n\nThe model stands for the hand.\n\n```console\n$ gcl conform --target sim\n...\n```\n\n## `gcl sim --pty`\n\nNot run: serves.\n",
    );
    let help = vec!["gcl explain HI".to_string(), "gcl sim --pty".to_string()];
    assert_eq!(check(&[doc(&fine_doc.text)], &[doc(&fine_stand_in.text)], &help), Vec::<String>::new());
    let fails = |docs: &[&str], stand_ins: &[&str], help: &[String], what: &str| {
        let docs: Vec<Doc> = docs.iter().map(|t| doc(t)).collect();
        let stand_ins: Vec<Doc> = stand_ins.iter().map(|t| doc(t)).collect();
        let wrong = check(&docs, &stand_ins, help);
        assert!(wrong.iter().any(|w| w.contains(what)), "expected {what:?} in {wrong:#?}");
    };
    // A documented command nobody runs; a --help example nobody runs.
    fails(&["```sh\ngcl fuzz device --target sim\n```\n"], &[], &[], "no stand-in quotes it");
    fails(&[], &[], &["gcl sim --tcp 127.0.0.1:0".to_string()], "no stand-in quotes it");
    // A stand-in for a command that is gone.
    fails(&[], &[&fine_stand_in.text], &[], "no document or --help gives any more");
    // A console block marked to be skipped; a program the checker does not run (a document's
    // blocks run `gcl` alone).
    fails(&["```console,ignore\n$ gcl explain HI\n```\n"], &[], &[], "marked `ignore`");
    fails(&["```console\n$ cargo run -- explain HI\n```\n"], &[], &[], "which the checker does not run");
    fails(&["```console\n$ sh -c 'gcl explain HI'\n```\n"], &[], &[], "which the checker does not run");
    // A document's command that goes on in trycmd's `> ` lines (a shell takes `\`).
    fails(&["```console\n$ gcl explain\n> HI\n```\n"], &[], &[], "which a shell cannot take");
    let wrong = check(&[doc("```console\n$ gcl explain \\\n    HI\n```\n")], &[doc("")], &[]);
    assert_eq!(wrong, Vec::<String>::new());
    assert_eq!(
        console_commands(&blocks("```console\n$ gcl explain \\\n    HI\n? 0\n> HI\n```\n")[0].1),
        vec![words("gcl explain HI")]
    );
    // A stand-in without a run or a reason, or with both.
    fails(&["```sh\ngcl a\n```\n"], &["## `gcl a`\n\nNothing.\n"], &[], "neither runs");
    fails(
        &["```sh\ngcl a\n```\n"],
        &["## `gcl a`\n\nNot run: no.\n\n```console\n$ gcl b\n```\n"],
        &[],
        "says it is not run",
    );
    // A command run elsewhere: the file must hold what it runs.
    let by_ci = |text: &str| format!("## `gcl a`\n\nRun by .ci/run: `{text}`.\n");
    assert_eq!(
        check(&[doc("```sh\ngcl a\n```\n")], &[doc(&by_ci("cargo fmt --all -- --check"))], &[]),
        Vec::<String>::new()
    );
    fails(&["```sh\ngcl a\n```\n"], &[&by_ci("gcl a --nowhere")], &[], "which does not hold `gcl a --nowhere`");
    fails(
        &["```sh\ngcl a\n```\n"],
        &["## `gcl a`\n\nRun by no/such/file: `gcl a`.\n"],
        &[],
        "not a file of the repository",
    );
    // The same command written otherwise (quotes, continuations) is the same command.
    let wrong = check(
        &[doc("```sh\ngcl explain \\\n  'HI'   # hi\n```\n")],
        &[doc("## `gcl explain HI`\n\n```console\n$ gcl explain\n> HI\n```\n")],
        &[],
    );
    assert_eq!(wrong, Vec::<String>::new());
}

/// The files the examples read: the blocks of the documents whose info string says
/// `file=NAME`, and the stand-ins' shell helpers.
fn fixtures(docs: &[Doc]) -> BTreeMap<String, String> {
    let mut files = BTreeMap::new();
    for doc in docs {
        for (_, block) in blocks(&doc.text) {
            if let Some(name) = block.file() {
                let text = block.lines.join("\n") + "\n";
                let old = files.insert(name.to_string(), text.clone());
                assert!(old.is_none_or(|o| o == text), "{}: two different files {name}", doc.path.display());
            }
        }
    }
    let lib = root().join("harness/tests/stand-ins/lib.sh");
    files.insert("lib.sh".into(), std::fs::read_to_string(lib).unwrap());
    files
}

/// Runs the `console` blocks of `doc` in order in `dir`, the programs by `bins`; the first
/// step that exits otherwise or prints otherwise than the document says ends the file (the
/// steps after it may rest on it), and is returned.
fn run_doc(doc: &Doc, dir: &Path, bins: &BTreeMap<String, PathBuf>, env: &[(String, String)]) -> Result<usize, String> {
    let name = doc.path.strip_prefix(root()).unwrap_or(&doc.path).display().to_string();
    // Bytes are compared as printed: trycmd would turn every `\` of the output into `/`.
    let assert = snapbox::Assert::new().normalize_paths(false);
    let mut ran = 0;
    for (_, block) in blocks(&doc.text) {
        if !block.is_console() {
            continue;
        }
        for step in steps(&block) {
            let at = format!("{name}:{}: `{}`", step.line, step.words.join(" "));
            let assignments: Vec<(&str, &str)> = step.words.iter().map_while(|w| w.split_once('=')).collect();
            // A word that starts `~/` is in the home folder, as a shell reads it (the checker's
            // home, a folder of its own).
            let home = env.iter().find(|(k, _)| k == "HOME").map(|(_, v)| v.as_str());
            let expanded: Vec<String> = step
                .words
                .iter()
                .map(|w| match (w.strip_prefix("~/"), home) {
                    (Some(rest), Some(h)) => format!("{h}/{rest}"),
                    _ => w.clone(),
                })
                .collect();
            let mut words = expanded.iter().skip(assignments.len());
            let program = words.next().ok_or_else(|| format!("{at}: no program"))?;
            let path =
                bins.get(program).ok_or_else(|| format!("{at}: `{program}` is not a program this checker runs"))?;
            let out = snapbox::cmd::Command::new(path)
                .args(words)
                .envs(env.iter().map(|(k, v)| (k.as_str(), v.as_str())))
                .envs(assignments)
                .current_dir(dir)
                .stderr_to_stdout()
                // A guard against a hang, not a measure: the longest step takes seconds.
                .timeout(Duration::from_secs(300))
                .output()
                .map_err(|e| format!("{at}: cannot run: {e}"))?;
            let printed = String::from_utf8_lossy(&out.stdout);
            let printed = printed.trim_end_matches('\n');
            let actual = if printed.is_empty() { String::new() } else { format!("{printed}\n") };
            if out.status.code() != Some(step.status) {
                return Err(format!(
                    "{at}: exit {:?}, the document says {}; it printed:\n{actual}",
                    out.status.code(),
                    step.status
                ));
            }
            if let Err(e) = assert.try_eq(
                Some(&"what it printed"),
                snapbox::Data::text(actual),
                snapbox::Data::text(step.expected.clone()),
            ) {
                return Err(format!(
                    "{at}: prints otherwise than the document says (`...` any lines, `[..]` any text):\n{e}"
                ));
            }
            ran += 1;
        }
    }
    Ok(ran)
}

#[test]
#[ignore = "slow: .ci/run runs it (cargo test --workspace -- --include-ignored)"]
fn documented_commands_run_as_written_or_by_their_stand_ins() {
    let Some(python) = deps::python_with(&["serial"]) else { return };
    let mut bins: BTreeMap<String, PathBuf> = BTreeMap::new();
    bins.insert("gcl".into(), GCL.into());
    bins.insert("sh".into(), "/bin/sh".into());
    for name in EXAMPLES {
        let Some(p) = deps::example(name) else { return };
        bins.insert(name.to_string(), p);
    }
    let dir = tempfile::tempdir().unwrap();
    // The documents' `python3`, on the stand-ins' PATH, is the Python the other tests use.
    let bin = dir.path().join("bin");
    std::fs::create_dir(&bin).unwrap();
    let wrapper = bin.join("python3"); // runs deps::python_with's interpreter
    std::fs::write(&wrapper, format!("#!/bin/sh\nexec '{python}' \"$@\"\n")).unwrap();
    std::fs::set_permissions(&wrapper, std::os::unix::fs::PermissionsExt::from_mode(0o755)).unwrap();
    // The shell finds the programs a console block runs, and no other of the build's: the
    // folder of `gcl` also holds the fuzz targets, one of them named `realtime` as an example is.
    for (name, path) in &bins {
        std::os::unix::fs::symlink(path, bin.join(name)).unwrap();
    }
    let env = vec![
        ("PATH".to_string(), format!("{}:{}", bin.display(), std::env::var("PATH").unwrap_or_default())),
        ("GCL_REPO".to_string(), root().display().to_string()),
        ("PYTHONDONTWRITEBYTECODE".to_string(), "1".to_string()),
    ];

    // Each file runs in a folder of its own holding the fixtures; two files at a time (the
    // real-time stand-ins keep to their deadlines on a busy machine).
    let docs = documents();
    let files = fixtures(&docs);
    let all: Vec<Doc> = docs.into_iter().chain(stand_ins()).collect();
    let next = std::sync::atomic::AtomicUsize::new(0);
    let results = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| {
                loop {
                    let i = next.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                    let Some(doc) = all.get(i) else { break };
                    let folder = dir.path().join(format!("{i}"));
                    std::fs::create_dir(&folder).unwrap();
                    for (name, text) in &files {
                        let path = folder.join(name);
                        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
                        std::fs::write(path, text).unwrap();
                    }
                    std::fs::create_dir(folder.join("home")).unwrap();
                    let mut env = env.clone();
                    env.push(("HOME".to_string(), folder.join("home").display().to_string()));
                    let r = run_doc(doc, &folder, &bins, &env);
                    results.lock().unwrap().push((doc.path.clone(), r));
                }
            });
        }
    });
    let results = results.into_inner().unwrap();
    let steps: usize = results.iter().filter_map(|(_, r)| r.as_ref().ok()).sum();
    let failures: Vec<&String> = results.iter().filter_map(|(_, r)| r.as_ref().err()).collect();
    assert!(
        failures.is_empty(),
        "{} of {} files have a command that does not do what the document says:\n\n{}",
        failures.len(),
        results.len(),
        failures.iter().map(|f| f.as_str()).collect::<Vec<_>>().join("\n\n")
    );
    eprintln!("ran {steps} commands of {} files (README.md, the chapters, the stand-ins)", results.len());
    assert!(steps > 50, "only {steps} commands ran");
}

/// The anchor a heading gets, as mdbook (and GitHub) make it: its text in lower case, spaces as
/// `-`, every character but letters, digits, `-` and `_` dropped.
fn anchor(heading: &str) -> String {
    heading
        .chars()
        .filter_map(|c| match c {
            c if c.is_alphanumeric() || c == '_' || c == '-' => Some(c.to_lowercase().next().unwrap_or(c)),
            c if c.is_whitespace() => Some('-'),
            _ => None,
        })
        .collect()
}

/// The links of a Markdown text (its images too), and the anchors of its headings.
fn links_and_anchors(text: &str) -> (Vec<String>, BTreeSet<String>) {
    use pulldown_cmark::{Event, Parser, Tag, TagEnd};
    let (mut links, mut anchors) = (Vec::new(), BTreeSet::new());
    let mut heading: Option<String> = None;
    for event in Parser::new(text) {
        match event {
            Event::Start(Tag::Link { dest_url, .. } | Tag::Image { dest_url, .. }) => links.push(dest_url.to_string()),
            Event::Start(Tag::Heading { id, .. }) => {
                if let Some(id) = id {
                    anchors.insert(id.to_string());
                }
                heading = Some(String::new());
            }
            Event::Text(t) | Event::Code(t) if heading.is_some() => heading.as_mut().unwrap().push_str(&t),
            Event::End(TagEnd::Heading(_)) => anchors.extend(heading.take().map(|h| anchor(&h))),
            _ => {}
        }
    }
    (links, anchors)
}

/// The links of `docs` that lead nowhere: a relative link to a file that is not there, or to
/// an anchor no heading of its file has. (Links to the web are not followed.)
fn broken_links(docs: &[Doc]) -> Vec<String> {
    let mut wrong = Vec::new();
    for doc in docs {
        let name = doc.path.strip_prefix(root()).unwrap_or(&doc.path).display().to_string();
        let (links, own) = links_and_anchors(&doc.text);
        // mdbook's `{{#include FILE}}` and `{{#include FILE:ANCHOR}}` (a missing one is an ERROR
        // line of `mdbook build`, which still exits 0).
        for include in doc.text.split("{{#include ").skip(1).filter_map(|s| s.split_once("}}")).map(|(s, _)| s.trim()) {
            let (file, part) = include.split_once(':').map_or((include, None), |(f, a)| (f, Some(a)));
            let target = doc.path.parent().unwrap().join(file);
            match std::fs::read_to_string(&target) {
                Err(_) => wrong.push(format!("{name}: `{{{{#include {include}}}}}`: there is no {}", target.display())),
                Ok(text) => {
                    if let Some(part) = part.filter(|p| p.parse::<usize>().is_err() && !p.is_empty())
                        && !text.contains(&format!("ANCHOR: {part}"))
                    {
                        wrong.push(format!("{name}: `{{{{#include {include}}}}}`: {file} has no `ANCHOR: {part}`"));
                    }
                }
            }
        }
        for link in links {
            if link.contains("://") || link.starts_with("mailto:") {
                continue;
            }
            let (file, fragment) = link.split_once('#').map_or((link.as_str(), None), |(f, a)| (f, Some(a)));
            let target = if file.is_empty() { doc.path.clone() } else { doc.path.parent().unwrap().join(file) };
            if !file.is_empty() && !target.exists() {
                wrong.push(format!("{name}: `{link}`: there is no {}", target.display()));
                continue;
            }
            let Some(fragment) = fragment else { continue };
            let anchors = if file.is_empty() {
                own.clone()
            } else if target.extension().is_some_and(|e| e == "md") {
                links_and_anchors(&std::fs::read_to_string(&target).unwrap()).1
            } else {
                wrong.push(format!("{name}: `{link}`: an anchor in a file that is not Markdown"));
                continue;
            };
            if !anchors.contains(fragment) {
                wrong.push(format!("{name}: `{link}`: no heading of {file} has the anchor #{fragment}"));
            }
        }
    }
    wrong
}

/// Every relative link of README.md and the guides leads to a file of the repository, and a
/// link with an anchor to a heading of that file.
#[test]
fn every_link_of_the_documents_leads_somewhere() {
    let docs = documents();
    let wrong = broken_links(&docs);
    assert!(wrong.is_empty(), "links that lead nowhere:\n{}", wrong.join("\n"));
    let count: usize = docs.iter().map(|d| links_and_anchors(&d.text).0.len()).sum();
    assert!(count > 20, "only {count} links");
}

/// The link check fails on a missing file, a missing anchor, and a missing anchor in another
/// file; it takes a heading's anchor as mdbook makes it.
#[test]
fn the_link_check_catches_a_link_to_nowhere() {
    let dir = tempfile::tempdir().unwrap();
    let other = dir.path().join("other.md");
    std::fs::write(&other, "# Other\n\n## Without a Rust toolchain: the `gcl` wheel\n").unwrap();
    let doc = |text: &str| Doc { path: dir.path().join("doc.md"), text: text.to_string() };
    let fine = doc(
        "## Here\n\n{{#include other.md}}\n\n[a](other.md) [b](other.md#without-a-rust-toolchain-the-gcl-wheel) [c](#here) [d](https://example.com/x.md)\n",
    );
    assert_eq!(broken_links(&[fine]), Vec::<String>::new());
    for (text, what) in [
        ("[a](gone.md)", "there is no"),
        ("[a](#gone)", "has the anchor #gone"),
        ("[a](other.md#the-wheel)", "has the anchor #the-wheel"),
        ("{{#include gone.md}}", "there is no"),
        ("{{#include other.md:intro}}", "has no `ANCHOR: intro`"),
    ] {
        let wrong = broken_links(&[doc(text)]);
        assert!(wrong.iter().any(|w| w.contains(what)), "{text}: expected {what:?} in {wrong:#?}");
    }
}

/// The options whose value is a path a command writes (`--keygen` a private key, and its
/// `.pub` beside it).
const OUTPUT_OPTIONS: &[&str] =
    &["--report", "--out", "--corpus", "--write-known-failures", "--keygen", "--plot", "--save-session", "--link"];

/// The paths the commands of `docs` write, each with where it is written and whether it is a
/// private key: every `sh` command and `console` step, as run from the checkout's root (a
/// `cd DIR &&` before a command moves it), relative paths joined to where it runs.
fn written_paths(docs: &[Doc]) -> Vec<(String, PathBuf, bool)> {
    let mut out = Vec::new();
    for doc in docs {
        let name = doc.path.strip_prefix(root()).unwrap_or(&doc.path).display().to_string();
        for (_, block) in blocks(&doc.text) {
            let commands: Vec<Vec<String>> = if block.is_console() {
                console_commands(&block)
            } else if block.lang() == "sh" {
                sh_commands(&block).iter().map(|c| words(c)).collect()
            } else {
                continue;
            };
            for c in commands {
                let mut cwd = PathBuf::new();
                for part in c.split(|w| w == "&&" || w == ";") {
                    if let [cd, dir] = part
                        && cd == "cd"
                    {
                        cwd.push(dir);
                        continue;
                    }
                    for (i, w) in part.iter().enumerate() {
                        let (option, value) = match w.split_once('=') {
                            Some((o, v)) if o.starts_with("--") => (o, Some(v.to_string())),
                            _ => (w.as_str(), part.get(i + 1).cloned()),
                        };
                        if !OUTPUT_OPTIONS.contains(&option) {
                            continue;
                        }
                        let Some(value) = value else { continue };
                        let at = format!("{name}:{}: `{}`", block.line, c.join(" "));
                        out.push((at, cwd.join(value), option == "--keygen"));
                    }
                }
            }
        }
    }
    out
}

/// What the commands of README.md, the guides and the `--help` examples write goes into a folder git ignores (run
/// from the checkout's root, they leave `git status` clean), or outside the checkout (a path
/// from `/` or `~/`); and a private key never into the checkout, ignored or not.
#[test]
fn the_documented_commands_write_only_where_git_ignores() {
    let repo = Command::new("git").args(["rev-parse", "--show-toplevel"]).current_dir(root()).output();
    if !repo.is_ok_and(|o| o.status.success()) {
        deps::missing("git and a git checkout", "run the tests in a clone of the repository");
        return;
    }
    // README.md, the chapters, and every `--help`'s examples.
    let (help, _) = help_examples();
    let mut docs = documents();
    docs.push(Doc { path: root().join("gcl --help"), text: format!("```sh\n{}\n```\n", help.join("\n")) });
    let written = written_paths(&docs);
    assert!(written.len() > 20, "only {} paths found: {written:?}", written.len());
    let wrong = not_ignored(&written);
    assert!(wrong.is_empty(), "documented commands that write where git does not ignore:\n{}", wrong.join("\n"));
    // The check fails on a file written at the root, and on a private key in an ignored folder.
    let doc = |text: &str| Doc { path: root().join("doc.md"), text: text.to_string() };
    for (text, what) in [
        ("```sh\ngcl conform --target sim --write-known-failures known.toml\n```\n", "known.toml"),
        ("```console\n$ gcl certify --keygen reports/key.pem\n```\n", "a private key"),
        ("```sh\ncd vectors && gcl record --target sim --script s --out my.gcl\n```\n", "vectors/my.gcl"),
    ] {
        let wrong = not_ignored(&written_paths(&[doc(text)]));
        assert!(wrong.iter().any(|w| w.contains(what)), "{text}: expected {what:?} in {wrong:?}");
    }
    let fine = "```sh\ngcl conform --target sim --report reports/x\ngcl certify --keygen ~/k.pem\n```\n";
    assert_eq!(not_ignored(&written_paths(&[doc(fine)])), Vec::<String>::new());
}

/// The paths of [`written_paths`] that git does not ignore, and private keys in the checkout.
fn not_ignored(written: &[(String, PathBuf, bool)]) -> Vec<String> {
    let mut wrong = Vec::new();
    for (at, path, key) in written {
        let text = path.display().to_string();
        if text.starts_with('/') || text.starts_with("~/") {
            continue;
        }
        if *key {
            wrong.push(format!("{at}: writes a private key into the checkout ({text}): write it outside, `~/...`"));
            continue;
        }
        let ignored = Command::new("git")
            .args(["check-ignore", "-q", "--no-index", "--"])
            .arg(path)
            .current_dir(root())
            .status()
            .unwrap();
        if !ignored.success() {
            wrong.push(format!("{at}: writes {text}, which git does not ignore"));
        }
    }
    wrong
}
