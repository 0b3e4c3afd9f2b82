//! The rule for every decision that promises something on the wire: a case checks the
//! promise, and the case would fail without it.
//!
//! A decision whose level is MUST or SHOULD binds a conformance check, and every such
//! decision in the built-in profiles is about bytes a host sees, so each is a wire promise.
//! On every profile, for each one:
//! - (a) at least one committed case checks it (cites it as a `decision:` clause; for a
//!   framing decision, any case resting on it, since every expectation spells out the echo,
//!   the line ending and the prompt);
//! - (b) some firmware fault (`gcl_model::Fault`) that violates it makes one of those cases
//!   fail, run in-process against the model.
//!
//! Which fault violates which decision is read from what the fault fails (see [`violates`]):
//! a fault that fails most of the suite (a broken echo, prompt or line ending) breaks the
//! framing, so it counts only for the framing decisions (the `framing-` ones and
//! `suite::FRAMING`); a fault that fails many cases counts only for a decision most of its
//! failures check; a narrow fault counts for each decision whose case it fails. A decision
//! that cannot meet (a) or (b) yet is listed, with its
//! reason, in `spec/uncovered-decisions.toml`; the list is kept honest both ways: a listed
//! decision that has become covered, or that is no longer a wire promise, fails this test,
//! so the list only shrinks.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use std::sync::Arc;

use gcl_harness::suite::{self, Case};
use gcl_host::SimLink;
use gcl_model::level::Level;
use gcl_model::{DeviceConfig, Fault, Profile};
use serde::Deserialize;

const SUITE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../vectors/suite");
const UNCOVERED: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../spec/uncovered-decisions.toml");

/// What a listed decision lacks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
enum Lacks {
    /// No case checks it.
    Case,
    /// Cases check it, but no fault breaks it.
    Fault,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Entry {
    id: String,
    /// The profiles it applies to; every profile that has the decision when absent.
    #[serde(default)]
    profiles: Vec<String>,
    lacks: Lacks,
    reason: String,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct List {
    #[serde(default)]
    uncovered: Vec<Entry>,
}

fn allow_list() -> Vec<Entry> {
    let text = std::fs::read_to_string(UNCOVERED).expect("spec/uncovered-decisions.toml");
    let list: List = toml::from_str(&text).expect("spec/uncovered-decisions.toml parses");
    for e in &list.uncovered {
        assert!(e.reason.trim().len() >= 20, "{}: give a reason of a sentence", e.id);
    }
    list.uncovered
}

fn is_wire_promise(level: &Level) -> bool {
    matches!(level, Level::Must | Level::Should)
}

fn is_framing(id: &str) -> bool {
    id.starts_with("framing-") || suite::FRAMING.contains(&id)
}

/// Whether `case` passes against the model of `profile` with `faults`.
fn passes(case: &Case, profile: &Arc<Profile>, faults: &[Fault]) -> bool {
    let config = DeviceConfig { faults: faults.to_vec(), ..suite::model_config(case.header()) };
    let mut link = SimLink::new(profile.clone(), config);
    suite::run_case(case, &mut link, &suite::replay_options()).is_pass()
}

/// For each fault, the ids of the cases it makes fail among `cases`; run on two threads.
fn failures(profile: &Arc<Profile>, cases: &[&Case]) -> BTreeMap<Fault, BTreeSet<String>> {
    let (a, b) = Fault::ALL.split_at(Fault::ALL.len() / 2);
    let run = |faults: &[Fault]| -> Vec<(Fault, BTreeSet<String>)> {
        faults
            .iter()
            .map(|&f| (f, cases.iter().filter(|c| !passes(c, profile, &[f])).map(|c| c.id().to_string()).collect()))
            .collect()
    };
    std::thread::scope(|s| {
        let t = s.spawn(|| run(a));
        let mut out: BTreeMap<Fault, BTreeSet<String>> = run(b).into_iter().collect();
        out.extend(t.join().unwrap());
        out
    })
}

/// Whether a fault that makes the cases `failed` fail (of `total`) violates a decision that
/// the cases `checking` check (`framing`: a framing decision, which every case resting on it
/// checks; `cited` are the cases that cite it as their clause).
/// - A fault that fails most of the suite breaks the framing every case spells out: it
///   violates the framing decisions only.
/// - A narrow fault (failing at most a fifth of the suite) violates a non-framing decision whose
///   case it fails, and a framing decision only through a case that cites it.
/// - A broad one (more than a fifth) only the decisions that at least half of its failures check:
///   a fault that reverses FGET's order fails a velocity case through its read-back, but it
///   does not break the velocity units.
fn violates(
    failed: &BTreeSet<String>,
    total: usize,
    checking: &BTreeSet<&str>,
    cited: &BTreeSet<&str>,
    framing: bool,
) -> bool {
    let hit = failed.iter().filter(|c| checking.contains(c.as_str())).count();
    if hit == 0 {
        return false;
    }
    if failed.len() * 2 > total {
        framing
    } else if framing {
        failed.iter().any(|c| cited.contains(c.as_str()))
    } else {
        failed.len() * 5 <= total || hit * 2 >= failed.len()
    }
}

/// The faults that fail a case in `checking` but mostly other cases, for a message.
fn incidental(failed: &BTreeMap<Fault, BTreeSet<String>>, checking: &BTreeSet<&str>) -> String {
    let some: Vec<String> = failed
        .iter()
        .filter_map(|(f, cs)| {
            let hit = cs.iter().filter(|c| checking.contains(c.as_str())).count();
            (hit > 0).then(|| format!("{f} ({hit} of the {} cases it fails)", cs.len()))
        })
        .collect();
    if some.is_empty() { String::new() } else { format!("; it is only among the failures of {}", some.join(", ")) }
}

#[test]
#[ignore = "slow: .ci/run runs it (cargo test --workspace -- --include-ignored)"]
fn every_wire_promise_is_checked_by_a_case_that_fails_without_it() {
    let list = allow_list();
    let listed = |p: &str, id: &str| -> Option<&Entry> {
        list.iter().find(|e| e.id == id && (e.profiles.is_empty() || e.profiles.iter().any(|x| x == p)))
    };
    let mut problems = Vec::new();
    let mut used: BTreeSet<(String, String)> = BTreeSet::new();
    for name in Profile::builtin_names() {
        let p = Profile::builtin(name).unwrap();
        let cases = suite::load_profile(Path::new(SUITE), &p.id).unwrap();
        let wire: Vec<&str> = p.decisions.iter().filter(|d| is_wire_promise(&d.level)).map(|d| d.id.as_str()).collect();
        // A framing decision is checked by every case that rests on it (each expectation
        // spells out the echo, line ending and prompt); any other by the cases that cite it.
        let checks = |c: &Case, d: &str| -> bool {
            if is_framing(d) {
                c.decisions().iter().any(|x| x == d)
            } else {
                c.checked_decisions().iter().any(|x| x == d)
            }
        };
        let citing = |d: &str| -> Vec<&Case> { cases.iter().filter(|c| checks(c, d)).collect() };
        // The model keeps every promise it makes: each citing case passes without a fault.
        let relevant: Vec<&Case> = cases.iter().filter(|c| wire.iter().any(|d| checks(c, d))).collect();
        for c in &relevant {
            assert!(passes(c, &p, &[]), "{}/{}: the model fails its own case", p.id, c.id());
        }
        let failed = failures(&p, &relevant);
        for d in &wire {
            let by = citing(d);
            let ids: BTreeSet<&str> = by.iter().map(|c| c.id()).collect();
            let cited: BTreeSet<&str> =
                by.iter().filter(|c| c.checked_decisions().iter().any(|x| x == d)).map(|c| c.id()).collect();
            // The violating fault most of whose failures check the decision.
            let share =
                |cs: &BTreeSet<String>| cs.iter().filter(|c| ids.contains(c.as_str())).count() as f64 / cs.len() as f64;
            let breaker = failed
                .iter()
                .filter(|(_, cs)| violates(cs, relevant.len(), &ids, &cited, is_framing(d)))
                .max_by(|a, b| share(a.1).total_cmp(&share(b.1)));
            let lacks = if by.is_empty() {
                Some(Lacks::Case)
            } else if breaker.is_none() {
                Some(Lacks::Fault)
            } else {
                None
            };
            match (lacks, listed(&p.id, d)) {
                (None, None) => {}
                (None, Some(e)) => {
                    let (f, cs) = breaker.unwrap();
                    let c = cs.iter().find(|c| ids.contains(c.as_str())).unwrap();
                    problems.push(format!(
                        "{}: {d} is listed as lacking a {:?}, but case {} checks it and fault {f} makes it fail: remove it from the list",
                        p.id,
                        e.lacks,
                        c
                    ))
                }
                (Some(l), None) => problems.push(format!(
                    "{}: {d} is a wire promise ({}) but {}",
                    p.id,
                    p.decisions.iter().find(|x| x.id == *d).unwrap().level,
                    match l {
                        Lacks::Case => "no case checks it".to_string(),
                        Lacks::Fault => format!(
                            "no fault that violates it makes a case that checks it fail ({}): add a fault, or list it with a reason{}",
                            ids.iter().copied().collect::<Vec<_>>().join(", "),
                            incidental(&failed, &ids)
                        ),
                    }
                )),
                (Some(l), Some(e)) => {
                    used.insert((e.id.clone(), p.id.clone()));
                    if l != e.lacks {
                        problems.push(format!("{}: {d} lacks a {l:?}, the list says a {:?}", p.id, e.lacks));
                    }
                }
            }
        }
    }
    // Every entry is still needed somewhere (or it names a decision that is no wire promise).
    for e in &list {
        if !used.iter().any(|(id, _)| *id == e.id) {
            problems
                .push(format!("{}: listed as uncovered, but it is covered (or no wire promise) on its profiles", e.id));
        }
    }
    assert!(problems.is_empty(), "{} problems:\n{}", problems.len(), problems.join("\n"));
}
