//! `layout`: RealTime flags and the motors of a loop, giving the control and feedback block
//! layouts. The oracle is the model's `RtLayout::compute`.

use gcl_model::params::ParamStore;
use gcl_model::realtime::BlockLayout;
use gcl_model::spec::Scope;
use gcl_model::{MotorSet, Profile, RtLayout};
use serde_json::{Value, json};

use super::{FileBuilder, Test, VectorsError, slug};

/// The names of the profile's RealTime flags (parameters that add a field), in table order.
pub(crate) fn rt_flags(p: &Profile) -> Vec<String> {
    p.param_ids().map(|id| p.param(id)).filter(|ps| ps.rt.is_some()).map(|ps| ps.name.clone()).collect()
}

/// The layouts of a loop of `motors` where exactly the flags `on` are 1 (every other
/// RealTime flag 0).
pub(crate) fn layout_with(p: &Profile, motors: MotorSet, on: &[&str]) -> RtLayout {
    let mut store = ParamStore::defaults(p);
    for id in p.param_ids() {
        let ps = p.param(id);
        if ps.rt.is_some() {
            let v = i64::from(on.contains(&ps.name.as_str()));
            let ms = if ps.scope == Scope::Global { MotorSet::ALL } else { motors | MotorSet::ALL };
            store.set_unchecked(p, id, ms, v);
        }
    }
    RtLayout::compute(p, &store, motors)
}

/// A block layout as JSON: size and fields.
pub(crate) fn block_json(l: &BlockLayout) -> Value {
    json!({
        "size": l.size(),
        "fields": l.fields().iter().map(|f| json!({
            "motor": f.motor(),
            "name": f.name(),
            "offset": f.offset(),
            "size": f.size(),
            "signed": f.signed(),
        })).collect::<Vec<_>>(),
    })
}

/// Decisions a layout with these flags depends on.
pub(crate) fn layout_flags(on: &[&str]) -> Vec<&'static str> {
    let mut f = vec!["seed-rt-field-order", "seed-rt-feedback-order", "bh8-44-rt-field-order", "bh8-loop-motors"];
    for n in on {
        f.extend(super::grammar::param_flags(n).iter().copied().filter(|d| !d.contains("range")));
    }
    f
}

pub(crate) fn build(b: &mut FileBuilder<'_>) -> Result<(), VectorsError> {
    let p = b.profile();
    let flags = rt_flags(p);
    let names: Vec<&str> = flags.iter().map(String::as_str).collect();
    let mut cases: Vec<(String, String, MotorSet, Vec<&str>)> = vec![
        ("none".into(), "no flag set: both blocks are the header alone".into(), MotorSet::FINGERS, vec![]),
        ("all-flags-all-motors".into(), "every flag on all four motors".into(), MotorSet::ALL, names.clone()),
        ("all-flags-motor-2".into(), "every flag, motor 2 alone".into(), MotorSet::from_motors([2]), names.clone()),
        ("all-flags-fingers".into(), "every flag on the three fingers".into(), MotorSet::FINGERS, names.clone()),
    ];
    for n in &names {
        cases.push((format!("only-{}", slug(n)), format!("{n} alone, fingers 1 2 3"), MotorSet::FINGERS, vec![*n]));
        cases.push((format!("only-{}-spread", slug(n)), format!("{n} alone, the spread"), MotorSet::SPREAD, vec![*n]));
    }
    for pair in [["LCV", "LFAP"], ["LCPG", "LFDP"], ["LFV", "LFS"]] {
        if pair.iter().all(|n| names.contains(n)) {
            let on: Vec<&str> = pair.to_vec();
            cases.push((
                format!("{}-and-{}-motors-1-3", slug(pair[0]), slug(pair[1])),
                format!("{} and {}, motors 1 and 3: fields are grouped by motor", pair[0], pair[1]),
                MotorSet::from_motors([1, 3]),
                on,
            ));
        }
    }
    for (id, comment, motors, on) in cases {
        let l = layout_with(p, motors, &on);
        let body = json!({
            "motors": motors.iter().collect::<Vec<u8>>(),
            "flags_on": on,
            "control": block_json(l.control()),
            "feedback": block_json(l.feedback()),
        });
        let comment = format!(
            "{comment}: control {} bytes, feedback {} bytes (headers included)",
            l.control().size(),
            l.feedback().size()
        );
        b.push(Test::new(format!("layout-{id}"), comment, true, body).flags(&layout_flags(&on)))?;
    }
    Ok(())
}
