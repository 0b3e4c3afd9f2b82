//! Scenario files: `gcl_model::Scenario` as TOML.
//!
//! TOML has no null, so `objects` (one optional position per motor) is written as a table
//! keyed by motor number: `objects = { 1 = 6000, 2 = 6500 }`. An array of four integers is
//! accepted too. Every other key is the field of `Scenario` of the same name.

use gcl_model::{Profile, Scenario};

use super::SimError;

/// An example scenario file, as shown in `gcl sim --help`.
pub const SCENARIO_EXAMPLE: &str = "\
# Where each motor meets an object when closing (motors without an entry close freely).
objects = { 1 = 6000, 2 = 6000, 3 = 7000 }
temperature = 400                      # ambient board temperature, tenths of a degree C
temperature_noise = 0                  # half-width of temperature noise, tenths of a degree
strain_noise = 0                       # half-width of strain noise, strain counts
initial_positions = [0, 0, 0, 0]       # joint positions at power-up, counts
analog_input = [0, 0, 0, 0]            # LFAIN per motor (bh8-262-4.4)";

/// Parses a scenario file's text.
pub fn parse_scenario(text: &str) -> Result<Scenario, SimError> {
    let bad = |m: String| SimError::Scenario(m);
    let mut table: toml::Table = toml::from_str(text).map_err(|e| bad(one_line(&e.to_string())))?;
    let objects = match table.remove("objects") {
        None => [None; 4],
        Some(toml::Value::Table(t)) => {
            let mut o = [None; 4];
            for (k, v) in t {
                let m: usize = k
                    .parse()
                    .ok()
                    .filter(|m| (1..=4).contains(m))
                    .ok_or_else(|| bad(format!("objects: `{k}` is not a motor number 1..=4")))?;
                let p = v.as_integer().ok_or_else(|| bad(format!("objects.{k}: expected an integer position")))?;
                o[m - 1] = Some(p);
            }
            o
        }
        Some(toml::Value::Array(a)) if a.len() == 4 => {
            let mut o = [None; 4];
            for (i, v) in a.iter().enumerate() {
                o[i] = Some(v.as_integer().ok_or_else(|| bad("objects: expected integer positions".into()))?);
            }
            o
        }
        Some(_) => return Err(bad("objects: expected a table like { 1 = 6000 } or an array of 4 integers".into())),
    };
    let mut scenario: Scenario =
        toml::Value::Table(table).try_into().map_err(|e: toml::de::Error| bad(one_line(&e.to_string())))?;
    scenario.objects = objects;
    Ok(scenario)
}

/// Checks a scenario's values against what the profile's hand can report: positions (objects,
/// initial positions) within each joint's travel, the temperature within the range of the
/// temperature parameter (when the profile has one), noise widths within that range and the
/// strain byte, analog inputs within one byte.
pub fn check_scenario(s: &Scenario, p: &Profile) -> Result<(), SimError> {
    let bad = |m: String| Err(SimError::Scenario(m));
    for m in 1..=4usize {
        let limit = if m == 4 { p.hand.spread_limit } else { p.hand.finger_limit };
        if let Some(o) = s.objects[m - 1]
            && !(0..=limit).contains(&o)
        {
            return bad(format!("objects.{m} = {o}: outside motor {m}'s travel 0..={limit}"));
        }
        let i = s.initial_positions[m - 1];
        if !(0..=limit).contains(&i) {
            return bad(format!("initial_positions[{}] = {i}: outside motor {m}'s travel 0..={limit}", m - 1));
        }
        let a = s.analog_input[m - 1];
        if !(0..=255).contains(&a) {
            return bad(format!("analog_input[{}] = {a}: outside one byte 0..=255", m - 1));
        }
    }
    let temp = ["TEMP", "TMP"].iter().find_map(|n| p.param_id(n)).map(|id| p.param(id));
    let (lo, hi) = temp.map_or((-550, 1250), |t| (t.min, t.max));
    if !(lo..=hi).contains(&s.temperature) {
        return bad(format!(
            "temperature = {}: outside the hand's range {lo}..={hi} (tenths of a degree C)",
            s.temperature
        ));
    }
    if !(0..=hi - lo).contains(&s.temperature_noise) {
        return bad(format!("temperature_noise = {}: outside 0..={}", s.temperature_noise, hi - lo));
    }
    if !(0..=255).contains(&s.strain_noise) {
        return bad(format!("strain_noise = {}: outside 0..=255 (the strain byte)", s.strain_noise));
    }
    Ok(())
}

fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_example_parses() {
        let s = parse_scenario(SCENARIO_EXAMPLE).unwrap();
        assert_eq!(s.objects, [Some(6000), Some(6000), Some(7000), None]);
        assert_eq!(s.temperature, 400);
        assert_eq!(s.strain_noise, 0);
    }

    #[test]
    fn values_are_checked_against_the_profile() {
        for name in Profile::builtin_names() {
            let p = Profile::builtin(name).unwrap();
            assert!(check_scenario(&parse_scenario(SCENARIO_EXAMPLE).unwrap(), &p).is_ok(), "{name}");
            assert!(check_scenario(&Scenario::default(), &p).is_ok(), "{name}");
            for text in [
                "temperature = 99999999",
                "initial_positions = [99999, 0, 0, 0]",
                "objects = { 4 = 99999 }",
                "objects = { 1 = -1 }",
                "analog_input = [0, 0, 0, 256]",
                "strain_noise = -1",
            ] {
                let err = check_scenario(&parse_scenario(text).unwrap(), &p).unwrap_err().to_string();
                assert!(err.contains("outside"), "{name} {text}: {err}");
            }
        }
    }

    #[test]
    fn defaults_and_errors() {
        assert_eq!(parse_scenario("").unwrap(), Scenario::default());
        assert_eq!(parse_scenario("objects = [1, 2, 3, 4]").unwrap().objects, [Some(1), Some(2), Some(3), Some(4)]);
        assert!(parse_scenario("objects = { 5 = 1 }").is_err());
        assert!(parse_scenario("tempreature = 3").is_err());
        assert!(parse_scenario("temperature = \"hot\"").is_err());
        assert!(parse_scenario("= =").is_err());
    }
}
