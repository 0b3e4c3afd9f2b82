//! The parameter store (the hand's RAM copy) and the non-volatile memory (its EEPROM),
//! both plain values.
//!
//! This module owns defaults, range-checked writes and the FSAVE/FLOAD/FDEF (PSAVE/PLOAD/PDEF)
//! transfers. Live values (P, SG, TEMP...) are the device's: the store only holds what is
//! written.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::motor::{Motor, MotorSet};
use crate::spec::{ParamId, Profile, Scope};

/// A write the store refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum StoreError {
    /// The value is outside the parameter's range or set (128).
    #[error("value out of range")]
    OutOfRange,
    /// The parameter is read-only (256).
    #[error("read-only parameter")]
    ReadOnly,
}

/// Working values of every stored parameter. Motor parameters hold one value per motor;
/// globals use slot 0.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParamStore {
    values: Vec<[i64; 4]>,
}

/// The transfers between RAM and EEPROM.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Transfer {
    /// RAM to EEPROM (FSAVE / PSAVE).
    Save,
    /// EEPROM to RAM (FLOAD / PLOAD).
    Load,
    /// Factory defaults to RAM (FDEF / PDEF).
    Defaults,
}

impl Transfer {
    fn command(self, scope: Scope) -> &'static str {
        match (self, scope) {
            (Transfer::Save, Scope::Motor) => "FSAVE",
            (Transfer::Load, Scope::Motor) => "FLOAD",
            (Transfer::Defaults, Scope::Motor) => "FDEF",
            (Transfer::Save, Scope::Global) => "PSAVE",
            (Transfer::Load, Scope::Global) => "PLOAD",
            (Transfer::Defaults, Scope::Global) => "PDEF",
        }
    }
}

impl ParamStore {
    /// Factory defaults for every stored parameter.
    pub fn defaults(profile: &Profile) -> ParamStore {
        let mut values = vec![[0i64; 4]; profile.slots];
        for id in profile.param_ids() {
            if profile.param(id).alias_of.is_some() {
                continue;
            }
            if let Some(v) = values.get_mut(profile.slot_of(id)) {
                *v = Motor::ALL.map(|m| profile.default_for(id, m.number()));
            }
        }
        ParamStore { values }
    }

    /// The stored value of a parameter for a motor (1..=4; ignored for globals). A number
    /// outside 1..=4, or an id of another profile, reads 0.
    pub fn get(&self, profile: &Profile, id: ParamId, motor: u8) -> i64 {
        let Some(values) = self.values.get(profile.slot_of(id)) else { return 0 };
        let motor = match profile.param(id).scope {
            Scope::Motor => Motor::new(motor),
            Scope::Global => Some(Motor::F1),
        };
        motor.map_or(0, |m| *m.pick(values))
    }

    /// Looks a parameter up by name and reads it; `None` if the profile lacks it.
    pub fn get_named(&self, profile: &Profile, name: &str, motor: u8) -> Option<i64> {
        profile.param_id(name).map(|id| self.get(profile, id, motor))
    }

    /// Writes a value after the range and read-only checks.
    pub fn set(&mut self, profile: &Profile, id: ParamId, motors: MotorSet, value: i64) -> Result<(), StoreError> {
        if profile.param(id).read_only {
            return Err(StoreError::ReadOnly);
        }
        if !profile.value_ok(id, value) {
            return Err(StoreError::OutOfRange);
        }
        self.set_unchecked(profile, id, motors, value);
        Ok(())
    }

    /// Writes a value with no checks (the model's own bookkeeping and faults).
    pub fn set_unchecked(&mut self, profile: &Profile, id: ParamId, motors: MotorSet, value: i64) {
        let Some(values) = self.values.get_mut(profile.slot_of(id)) else { return };
        match profile.param(id).scope {
            Scope::Motor => {
                for m in motors.motors() {
                    *m.pick_mut(values) = value;
                }
            }
            Scope::Global => *Motor::F1.pick_mut(values) = value,
        }
    }

    /// Runs FSAVE/FLOAD/FDEF (`scope` motor, on `motors`) or PSAVE/PLOAD/PDEF (`scope`
    /// global) for every parameter whose `persist` list names the command.
    pub fn transfer(&mut self, profile: &Profile, nv: &mut NvMemory, t: Transfer, scope: Scope, motors: MotorSet) {
        let cmd = t.command(scope);
        let targets: &[Motor] = match scope {
            Scope::Motor => &Motor::ALL,
            Scope::Global => &[Motor::F1],
        };
        for &id in profile.persisted(cmd) {
            if t == Transfer::Save {
                for m in targets.iter().filter(|m| scope == Scope::Global || motors.contains(m.number())) {
                    nv.store(profile, id, m.number(), self.get(profile, id, m.number()));
                }
                continue;
            }
            // (what `NvMemory::load` gives, the saved entry looked up once per parameter)
            let saved = match (t, scope) {
                (Transfer::Load, Scope::Motor) => nv.motor.get(&profile.param(id).name).copied(),
                (Transfer::Load, Scope::Global) => nv.global.get(&profile.param(id).name).map(|v| [*v; 4]),
                _ => None,
            };
            let Some(values) = self.values.get_mut(profile.slot_of(id)) else { continue };
            for m in targets.iter().filter(|m| scope == Scope::Global || motors.contains(m.number())) {
                let v = match saved.map(|a| *m.pick(&a)) {
                    Some(v) if profile.value_ok(id, v) => v,
                    _ => profile.default_for(id, m.number()),
                };
                *m.pick_mut(values) = v;
            }
        }
    }

    /// The state after power-up or RESET: factory defaults, then FLOAD and PLOAD from `nv`.
    pub fn power_up(profile: &Profile, nv: &mut NvMemory) -> ParamStore {
        let mut s = ParamStore::defaults(profile);
        // With nothing saved, FLOAD and PLOAD put back the factory default of every
        // parameter they move, which `defaults` has just written: skip them (a fuzzing
        // campaign powers a fresh hand up for every case).
        if nv.motor.is_empty() && nv.global.is_empty() {
            return s;
        }
        s.transfer(profile, nv, Transfer::Load, Scope::Motor, MotorSet::ALL);
        s.transfer(profile, nv, Transfer::Load, Scope::Global, MotorSet::ALL);
        s
    }
}

/// The hand's non-volatile memory: saved parameters by name, and the values the hand keeps
/// by itself (odometer, powered seconds, peak temperature, serial number).
///
/// Held as a value so that the harness can persist it (`gcl sim --eeprom FILE`) and tests can
/// compare it.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct NvMemory {
    /// Saved motor parameters: name → value per motor 1..=4.
    #[serde(default)]
    pub motor: BTreeMap<String, [i64; 4]>,
    /// Saved global parameters: name → value.
    #[serde(default)]
    pub global: BTreeMap<String, i64>,
    /// Self-stored values: odometer counts per motor (OD is this ÷ 1000).
    #[serde(default)]
    pub odometer_counts: [u64; 4],
    /// Self-stored: powered milliseconds (UPSECS is this ÷ 1000).
    #[serde(default)]
    pub powered_ms: u64,
    /// Self-stored: the highest temperature seen, tenths of °C.
    #[serde(default)]
    pub peak_temperature: i64,
    /// Self-stored: the serial number.
    #[serde(default)]
    pub serial_number: i64,
    /// How many FSAVE/PSAVE writes the memory has taken (the parts wear out near 5000).
    #[serde(default)]
    pub writes: u64,
}

impl NvMemory {
    /// The saved value of a parameter, or its factory default if none was saved.
    pub fn load(&self, profile: &Profile, id: ParamId, motor: u8) -> i64 {
        let p = profile.param(id);
        let saved = match p.scope {
            Scope::Motor => self.motor.get(&p.name).zip(Motor::new(motor)).map(|(v, m)| *m.pick(v)),
            Scope::Global => self.global.get(&p.name).copied(),
        };
        match saved {
            Some(v) if profile.value_ok(id, v) => v,
            _ => profile.default_for(id, motor),
        }
    }

    fn store(&mut self, profile: &Profile, id: ParamId, motor: u8, value: i64) {
        let p = profile.param(id);
        self.writes += 1;
        match p.scope {
            Scope::Motor => {
                let entry = self
                    .motor
                    .entry(p.name.clone())
                    .or_insert_with(|| Motor::ALL.map(|m| profile.default_for(id, m.number())));
                if let Some(m) = Motor::new(motor) {
                    *m.pick_mut(entry) = value;
                }
            }
            Scope::Global => {
                self.global.insert(p.name.clone(), value);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_id_of_another_profile_reads_as_nothing_instead_of_panicking() {
        let seed = Profile::builtin("seed").unwrap();
        let store = ParamStore::defaults(&seed);
        let foreign = crate::spec::ParamId(u16::MAX);
        assert_eq!(seed.param(foreign).name, "");
        assert!(seed.param(foreign).read_only);
        assert_eq!(seed.command(crate::spec::CommandId(u16::MAX)).name, "");
        assert_eq!(store.get(&seed, foreign, 1), 0);
        let dp = seed.param_id("DP").unwrap();
        assert_eq!(store.get(&seed, dp, 2), 1000);
        assert_eq!(store.get(&seed, dp, 0), 0, "motor 0 does not exist");
        assert_eq!(store.get(&seed, dp, 5), 0, "motor 5 does not exist");
    }

    #[test]
    fn powering_up_with_nothing_saved_is_defaults_then_the_loads() {
        for name in Profile::builtin_names() {
            let p = Profile::builtin(name).unwrap();
            let mut nv = NvMemory::default();
            let mut loaded = ParamStore::defaults(&p);
            loaded.transfer(&p, &mut nv, Transfer::Load, Scope::Motor, MotorSet::ALL);
            loaded.transfer(&p, &mut nv, Transfer::Load, Scope::Global, MotorSet::ALL);
            assert_eq!(ParamStore::power_up(&p, &mut nv), loaded, "{name}");
            assert_eq!(nv, NvMemory::default(), "{name}: powering up writes nothing");
        }
    }

    #[test]
    fn save_load_defaults() {
        let p = Profile::builtin("seed").unwrap();
        let mut nv = NvMemory::default();
        let mut s = ParamStore::power_up(&p, &mut nv);
        let dp = p.param_id("DP").unwrap();
        assert_eq!(s.get(&p, dp, 1), 1000);
        assert_eq!(s.get(&p, dp, 4), 150);
        s.set(&p, dp, MotorSet::from_motors([1]), 5000).unwrap();
        assert_eq!(s.set(&p, dp, MotorSet::ALL, 20001), Err(StoreError::OutOfRange));
        s.transfer(&p, &mut nv, Transfer::Save, Scope::Motor, MotorSet::ALL);
        s.transfer(&p, &mut nv, Transfer::Defaults, Scope::Motor, MotorSet::ALL);
        assert_eq!(s.get(&p, dp, 1), 1000);
        let s2 = ParamStore::power_up(&p, &mut nv);
        assert_eq!(s2.get(&p, dp, 1), 5000);
        let baud = p.param_id("BAUD").unwrap();
        assert_eq!(s2.get(&p, baud, 3), 96);
    }
}
