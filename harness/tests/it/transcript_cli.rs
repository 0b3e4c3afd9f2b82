//! `gcl replay` and `gcl record` as a user runs them: exit codes, the mismatch report, and a
//! recording that replays.

use std::path::PathBuf;
use std::process::Command;

fn gcl() -> Command {
    Command::new(env!("CARGO_BIN_EXE_gcl"))
}

fn golden(profile: &str, id: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../vectors/suite").join(profile).join(format!("{id}.gcl"))
}

#[test]
fn replay_exits_0_on_a_match() {
    let out = gcl().args(["replay", "--target", "sim"]).arg(golden("seed", "framing-echo")).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}{}", String::from_utf8_lossy(&out.stderr));
    assert!(stdout.starts_with("PASS "), "{stdout}");
}

#[test]
fn replay_exits_1_and_shows_the_parting_byte_on_a_mismatch() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(golden("seed", "param-dp-default")).unwrap();
    let edited = text.replace("1000 1000 1000 150", "1000 1000 1001 150");
    assert_ne!(text, edited);
    let f = dir.path().join("param-dp-default.gcl");
    std::fs::write(&f, edited).unwrap();
    let out = gcl().args(["replay", "--target", "sim:seed"]).arg(&f).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    assert!(stdout.contains("FAIL "), "{stdout}");
    assert!(stdout.contains("expected: \"FGET DP"), "{stdout}");
    assert!(stdout.contains("1001 150\\n\\r=> \""), "{stdout}");
    assert!(stdout.contains("1000 150\\n\\r=> \""), "{stdout}");
    assert!(stdout.contains("^ byte 22"), "{stdout}");
    // The expected line shows the whole golden already: no second line repeats it.
    assert!(!stdout.contains("golden:"), "{stdout}");
}

#[test]
fn replaying_a_transcript_against_a_sim_of_another_profile_warns() {
    let f = golden("seed", "framing-echo");
    let out = gcl().args(["replay", "--target", "sim:bh8-262"]).arg(&f).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("is written for profile seed, but the target simulates bh8-262-4.4"),
        "{stderr}{}",
        String::from_utf8_lossy(&out.stdout)
    );
    let out = gcl().args(["replay", "--target", "sim:seed"]).arg(&f).output().unwrap();
    assert!(!String::from_utf8_lossy(&out.stderr).contains("warning"), "the same profile: no warning");
}

#[test]
fn replay_exits_2_on_a_file_that_does_not_parse() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("bad.gcl");
    std::fs::write(&f, "gcl-transcript 1\nid: x\ntitle: t\nclause: c\nlevel: MUST\nprofile: seed\nsend \"\\q\"\n")
        .unwrap();
    let out = gcl().args(["replay", "--target", "sim"]).arg(&f).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("line 7, column 7"), "{stderr}");
}

#[test]
fn a_recording_of_the_simulator_replays_against_it() {
    let dir = tempfile::tempdir().unwrap();
    let script = dir.path().join("abort-close.script");
    std::fs::write(
        &script,
        "# my case\nid: abort-close\nlevel: SHOULD\nclause: decision:bh8-abort-motion\nrequires: motion, abort-timing\n\
         abort\nRESET\nHI\n1FSET LCV 0 LCPG 0 LFV 0 LFS 0 LFAP 1 LFDP 0\n1LOOP\nblock: 41\nabort\nnowait: GC\npause: 200ms\nabort\n",
    )
    .unwrap();
    let out_file = dir.path().join("abort-close.gcl");
    let out = gcl()
        .args(["record", "--target", "sim:bh8-262-4.4", "--title", "^C during C"])
        .arg("--script")
        .arg(&script)
        .arg("--out")
        .arg(&out_file)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(stderr.contains("gcl record: wrote ") && stderr.contains("abort-close.gcl ("), "success is said: {stderr}");
    let text = std::fs::read_to_string(&out_file).unwrap();
    assert!(text.contains("id: abort-close\ntitle: ^C during C\n"), "{text}");
    assert!(text.contains("profile: bh8-262-4.4\n"), "{text}");
    assert!(text.contains("expect within 10s \"RESET{any}BarrettHand Firmware{any}\\n\\r=> \""), "{text}");
    assert!(text.contains("pause 200ms\nsend \"\\x03\"\nexpect \"\\n\\rERR 16384\\n\\r=> \""), "{text}");
    assert!(text.contains("send hex 41\nexpect hex 2A 00 00"), "{text}");
    let t = gcl_transcript::parse(&text).unwrap();
    assert_eq!(t.header.level, gcl_transcript::Level::Should);
    let out = gcl().args(["replay", "--target", "sim"]).arg(&out_file).output().unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stdout));
}

/// A script's `setup:` places an object on `sim` as it records, the transcript keeps it, and
/// replaying it places the object again on `sim`; on another hand it is SKIP unless the
/// object is declared in place.
#[test]
fn a_setup_is_recorded_and_replayed_with_its_object() {
    let dir = tempfile::tempdir().unwrap();
    let script = dir.path().join("press.script");
    std::fs::write(&script, "id: press\nrequires: motion, object\nsetup: object 1 8500\nRESET\nHI\n1C\n1FGET SG\n")
        .unwrap();
    let out_file = dir.path().join("press.gcl");
    let out = gcl()
        .args(["record", "--target", "sim:seed", "--script"])
        .arg(&script)
        .arg("--out")
        .arg(&out_file)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let text = std::fs::read_to_string(&out_file).unwrap();
    assert!(text.contains("requires: motion, object\nsetup: object 1 8500\n"), "{text}");
    // Pressed into the object, the finger reads more than a free one's strain.
    let t = gcl_transcript::parse(&text).unwrap();
    let sg = String::from_utf8_lossy(&t.steps.last().unwrap().expect.exact_bytes().unwrap()).into_owned();
    let strain: i64 = sg.split("\n\r").nth(1).unwrap().parse().unwrap();
    assert!(strain > 40, "{sg}");
    let out = gcl().args(["replay", "--target", "sim"]).arg(&out_file).output().unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stdout));
    let target = format!("exec:{} sim --stdio --profile seed", env!("CARGO_BIN_EXE_gcl"));
    let out = gcl().args(["replay", "--target", &target]).arg(&out_file).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}");
    assert!(
        stdout.starts_with("SKIP ") && stdout.contains("object 1 8500") && stdout.contains("--fixture object"),
        "{stdout}"
    );
    // Declared in place, but not there: the strain is a free finger's, and the replay fails.
    let out = gcl().args(["replay", "--target", &target, "--fixture", "object"]).arg(&out_file).output().unwrap();
    assert_eq!(out.status.code(), Some(1), "{}", String::from_utf8_lossy(&out.stdout));
}

#[test]
fn suite_check_passes_on_the_committed_suite() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../vectors/suite");
    let out = gcl().args(["suite", "check", "--dir"]).arg(&dir).output().unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stdout));
    let out = gcl().args(["suite", "list", "--profile", "seed", "--dir"]).arg(&dir).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("seed         framing-echo"), "{stdout}");
}

/// `gcl suite list` is a table: each column starts at one offset on every line, the title
/// last (a level or a list of requirements longer than its column used to push the rest).
#[test]
fn suite_list_lines_up_its_columns() {
    let out = gcl().args(["suite", "list"]).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let lines: Vec<&str> = stdout.lines().filter(|l| !l.contains(" cases: ")).collect();
    assert!(lines.len() > 300, "{stdout}");
    // Where each of the first five fields starts.
    let starts = |l: &str| -> Vec<usize> {
        let mut v = Vec::new();
        let mut prev = ' ';
        for (i, c) in l.char_indices() {
            if c != ' ' && prev == ' ' && v.len() < 5 {
                v.push(i);
            }
            prev = c;
        }
        v
    };
    let first = starts(lines[0]);
    for l in &lines {
        assert_eq!(starts(l), first, "{l}\n(first line: {})", lines[0]);
    }
    assert!(lines.iter().any(|l| l.contains(" SHOULD ")) && lines.iter().any(|l| l.contains(" MUST ")));
}
