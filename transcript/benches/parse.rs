//! Figures of the transcript crate: reading every committed golden, and matching answers.
//!
//! Run with `cargo bench -p gcl-transcript --bench parse -- --warm-up-time 1 --measurement-time 3`.
//!
//! Figures (criterion's estimates, `Throughput::Bytes`):
//! - `parse-goldens`: `parse` of every file under `vectors/suite/` (about 1.4 MB of text);
//! - `match-goldens`: a `Matcher` fed, byte by byte, every exact expectation of those files
//!   (the model's own answers), as a runner does.
//!
//! Under `cargo test --all-targets` (no `--bench` argument) criterion runs each routine once
//! and this binary checks that every golden parses and every exact answer matches.

use std::hint::black_box;
use std::path::{Path, PathBuf};

use criterion::{Criterion, Throughput};
use gcl_transcript::matcher::{Feed, Matcher};
use gcl_transcript::{Transcript, parse};

fn goldens() -> Vec<String> {
    let mut files = Vec::new();
    let mut stack = vec![PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../vectors/suite"))];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "gcl") {
                files.push(p);
            }
        }
    }
    files.sort();
    files.iter().map(|p: &PathBuf| std::fs::read_to_string(Path::new(p)).unwrap()).collect()
}

fn main() {
    let mut c = Criterion::default().configure_from_args();
    let texts = goldens();
    assert!(texts.len() > 100, "{} goldens", texts.len());
    let bytes: usize = texts.iter().map(String::len).sum();
    let parsed: Vec<Transcript> = texts.iter().map(|t| parse(t).unwrap()).collect();
    let answers: Vec<_> = parsed
        .iter()
        .flat_map(|t| t.steps.iter())
        .filter_map(|s| s.expect.exact_bytes().map(|b| (s.expect.clone(), b)))
        .collect();
    let answer_bytes: usize = answers.iter().map(|(_, b)| b.len()).sum();

    let mut g = c.benchmark_group("transcript");
    g.throughput(Throughput::Bytes(bytes as u64));
    g.bench_function("parse-goldens", |b| {
        b.iter(|| {
            for t in &texts {
                black_box(parse(black_box(t)).unwrap());
            }
        })
    });
    g.throughput(Throughput::Bytes(answer_bytes as u64));
    g.bench_function("match-goldens", |b| {
        b.iter(|| {
            for (expect, answer) in &answers {
                let mut m = Matcher::new(expect);
                let mut last = Feed::Alive;
                for &byte in answer {
                    last = m.feed(black_box(byte));
                }
                assert_eq!(last, Feed::Complete);
            }
        })
    });
    g.finish();
    c.final_summary();
}
