//! BUG: reads each answer with a blocking read and no deadline (std only, built with
//! `rustc`). A cut or unended answer leaves it waiting for ever in `wait_for_prompt`.
//! Expected: `gcl fuzz host` reports one hang whose signature names `wait_for_prompt`.
use std::io::{Read, Write};

#[inline(never)]
fn wait_for_prompt(port: &mut std::fs::File) -> Vec<u8> {
    let mut got = Vec::new();
    let mut b = [0u8; 1];
    while !got.ends_with(b"=> ") {
        match port.read(&mut b) {
            Ok(1) => got.push(b[0]),
            _ => std::process::exit(1),
        }
    }
    got
}

fn main() {
    let path = std::env::var("GCL_PORT").expect("GCL_PORT");
    let mut port = std::fs::OpenOptions::new().read(true).write(true).open(&path).expect("open port");
    for line in ["\x03", "HI\r", "FGET DP\r", "1M 5000\r", "FGET P\r", "C\r", "O\r"] {
        port.write_all(line.as_bytes()).expect("write");
        wait_for_prompt(&mut port);
    }
}
