//! The spec files and the model agree. Each profile is read here a second time, straight
//! from the TOML under `spec/` with a merge written for this test (includes first, later
//! entries replace earlier ones of the same name), and what the files say is checked against
//! the loaded [`Profile`] and against the bytes of a freshly powered-up [`Device`].

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use gcl_model::spec::{ArgRule, PrefixRule};
use gcl_model::{Device, DeviceConfig, Profile};
use toml::Value;

fn spec_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../spec")
}

/// A profile as the files state it, merged by this test.
#[derive(Default)]
struct FileProfile {
    id: String,
    aliases: Vec<String>,
    commands: Vec<Value>,
    params: Vec<Value>,
    status: BTreeMap<u32, String>,
}

fn str_of<'a>(v: &'a Value, key: &str) -> Option<&'a str> {
    v.get(key).and_then(Value::as_str)
}

fn int_of(v: &Value, key: &str) -> Option<i64> {
    v.get(key).and_then(Value::as_integer)
}

fn bool_of(v: &Value, key: &str) -> bool {
    v.get(key).and_then(Value::as_bool).unwrap_or(false)
}

fn array_of<'a>(v: &'a Value, key: &str) -> &'a [Value] {
    v.get(key).and_then(Value::as_array).map_or(&[], Vec::as_slice)
}

fn merge_by_name(into: &mut Vec<Value>, from: &[Value]) {
    for item in from {
        let name = str_of(item, "name").unwrap();
        match into.iter_mut().find(|x| str_of(x, "name") == Some(name)) {
            Some(slot) => *slot = item.clone(),
            None => into.push(item.clone()),
        }
    }
}

fn remove_named(list: &mut Vec<Value>, names: &[Value]) {
    list.retain(|x| !names.iter().any(|n| n.as_str() == str_of(x, "name")));
}

fn merge_file(rel: &str, into: &mut FileProfile) {
    let path = spec_dir().join(rel);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let file: Value = toml::from_str(&text).unwrap_or_else(|e| panic!("{rel}: {e}"));
    for inc in array_of(&file, "include") {
        merge_file(inc.as_str().unwrap(), into);
    }
    if let Some(id) = str_of(&file, "id") {
        into.id = id.to_string();
    }
    into.aliases.extend(array_of(&file, "aliases").iter().map(|a| a.as_str().unwrap().to_string()));
    merge_by_name(&mut into.commands, array_of(&file, "commands"));
    remove_named(&mut into.commands, array_of(&file, "remove_commands"));
    merge_by_name(&mut into.params, array_of(&file, "params"));
    remove_named(&mut into.params, array_of(&file, "remove_params"));
    for s in array_of(&file, "status") {
        into.status.insert(int_of(s, "bit").unwrap() as u32, str_of(s, "text").unwrap().to_string());
    }
}

/// Every top-level file under `spec/` with an `id`: a profile.
fn file_profiles() -> Vec<FileProfile> {
    let mut files: Vec<String> = std::fs::read_dir(spec_dir())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".toml"))
        .collect();
    files.sort();
    let mut out = Vec::new();
    for f in files {
        let mut p = FileProfile::default();
        merge_file(&f, &mut p);
        if !p.id.is_empty() {
            out.push(p);
        }
    }
    out
}

fn fresh(profile: &Arc<Profile>) -> Device {
    support::hand_with(profile.clone(), DeviceConfig::default())
}

use crate::support;
use support::send;

fn err(line: &str, status: u32) -> String {
    format!("{line}\n\rERR {status}\n\r=> ")
}

/// The command word that reads a parameter, as the file states it.
fn getter(p: &Value) -> String {
    str_of(p, "get").map(str::to_string).unwrap_or_else(|| match str_of(p, "scope") {
        Some("motor") => "FGET".into(),
        _ => "PGET".into(),
    })
}

/// The command word that writes a parameter, as the file states it.
fn setter(p: &Value) -> String {
    str_of(p, "set").map(str::to_string).unwrap_or_else(|| match str_of(p, "scope") {
        Some("motor") => "FSET".into(),
        _ => "PSET".into(),
    })
}

fn has_command(fp: &FileProfile, name: &str) -> bool {
    fp.commands.iter().any(|c| str_of(c, "name") == Some(name))
}

#[test]
fn there_are_three_profiles_and_an_alias() {
    let fps = file_profiles();
    let ids: Vec<&str> = fps.iter().map(|p| p.id.as_str()).collect();
    assert_eq!(ids, vec!["bh8-262-4.3", "bh8-262-4.4", "seed"]);
    let mut builtin: Vec<&str> = Profile::builtin_names().collect();
    builtin.sort();
    assert_eq!(builtin, ids);
    for fp in &fps {
        assert_eq!(Profile::builtin(&fp.id).unwrap().id, fp.id);
        for alias in &fp.aliases {
            assert_eq!(Profile::builtin(alias).unwrap().id, fp.id, "alias {alias}");
        }
    }
    assert_eq!(Profile::builtin("bh8-262").unwrap().id, "bh8-262-4.4");
    assert!(Profile::builtin("bh8-262-9.9").is_err());
}

#[test]
fn every_command_in_the_files_is_in_the_profile() {
    for fp in file_profiles() {
        let profile = Profile::builtin(&fp.id).unwrap();
        assert_eq!(profile.commands.len(), fp.commands.len(), "{}: number of commands", fp.id);
        for c in &fp.commands {
            let name = str_of(c, "name").unwrap();
            let id = profile.command_id(name).unwrap_or_else(|| panic!("{}: {name} missing", fp.id));
            let spec = profile.command(id);
            let prefix = match spec.prefix {
                PrefixRule::Allowed => "allowed",
                PrefixRule::Forbidden => "forbidden",
            };
            let args = match spec.args {
                ArgRule::None => "none",
                ArgRule::OptionalInteger => "optional-integer",
                ArgRule::Names => "names",
                ArgRule::Pairs => "pairs",
            };
            assert_eq!(Some(prefix), str_of(c, "prefix"), "{}: prefix rule of {name}", fp.id);
            assert_eq!(Some(args), str_of(c, "args"), "{}: argument rule of {name}", fp.id);
            assert_eq!(spec.arg_min, int_of(c, "arg_min"), "{}: arg_min of {name}", fp.id);
            assert_eq!(spec.arg_max, int_of(c, "arg_max"), "{}: arg_max of {name}", fp.id);
        }
    }
}

/// A well-formed use of a command with a prefix glued on, so that the prefix is its only fault.
fn prefixed_use(fp: &FileProfile, c: &Value) -> String {
    let name = str_of(c, "name").unwrap();
    let tail = match str_of(c, "args").unwrap() {
        "names" => {
            let p = fp.params.iter().find(|p| getter(p) == name).expect("a parameter to read");
            format!(" {}", str_of(p, "name").unwrap())
        }
        "pairs" => {
            let p = fp
                .params
                .iter()
                .find(|p| setter(p) == name && !bool_of(p, "read_only") && int_of(p, "default").is_some())
                .expect("a parameter to write");
            format!(" {} {}", str_of(p, "name").unwrap(), int_of(p, "default").unwrap())
        }
        _ => String::new(),
    };
    format!("1{name}{tail}")
}

#[test]
fn a_prefix_on_a_command_that_takes_none_gives_4096() {
    for fp in file_profiles() {
        let profile = Profile::builtin(&fp.id).unwrap();
        let mut d = fresh(&profile);
        let mut checked = 0;
        for c in fp.commands.iter().filter(|c| str_of(c, "prefix") == Some("forbidden")) {
            let line = prefixed_use(&fp, c);
            assert_eq!(send(&mut d, &line), err(&line, 4096), "{}", fp.id);
            checked += 1;
        }
        assert!(checked >= 4, "{}: only {checked} no-prefix commands", fp.id);
        // Nothing above ran: the hand is still as it powered up.
        assert_eq!(send(&mut d, "C"), err("C", 4), "{}", fp.id);
    }
}

#[test]
fn fresh_hands_read_the_files_defaults() {
    for fp in file_profiles() {
        let profile = Profile::builtin(&fp.id).unwrap();
        let mut d = fresh(&profile);
        let mut checked = 0;
        for p in fp.params.iter().filter(|p| !bool_of(p, "live")) {
            let name = str_of(p, "name").unwrap();
            let get = getter(p);
            let Some(finger) = int_of(p, "default") else { continue };
            let spread = int_of(p, "default_spread").unwrap_or(finger);
            let values =
                if get == "FGET" { format!("{finger} {finger} {finger} {spread}") } else { finger.to_string() };
            let line = format!("{get} {name}");
            assert_eq!(send(&mut d, &line), format!("{line}\n\r{values}\n\r=> "), "{}", fp.id);
            checked += 1;
        }
        assert!(checked >= 20, "{}: only {checked} defaults", fp.id);
    }
}

#[test]
fn writes_one_past_the_range_give_128() {
    for fp in file_profiles() {
        let profile = Profile::builtin(&fp.id).unwrap();
        let mut d = fresh(&profile);
        for p in fp.params.iter().filter(|p| !bool_of(p, "read_only") && !bool_of(p, "live")) {
            let name = str_of(p, "name").unwrap();
            let set = setter(p);
            let (min, max) = (int_of(p, "min").unwrap(), int_of(p, "max").unwrap());
            let mut bad = vec![max + 1, min - 1];
            if let Some(values) = p.get("values").and_then(Value::as_array) {
                let values: Vec<i64> = values.iter().map(|v| v.as_integer().unwrap()).collect();
                bad.extend((min..=max).filter(|v| !values.contains(v)).take(3));
            }
            for v in bad {
                let line = format!("{set} {name} {v}");
                assert_eq!(send(&mut d, &line), err(&line, 128), "{}", fp.id);
            }
            // The edges themselves are fine.
            for v in [min, max] {
                let v = match p.get("values").and_then(Value::as_array) {
                    Some(vs) if v == min => vs[0].as_integer().unwrap(),
                    Some(vs) => vs[vs.len() - 1].as_integer().unwrap(),
                    None => v,
                };
                let line = format!("{set} {name} {v}");
                assert_eq!(send(&mut d, &line), format!("{line}\n\r=> "), "{}", fp.id);
            }
        }
    }
}

#[test]
fn writes_to_read_only_parameters_give_256() {
    for fp in file_profiles() {
        let profile = Profile::builtin(&fp.id).unwrap();
        let mut d = fresh(&profile);
        let mut checked = 0;
        for p in fp.params.iter().filter(|p| bool_of(p, "read_only")) {
            let set = setter(p);
            if !has_command(&fp, &set) {
                // The seed has no PSET: TEMP cannot be written by any command.
                continue;
            }
            let line = format!("{set} {} {}", str_of(p, "name").unwrap(), int_of(p, "min").unwrap());
            assert_eq!(send(&mut d, &line), err(&line, 256), "{}", fp.id);
            checked += 1;
        }
        assert!(checked >= 3, "{}: only {checked} read-only parameters", fp.id);
    }
}

#[test]
fn err_prints_the_files_text_for_each_bit() {
    for fp in file_profiles() {
        let profile = Profile::builtin(&fp.id).unwrap();
        let mut d = fresh(&profile);
        assert!(fp.status.len() >= 13, "{}", fp.id);
        for (bit, text) in &fp.status {
            let line = format!("ERR {bit}");
            assert_eq!(send(&mut d, &line), format!("{line}\n\r{bit}: {text}\n\r=> "), "{}", fp.id);
        }
        // A bit the files do not define prints nothing.
        for bit in (0..16).map(|b| 1u32 << b).filter(|b| !fp.status.contains_key(b)) {
            let line = format!("ERR {bit}");
            assert_eq!(send(&mut d, &line), format!("{line}\n\r=> "), "{}", fp.id);
        }
    }
}
