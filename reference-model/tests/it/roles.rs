//! What a profile without a role's parameter means ([`Absence`]): a required role refuses
//! the profile at load with [`SpecError::MissingRole`]; an optional one gives the hand the
//! behaviour its absence declares. Each profile here is a built-in one with parameters
//! removed (`remove_params`) in a top file written by the test.

use crate::support;

use std::sync::Arc;

use gcl_model::spec::{Absence, Role, SpecError, embedded};
use gcl_model::{DeviceConfig, Motor, Profile, Scenario};
use support::{hand_with, load_top, send};

/// `base` (a built-in top file) as profile `x` without the parameters `removed`.
fn without(base: &str, removed: &[&str]) -> Result<Profile, SpecError> {
    let list: Vec<String> = removed.iter().map(|n| format!("\"{n}\"")).collect();
    load_top(&format!("include = [\"{base}\"]\nid = \"x\"\nremove_params = [{}]\n", list.join(", ")))
}

/// [`without`], loaded.
fn loaded(base: &str, removed: &[&str]) -> Arc<Profile> {
    Arc::new(without(base, removed).unwrap_or_else(|e| panic!("{base} without {removed:?}: {e}")))
}

/// A quiet world (no noise) with an object in finger 1's way at 5000.
fn object_at_5000() -> DeviceConfig {
    DeviceConfig {
        scenario: Scenario { objects: [Some(5000), None, None, None], strain_noise: 0, ..Scenario::default() },
        ..DeviceConfig::default()
    }
}

#[test]
fn a_profile_without_a_required_role_does_not_load_and_the_error_names_it() {
    let required: Vec<Role> = Role::ALL.iter().copied().filter(|r| r.absence() == Absence::Required).collect();
    assert!(required.contains(&Role::Position) && required.contains(&Role::CloseVelocity), "{required:?}");
    for role in required {
        // Every name of the role goes: bh8-262 has both HSG and MSG.
        let err = without("bh8-262-4.4.toml", role.names()).unwrap_err();
        assert_eq!(err, SpecError::MissingRole { profile: "x".into(), role, names: role.names() });
        let text = err.to_string();
        assert!(text.contains(role.names()[0]) && text.contains(role.absence_reason()), "{text}");
    }
}

#[test]
fn a_realtime_coefficient_is_required_only_with_its_flag() {
    for (coefficient, flag, role) in [
        ("LCVC", "LCV", Role::VelocityCoefficient),
        ("LFVC", "LFV", Role::FeedbackVelocityCoefficient),
        ("LFDPC", "LFDP", Role::DeltaCoefficient),
        ("BP", "LFBP", Role::BreakawayPosition),
    ] {
        let err = without("bh8-262-4.4.toml", &[coefficient]).unwrap_err();
        assert_eq!(err, SpecError::MissingRole { profile: "x".into(), role, names: role.names() }, "{coefficient}");
        let p = loaded("bh8-262-4.4.toml", &[coefficient, flag]);
        assert_eq!(p.role(role), None, "{coefficient}");
    }
    // bh8-262 4.3 has no LFBP, so it may lack BP.
    assert!(without("bh8-262-4.3.toml", &["BP"]).is_ok());
}

#[test]
fn without_ct_the_hand_table_must_give_both_close_targets() {
    let err = without("bh8-262-4.4.toml", &["CT"]).unwrap_err();
    let role = Role::CloseTarget;
    assert_eq!(err, SpecError::MissingRole { profile: "x".into(), role, names: role.names() });
    // The seed has no CT and states both targets; without one of them it does not load.
    let seed = embedded("seed.toml").unwrap();
    for line in ["finger_close_target = 17000\n", "spread_close_target = 3150\n"] {
        assert!(seed.contains(line), "{line}");
        let err = load_top(&seed.replacen(line, "", 1)).unwrap_err();
        assert!(matches!(err, SpecError::MissingRole { role: Role::CloseTarget, .. }), "{line}: {err}");
    }
}

#[test]
fn every_built_in_profile_has_what_it_requires() {
    for (name, _) in gcl_model::spec::EMBEDDED_PROFILES {
        let p = Profile::builtin(name).unwrap();
        for r in Role::ALL.iter().filter(|r| r.absence() == Absence::Required) {
            assert!(p.role(*r).is_some(), "{name} {r:?}");
        }
    }
    for r in Role::ALL {
        assert!(!r.absence_reason().is_empty(), "{r:?} gives no reason");
    }
}

#[test]
fn without_hold_a_finger_is_released_after_its_move() {
    // Pressing into the object, a powered finger's strain counts in full, a released one's
    // by half. Without HOLD the finger behaves as with HOLD 0.
    let strain_after_close = |profile: Arc<Profile>, hold: Option<&str>| {
        let mut d = hand_with(profile, object_at_5000());
        send(&mut d, "HI");
        if let Some(v) = hold {
            send(&mut d, &format!("1FSET HOLD {v}"));
        }
        assert_eq!(send(&mut d, "1C"), "1C\n\r=> ");
        send(&mut d, "1FGET SG")
    };
    let full = Profile::builtin("bh8-262-4.4").unwrap();
    let released = strain_after_close(full.clone(), Some("0"));
    let held = strain_after_close(full, Some("1"));
    assert_ne!(released, held, "HOLD must change the strain against the object");
    assert_eq!(strain_after_close(loaded("bh8-262-4.4.toml", &["HOLD"]), None), released);
}

#[test]
fn without_en_every_motor_takes_unprefixed_motion() {
    let mut d = hand_with(loaded("bh8-262-4.4.toml", &["EN"]), DeviceConfig::default());
    send(&mut d, "HI");
    assert_eq!(send(&mut d, "M 2000"), "M 2000\n\r=> ");
    assert_eq!(send(&mut d, "FGET P"), "FGET P\n\r2000 2000 2000 2000\n\r=> ");
}

#[test]
fn without_ct_c_closes_to_the_hand_tables_targets() {
    let text = embedded("bh8-262-4.4.toml").unwrap();
    let start = text.find("[hand]").unwrap();
    let end = text[start..].find("\n\n").map_or(text.len(), |e| start + e);
    let hand = &text[start..end];
    let top = format!(
        "include = [\"bh8-262-4.4.toml\"]\nid = \"x\"\nremove_params = [\"CT\"]\n{hand}\nfinger_close_target = 12000\nspread_close_target = 2000\n"
    );
    let mut d = hand_with(Arc::new(load_top(&top).unwrap()), DeviceConfig::default());
    send(&mut d, "HI");
    assert_eq!(send(&mut d, "C"), "C\n\r=> ");
    assert_eq!(send(&mut d, "FGET P"), "FGET P\n\r12000 12000 12000 2000\n\r=> ");
}

#[test]
fn without_lcv_and_lcvc_the_loop_still_runs() {
    let mut d = hand_with(loaded("bh8-262-4.4.toml", &["LCV", "LCVC"]), DeviceConfig::default());
    send(&mut d, "HI");
    send(&mut d, "1M 1500");
    send(&mut d, "1FSET LCPG 0 LFV 0 LFS 0 LFAP 1 LFDP 0 LFBP 0 LFAIN 0");
    assert_eq!(send(&mut d, "1LOOP"), "1LOOP*");
    d.handle_input(d.now(), b"A");
    // LFAP of 1500, big-endian.
    assert_eq!(d.take_output(), [b'*', 0x05, 0xDC]);
}

#[test]
fn without_bd_and_bp_a_breakaway_still_stops_the_finger_but_is_not_reported() {
    let run = |profile: Arc<Profile>| {
        let mut d = hand_with(profile, object_at_5000());
        send(&mut d, "HI");
        send(&mut d, "1FSET BS 1");
        let answer = send(&mut d, "1C");
        (answer, d.position(Motor::F1), d)
    };
    let (answer, at, mut full) = run(Profile::builtin("bh8-262-4.3").unwrap());
    assert_eq!(send(&mut full, "1FGET BD"), "1FGET BD\n\r1\n\r=> ", "the full profile breaks away");
    let (answer_without, at_without, _) = run(loaded("bh8-262-4.3.toml", &["BD", "BP"]));
    assert_eq!((answer_without, at_without), (answer, at));
}

#[test]
fn spec_readme_table_says_what_each_roles_absence_is() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../spec/README.md");
    let readme = std::fs::read_to_string(&path).unwrap();
    let section = readme.split("## Roles").nth(1).expect("spec/README.md has a Roles section");
    let mut seen: Vec<Role> = Vec::new();
    for row in section.lines().filter(|l| l.starts_with("| ") && !l.starts_with("| parameter")) {
        let cells: Vec<&str> = row.trim_matches('|').split('|').map(str::trim).collect();
        let [names, absence] = cells[..] else { panic!("row `{row}` needs two cells") };
        for name in names.split(", ").flat_map(|n| n.split(" or ")) {
            let role =
                *Role::ALL.iter().find(|r| r.names().contains(&name)).unwrap_or_else(|| panic!("{name}: no role"));
            let says = match role.absence() {
                Absence::Required => absence == "required",
                Absence::RequiredWith(_) => absence.starts_with("required with"),
                Absence::Value(v) => absence.starts_with(&format!("reads as {v}:")),
                Absence::HandCloseTargets => absence.starts_with("`[hand]`"),
                Absence::Unreported => absence.starts_with("not reported"),
            };
            assert!(says, "spec/README.md says {name} absent is `{absence}`, the code {:?}", role.absence());
            if !seen.contains(&role) {
                seen.push(role);
            }
        }
    }
    let missing: Vec<&Role> = Role::ALL.iter().filter(|r| !seen.contains(r)).collect();
    assert!(missing.is_empty(), "roles spec/README.md does not list: {missing:?}");
}
