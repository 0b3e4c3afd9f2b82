//! The one driver of the model's integration tests: a fresh hand, a line in and its answer
//! out, and [`check`] for a whole session (what the `.gcl` files under `testdata/sessions/`
//! hold). Each test file includes it with `mod support;`.
#![allow(dead_code)]

use std::sync::Arc;
use std::time::Duration;

use gcl_model::escape::{escape, unescape};
use gcl_model::spec::{SpecError, embedded};
use gcl_model::{Device, DeviceConfig, Profile};

/// A built-in profile.
pub fn profile(name: &str) -> Arc<Profile> {
    Profile::builtin(name).unwrap_or_else(|e| panic!("{e}"))
}

/// Loads `top` as the top file of a profile; its includes resolve to the embedded spec files.
pub fn load_top(top: &str) -> Result<Profile, SpecError> {
    Profile::load_with("top.toml", &|f| {
        if f == "top.toml" { Some(top.to_string()) } else { embedded(f).map(str::to_string) }
    })
}

/// A powered-up hand of a built-in profile (noise seed 5), banner taken.
pub fn hand(profile_name: &str) -> Device {
    hand_with(profile(profile_name), DeviceConfig { seed: 5, ..DeviceConfig::default() })
}

/// A powered-up hand of any profile and conditions, banner taken.
pub fn hand_with(profile: Arc<Profile>, config: DeviceConfig) -> Device {
    let mut d = Device::new(profile, config);
    d.clear_output();
    d
}

/// Sends bytes at the hand's present time, runs any command they start to completion (at
/// most 600 s of simulated time), returns the bytes the hand wrote.
pub fn exchange(d: &mut Device, bytes: &[u8]) -> Vec<u8> {
    let now = d.now();
    d.handle_input(now, bytes);
    d.run_until_idle(Duration::from_secs(600));
    d.take_output()
}

/// Sends one line and its CR, runs it to completion, returns the bytes the hand wrote.
pub fn send_bytes(d: &mut Device, line: &str) -> Vec<u8> {
    exchange(d, format!("{line}\r").as_bytes())
}

/// [`send_bytes`] as text (lossy).
pub fn send(d: &mut Device, line: &str) -> String {
    String::from_utf8_lossy(&send_bytes(d, line)).into_owned()
}

/// Runs `script` (one line each) on a fresh hand of `profile` and checks each answer against
/// `expected` (escaped as [`escape`] writes bytes).
pub fn check(profile: &str, script: &[&str], expected: &[&str]) {
    assert_eq!(script.len(), expected.len(), "one expected answer per line");
    let mut d = hand(profile);
    for (line, want) in script.iter().zip(expected) {
        let got = send_bytes(&mut d, line);
        let want_bytes = unescape(want).unwrap_or_else(|e| panic!("expected answer {want:?}: {e}"));
        assert_eq!(escape(&got), escape(&want_bytes), "{profile}: answer to {line:?}");
    }
}

/// Runs a session file: `profile NAME` lines start a fresh hand (one file may cover several
/// profiles), `> LINE` sends a line, `< "ANSWER"` is the escaped answer to the line before;
/// `#` starts a comment.
pub fn run_session(name: &str, text: &str) {
    let mut profile: Option<String> = None;
    let mut script: Vec<String> = Vec::new();
    let mut expected: Vec<String> = Vec::new();
    let flush = |profile: &Option<String>, script: &mut Vec<String>, expected: &mut Vec<String>| {
        if let Some(p) = profile {
            let s: Vec<&str> = script.iter().map(String::as_str).collect();
            let e: Vec<&str> = expected.iter().map(String::as_str).collect();
            check(p, &s, &e);
        }
        script.clear();
        expected.clear();
    };
    for (n, raw) in text.lines().enumerate() {
        let line = raw.trim_end();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        if let Some(p) = line.strip_prefix("profile ") {
            flush(&profile, &mut script, &mut expected);
            profile = Some(p.trim().to_string());
        } else if let Some(l) = line.strip_prefix("> ").or_else(|| (line == ">").then_some("")) {
            assert_eq!(script.len(), expected.len(), "{name}:{}: a line without its answer before it", n + 1);
            script.push(l.to_string());
        } else if let Some(a) = line.strip_prefix("< ") {
            let a = a.strip_prefix('"').and_then(|a| a.strip_suffix('"'));
            let a = a.unwrap_or_else(|| panic!("{name}:{}: an answer is quoted", n + 1));
            expected.push(a.to_string());
        } else {
            panic!("{name}:{}: not `profile`, `>`, `<` or `#`: {raw:?}", n + 1);
        }
    }
    assert!(profile.is_some(), "{name}: no `profile` line");
    flush(&profile, &mut script, &mut expected);
}
