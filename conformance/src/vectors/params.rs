//! `parameters`: the parameter table as a host or a firmware sees it: scope, range, defaults
//! for fingers and spread, read-only, the commands that read and write it and the
//! save/load/default commands that cover it. The oracle is the profile.

use gcl_model::spec::Scope;
use serde_json::json;

use super::grammar::param_flags;
use super::{FileBuilder, Test, VectorsError, slug};

pub(crate) fn build(b: &mut FileBuilder<'_>) -> Result<(), VectorsError> {
    let p = b.profile();
    for id in p.param_ids() {
        let ps = p.param(id);
        let scope = match ps.scope {
            Scope::Motor => "motor",
            Scope::Global => "global",
        };
        let mut flags: Vec<&'static str> = param_flags(&ps.name).to_vec();
        if !ps.persist.is_empty() {
            flags.extend(["seed-saved-set", "bh8-saved-sets"]);
        }
        // The profiles give the spread no default of its own where the manual says "N/A"; the
        // spread then starts at the finger default (an open decision).
        if ps.scope == Scope::Motor && ps.default_spread.is_none() && !ps.read_only {
            flags.push("bh8-spread-defaults");
        }
        let finger_default = (ps.default.is_some() || ps.default_spread.is_some()).then(|| p.default_for(id, 1));
        let spread_default = match ps.scope {
            Scope::Motor => finger_default.map(|_| p.default_for(id, 4)),
            Scope::Global => None,
        };
        let body = json!({
            "name": ps.name,
            "scope": scope,
            "section": ps.section,
            "description": ps.description,
            "min": ps.min,
            "max": ps.max,
            "values": ps.values,
            "default": finger_default,
            "default_spread": spread_default,
            "read_only": ps.read_only,
            "advanced": ps.advanced,
            "get": p.getter(id),
            "set": if ps.read_only { None } else { Some(p.setter(id)) },
            "persist": ps.persist,
            "alias_of": ps.alias_of,
            "input_aliases": ps.input_aliases,
            "live": ps.live,
            "self_stored": ps.self_stored,
            "realtime": ps.rt.map(|rt| json!({
                "block": match rt.block { gcl_model::spec::BlockKind::Control => "control", gcl_model::spec::BlockKind::Feedback => "feedback" },
                "size": rt.size,
                "signed": rt.signed,
            })),
        });
        let comment = format!(
            "{} ({scope}): {}; {}",
            ps.name,
            ps.description,
            match &ps.values {
                Some(vs) => format!("one of {vs:?}"),
                None => format!("{}..{}", ps.min, ps.max),
            }
        );
        b.push(Test::new(format!("param-{}", slug(&ps.name)), comment, true, body).flags(&flags))?;
    }
    Ok(())
}
