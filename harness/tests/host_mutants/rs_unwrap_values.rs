//! Mutant: parses every FGET answer's values with `.parse().unwrap()`.
//! Plausible bug: "the hand only ever prints numbers"; garbage or a cut answer panics.
//! Expected finding: crash (Rust panic). std only: the pty is raw already.
use std::io::{Read, Write};
use std::sync::mpsc;
use std::time::Duration;

fn main() {
    let path = std::env::var("GCL_PORT").expect("GCL_PORT");
    let mut port = std::fs::OpenOptions::new().read(true).write(true).open(&path).expect("open port");
    let mut reader = port.try_clone().expect("clone");
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let mut b = [0u8; 256];
        while let Ok(n) = reader.read(&mut b) {
            if n == 0 || tx.send(b[..n].to_vec()).is_err() {
                break;
            }
        }
    });
    let mut ask = |line: &str| -> Option<String> {
        port.write_all(format!("{line}\r").as_bytes()).ok()?;
        let mut got = Vec::new();
        while !got.ends_with(b"=> ") {
            got.extend(rx.recv_timeout(Duration::from_secs(1)).ok()?);
        }
        Some(String::from_utf8_lossy(&got).into_owned())
    };
    for line in ["FGET DP", "HI", "1M 5000", "123FGET P", "C", "123FGET P"] {
        let Some(answer) = ask(line) else {
            eprintln!("host: no answer to {line}");
            std::process::exit(1);
        };
        if line.contains("FGET") {
            let values: Vec<i64> = answer.split("\n\r").nth(1).unwrap_or("").split(' ').map(|v| v.parse().unwrap()).collect();
            println!("{line}: {values:?}");
        }
    }
}
