//! Every parameter's effect: each parameter the profile marks with `effect` has a case about
//! it (a `Parameter X` clause) that sets it to a value other than its default and then does
//! something whose answer shows the difference (a motion, LOOP, a RealTime block, ^C, or a read
//! of another value), not only a read-back of the parameter itself.

use std::path::Path;

use gcl_harness::suite::{self, Case};
use gcl_model::Profile;
use gcl_model::grammar::{Args, Line, parse_line};
use gcl_model::spec::{CommandKind, ParamId};

const SUITE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../vectors/suite");

/// The stored parameter a name stands for (an alias's target).
fn canon(p: &Profile, id: ParamId) -> String {
    let x = p.param(id);
    x.alias_of.clone().unwrap_or_else(|| x.name.clone())
}

/// Whether the case sets `name` to a non-default value and later shows an effect.
fn shows_effect(p: &Profile, case: &Case, name: &str) -> bool {
    let mut set = false;
    for step in &case.transcript.steps {
        let Some(send) = &step.send else { continue };
        let bytes = send.bytes.strip_suffix(&[p.framing.terminator]).unwrap_or(&send.bytes);
        let parsed = parse_line(p, bytes);
        let line = match parsed {
            Ok(Line::Command(c)) => Some(c),
            _ => None,
        };
        let kind = line.as_ref().map(|c| p.command(c.command).kind);
        if let (Some(c), Some(CommandKind::MotorSet | CommandKind::GlobalSet)) = (&line, kind) {
            if let Args::Pairs(pairs) = &c.args {
                let motors: Vec<u8> = c.prefix.map_or(vec![1, 2, 3, 4], |m| m.iter().collect());
                for (id, v) in pairs {
                    if canon(p, *id) == name && motors.iter().any(|m| p.default_for(*id, *m) != *v) {
                        set = true;
                    }
                }
            }
            continue;
        }
        if !set {
            continue;
        }
        let only_reads_itself = match (&line, kind) {
            (Some(c), Some(CommandKind::MotorGet | CommandKind::GlobalGet)) => match &c.args {
                Args::Names(ns) => ns.iter().all(|id| canon(p, *id) == name),
                _ => true,
            },
            (Some(_), Some(k)) => matches!(
                k,
                CommandKind::MotorDefaults
                    | CommandKind::MotorLoad
                    | CommandKind::MotorSave
                    | CommandKind::GlobalDefaults
                    | CommandKind::GlobalLoad
                    | CommandKind::GlobalSave
                    | CommandKind::Reset
            ),
            // A RealTime block, ^C, or several lines at once.
            _ => false,
        };
        if !only_reads_itself {
            return true;
        }
    }
    false
}

#[test]
fn every_parameter_with_an_effect_has_a_case_that_shows_it() {
    let mut missing = Vec::new();
    let mut marked = 0;
    for name in Profile::builtin_names() {
        let p = Profile::builtin(name).unwrap();
        let cases = suite::load_profile(Path::new(SUITE), &p.id).unwrap();
        for x in p.params.iter().filter(|x| x.effect.is_some()) {
            marked += 1;
            assert!(x.alias_of.is_none(), "{}: mark {}'s target, not the alias", p.id, x.name);
            let clause = format!(": Parameter {}", x.name);
            let shown = cases
                .iter()
                .filter(|c| c.header().clauses.iter().any(|k| k.ends_with(&clause)))
                .any(|c| shows_effect(&p, c, &x.name));
            if !shown {
                missing.push(format!("{}: {}", p.id, x.name));
            }
        }
    }
    assert!(marked > 50, "only {marked} marked parameters");
    assert!(missing.is_empty(), "parameters with an effect and no case showing it:\n{}", missing.join("\n"));
}
