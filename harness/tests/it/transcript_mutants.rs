//! Every deliberate firmware bug of the simulator fails at least one golden case, and the
//! failure points at the byte where the answer parts. (In-process and in simulated time: the
//! subprocess version of this check belongs to `gcl conform`.)

use std::path::PathBuf;

use gcl_harness::replay::ReplayOutcome;
use gcl_harness::suite;
use gcl_host::SimLink;
use gcl_model::{DeviceConfig, Fault, Profile};

fn committed() -> Vec<suite::Case> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..").join(suite::DEFAULT_DIR);
    suite::load_dir(&dir).unwrap()
}

#[test]
fn every_fault_is_caught_by_some_case() {
    let cases = committed();
    let mut missed = Vec::new();
    for &fault in Fault::ALL {
        let caught = cases.iter().find_map(|case| {
            let profile = Profile::builtin(&case.profile).unwrap();
            let config = DeviceConfig { faults: vec![fault], ..suite::model_config(case.header()) };
            let mut link = SimLink::new(profile, config);
            let out = suite::run_case(case, &mut link, &suite::replay_options());
            (!out.is_pass()).then(|| (case.rel_path(), out))
        });
        match caught {
            Some((path, out)) => {
                assert!(out.failed_step().is_some(), "{fault}: {}", path.display());
                println!("{fault:>20}: {} — {}", path.display(), out.summary());
            }
            None => missed.push(fault.name()),
        }
    }
    assert!(missed.is_empty(), "faults no case catches: {missed:?}");
}

#[test]
fn crlf_mismatch_shows_expected_and_actual_at_the_parting_byte() {
    let cases = committed();
    let case = cases.iter().find(|c| c.profile == "seed" && c.id() == "framing-echo").unwrap();
    let mut link = SimLink::new(
        Profile::builtin("seed").unwrap(),
        DeviceConfig { faults: vec![Fault::CrLf], ..Default::default() },
    );
    let out = suite::run_case(case, &mut link, &suite::replay_options());
    let ReplayOutcome::Mismatch(m) = &out else { panic!("{}", out.render()) };
    assert_eq!((m.step, m.offset), (0, 0));
    assert_eq!(m.expected, "\\n\\r=> ");
    assert_eq!(m.actual, "\\r\\n=> ");
    let text = out.render();
    assert!(text.contains("expected: \"\\n\\r=> \""), "{text}");
    assert!(text.contains("actual:   \"\\r\\n=> \""), "{text}");
    assert!(text.contains("^ byte 0"), "{text}");
}

#[test]
fn little_endian_lfap_parts_at_the_high_byte() {
    let cases = committed();
    let case = cases.iter().find(|c| c.profile == "bh8-262-4.4" && c.id() == "rt-lfap-byte-order").unwrap();
    let mut link = SimLink::new(
        Profile::builtin("bh8-262-4.4").unwrap(),
        DeviceConfig { faults: vec![Fault::LittleEndianLfap], ..Default::default() },
    );
    let out = suite::run_case(case, &mut link, &suite::replay_options());
    let ReplayOutcome::Mismatch(m) = &out else { panic!("{}", out.render()) };
    assert_eq!(m.offset, 1, "{}", out.render());
    assert_eq!(m.actual, "88 13");
    assert_eq!(m.expected, "{u16 4950..5050}");
}
