//! The example transcript in `vectors/README.md` is the first one other implementers read:
//! it must parse and pass against the reference model, so it cannot rot.

use gcl_harness::replay::{ReplayOptions, replay};
use gcl_host::{SimLink, Target, target};
use gcl_transcript::parse;

#[test]
fn the_readme_example_transcript_passes_on_the_model() {
    let readme = include_str!("../../../vectors/README.md");
    let start = readme.find("```\ngcl-transcript 1").expect("the README shows a transcript") + 4;
    let end = start + readme[start..].find("```").expect("the block ends");
    let t = parse(&readme[start..end]).unwrap_or_else(|e| panic!("the README example does not parse: {e}"));
    let profile = &t.header.profiles[0];
    let opts = target::OpenOptions::default();
    let mut link = target::open(&Target::Sim { profile: Some(profile.clone()) }, &opts).unwrap();
    let out = replay(&t, link.as_mut(), &ReplayOptions::default());
    assert!(out.is_pass(), "{}", out.render());
    // And it is the model's own answer, not a lenient one: a hand with little-endian LFAP fails.
    let p = gcl_model::Profile::builtin(profile).unwrap();
    let faulty = gcl_model::DeviceConfig { faults: vec![gcl_model::Fault::LittleEndianLfap], ..Default::default() };
    let mut bad = SimLink::new(p, faulty);
    assert!(!replay(&t, &mut bad, &ReplayOptions::default()).is_pass());
}
