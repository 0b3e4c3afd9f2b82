//! The grammar table (`testdata/grammar.toml`) against every built-in profile: each line gets
//! the status the table gives for that profile, and nothing else.

use std::collections::BTreeMap;

use gcl_model::{Profile, parse_line};
use serde::Deserialize;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Table {
    row: Vec<Row>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Row {
    line: String,
    status: u32,
    #[serde(default, rename = "override")]
    overrides: BTreeMap<String, u32>,
    #[serde(default)]
    why: String,
}

#[test]
fn every_profile_answers_every_line_of_the_grammar_table() {
    let table: Table = toml::from_str(include_str!("../../testdata/grammar.toml")).unwrap();
    assert!(table.row.len() >= 30, "the table has {} rows", table.row.len());
    let names: Vec<&str> = Profile::builtin_names().collect();
    let mut failures = Vec::new();
    for row in &table.row {
        for unknown in row.overrides.keys().filter(|k| !names.contains(&k.as_str())) {
            failures.push(format!("{:?}: override for unknown profile {unknown}", row.line));
        }
        for name in &names {
            let p = Profile::builtin(name).unwrap();
            let want = row.overrides.get(*name).copied().unwrap_or(row.status);
            let got = match parse_line(&p, row.line.as_bytes()) {
                Ok(_) => 0,
                Err(r) => r.status.code(),
            };
            if got != want {
                failures.push(format!("{name}: {:?} gives {got}, the table says {want} ({})", row.line, row.why));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
