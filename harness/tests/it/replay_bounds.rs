//! `gcl replay` never hangs on a hand that stops taking bytes: every write to a link has a
//! deadline, `exec:` targets included.

use std::process::Command;

const GCL: &str = env!("CARGO_BIN_EXE_gcl");

#[test]
fn a_big_step_to_a_child_that_does_not_read_ends_as_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("big.gcl");
    let big = "x".repeat(200_000);
    let text = format!(
        "gcl-transcript 1\nid: big\ntitle: a 200 kB line\nclause: c\nlevel: INFO\nprofile: seed\n\nsend \"{big}\\r\"\nexpect \"x\"\n"
    );
    std::fs::write(&path, text).unwrap();
    // `sleep` never reads its stdin: the pipe fills after 64 kB and the write must give up.
    let o = Command::new(GCL)
        .args(["replay", path.to_str().unwrap(), "--target", "exec:sleep 60"])
        .output()
        .expect("gcl runs");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(2), "{stdout}{}", String::from_utf8_lossy(&o.stderr));
    assert!(stdout.contains("ERROR") && stdout.contains("pending bytes within"), "{stdout}");
}
