//! Correct: a Rust host built with `cargo afl build` (or by hand with the same instrumentation:
//! sanitizer coverage's pc-guard linked with AFL++'s runtime), so that it writes the edges it
//! reaches to the map of `__AFL_SHM_ID` (issue 42). Std only. It asks `1FGET P` eight times,
//! the same commands whatever it reads, and sorts each answer by what it holds (a value, an
//! `ERR` code, a byte no answer has, a line over 80 bytes, nothing before its deadline): each
//! kind is code of its own, so the edges it reaches rise as a campaign's misbehaviours vary,
//! while the wire shows no difference. Every read has a 1 s deadline; it exits 0 at the end.
//! Expected: no finding; `gcl fuzz host` reads its edges (harness/tests/it/fuzz_host_coverage.rs).
use std::io::{Read, Write};
use std::sync::mpsc::{channel, Receiver, RecvTimeoutError};
use std::time::Duration;

/// What an answer held, as far as this host cares.
#[derive(Debug, Default)]
struct Seen {
    values: u32,
    errors: u32,
    foreign: u32,
    long_lines: u32,
    silent: u32,
}

/// The bytes of one answer up to its prompt, or what came before 1 s without a byte.
fn read_answer(bytes: &Receiver<u8>) -> (Vec<u8>, bool) {
    let mut got = Vec::new();
    while !got.ends_with(b"=> ") {
        match bytes.recv_timeout(Duration::from_secs(1)) {
            Ok(b) => got.push(b),
            Err(RecvTimeoutError::Timeout) => return (got, false),
            Err(RecvTimeoutError::Disconnected) => std::process::exit(0),
        }
    }
    (got, true)
}

fn sort(answer: &[u8], ended: bool, seen: &mut Seen) {
    if !ended {
        seen.silent += 1;
    }
    if answer.iter().any(|&c| (c < 0x20 && c != b'\r' && c != b'\n') || c > 0x7e) {
        seen.foreign += 1;
    }
    if answer.split(|&c| c == b'\r' || c == b'\n').any(|line| line.len() > 80) {
        seen.long_lines += 1;
    }
    let text = String::from_utf8_lossy(answer);
    if let Some(at) = text.find("ERR ") {
        let code: String = text[at + 4..].chars().take_while(char::is_ascii_digit).collect();
        match code.parse::<u64>() {
            Ok(n) if n < 1 << 16 => seen.errors += 1,
            Ok(_) => seen.errors += 2,
            Err(_) => seen.errors += 3,
        }
    } else if text.split_whitespace().any(|w| w.parse::<i64>().is_ok()) {
        seen.values += 1;
    }
}

fn main() {
    let path =
        std::env::args().nth(1).or_else(|| std::env::var("GCL_PORT").ok()).expect("the port: argv[1] or GCL_PORT");
    let mut port = std::fs::OpenOptions::new().read(true).write(true).open(&path).expect("open the port");
    let mut reader = port.try_clone().expect("a second handle on the port");
    let (tx, bytes) = channel();
    std::thread::spawn(move || {
        let mut b = [0u8; 1];
        while let Ok(1) = reader.read(&mut b) {
            if tx.send(b[0]).is_err() {
                break;
            }
        }
    });
    let mut seen = Seen::default();
    port.write_all(b"\x03").expect("write");
    read_answer(&bytes);
    for _ in 0..8 {
        port.write_all(b"1FGET P\r").expect("write");
        let (answer, ended) = read_answer(&bytes);
        sort(&answer, ended, &mut seen);
    }
    println!("{seen:?}");
}
