//! The protocol as data: the schema of the files under `spec/` and the loader that turns
//! them into a resolved [`Profile`].
//!
//! This module owns the mapping from TOML text to typed tables. It never touches the file
//! system: the embedded profiles come in through `include_str!`, and a profile from
//! elsewhere comes in through a caller-supplied resolver (see [`Profile::load_with`]).
//!
//! Includes expand to at most `MAX_SPEC_FILES` files and `MAX_SPEC_BYTES` of text
//! (`SpecError::TooManyIncludes` / `TooLarge`), so an include bomb is refused before it costs
//! memory.
//! A TOML error names line and column but never quotes the file: a file named as a profile may be
//! none.
//!
//! Protocol names resolve to closed types here, once. Every parameter with an `rt` table must be a
//! known `RtFlag` with a GCL `FieldType`, block and scope (else `SpecError::UnknownRtFlag` /
//! `RtField`); a decision's `level` is a `Level`, so a typo fails the load.
//!
//! The parameters the device interprets are found by `Role` (`Profile::role(Role::PositionError)`,
//! `Profile::role_of(id)`). Each role declares in the `roles!` table what a profile without its
//! parameter means (`Absence`: required, required with a RealTime flag, a value, the `[hand]` close
//! targets, or not reported); that is checked here (`SpecError::MissingRole`) and applied by the
//! device's one role reader (`Device::role`, through `Profile::absent_value`).
//!
//! Where the hand reads HI's speed and hold repetitions, its line rate and its low-strain stop is
//! `[hand]` data (a parameter name or a fixed value), resolved to `Profile::hand_sources()`; an
//! unknown name is `SpecError::UnknownHandParam`. So the device has no protocol fallback in code.

use std::sync::Arc;

use serde::{Deserialize, Serialize};

use crate::level::Level;
pub use crate::rtflags::BlockKind;
use crate::rtflags::{FieldType, RtFlag};
use crate::status::{StatusBits, StatusTexts};

/// Files under `spec/` compiled into the model, by their path relative to `spec/`.
pub const EMBEDDED_FILES: &[(&str, &str)] = &[
    ("shared/framing.toml", include_str!("../../spec/shared/framing.toml")),
    ("shared/status.toml", include_str!("../../spec/shared/status.toml")),
    ("seed.toml", include_str!("../../spec/seed.toml")),
    ("bh8-262/common.toml", include_str!("../../spec/bh8-262/common.toml")),
    ("bh8-262-4.3.toml", include_str!("../../spec/bh8-262-4.3.toml")),
    ("bh8-262-4.4.toml", include_str!("../../spec/bh8-262-4.4.toml")),
];

/// The most files a profile may expand to, counting a file once per time it is included: the
/// built-in profiles use 4; an include bomb (three levels of 200 includes) is refused here
/// before it costs memory.
pub const MAX_SPEC_FILES: usize = 256;

/// The most spec text a profile may expand to, all included files' text summed (the built-in
/// profiles hold about 150 KB).
pub const MAX_SPEC_BYTES: usize = 16 << 20;

/// The profiles shipped with the model: `(name, top-level file)`.
pub const EMBEDDED_PROFILES: &[(&str, &str)] =
    &[("seed", "seed.toml"), ("bh8-262-4.3", "bh8-262-4.3.toml"), ("bh8-262-4.4", "bh8-262-4.4.toml")];

/// Why a spec file could not become a profile.
#[derive(Debug, Clone, thiserror::Error, PartialEq, Eq)]
pub enum SpecError {
    /// No embedded profile or alias has this name.
    #[error("unknown profile `{0}` (known: seed, bh8-262-4.3, bh8-262-4.4, bh8-262)")]
    UnknownProfile(String),
    /// An `include` named a file the resolver could not supply.
    #[error("spec file `{0}` not found")]
    MissingFile(String),
    /// A file is not valid TOML for the schema.
    #[error("spec file `{file}`: {message}")]
    Syntax {
        /// The file.
        file: String,
        /// What the TOML parser said.
        message: String,
    },
    /// The files parse but contradict each other or the model.
    #[error("profile `{profile}`: {message}")]
    Invalid {
        /// The profile being resolved.
        profile: String,
        /// What is wrong.
        message: String,
    },
    /// Includes loop back on themselves.
    #[error("spec include cycle through `{0}`")]
    IncludeCycle(String),
    /// A profile's files, includes counted each time they are included, are more than
    /// [`MAX_SPEC_FILES`] (an include bomb: many includes of many includes).
    #[error("spec `{file}`: more than {limit} files once includes are expanded (an include bomb?)")]
    TooManyIncludes {
        /// The file whose include passed the limit.
        file: String,
        /// The limit.
        limit: usize,
    },
    /// A profile's files, includes expanded, hold more than [`MAX_SPEC_BYTES`] of text.
    #[error("spec `{file}`: more than {limit} bytes of spec text once includes are expanded (an include bomb?)")]
    TooLarge {
        /// The file whose text passed the limit.
        file: String,
        /// The limit.
        limit: usize,
    },
    /// A parameter has an `rt` table but its name is not a RealTime flag GCL defines.
    #[error("profile `{profile}`: parameter `{param}` has an rt field but is not a RealTime flag (known: {known})", known = RtFlag::ALL.map(RtFlag::name).join(", "))]
    UnknownRtFlag {
        /// The profile being resolved.
        profile: String,
        /// The parameter.
        param: String,
    },
    /// A `[hand]` key that says where a behaviour value comes from names a parameter the
    /// profile does not have.
    #[error("profile `{profile}`: [hand] {key} names parameter `{param}`, which the profile lacks")]
    UnknownHandParam {
        /// The profile being resolved.
        profile: String,
        /// The `[hand]` key.
        key: &'static str,
        /// The parameter name it gives.
        param: String,
    },
    /// The profile lacks a parameter whose role it cannot do without (see [`Absence`]).
    #[error("profile `{profile}` lacks parameter {names} ({role:?}): {why}", names = names.join(" or "), why = role.absence_reason())]
    MissingRole {
        /// The profile being resolved.
        profile: String,
        /// The role no parameter plays.
        role: Role,
        /// The names that would take the role.
        names: &'static [&'static str],
    },
    /// A RealTime flag's field does not have a GCL field type, block or scope.
    #[error("profile `{profile}`: RealTime flag `{param}`: {message}")]
    RtField {
        /// The profile being resolved.
        profile: String,
        /// The parameter.
        param: String,
        /// What is wrong.
        message: String,
    },
}

/// One spec file as written. Lists from included files come first; an entry with the same
/// name later in the chain replaces the earlier one in place.
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SpecFile {
    /// The profile id (top-level files only).
    #[serde(default)]
    pub id: Option<String>,
    /// A one-line title.
    #[serde(default)]
    pub title: Option<String>,
    /// Other names this profile answers to.
    #[serde(default)]
    pub aliases: Vec<String>,
    /// Files (relative to `spec/`) merged before this one, in order.
    #[serde(default)]
    pub include: Vec<String>,
    /// Byte-level framing.
    #[serde(default)]
    pub framing: Option<Framing>,
    /// Lines of the power-up and RESET banner.
    #[serde(default)]
    pub banner: Option<Vec<String>>,
    /// Lines printed by `VERS`.
    #[serde(default)]
    pub version: Option<Vec<String>>,
    /// Physical and behavioural constants of the grasper.
    #[serde(default)]
    pub hand: Option<Hand>,
    /// Motor prefix characters.
    #[serde(default)]
    pub prefixes: Vec<PrefixSpec>,
    /// Commands.
    #[serde(default)]
    pub commands: Vec<CommandSpec>,
    /// Names of commands from included files that this profile does not have.
    #[serde(default)]
    pub remove_commands: Vec<String>,
    /// Parameters.
    #[serde(default)]
    pub params: Vec<ParamSpec>,
    /// Names of parameters from included files that this profile does not have.
    #[serde(default)]
    pub remove_params: Vec<String>,
    /// Status bits.
    #[serde(default)]
    pub status: Vec<StatusSpec>,
    /// Decisions taken where the seed is silent or wrong.
    #[serde(default)]
    pub decisions: Vec<Decision>,
}

/// Framing: how bytes become lines and lines become output.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq, Eq)]
#[serde(deny_unknown_fields)]
pub struct Framing {
    /// The byte that ends a command line (CR, 13).
    pub terminator: u8,
    /// Whether every received byte is echoed.
    pub echo: bool,
    /// The bytes written in front of every output line and the prompt.
    pub line_ending: String,
    /// The prompt text.
    pub prompt: String,
    /// Longest command line accepted, in bytes, terminator excluded.
    pub max_line: usize,
    /// Status sent for a line longer than `max_line`.
    pub overlong_status: u32,
    /// The abort byte (^C, 3).
    pub abort: u8,
}

/// Constants of the simulated grasper that the protocol text does not cover but a model needs.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Hand {
    /// Position of the finger's closed joint stop, in encoder counts.
    pub finger_limit: i64,
    /// Position of the spread's closed joint stop.
    pub spread_limit: i64,
    /// Encoder counts per millisecond for one unit of MCV/MOV/IVEL and of RealTime velocity.
    pub counts_per_ms_per_velocity_unit: f64,
    /// Velocity units per millisecond gained for each unit of ACCEL.
    pub velocity_units_per_ms_per_accel: f64,
    /// Fraction bits in the RealTime LCV datum (0 in the seed; 4.4 fixed point in 4.3x).
    pub lcv_fraction_bits: u32,
    /// Encoder counts per millisecond for a RealTime velocity of 1.0 (LCV datum × LCVC,
    /// after the fraction bits).
    pub rt_velocity_counts_per_ms: f64,
    /// Encoder counts per millisecond that one unit of raw feedback velocity (LFV × LFVC) stands for.
    pub lfv_counts_per_ms: f64,
    /// Target of C in profiles without a CT parameter: fingers.
    #[serde(default)]
    pub finger_close_target: Option<i64>,
    /// Target of C in profiles without a CT parameter: spread.
    #[serde(default)]
    pub spread_close_target: Option<i64>,
    /// Status a ^C during motion sends (0: prompt only).
    pub abort_status: u32,
    /// Status `T` sends for an uninitialised motor.
    pub terminate_uninitialized_status: u32,
    /// Status any other motion command sends for an uninitialised motor.
    pub uninitialized_status: u32,
    /// Status for a motion command while over temperature (0: no overtemperature check).
    pub overtemp_status: u32,
    /// Status when a position move ends outside MPE.
    pub missed_position_status: u32,
    /// Status for a bad RealTime header.
    pub bad_header_status: u32,
    /// Value of the `S` parameter before HI.
    pub uninitialized_state_value: i64,
    /// Strain reading of a finger touching nothing.
    pub free_strain: i64,
    /// Strain counts gained per encoder count pressed into an object.
    pub strain_per_count: f64,
    /// How far, in counts, a finger can press into an object before it stalls.
    pub object_compliance: i64,
    /// Time HI spends at the open stop (vibration, commutation), in ms, per motor.
    pub hi_settle_ms: u64,
    /// How fast the board warms while motors move: tenths of a degree Celsius per second
    /// for each moving motor.
    pub heat_per_motor_s: f64,
    /// The time constant, in seconds, with which the board cools toward its ambient
    /// temperature (Newton's law, moving or not): with `m` motors moving for long, the board
    /// settles `m` × `heat_per_motor_s` × `cooling_time_s` tenths above ambient.
    pub cooling_time_s: f64,
    /// Whether the RealTime LFT field exists and its width in bytes (0: none).
    pub lft_size: usize,
    /// Whether an LFT of width 1 carries whole degrees (true) or tenths (false).
    pub lft_whole_degrees: bool,
    /// Whether a bare `?` lists only standard commands (advanced ones through `A?`).
    pub help_lists_standard_only: bool,
    /// The speed HI opens a motor at, in MCV/MOV units: a parameter (IVEL) or a value.
    pub hi_velocity: HandValue,
    /// How many times HI spends `hi_settle_ms` at the open stop (at least once): a
    /// parameter (IHIT) or a value.
    pub hi_hold_repetitions: HandValue,
    /// The serial rate: a parameter in hundreds of bit/s (BAUD), or a value in bit/s.
    pub baud: HandValue,
    /// The strain below which a moving motor stops: a parameter (LSG) or a value; 255 and
    /// above never stop a motor.
    pub low_strain_stop: HandValue,
}

/// Where the hand reads one of its behaviour values (a `[hand]` key such as `hi_velocity`):
/// a parameter of the profile, by name, or a fixed value.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq, Eq)]
#[serde(untagged)]
pub enum HandValue {
    /// The parameter's value, per motor, as the hand's behaviour reads it.
    Param(String),
    /// This value, whatever the parameters say.
    Fixed(i64),
}

/// A [`HandValue`] resolved when the profile loads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ValueSource {
    /// The value of this parameter.
    Param(ParamId),
    /// This value.
    Fixed(i64),
}

/// The `[hand]` keys that say where a behaviour value comes from, resolved against the
/// profile's parameters (see [`Profile::hand_sources`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HandSources {
    /// [`Hand::hi_velocity`].
    pub hi_velocity: ValueSource,
    /// [`Hand::hi_hold_repetitions`].
    pub hi_hold_repetitions: ValueSource,
    /// [`Hand::baud`].
    pub baud: ValueSource,
    /// [`Hand::low_strain_stop`].
    pub low_strain_stop: ValueSource,
}

/// One motor prefix character.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq, Eq)]
#[serde(deny_unknown_fields)]
pub struct PrefixSpec {
    /// The character, upper case.
    pub char: char,
    /// The motors it names, 1..=4.
    pub motors: Vec<u8>,
}

/// What a command does, in the model's terms. Each kind has one implementation.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Hash)]
#[serde(rename_all = "kebab-case")]
pub enum CommandKind {
    /// `C`: move to the close target.
    Close,
    /// `O`: move to the open target.
    Open,
    /// `M [pos]`: move to a position (DP when none).
    Move,
    /// `IC [dist]`: incremental close by DS or the argument.
    IncrementalClose,
    /// `IO [dist]`: incremental open.
    IncrementalOpen,
    /// `HOME`: move to 0.
    Home,
    /// `TC`: velocity close until stall.
    TorqueClose,
    /// `TO`: velocity open until stall.
    TorqueOpen,
    /// `HI`: initialise and home.
    Initialize,
    /// `T`: cut motor power.
    Terminate,
    /// `LOOP`: enter RealTime mode.
    Loop,
    /// `FSET name value ...`.
    MotorSet,
    /// `FGET name ...`.
    MotorGet,
    /// `FDEF`.
    MotorDefaults,
    /// `FLOAD`.
    MotorLoad,
    /// `FSAVE`.
    MotorSave,
    /// `FLIST`: standard motor parameter names.
    MotorList,
    /// `FLISTV`: standard motor parameter values.
    MotorListValues,
    /// `FLISTA`: all motor parameter names.
    MotorListAll,
    /// `FLISTAV`: all motor parameter values.
    MotorListAllValues,
    /// `PSET name value ...`.
    GlobalSet,
    /// `PGET name ...`.
    GlobalGet,
    /// `PDEF`.
    GlobalDefaults,
    /// `PLOAD`.
    GlobalLoad,
    /// `PSAVE`.
    GlobalSave,
    /// `PLIST`.
    GlobalList,
    /// `PLISTV`.
    GlobalListValues,
    /// `PLISTA`.
    GlobalListAll,
    /// `PLISTAV`.
    GlobalListAllValues,
    /// `RESET`: as a power cycle.
    Reset,
    /// `ERR [n]`: describe status bits.
    ErrorText,
    /// `VERS`.
    Version,
    /// `?` and `?CMD`.
    Help,
    /// `A?`: standard and advanced commands.
    HelpAll,
}

impl CommandKind {
    /// Whether the command moves motors and so needs HI first.
    pub fn is_motion(self) -> bool {
        matches!(
            self,
            Self::Close
                | Self::Open
                | Self::Move
                | Self::IncrementalClose
                | Self::IncrementalOpen
                | Self::Home
                | Self::TorqueClose
                | Self::TorqueOpen
        )
    }
}

/// Whether a command takes a motor prefix.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum PrefixRule {
    /// A prefix is allowed; with none the command acts on the EN motors (motion) or all four.
    Allowed,
    /// A prefix gives 4096.
    Forbidden,
}

/// What follows the command word.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum ArgRule {
    /// Nothing; any argument gives 1024.
    None,
    /// Zero or one integer in `arg_min..=arg_max`.
    OptionalInteger,
    /// One or more parameter names.
    Names,
    /// One or more `name value` pairs.
    Pairs,
}

/// One command of a profile.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq, Eq)]
#[serde(deny_unknown_fields)]
pub struct CommandSpec {
    /// The command word, upper case.
    pub name: String,
    /// A grouping for people: movement, realtime, motor-param, global-param, admin, advanced.
    pub category: String,
    /// What it does.
    pub kind: CommandKind,
    /// Whether it takes a prefix.
    pub prefix: PrefixRule,
    /// What follows it.
    pub args: ArgRule,
    /// Lowest integer argument (with `optional-integer`).
    #[serde(default)]
    pub arg_min: Option<i64>,
    /// Highest integer argument (with `optional-integer`).
    #[serde(default)]
    pub arg_max: Option<i64>,
    /// Listed only by `A?`, not by `?`.
    #[serde(default)]
    pub advanced: bool,
    /// What it prints on success, for people.
    pub prints: String,
    /// The `?CMD` text.
    pub help: String,
}

/// Whether a parameter belongs to each motor or to the hand.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum Scope {
    /// One value per motor.
    Motor,
    /// One value for the hand.
    Global,
}

/// The field a RealTime flag adds when it is 1.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq)]
#[serde(deny_unknown_fields)]
pub struct RtField {
    /// The block.
    pub block: BlockKind,
    /// Width in bytes (1 or 2; two-byte fields are big-endian).
    pub size: usize,
    /// Two's complement or unsigned.
    pub signed: bool,
    /// Position among the fields of one motor (or among global fields).
    pub order: u32,
}

/// One parameter of a profile.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq, Eq)]
#[serde(deny_unknown_fields)]
pub struct ParamSpec {
    /// The name, upper case.
    pub name: String,
    /// Per motor or per hand.
    pub scope: Scope,
    /// Grouping: movement, status, realtime, advanced, config.
    pub section: String,
    /// What it means.
    pub description: String,
    /// Lowest value.
    pub min: i64,
    /// Highest value.
    pub max: i64,
    /// When set, only these values are valid.
    #[serde(default)]
    pub values: Option<Vec<i64>>,
    /// Default for F1..F3 (or the global default).
    #[serde(default)]
    pub default: Option<i64>,
    /// Default for the spread, when it differs.
    #[serde(default)]
    pub default_spread: Option<i64>,
    /// Read-only: a write gives 256.
    #[serde(default)]
    pub read_only: bool,
    /// Listed only by the `...A` list commands.
    #[serde(default)]
    pub advanced: bool,
    /// Which of FSAVE/FLOAD/FDEF (or PSAVE/PLOAD/PDEF) cover it.
    #[serde(default)]
    pub persist: Vec<String>,
    /// The command that reads it (default FGET for motor, PGET for global parameters).
    #[serde(default)]
    pub get: Option<String>,
    /// The command that writes it (default FSET / PSET).
    #[serde(default)]
    pub set: Option<String>,
    /// Another name for the same storage.
    #[serde(default)]
    pub alias_of: Option<String>,
    /// Extra names accepted on input only.
    #[serde(default)]
    pub input_aliases: Vec<String>,
    /// The value is computed from the hand's state, not stored.
    #[serde(default)]
    pub live: bool,
    /// Kept by the hand itself across RESET and power loss (odometer, serial number...).
    #[serde(default)]
    pub self_stored: bool,
    /// The RealTime field this flag adds.
    #[serde(default)]
    pub rt: Option<RtField>,
    /// What the value changes in the hand's behaviour on the wire, for parameters whose value
    /// does more than read back. The suite has a case that sets every such parameter to a
    /// value other than its default and observes this.
    #[serde(default)]
    pub effect: Option<String>,
}

/// One status bit.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq, Eq)]
#[serde(deny_unknown_fields)]
pub struct StatusSpec {
    /// The bit value (a power of two).
    pub bit: u32,
    /// The `ERR` description.
    pub text: String,
    /// Whether the model ever sends it.
    pub sent: bool,
}

/// One decision taken where the seed is silent or wrong.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq, Eq)]
#[serde(deny_unknown_fields)]
pub struct Decision {
    /// A stable slug.
    pub id: String,
    /// The clause of the seed (or manual) it resolves.
    pub clause: String,
    /// What the model does.
    pub resolution: String,
    /// How a conformance check of it is graded: MUST, SHOULD, MAY or INFO (any other name
    /// is refused when the file loads). The loader bounds it by [`Decision::evidence`] (see
    /// [`Evidence::strongest_level`]).
    pub level: Level,
    /// What supports the resolution, graded as in `protocol-notes.md`: `[doc]` (a Barrett
    /// manual or the seed says it), `[code×N]` (N independent host libraries depend on it;
    /// `[code]` is one, `x` may stand for `×`), `[open]` (no source settles it). `[doc]` and
    /// `[code×N]` combine: `[doc][code×3]`.
    pub evidence: String,
    /// Where the facts behind it come from (a manual's section, a wiki page, a public host
    /// library's file), one source per entry; empty where the project simply chose.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub sources: Vec<String>,
}

/// The grade of a decision's evidence, parsed from [`Decision::evidence`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Evidence {
    /// A Barrett manual or the seed states it.
    pub doc: bool,
    /// How many independent host libraries depend on it.
    pub code: u32,
}

impl Evidence {
    /// Parses `[doc]`, `[code]`, `[code×N]` (or `[codexN]`), combinations of those, or
    /// `[open]` alone.
    pub fn parse(text: &str) -> Result<Evidence, String> {
        let mut e = Evidence::default();
        let mut open = false;
        let mut rest = text.trim();
        if rest.is_empty() {
            return Err("evidence is empty: use [doc], [code×N] or [open]".into());
        }
        while !rest.is_empty() {
            let inner_end = rest
                .find(']')
                .filter(|_| rest.starts_with('['))
                .ok_or_else(|| format!("evidence `{text}`: expected [doc], [code×N] or [open] at `{rest}`"))?;
            let tag = &rest[1..inner_end];
            rest = rest[inner_end + 1..].trim_start();
            match tag {
                "doc" if !e.doc => e.doc = true,
                "open" => open = true,
                "code" if e.code == 0 => e.code = 1,
                t if e.code == 0 && (t.starts_with("code×") || t.starts_with("codex")) => {
                    let n = t.trim_start_matches("code").trim_start_matches('×').trim_start_matches('x');
                    e.code = n
                        .parse::<u32>()
                        .ok()
                        .filter(|n| (1..=99).contains(n))
                        .ok_or_else(|| format!("evidence `{text}`: `[{t}]` needs a count 1..=99"))?;
                }
                t => return Err(format!("evidence `{text}`: unknown or repeated grade `[{t}]`")),
            }
        }
        if open && (e.doc || e.code > 0) {
            return Err(format!("evidence `{text}`: [open] cannot be combined with a source"));
        }
        Ok(e)
    }

    /// Whether no source settles it.
    pub fn is_open(self) -> bool {
        !self.doc && self.code == 0
    }

    /// The strongest level a conformance check resting on this evidence may carry: MUST on
    /// `[doc]` or `[code×N]` with N ≥ 2; SHOULD on one host library; INFO when open.
    pub fn strongest_level(self) -> Level {
        if self.doc || self.code >= 2 {
            Level::Must
        } else if self.code == 1 {
            Level::Should
        } else {
            Level::Info
        }
    }
}

impl Decision {
    /// The parsed evidence (the loader has checked it for every built-in profile).
    pub fn grade(&self) -> Evidence {
        Evidence::parse(&self.evidence).unwrap_or_default()
    }

    /// Checks that the evidence supports the level.
    fn check(&self) -> Result<(), String> {
        let e = Evidence::parse(&self.evidence).map_err(|m| format!("decision `{}`: {m}", self.id))?;
        let max = e.strongest_level();
        if self.level < max {
            return Err(format!(
                "decision `{}` is {} but its evidence {} supports at most {max}",
                self.id, self.level, self.evidence
            ));
        }
        Ok(())
    }
}

/// A RealTime flag of a profile, resolved at load: the parameter that switches it, and the
/// type of the field it adds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RtSlot {
    /// The parameter.
    pub param: ParamId,
    /// The flag.
    pub flag: RtFlag,
    /// The field's wire type.
    pub ty: FieldType,
}

/// What a profile without a role's parameter means. Each [`Role`] declares one, with its
/// reason, in the `roles!` table; the loader checks it (see [`SpecError::MissingRole`]) and
/// the device applies it in one place, so no reader invents a default of its own.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Absence {
    /// The hand cannot do its job without it: a profile that lacks it does not load.
    Required,
    /// Required when the profile has this RealTime flag, whose field is the parameter's only
    /// reader; without the flag nothing reads it.
    RequiredWith(RtFlag),
    /// The hand behaves as if the parameter held this value on every motor.
    Value(i64),
    /// C closes to `[hand]` `finger_close_target` / `spread_close_target`; a profile without
    /// the parameter needs both.
    HandCloseTargets,
    /// A quantity the hand keeps for itself and reports only through this parameter: without
    /// it nothing reads it back and what the hand would record there is dropped.
    Unreported,
}

macro_rules! roles {
    ($( $(#[doc = $doc:literal])* $variant:ident => [$($name:literal),+], absent: $absent:expr, $why:literal, )*) => {
        /// What the device does with a parameter beyond storing it: the parameters the
        /// hand's behaviour reads or that read back its state. Resolved by name when a
        /// profile loads (see [`Profile::role`]); what a profile without one means is the
        /// role's [`Role::absence`], checked at load.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum Role {
            $( $(#[doc = $doc])* $variant, )*
        }

        impl Role {
            /// Every role.
            pub const ALL: &'static [Role] = &[$(Role::$variant,)*];

            /// The parameter names that take this role, first match wins.
            pub fn names(self) -> &'static [&'static str] {
                match self { $(Role::$variant => &[$($name),+],)* }
            }

            /// What a profile without this role's parameter means.
            pub fn absence(self) -> Absence {
                match self { $(Role::$variant => $absent,)* }
            }

            /// Why the absence means what [`Role::absence`] says.
            pub fn absence_reason(self) -> &'static str {
                match self { $(Role::$variant => $why,)* }
            }
        }
    };
}

roles! {
    /// P: present position (live).
    Position => ["P"], absent: Absence::Required,
        "a host sees where a motor stopped only through P (LFAP exists only inside the RealTime loop)",
    /// S: motor state (live).
    State => ["S"], absent: Absence::Unreported, "the hand still tracks initialisation; nothing reads it back",
    /// SG: strain gauge (live).
    Strain => ["SG"], absent: Absence::Unreported, "the hand still senses strain (HSG, LFS); nothing reads it back",
    /// TEMP: board temperature (live).
    Temperature => ["TEMP"], absent: Absence::Unreported, "the hand still heats (OTEMP, LFT); nothing reads it back",
    /// PTEMP: peak temperature (kept by the hand).
    PeakTemperature => ["PTEMP"], absent: Absence::Unreported, "the seed's hand keeps no record a host can read",
    /// UPSECS: powered seconds (kept by the hand).
    UpSeconds => ["UPSECS"], absent: Absence::Unreported, "the seed's hand keeps no record a host can read",
    /// SN: serial number (kept by the hand).
    SerialNumber => ["SN"], absent: Absence::Unreported, "the seed's hand keeps no record a host can read",
    /// OD: odometer (kept by the hand).
    Odometer => ["OD"], absent: Absence::Unreported, "the seed's hand keeps no record a host can read",
    /// BD: breakaway detected.
    BreakawayDetected => ["BD"], absent: Absence::Unreported, "a breakaway (if BS is on) is not reported",
    /// BP: breakaway position.
    BreakawayPosition => ["BP"], absent: Absence::RequiredWith(RtFlag::Lfbp),
        "the LFBP feedback field reports it; without LFBP a breakaway position is not reported",
    /// EN: motor enabled for unprefixed motion.
    Enabled => ["EN"], absent: Absence::Value(1), "every motor takes unprefixed motion commands",
    /// DP: default position of M.
    DefaultPosition => ["DP"], absent: Absence::Required, "M without an argument has no target",
    /// DS: default step of IC/IO.
    DefaultStep => ["DS"], absent: Absence::Required, "IC and IO without an argument have no step",
    /// CT: close target.
    CloseTarget => ["CT"], absent: Absence::HandCloseTargets,
        "C closes to [hand] finger_close_target and spread_close_target, both needed then",
    /// OT: open target.
    OpenTarget => ["OT"], absent: Absence::Value(0), "O opens to 0, the open stop HI finds (decision seed-close-open-targets)",
    /// MCV: maximum close velocity.
    CloseVelocity => ["MCV"], absent: Absence::Required, "C and TC have no speed",
    /// MOV: maximum open velocity.
    OpenVelocity => ["MOV"], absent: Absence::Required, "O and TO have no speed",
    /// ACCEL: acceleration.
    Acceleration => ["ACCEL"], absent: Absence::Required, "no move can ramp up",
    /// MPE: maximum position error of a move.
    PositionError => ["MPE"], absent: Absence::Required, "no move can say whether it missed its target",
    /// TSTOP: stall time that ends a move.
    StopTime => ["TSTOP"], absent: Absence::Required, "a stalled move never ends",
    /// HOLD: keep power after a move.
    Hold => ["HOLD"], absent: Absence::Value(0), "the motors are not held: power drops when a move ends",
    /// HSG (MSG in the seed): high strain that stops a close.
    HighStrain => ["HSG", "MSG"], absent: Absence::Required, "a close against an object never stops on strain",
    /// BS: breakaway on.
    Breakaway => ["BS"], absent: Absence::Value(0), "no breakaway: a finger that meets an object stops there",
    /// SGFLIP: strain reading mirrored.
    StrainFlip => ["SGFLIP"], absent: Absence::Value(0), "strain reads unmirrored",
    /// OTEMP: overtemperature threshold.
    OverTemperature => ["OTEMP"], absent: Absence::Value(0), "no overtemperature refusal (OTEMP 0 turns it off)",
    /// LCVC: LCV coefficient.
    VelocityCoefficient => ["LCVC"], absent: Absence::RequiredWith(RtFlag::Lcv), "an LCV datum has no scale",
    /// LFVC: LFV coefficient.
    FeedbackVelocityCoefficient => ["LFVC"], absent: Absence::RequiredWith(RtFlag::Lfv),
        "an LFV value has no scale",
    /// LFDPC: LFDP coefficient.
    DeltaCoefficient => ["LFDPC"], absent: Absence::RequiredWith(RtFlag::Lfdp), "an LFDP value has no scale",
    /// LFDPD: LFDP discards the clipped rest.
    DeltaDiscard => ["LFDPD"], absent: Absence::Value(0),
        "LFDP carries the clipped rest into later blocks, as LFDPD 0 does in bh8-262",
    /// LCPG: the control-gain flag (read when control data arrives).
    ControlGain => ["LCPG"], absent: Absence::Value(0), "control blocks carry no gain",
}

/// Index of a command in [`Profile::commands`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub struct CommandId(pub u16);

/// Index of a parameter in [`Profile::params`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub struct ParamId(pub u16);

/// A resolved profile: every include merged, every cross reference checked, indexes built.
#[derive(Debug, Clone, Serialize)]
pub struct Profile {
    /// The profile id.
    pub id: String,
    /// A one-line title.
    pub title: String,
    /// Other names.
    pub aliases: Vec<String>,
    /// Framing.
    pub framing: Framing,
    /// Lines of the power-up and RESET banner.
    pub banner: Vec<String>,
    /// Lines printed by `VERS`.
    pub version: Vec<String>,
    /// Hand constants.
    pub hand: Hand,
    /// Motor prefixes.
    pub prefixes: Vec<PrefixSpec>,
    /// Commands, in listing order.
    pub commands: Vec<CommandSpec>,
    /// Parameters, in listing order.
    pub params: Vec<ParamSpec>,
    /// Status bits, lowest first.
    pub status: Vec<StatusSpec>,
    /// Decisions, in file order.
    pub decisions: Vec<Decision>,
    /// Storage slot of each parameter (aliases share their target's slot).
    #[serde(skip)]
    pub(crate) slot: Vec<u16>,
    /// Number of distinct storage slots.
    #[serde(skip)]
    pub(crate) slots: usize,
    /// The RealTime flags, in field order.
    #[serde(skip)]
    rt_slots: Vec<RtSlot>,
    /// The parameter of each [`Role`], by `Role as usize`.
    #[serde(skip)]
    roles: Vec<Option<ParamId>>,
    /// The role of each parameter, by [`ParamId`].
    #[serde(skip)]
    role_of: Vec<Option<Role>>,
    /// The `[hand]` value sources, resolved.
    #[serde(skip)]
    hand_sources: HandSources,
    /// The parameters each of the six transfers moves ([`PERSIST_COMMANDS`] order): those of
    /// its scope, no alias, whose `persist` names it.
    #[serde(skip)]
    persisted: Vec<Vec<ParamId>>,
    /// Every parameter name and input alias of at most [`NAME_KEY_BYTES`] bytes as its
    /// [`name_key`], with the first parameter that answers to it, sorted by key: what
    /// [`Profile::param_id`] searches (the model looks a name up for every parameter a line
    /// names).
    #[serde(skip)]
    param_index: Vec<(u128, u16)>,
    /// The same for the command names, for [`Profile::command_id`] (every line names one).
    #[serde(skip)]
    command_index: Vec<(u128, u16)>,
}

/// The longest name [`name_key`] turns into a number.
const NAME_KEY_BYTES: usize = 15;

/// A name of at most [`NAME_KEY_BYTES`] bytes as one number, ASCII letters upper-cased: two
/// names have the same key exactly when `eq_ignore_ascii_case` holds between them. (The bytes
/// in base 256, then the length, which keeps `A` apart from `\0A`.)
fn name_key(name: &[u8]) -> Option<u128> {
    (name.len() <= NAME_KEY_BYTES).then(|| {
        let bytes = name.iter().fold(0u128, |k, b| (k << 8) | u128::from(b.to_ascii_uppercase()));
        (bytes << 8) | name.len() as u128
    })
}

/// The index of names [`find_by_key`] searches: each name's [`name_key`] (names too long for a
/// key are left out) with its position, the first position a name has where names repeat.
fn name_index<'a>(names: impl Iterator<Item = (&'a str, usize)>) -> Vec<(u128, u16)> {
    let mut index: Vec<(u128, u16)> = names.filter_map(|(n, i)| Some((name_key(n.as_bytes())?, i as u16))).collect();
    // (a stable sort, so that the first position of a repeated name stays first)
    index.sort_by_key(|(k, _)| *k);
    index.dedup_by_key(|(k, _)| *k);
    index
}

/// The position [`name_index`] holds for `name`: `Err(())` when the name is too long for a
/// key, and only a scan can tell.
fn find_by_key(index: &[(u128, u16)], name: &str) -> Result<Option<u16>, ()> {
    let key = name_key(name.as_bytes()).ok_or(())?;
    Ok(index.binary_search_by_key(&key, |(k, _)| *k).ok().and_then(|i| index.get(i)).map(|(_, at)| *at))
}

/// The transfer commands a parameter's `persist` list may name, in the order
/// [`Profile::persisted`] keeps them.
pub const PERSIST_COMMANDS: [&str; 6] = ["FSAVE", "FLOAD", "FDEF", "PSAVE", "PLOAD", "PDEF"];

/// The largest magnitude a parameter value, range or argument may have in a spec file, so
/// that the model's arithmetic on values can never overflow.
pub const MAX_VALUE: i64 = 1 << 40;

/// Checks that framing and hand constants lie where the model's arithmetic and buffers are
/// safe. A spec file is input: out-of-bounds constants are an error, never a panic later.
fn check_bounds(framing: &Framing, hand: &Hand) -> Result<(), String> {
    let status_ok = |name: &str, v: u32| {
        StatusBits::from_bits(v).map(|_| ()).ok_or_else(|| format!("{name} = {v} is not a combination of status bits"))
    };
    if !(1..=4096).contains(&framing.max_line) {
        return Err(format!("framing.max_line = {} must be 1..=4096", framing.max_line));
    }
    if framing.line_ending.len() > 16 || framing.prompt.len() > 16 {
        return Err("framing.line_ending and framing.prompt must be at most 16 bytes".into());
    }
    if framing.terminator == framing.abort {
        return Err("framing.terminator and framing.abort must differ".into());
    }
    status_ok("framing.overlong_status", framing.overlong_status)?;
    for (name, v) in [
        ("hand.abort_status", hand.abort_status),
        ("hand.terminate_uninitialized_status", hand.terminate_uninitialized_status),
        ("hand.uninitialized_status", hand.uninitialized_status),
        ("hand.overtemp_status", hand.overtemp_status),
        ("hand.missed_position_status", hand.missed_position_status),
        ("hand.bad_header_status", hand.bad_header_status),
    ] {
        status_ok(name, v)?;
    }
    let counts = |name: &str, v: i64| {
        if (0..=65535).contains(&v) { Ok(()) } else { Err(format!("{name} = {v} must be 0..=65535")) }
    };
    counts("hand.finger_limit", hand.finger_limit)?;
    counts("hand.spread_limit", hand.spread_limit)?;
    counts("hand.object_compliance", hand.object_compliance)?;
    counts("hand.uninitialized_state_value", hand.uninitialized_state_value)?;
    for (name, v) in
        [("hand.finger_close_target", hand.finger_close_target), ("hand.spread_close_target", hand.spread_close_target)]
    {
        if let Some(v) = v {
            counts(name, v)?;
        }
    }
    if !(0..=255).contains(&hand.free_strain) {
        return Err(format!("hand.free_strain = {} must be 0..=255", hand.free_strain));
    }
    for (name, v) in [
        ("hand.counts_per_ms_per_velocity_unit", hand.counts_per_ms_per_velocity_unit),
        ("hand.velocity_units_per_ms_per_accel", hand.velocity_units_per_ms_per_accel),
        ("hand.rt_velocity_counts_per_ms", hand.rt_velocity_counts_per_ms),
        ("hand.lfv_counts_per_ms", hand.lfv_counts_per_ms),
        ("hand.strain_per_count", hand.strain_per_count),
        ("hand.heat_per_motor_s", hand.heat_per_motor_s),
        ("hand.cooling_time_s", hand.cooling_time_s),
    ] {
        if !(v.is_finite() && v > 0.0 && v <= 10_000.0) {
            return Err(format!("{name} = {v} must be a number in (0, 10000]"));
        }
    }
    if hand.lcv_fraction_bits > 15 {
        return Err(format!("hand.lcv_fraction_bits = {} must be 0..=15", hand.lcv_fraction_bits));
    }
    if hand.hi_settle_ms > 60_000 {
        return Err(format!("hand.hi_settle_ms = {} must be at most 60000", hand.hi_settle_ms));
    }
    if hand.lft_size > 2 {
        return Err(format!("hand.lft_size = {} must be 0, 1 or 2", hand.lft_size));
    }
    for (name, v, max) in [
        ("hand.hi_velocity", &hand.hi_velocity, MAX_VALUE),
        ("hand.hi_hold_repetitions", &hand.hi_hold_repetitions, MAX_VALUE),
        ("hand.baud", &hand.baud, i64::from(u32::MAX)),
        ("hand.low_strain_stop", &hand.low_strain_stop, MAX_VALUE),
    ] {
        if let HandValue::Fixed(v) = v
            && !(0..=max).contains(v)
        {
            return Err(format!("{name} = {v} must be 0..={max}"));
        }
    }
    Ok(())
}

/// Parses one spec file. The error names the line and column and says what is wrong, but
/// never quotes the file's text: a file named as a profile may be no profile at all (a
/// bundle naming `/etc/shadow`), and its lines must not reach a message.
fn parse_file(name: &str, text: &str) -> Result<SpecFile, SpecError> {
    toml::from_str(text).map_err(|e| {
        let at = e.span().map(|span| {
            let before = text.get(..span.start).unwrap_or_default();
            let line = before.matches('\n').count() + 1;
            let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
            format!("line {line}, column {column}: ")
        });
        SpecError::Syntax { file: name.to_string(), message: format!("{}{}", at.unwrap_or_default(), e.message()) }
    })
}

fn merge_named<T: Clone>(into: &mut Vec<T>, from: &[T], name: impl Fn(&T) -> &str) {
    for item in from {
        match into.iter_mut().find(|x| name(x) == name(item)) {
            Some(slot) => *slot = item.clone(),
            None => into.push(item.clone()),
        }
    }
}

impl Profile {
    /// The embedded profile with this name or alias (`bh8-262` is `bh8-262-4.4`).
    pub fn builtin(name: &str) -> Result<Arc<Profile>, SpecError> {
        use std::sync::OnceLock;
        static CACHE: OnceLock<Vec<Result<Arc<Profile>, SpecError>>> = OnceLock::new();
        // The embedded files are checked by this crate's tests; should one still fail to load,
        // asking for any built-in profile says why.
        let all = CACHE.get_or_init(|| {
            EMBEDDED_PROFILES
                .iter()
                .map(|(_, file)| Profile::load_with(file, &|f| embedded(f).map(str::to_string)).map(Arc::new))
                .collect()
        });
        if let Some(Err(e)) = all.iter().find(|p| p.is_err()) {
            return Err(e.clone());
        }
        all.iter()
            .flatten()
            .find(|p| p.id.eq_ignore_ascii_case(name) || p.aliases.iter().any(|a| a.eq_ignore_ascii_case(name)))
            .cloned()
            .ok_or_else(|| SpecError::UnknownProfile(name.to_string()))
    }

    /// Names of the embedded profiles.
    pub fn builtin_names() -> impl Iterator<Item = &'static str> {
        EMBEDDED_PROFILES.iter().map(|(n, _)| *n)
    }

    /// Loads a profile from `top`, asking `resolve` for the text of each file by its path
    /// relative to `spec/`. The model itself never reads files.
    pub fn load_with(top: &str, resolve: &dyn Fn(&str) -> Option<String>) -> Result<Profile, SpecError> {
        let mut merged = SpecFile::default();
        let mut stack = Vec::new();
        let mut expanded = (0usize, 0usize);
        Self::merge_file(top, resolve, &mut merged, &mut stack, &mut expanded)?;
        Self::resolve(merged)
    }

    /// Merges `name` and its includes into `into`; `expanded` counts the files and bytes
    /// resolved so far, against [`MAX_SPEC_FILES`] and [`MAX_SPEC_BYTES`].
    fn merge_file(
        name: &str,
        resolve: &dyn Fn(&str) -> Option<String>,
        into: &mut SpecFile,
        stack: &mut Vec<String>,
        expanded: &mut (usize, usize),
    ) -> Result<(), SpecError> {
        if stack.iter().any(|s| s == name) {
            return Err(SpecError::IncludeCycle(name.to_string()));
        }
        expanded.0 += 1;
        if expanded.0 > MAX_SPEC_FILES {
            return Err(SpecError::TooManyIncludes { file: name.to_string(), limit: MAX_SPEC_FILES });
        }
        let text = resolve(name).ok_or_else(|| SpecError::MissingFile(name.to_string()))?;
        expanded.1 = expanded.1.saturating_add(text.len());
        if expanded.1 > MAX_SPEC_BYTES {
            return Err(SpecError::TooLarge { file: name.to_string(), limit: MAX_SPEC_BYTES });
        }
        let file = parse_file(name, &text)?;
        // Checked before any include is resolved: a file of a million includes is refused
        // whole, not after reading 256 of them.
        if expanded.0 + file.include.len() > MAX_SPEC_FILES {
            return Err(SpecError::TooManyIncludes { file: name.to_string(), limit: MAX_SPEC_FILES });
        }
        stack.push(name.to_string());
        for inc in &file.include {
            Self::merge_file(inc, resolve, into, stack, expanded)?;
        }
        stack.pop();
        if file.id.is_some() {
            into.id = file.id.clone();
        }
        if file.title.is_some() {
            into.title = file.title.clone();
        }
        into.aliases.extend(file.aliases.iter().cloned());
        if file.framing.is_some() {
            into.framing = file.framing.clone();
        }
        if file.hand.is_some() {
            into.hand = file.hand.clone();
        }
        if file.banner.is_some() {
            into.banner = file.banner.clone();
        }
        if file.version.is_some() {
            into.version = file.version.clone();
        }
        if !file.prefixes.is_empty() {
            into.prefixes = file.prefixes.clone();
        }
        merge_named(&mut into.commands, &file.commands, |c| &c.name);
        into.commands.retain(|c| !file.remove_commands.contains(&c.name));
        merge_named(&mut into.params, &file.params, |p| &p.name);
        into.params.retain(|p| !file.remove_params.contains(&p.name));
        let mut status = into.status.clone();
        for s in &file.status {
            match status.iter_mut().find(|x| x.bit == s.bit) {
                Some(slot) => *slot = s.clone(),
                None => status.push(s.clone()),
            }
        }
        into.status = status;
        merge_named(&mut into.decisions, &file.decisions, |d| &d.id);
        Ok(())
    }

    fn resolve(f: SpecFile) -> Result<Profile, SpecError> {
        let id = f.id.clone().unwrap_or_default();
        let invalid = |message: String| SpecError::Invalid { profile: id.clone(), message };
        if id.is_empty() {
            return Err(invalid("no `id`".into()));
        }
        let framing = f.framing.ok_or_else(|| invalid("no [framing]".into()))?;
        let hand = f.hand.ok_or_else(|| invalid("no [hand]".into()))?;
        let banner = f.banner.ok_or_else(|| invalid("no `banner`".into()))?;
        let version = f.version.ok_or_else(|| invalid("no `version`".into()))?;
        check_bounds(&framing, &hand).map_err(&invalid)?;
        if f.prefixes.is_empty() {
            return Err(invalid("no [[prefixes]]".into()));
        }
        for p in &f.prefixes {
            if p.motors.is_empty() || p.motors.iter().any(|m| !(1..=4).contains(m)) {
                return Err(invalid(format!("prefix `{}` names motors outside 1..=4", p.char)));
            }
        }
        let mut status = f.status;
        status.sort_by_key(|s| s.bit);
        for s in &status {
            if !s.bit.is_power_of_two() || StatusBits::from_bits(s.bit).is_none() {
                return Err(invalid(format!("status {} is not a known single bit", s.bit)));
            }
        }
        let mut seen = std::collections::HashSet::new();
        for c in &f.commands {
            if !seen.insert(c.name.to_ascii_uppercase()) {
                return Err(invalid(format!("command `{}` twice", c.name)));
            }
            if c.name.is_empty() || c.name.starts_with(|ch: char| f.prefixes.iter().any(|p| p.char == ch)) {
                return Err(invalid(format!("command `{}` starts with a prefix character", c.name)));
            }
            if c.args == ArgRule::OptionalInteger && (c.arg_min.is_none() || c.arg_max.is_none()) {
                return Err(invalid(format!("command `{}` needs arg_min and arg_max", c.name)));
            }
            if c.arg_min.into_iter().chain(c.arg_max).any(|v| v.abs() > MAX_VALUE) {
                return Err(invalid(format!("command `{}`: arguments beyond ±{MAX_VALUE}", c.name)));
            }
        }
        let mut seen = std::collections::HashSet::new();
        for p in &f.params {
            for n in std::iter::once(&p.name).chain(&p.input_aliases) {
                if !seen.insert(n.to_ascii_uppercase()) {
                    return Err(invalid(format!("parameter name `{n}` twice")));
                }
            }
            if p.min > p.max {
                return Err(invalid(format!("parameter `{}` has min > max", p.name)));
            }
            let extremes = [p.min, p.max].into_iter().chain(p.values.iter().flatten().copied());
            if extremes.chain(p.default).chain(p.default_spread).any(|v| v.abs() > MAX_VALUE) {
                return Err(invalid(format!("parameter `{}`: values beyond ±{MAX_VALUE}", p.name)));
            }
            let in_range = |v: i64| match &p.values {
                Some(vs) => vs.contains(&v),
                None => (p.min..=p.max).contains(&v),
            };
            if let Some(d) = p.default.into_iter().chain(p.default_spread).find(|d| !in_range(*d)) {
                return Err(invalid(format!("parameter `{}`: default {d} is outside its range", p.name)));
            }
            if !p.live && !p.read_only && p.alias_of.is_none() && p.default.is_none() {
                return Err(invalid(format!("writable parameter `{}` has no default", p.name)));
            }
            for cmd in p.get.iter().chain(&p.set).chain(&p.persist) {
                if !f.commands.iter().any(|c| &c.name == cmd) {
                    return Err(invalid(format!(
                        "parameter `{}` names command `{cmd}`, which the profile lacks",
                        p.name
                    )));
                }
            }
        }
        // RealTime flags: closed names and types, in field order (`order`, then listing).
        let mut rt_slots = Vec::new();
        for (i, p) in f.params.iter().enumerate() {
            let Some(rt) = &p.rt else { continue };
            let flag = RtFlag::from_name(&p.name)
                .ok_or_else(|| SpecError::UnknownRtFlag { profile: id.clone(), param: p.name.clone() })?;
            let bad = |message: String| SpecError::RtField { profile: id.clone(), param: p.name.clone(), message };
            let ty = FieldType::new(rt.size, rt.signed)
                .ok_or_else(|| bad(format!("a field of {} bytes is not u8, i8, u16 or i16", rt.size)))?;
            if rt.block != flag.block() {
                return Err(bad(format!("belongs in the {:?} block", flag.block()).to_lowercase()));
            }
            if flag.is_global() != (p.scope == Scope::Global) {
                return Err(bad(format!("must have {} scope", if flag.is_global() { "global" } else { "motor" })));
            }
            rt_slots.push((rt.order, RtSlot { param: ParamId(i as u16), flag, ty }));
        }
        // A stable sort: equal orders keep their listing order.
        rt_slots.sort_by_key(|(order, _)| *order);
        let rt_slots: Vec<RtSlot> = rt_slots.into_iter().map(|(_, s)| s).collect();
        for d in &f.decisions {
            d.check().map_err(&invalid)?;
        }
        // Storage slots: aliases share the slot of their target.
        let mut slot = vec![0u16; f.params.len()];
        let mut slots = 0usize;
        for (s, p) in slot.iter_mut().zip(&f.params) {
            if p.alias_of.is_none() {
                *s = slots as u16;
                slots += 1;
            }
        }
        for (i, p) in f.params.iter().enumerate() {
            if let Some(target) = &p.alias_of {
                let t = f
                    .params
                    .iter()
                    .position(|q| &q.name == target && q.alias_of.is_none())
                    .and_then(|t| slot.get(t).copied())
                    .ok_or_else(|| invalid(format!("`{}` is an alias of unknown `{target}`", p.name)))?;
                if let Some(s) = slot.get_mut(i) {
                    *s = t;
                }
            }
        }
        let find = |name: &str| {
            f.params.iter().position(|p| {
                p.name.eq_ignore_ascii_case(name) || p.input_aliases.iter().any(|a| a.eq_ignore_ascii_case(name))
            })
        };
        let roles = Role::ALL
            .iter()
            .map(|r| r.names().iter().find_map(|n| find(n)).map(|i| ParamId(i as u16)))
            .collect::<Vec<Option<ParamId>>>();
        // Each role's absence, checked once here so that the device can rely on it.
        for (r, param) in Role::ALL.iter().zip(&roles) {
            let needed = match r.absence() {
                Absence::Required => true,
                Absence::RequiredWith(flag) => rt_slots.iter().any(|s| s.flag == flag),
                Absence::HandCloseTargets => hand.finger_close_target.is_none() || hand.spread_close_target.is_none(),
                Absence::Value(_) | Absence::Unreported => false,
            };
            if param.is_none() && needed {
                return Err(SpecError::MissingRole { profile: id.clone(), role: *r, names: r.names() });
            }
        }
        let source = |key: &'static str, v: &HandValue| match v {
            HandValue::Fixed(v) => Ok(ValueSource::Fixed(*v)),
            HandValue::Param(name) => find(name)
                .map(|i| ValueSource::Param(ParamId(i as u16)))
                .ok_or_else(|| SpecError::UnknownHandParam { profile: id.clone(), key, param: name.clone() }),
        };
        let hand_sources = HandSources {
            hi_velocity: source("hi_velocity", &hand.hi_velocity)?,
            hi_hold_repetitions: source("hi_hold_repetitions", &hand.hi_hold_repetitions)?,
            baud: source("baud", &hand.baud)?,
            low_strain_stop: source("low_strain_stop", &hand.low_strain_stop)?,
        };
        let persisted = PERSIST_COMMANDS
            .iter()
            .map(|cmd| {
                let scope = if cmd.starts_with('F') { Scope::Motor } else { Scope::Global };
                f.params
                    .iter()
                    .enumerate()
                    .filter(|(_, p)| p.scope == scope && p.alias_of.is_none() && p.persist.iter().any(|c| c == cmd))
                    .map(|(i, _)| ParamId(i as u16))
                    .collect()
            })
            .collect();
        let mut role_of = vec![None; f.params.len()];
        for (r, id) in Role::ALL.iter().zip(&roles) {
            if let Some(slot) = id.and_then(|id| role_of.get_mut(id.0 as usize)) {
                *slot = Some(*r);
            }
        }
        let param_index = name_index(
            f.params
                .iter()
                .enumerate()
                .flat_map(|(i, p)| std::iter::once(&p.name).chain(&p.input_aliases).map(move |n| (n.as_str(), i))),
        );
        let command_index = name_index(f.commands.iter().enumerate().map(|(i, c)| (c.name.as_str(), i)));
        Ok(Profile {
            param_index,
            command_index,
            persisted,
            rt_slots,
            roles,
            role_of,
            hand_sources,
            title: f.title.unwrap_or_default(),
            aliases: f.aliases,
            framing,
            banner,
            version,
            hand,
            prefixes: f.prefixes,
            commands: f.commands,
            params: f.params,
            status,
            decisions: f.decisions,
            slot,
            slots,
            id,
        })
    }

    /// The parameters the transfer command `cmd` (one of [`PERSIST_COMMANDS`]) moves.
    pub fn persisted(&self, cmd: &str) -> &[ParamId] {
        PERSIST_COMMANDS.iter().position(|c| *c == cmd).and_then(|i| self.persisted.get(i)).map_or(&[], Vec::as_slice)
    }

    /// The parameter that plays `role` in this profile, if it has one.
    pub fn role(&self, role: Role) -> Option<ParamId> {
        self.roles.get(role as usize).copied().flatten()
    }

    /// What the hand reads for `role` on `motor` when this profile lacks its
    /// parameter: the role's [`Absence`] resolved against the profile. `None` when nothing
    /// may read it: a required role is present in every loaded profile, one required with a
    /// RealTime flag is read only by that flag's field, and an unreported one is never read.
    pub fn absent_value(&self, role: Role, motor: crate::motor::Motor) -> Option<i64> {
        match role.absence() {
            Absence::Value(v) => Some(v),
            Absence::HandCloseTargets if motor == crate::motor::Motor::SPREAD => self.hand.spread_close_target,
            Absence::HandCloseTargets => self.hand.finger_close_target,
            Absence::Required | Absence::RequiredWith(_) | Absence::Unreported => None,
        }
    }

    /// Where the hand reads the behaviour values its `[hand]` table names by source: HI's
    /// speed and hold repetitions, the serial rate, the low-strain stop.
    pub fn hand_sources(&self) -> &HandSources {
        &self.hand_sources
    }

    /// The role a parameter plays, if any.
    pub fn role_of(&self, id: ParamId) -> Option<Role> {
        self.role_of.get(id.0 as usize).copied().flatten()
    }

    /// The RealTime flags, in the order their fields appear (per motor, then hand-wide).
    pub fn rt_slots(&self) -> &[RtSlot] {
        &self.rt_slots
    }

    /// Finds a command by name, ignoring ASCII case.
    pub fn command_id(&self, name: &str) -> Option<CommandId> {
        if let Ok(at) = find_by_key(&self.command_index, name) {
            return at.map(CommandId);
        }
        self.commands.iter().position(|c| c.name.eq_ignore_ascii_case(name)).map(|i| CommandId(i as u16))
    }

    /// The command with this id (an id of another profile, out of range, reads as a
    /// nameless command that does nothing).
    pub fn command(&self, id: CommandId) -> &CommandSpec {
        self.commands.get(usize::from(id.0)).unwrap_or(&NO_COMMAND)
    }

    /// The first command of this kind, if the profile has one.
    pub fn command_of_kind(&self, kind: CommandKind) -> Option<CommandId> {
        self.commands.iter().position(|c| c.kind == kind).map(|i| CommandId(i as u16))
    }

    /// Finds a parameter by name or input alias, ignoring ASCII case.
    pub fn param_id(&self, name: &str) -> Option<ParamId> {
        if let Ok(at) = find_by_key(&self.param_index, name) {
            return at.map(ParamId);
        }
        self.params
            .iter()
            .position(|p| {
                p.name.eq_ignore_ascii_case(name) || p.input_aliases.iter().any(|a| a.eq_ignore_ascii_case(name))
            })
            .map(|i| ParamId(i as u16))
    }

    /// The parameter with this id (an id of another profile, out of range, reads as a
    /// nameless read-only parameter).
    pub fn param(&self, id: ParamId) -> &ParamSpec {
        self.params.get(usize::from(id.0)).unwrap_or(&NO_PARAM)
    }

    /// The storage slot of a parameter (aliases share their target's).
    pub(crate) fn slot_of(&self, id: ParamId) -> usize {
        self.slot.get(usize::from(id.0)).map_or(usize::MAX, |s| usize::from(*s))
    }

    /// All parameter ids, in listing order.
    pub fn param_ids(&self) -> impl Iterator<Item = ParamId> + '_ {
        (0..self.params.len()).map(|i| ParamId(i as u16))
    }

    /// The command word that reads this parameter.
    pub fn getter(&self, id: ParamId) -> &str {
        let p = self.param(id);
        p.get.as_deref().unwrap_or(match p.scope {
            Scope::Motor => "FGET",
            Scope::Global => "PGET",
        })
    }

    /// The command word that writes this parameter.
    pub fn setter(&self, id: ParamId) -> &str {
        let p = self.param(id);
        p.set.as_deref().unwrap_or(match p.scope {
            Scope::Motor => "FSET",
            Scope::Global => "PSET",
        })
    }

    /// The text of one status bit, if the profile defines it.
    pub fn status_text(&self, bit: u32) -> Option<&str> {
        self.status.iter().find(|s| s.bit == bit).map(|s| s.text.as_str())
    }

    /// The default of a parameter for a motor (1..=4) or, for globals, the hand.
    pub fn default_for(&self, id: ParamId, motor: u8) -> i64 {
        let p = self.param(id);
        if motor == 4 { p.default_spread.or(p.default).unwrap_or(0) } else { p.default.unwrap_or(0) }
    }

    /// Whether a value is valid for a parameter.
    pub fn value_ok(&self, id: ParamId, value: i64) -> bool {
        let p = self.param(id);
        match &p.values {
            Some(vs) => vs.contains(&value),
            None => (p.min..=p.max).contains(&value),
        }
    }

    /// The motors a prefix character names.
    pub fn prefix_motors(&self, ch: char) -> Option<&[u8]> {
        self.prefixes.iter().find(|p| p.char.eq_ignore_ascii_case(&ch)).map(|p| p.motors.as_slice())
    }
}

impl StatusTexts for Profile {
    fn status_text(&self, bit: u32) -> Option<&str> {
        Profile::status_text(self, bit)
    }
}

/// What [`Profile::command`] gives for an id the profile does not have.
static NO_COMMAND: CommandSpec = CommandSpec {
    name: String::new(),
    category: String::new(),
    kind: CommandKind::Help,
    prefix: PrefixRule::Forbidden,
    args: ArgRule::None,
    arg_min: None,
    arg_max: None,
    advanced: true,
    prints: String::new(),
    help: String::new(),
};

/// What [`Profile::param`] gives for an id the profile does not have.
static NO_PARAM: ParamSpec = ParamSpec {
    name: String::new(),
    scope: Scope::Global,
    section: String::new(),
    description: String::new(),
    min: 0,
    max: 0,
    values: None,
    default: None,
    default_spread: None,
    read_only: true,
    advanced: true,
    persist: Vec::new(),
    get: None,
    set: None,
    alias_of: None,
    input_aliases: Vec::new(),
    live: true,
    self_stored: false,
    rt: None,
    effect: None,
};

/// The text of an embedded spec file, by its path relative to `spec/`.
pub fn embedded(path: &str) -> Option<&'static str> {
    EMBEDDED_FILES.iter().find(|(p, _)| *p == path).map(|(_, t)| *t)
}

/// Loads `top` as the top file of a profile; its includes resolve to the embedded spec files.
#[cfg(test)]
fn load_top(top: &str) -> Result<Profile, SpecError> {
    Profile::load_with("top.toml", &|p| {
        if p == "top.toml" { Some(top.to_string()) } else { embedded(p).map(str::to_string) }
    })
}

#[cfg(test)]
mod evidence_tests {
    use super::*;

    #[test]
    fn evidence_grades_parse_and_bound_the_level() {
        let e = Evidence::parse("[doc][code×3]").unwrap();
        assert_eq!((e.doc, e.code, e.strongest_level()), (true, 3, Level::Must));
        assert_eq!(Evidence::parse("[codex2]").unwrap().strongest_level(), Level::Must);
        assert_eq!(Evidence::parse("[code]").unwrap().strongest_level(), Level::Should);
        assert!(Evidence::parse("[open]").unwrap().is_open());
        for bad in ["", "doc", "[open][doc]", "[code×0]", "[guess]", "[doc][doc]"] {
            assert!(Evidence::parse(bad).is_err(), "{bad:?}");
        }
    }

    #[test]
    fn the_loader_refuses_a_must_without_two_sources() {
        let seed = embedded("seed.toml").unwrap();
        let top = format!(
            "{seed}\n[[decisions]]\nid = \"x-guess\"\nclause = \"c\"\nresolution = \"r\"\nlevel = \"MUST\"\nevidence = \"[code]\"\n"
        );
        let err = load_top(&top).unwrap_err().to_string();
        assert!(err.contains("x-guess") && err.contains("at most SHOULD"), "{err}");
    }

    #[test]
    fn a_typo_in_a_decision_level_is_refused_at_load() {
        let seed = embedded("seed.toml").unwrap();
        let top = format!(
            "{seed}\n[[decisions]]\nid = \"x-typo\"\nclause = \"c\"\nresolution = \"r\"\nlevel = \"MUTS\"\nevidence = \"[doc]\"\n"
        );
        match load_top(&top) {
            Err(SpecError::Syntax { file, message }) => {
                assert_eq!(file, "top.toml");
                assert!(message.contains("MUTS") && message.contains("INFO"), "{message}");
            }
            other => panic!("a level typo must be refused, got {other:?}"),
        }
    }
}

#[cfg(test)]
mod closed_names_tests {
    use super::*;

    #[test]
    fn texts_come_from_the_profile() {
        let seed = Profile::builtin("seed").unwrap();
        assert_eq!(crate::status::StatusBits::TIMEOUT.describe(&seed), vec!["512: Timeout"]);
        // The seed defines no 16384.
        assert!(crate::status::StatusBits::ABORTED.describe(&seed).is_empty());
    }

    /// Loads the seed with `extra` TOML appended to its top file.
    fn seed_with(extra: &str) -> Result<Profile, SpecError> {
        let seed = embedded("seed.toml").unwrap_or_default();
        load_top(&format!("{seed}\n{extra}"))
    }

    const FLAG: &str = "[[params]]\nname = \"{name}\"\nscope = \"{scope}\"\nsection = \"realtime\"\ndescription = \"d\"\nmin = 0\nmax = 1\ndefault = 0\nrt = {{ block = \"{block}\", size = {size}, signed = false, order = 9 }}\n";

    fn flag(name: &str, scope: &str, block: &str, size: usize) -> String {
        FLAG.replace("{name}", name)
            .replace("{scope}", scope)
            .replace("{block}", block)
            .replace("{size}", &size.to_string())
            .replace("{{", "{")
            .replace("}}", "}")
    }

    /// Loads the seed with `line` of its top file replaced by `by`.
    fn seed_replacing(line: &str, by: &str) -> Result<Profile, SpecError> {
        let seed = embedded("seed.toml").unwrap_or_default();
        assert!(seed.contains(line), "the seed has no line `{line}`");
        load_top(&seed.replacen(line, by, 1))
    }

    #[test]
    fn the_hand_states_where_hi_the_line_rate_and_the_strain_stop_read_their_values() {
        let seed = Profile::builtin("seed").unwrap();
        let mov = seed.param_id("MOV").unwrap();
        let baud = seed.param_id("BAUD").unwrap();
        assert_eq!(
            *seed.hand_sources(),
            HandSources {
                hi_velocity: ValueSource::Param(mov),
                hi_hold_repetitions: ValueSource::Fixed(1),
                baud: ValueSource::Param(baud),
                low_strain_stop: ValueSource::Fixed(256),
            }
        );
        for name in ["bh8-262-4.3", "bh8-262-4.4"] {
            let p = Profile::builtin(name).unwrap();
            let param = |s: ValueSource| match s {
                ValueSource::Param(id) => p.param(id).name.clone(),
                ValueSource::Fixed(v) => panic!("{name}: a fixed {v} where the manual names a parameter"),
            };
            let s = p.hand_sources();
            assert_eq!(
                [s.hi_velocity, s.hi_hold_repetitions, s.baud, s.low_strain_stop].map(param),
                ["IVEL", "IHIT", "BAUD", "LSG"],
                "{name}"
            );
        }
    }

    #[test]
    fn a_hand_without_a_value_source_is_refused() {
        for key in ["hi_velocity = \"MOV\"", "hi_hold_repetitions = 1", "baud = \"BAUD\"", "low_strain_stop = 256"] {
            let name = key.split(' ').next().unwrap_or_default();
            match seed_replacing(key, "") {
                Err(SpecError::Syntax { message, .. }) => assert!(message.contains(name), "{key}: {message}"),
                other => panic!("without `{key}` the seed loaded or failed otherwise: {other:?}"),
            }
        }
    }

    #[test]
    fn a_value_source_naming_an_unknown_parameter_is_refused() {
        // IVEL is a BH8-262 parameter the seed does not have.
        let err = seed_replacing("hi_velocity = \"MOV\"", "hi_velocity = \"IVEL\"").unwrap_err();
        assert_eq!(
            err,
            SpecError::UnknownHandParam { profile: "seed".into(), key: "hi_velocity", param: "IVEL".into() }
        );
        let err = seed_replacing("low_strain_stop = 256", "low_strain_stop = \"LSG\"").unwrap_err();
        assert_eq!(
            err,
            SpecError::UnknownHandParam { profile: "seed".into(), key: "low_strain_stop", param: "LSG".into() }
        );
        // A fixed rate must fit the serial port's u32.
        let err = seed_replacing("baud = \"BAUD\"", "baud = 5000000000").unwrap_err();
        assert!(matches!(&err, SpecError::Invalid { message, .. } if message.contains("hand.baud")), "{err}");
    }

    #[test]
    fn an_unknown_realtime_flag_is_refused_by_name() {
        let err = seed_with(&flag("LFXYZ", "motor", "feedback", 1)).unwrap_err();
        assert_eq!(err, SpecError::UnknownRtFlag { profile: "seed".into(), param: "LFXYZ".into() });
        assert!(err.to_string().contains("LFXYZ") && err.to_string().contains("LFAP"), "{err}");
    }

    #[test]
    fn a_realtime_field_must_have_a_gcl_type_block_and_scope() {
        for (extra, says) in [
            (flag("LFT", "global", "feedback", 3), "3 bytes"),
            (flag("LFT", "global", "control", 1), "feedback block"),
            (flag("LFT", "motor", "feedback", 1), "global scope"),
        ] {
            match seed_with(&extra) {
                Err(SpecError::RtField { param, message, .. }) => {
                    assert_eq!(param, "LFT");
                    assert!(message.contains(says), "{message}");
                }
                other => panic!("expected an RtField error for {says}, got {other:?}"),
            }
        }
    }

    #[test]
    fn roles_resolve_by_name_and_alias() {
        let seed = Profile::builtin("seed").unwrap();
        let bh8 = Profile::builtin("bh8-262").unwrap();
        let name = |p: &Profile, r: Role| p.role(r).map(|id| p.param(id).name.clone());
        // The seed calls the high strain MSG; bh8-262 calls it HSG.
        assert_eq!(name(&seed, Role::HighStrain).as_deref(), Some("MSG"));
        assert_eq!(name(&bh8, Role::HighStrain).as_deref(), Some("HSG"));
        assert_eq!(name(&bh8, Role::Position).as_deref(), Some("P"));
        for p in [&seed, &bh8] {
            for r in Role::ALL {
                if let Some(id) = p.role(*r) {
                    assert_eq!(p.role_of(id), Some(*r), "{} {r:?}", p.id);
                }
            }
        }
    }
}

#[cfg(test)]
mod include_limit_tests {
    use super::*;

    /// Issue 20 item 12: three levels of 200 includes of small files (8 million merges, 3.9 GB
    /// before) are refused as a typed error after at most [`MAX_SPEC_FILES`] files.
    #[test]
    fn an_include_bomb_is_refused() {
        let resolved = std::cell::Cell::new(0usize);
        let list = |prefix: &str| -> String {
            let names: Vec<String> = (0..200).map(|i| format!("\"{prefix}{i}.toml\"")).collect();
            format!("include = [{}]\n", names.join(", "))
        };
        let resolve = |p: &str| -> Option<String> {
            resolved.set(resolved.get() + 1);
            Some(match p {
                "top.toml" => list("a"),
                p if p.starts_with('a') => list("b"),
                p if p.starts_with('b') => list("c"),
                _ => "# small\n".to_string(),
            })
        };
        match Profile::load_with("top.toml", &resolve) {
            Err(SpecError::TooManyIncludes { limit, .. }) => assert_eq!(limit, MAX_SPEC_FILES),
            other => panic!("an include bomb must be refused, got {other:?}"),
        }
        assert!(resolved.get() <= MAX_SPEC_FILES, "{} files resolved", resolved.get());
        // Few files, but each large: the expanded text is bounded too.
        let big = format!("# {}\n", "x".repeat(1 << 20));
        let resolve = |p: &str| -> Option<String> {
            Some(if p == "top.toml" {
                let names: Vec<String> = (0..40).map(|i| format!("\"f{i}.toml\"")).collect();
                format!("include = [{}]\n", names.join(", "))
            } else {
                big.clone()
            })
        };
        assert!(matches!(Profile::load_with("top.toml", &resolve), Err(SpecError::TooLarge { .. })));
    }

    /// Issue 20 item 14: a file that is no profile (a shadow file named as one) is refused
    /// without its text in the message.
    #[test]
    fn a_syntax_error_never_quotes_the_file() {
        let shadow = "root:$6$secretsalt$hash:19000:0:99999:7:::\n";
        let err = Profile::load_with("top.toml", &|_| Some(shadow.to_string())).unwrap_err().to_string();
        assert!(!err.contains("secretsalt") && !err.contains("root"), "{err}");
        assert!(err.contains("top.toml") && err.contains("line 1"), "{err}");
    }
}

#[cfg(test)]
mod param_lookup_tests {
    use super::*;

    /// The search [`Profile::param_id`] made before its index: the first parameter whose name
    /// or an input alias is the name, ignoring ASCII case.
    fn scan(p: &Profile, name: &str) -> Option<ParamId> {
        p.params
            .iter()
            .position(|s| {
                s.name.eq_ignore_ascii_case(name) || s.input_aliases.iter().any(|a| a.eq_ignore_ascii_case(name))
            })
            .map(|i| ParamId(i as u16))
    }

    /// A name to look up, made from one the profile has: in the case `upper` gives its letters,
    /// then as it is (`edit` 0), a byte longer, a byte shorter, after a NUL, or `noise` instead.
    fn variant(base: &str, upper: &[bool], edit: u8, noise: &str) -> String {
        let cased: String = base
            .chars()
            .zip(upper.iter().cycle())
            .map(|(c, u)| if *u { c.to_ascii_uppercase() } else { c.to_ascii_lowercase() })
            .collect();
        match edit {
            0 => cased,
            1 => format!("{cased}X"),
            2 => cased[..cased.len().saturating_sub(1)].to_string(),
            3 => format!("\0{cased}"),
            _ => noise.to_string(),
        }
    }

    proptest::proptest! {
        /// The index finds what the scan finds, for every built-in profile: each parameter's
        /// name and alias in any case, with a byte more or less, a NUL in front, and names of
        /// every length up to past the index's longest.
        #[test]
        fn a_name_is_found_by_the_index_as_by_a_scan(
            pick in 0usize..1000,
            upper in proptest::collection::vec(proptest::bool::ANY, 20),
            edit in 0u8..5,
            noise in "[A-Za-z0-9\\x00]{0,18}",
        ) {
            for id in Profile::builtin_names() {
                let p = Profile::builtin(id).unwrap();
                let names: Vec<&String> = p.params.iter().flat_map(|s| std::iter::once(&s.name).chain(&s.input_aliases)).collect();
                let name = variant(names[pick % names.len()], &upper, edit, &noise);
                proptest::prop_assert_eq!(p.param_id(&name), scan(&p, &name), "{} in {}", name.escape_debug(), id);
            }
        }
    }

    proptest::proptest! {
        /// The same for command names ([`Profile::command_id`]).
        #[test]
        fn a_command_is_found_by_the_index_as_by_a_scan(
            pick in 0usize..1000,
            upper in proptest::collection::vec(proptest::bool::ANY, 20),
            edit in 0u8..5,
            noise in "[A-Za-z?\\x00]{0,18}",
        ) {
            for id in Profile::builtin_names() {
                let p = Profile::builtin(id).unwrap();
                let name = variant(&p.commands[pick % p.commands.len()].name, &upper, edit, &noise);
                let scan = p.commands.iter().position(|c| c.name.eq_ignore_ascii_case(&name)).map(|i| CommandId(i as u16));
                proptest::prop_assert_eq!(p.command_id(&name), scan, "{} in {}", name.escape_debug(), id);
            }
        }
    }

    /// A name of more than the index's bytes is still found (by the scan), and its short alias
    /// by the index. (Two parameters never answer to one name: the loader refuses that.)
    #[test]
    fn long_names_are_found_and_their_short_aliases_too() {
        let mut f = embedded("seed.toml").unwrap().to_string();
        f.push_str("\n[[params]]\nname = \"AVERYLONGPARAMETERNAME\"\nscope = \"motor\"\nsection = \"advanced\"\ndescription = \"d\"\nmin = 0\nmax = 1\ndefault = 0\ninput_aliases = [\"avlpn\"]\n");
        let p = Profile::load_with("seed.toml", &|n| {
            (n == "seed.toml").then(|| f.clone()).or_else(|| embedded(n).map(str::to_string))
        })
        .unwrap();
        let long = p.param_id("averylongparametername").expect("the long name");
        assert_eq!(p.param(long).name, "AVERYLONGPARAMETERNAME");
        assert_eq!(p.param_id("AVLPN"), Some(long));
        assert_eq!(p.param_id("averylongparametername2"), None);
    }
}
