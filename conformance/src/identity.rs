//! Who the hand says it is: the firmware version named in its banner (after RESET) and in its
//! `VERS` answer, held against the version the chosen profile models.
//!
//! A profile models one firmware: the version its own banner and `VERS` lines name (`Version
//! 4.34` in `bh8-262-4.3`, `Version 4.4x` in `bh8-262-4.4`; the seed profile names none and is
//! never held against a hand). A hand that names another version was given the wrong profile:
//! every difference between the two firmwares then shows as a failure of the hand, so `gcl
//! conform`, `gcl certify` and `gcl fuzz device` say so in their first lines, with the built-in
//! profile that names the hand's version ([`mismatch`]).
//!
//! Versions are compared by their first two numbers (`4.34` and `4.3.3` are both `4.3`, `4.4x`
//! is `4.4`): the profiles model a firmware series, not one build. A hand that names no version
//! (or no `N.N` after the word `Version`) is not judged: nothing is said.

use gcl_model::Profile;

/// The firmware series (`4.3`) named in `lines`: the first `MAJOR.MINOR` number that follows
/// the word `Version` (any case) on a line; `None` when no line names one.
pub fn version_in<S: AsRef<str>>(lines: &[S]) -> Option<String> {
    lines.iter().find_map(|l| {
        let l = l.as_ref();
        let at = l.to_ascii_lowercase().find("version")?;
        series(l.get(at + "version".len()..)?)
    })
}

/// The first `MAJOR.MINOR` in `text` (its first digit after the dot only): `" 4.34 (x)"` gives
/// `4.3`, `"V4.4x"` gives `4.4`.
fn series(text: &str) -> Option<String> {
    let b = text.as_bytes();
    let start = b.iter().position(u8::is_ascii_digit)?;
    let major_end = start + b[start..].iter().take_while(|c| c.is_ascii_digit()).count();
    match (b.get(major_end), b.get(major_end + 1)) {
        (Some(b'.'), Some(minor)) if minor.is_ascii_digit() => {
            Some(format!("{}.{}", &text[start..major_end], *minor as char))
        }
        _ => None,
    }
}

/// The firmware series a profile models: named in its banner or its `VERS` lines.
pub fn profile_version(p: &Profile) -> Option<String> {
    version_in(&p.banner).or_else(|| version_in(&p.version))
}

/// The line to print first when the hand names another firmware series than `profile` models
/// (`lines`: what it said to RESET and `VERS`): "the hand says 4.4; you chose bh8-262-4.3 (4.3):
/// run with --profile bh8-262-4.4". `None` when they agree, or either names no version.
pub fn mismatch<S: AsRef<str>>(profile: &Profile, lines: &[S]) -> Option<String> {
    let want = profile_version(profile)?;
    let said = version_in(lines)?;
    if said == want {
        return None;
    }
    let other = Profile::builtin_names()
        .filter_map(|n| Profile::builtin(n).ok())
        .find(|p| profile_version(p).as_deref() == Some(said.as_str()));
    let advice = match other {
        Some(p) => format!("run with --profile {}", p.id),
        None => "no built-in profile models it: expect failures wherever the two firmwares differ".to_string(),
    };
    Some(format!("identity: the hand says firmware {said}; you chose {} (firmware {want}): {advice}", profile.id))
}

/// The text lines of a hand's answer bytes (banner, `VERS`): split at CR and LF, trimmed,
/// without the prompt, the echo or status lines.
pub fn answer_lines(bytes: &[u8], profile: &Profile) -> Vec<String> {
    let prompt = profile.framing.prompt.trim();
    String::from_utf8_lossy(bytes)
        .split(['\r', '\n'])
        .map(str::trim)
        .filter(|l| !l.is_empty() && *l != prompt)
        .map(str::to_string)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn builtin(n: &str) -> std::sync::Arc<Profile> {
        Profile::builtin(n).unwrap()
    }

    #[test]
    fn versions_are_read_as_a_series() {
        assert_eq!(version_in(&["BarrettHand Firmware", "Version 4.34 (gcl)"]).as_deref(), Some("4.3"));
        assert_eq!(version_in(&["Firmware VERSION 4.4x"]).as_deref(), Some("4.4"));
        assert_eq!(version_in(&["version: 4.3.3"]).as_deref(), Some("4.3"));
        assert_eq!(version_in(&["BH8-262 hand", "Version none"]), None);
        assert_eq!(version_in(&["Version 4", "no more"]), None);
        assert_eq!(version_in::<&str>(&[]), None);
    }

    #[test]
    fn the_built_in_profiles_name_their_series() {
        assert_eq!(profile_version(&builtin("bh8-262-4.3")).as_deref(), Some("4.3"));
        assert_eq!(profile_version(&builtin("bh8-262-4.4")).as_deref(), Some("4.4"));
        assert_eq!(profile_version(&builtin("seed")), None);
    }

    #[test]
    fn a_hand_of_another_series_is_named_with_the_profile_to_use() {
        let p43 = builtin("bh8-262-4.3");
        let hand44 = builtin("bh8-262-4.4");
        let line = mismatch(&p43, &hand44.banner).unwrap();
        assert_eq!(
            line,
            "identity: the hand says firmware 4.4; you chose bh8-262-4.3 (firmware 4.3): run with --profile bh8-262-4.4"
        );
        assert_eq!(mismatch(&p43, &p43.banner), None);
        assert_eq!(mismatch(&p43, &["Version 4.3.3"]), None);
        // A series no built-in models, and a hand that names none.
        assert!(mismatch(&p43, &["Version 5.1"]).unwrap().contains("no built-in profile models it"));
        assert_eq!(mismatch(&p43, &["BarrettHand Firmware"]), None);
        // The seed profile names no series: never held against a hand.
        assert_eq!(mismatch(&builtin("seed"), &hand44.banner), None);
    }

    #[test]
    fn answer_lines_drop_the_prompt_and_blank_lines() {
        let p = builtin("bh8-262-4.4");
        let got = answer_lines(b"VERS\n\rFirmware Version 4.4x\n\rsecond\n\r=> ", &p);
        assert_eq!(got, vec!["VERS", "Firmware Version 4.4x", "second"]);
    }
}
