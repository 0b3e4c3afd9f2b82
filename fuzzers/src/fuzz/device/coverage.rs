//! Model-guided coverage: what the shadow model exercised, as `category:item` features
//! (commands, prefixes, parameters read and written, status bits, mode transitions, RealTime
//! layouts and headers, aborts), and the table of what a run reached out of what the profile
//! has. Computed from the model's public API only; the model itself is not instrumented.

use std::collections::{BTreeMap, BTreeSet};

use gcl_model::{Profile, StatusBits};
use serde::Serialize;

/// One row of the coverage table.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, serde::Deserialize)]
pub struct CoverageRow {
    /// The category (`command`, `param-write`, `status`, ...).
    pub category: String,
    /// Features reached.
    pub reached: usize,
    /// Features the profile has (`None` where the set is open, as layouts).
    pub total: Option<usize>,
    /// Features of the profile not reached.
    pub missing: Vec<String>,
}

/// Every feature the profile offers, by category (open categories are absent).
pub fn universe(p: &Profile) -> BTreeMap<String, BTreeSet<String>> {
    let mut u: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    let mut add = |c: &str, i: String| {
        u.entry(c.to_string()).or_default().insert(i);
    };
    for c in &p.commands {
        add("command", c.name.clone());
    }
    add("command", "(empty line)".into());
    for s in &p.params {
        add("param-read", s.name.clone());
        if !s.read_only {
            add("param-write", s.name.clone());
        }
    }
    for s in &p.status {
        // Bits the model never sends (the profile says so) cannot be reached through it.
        if s.sent && StatusBits::from_bits(s.bit).is_some() {
            add("status", s.bit.to_string());
        }
    }
    for t in ["Idle->Busy", "Busy->Idle", "Idle->Loop", "Loop->Idle"] {
        add("mode", t.into());
    }
    for h in ["C", "c", "A", "a", "invalid"] {
        add("rt-header", h.into());
    }
    for a in ["idle", "loop", "mid-line", "mid-motion", "mid-block"] {
        add("abort", a.into());
    }
    u
}

/// The coverage table of a set of features against the profile.
pub fn table(p: &Profile, reached: &BTreeSet<String>) -> Vec<CoverageRow> {
    let mut by: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for f in reached {
        if let Some((c, i)) = f.split_once(':') {
            by.entry(c.to_string()).or_default().insert(i.to_string());
        }
    }
    let u = universe(p);
    let mut cats: BTreeSet<String> = u.keys().cloned().collect();
    cats.extend(by.keys().cloned());
    cats.into_iter()
        .map(|c| {
            let got = by.get(&c).cloned().unwrap_or_default();
            match u.get(&c) {
                Some(all) => CoverageRow {
                    reached: all.intersection(&got).count(),
                    total: Some(all.len()),
                    missing: all.difference(&got).cloned().collect(),
                    category: c,
                },
                None => CoverageRow { reached: got.len(), total: None, missing: Vec::new(), category: c },
            }
        })
        .collect()
}

/// The table as text for a console.
pub fn render(rows: &[CoverageRow]) -> String {
    let mut s = String::from("coverage (model features reached):\n");
    for r in rows {
        let total = r.total.map_or("-".to_string(), |t| t.to_string());
        let mut missing = r.missing.iter().take(12).cloned().collect::<Vec<_>>().join(" ");
        if r.missing.len() > 12 {
            missing.push_str(&format!(" ... (+{})", r.missing.len() - 12));
        }
        s.push_str(&format!(
            "  {:<12} {:>4} / {:<4} {}\n",
            r.category,
            r.reached,
            total,
            if missing.is_empty() { String::new() } else { format!("not reached: {missing}") }
        ));
    }
    s
}
