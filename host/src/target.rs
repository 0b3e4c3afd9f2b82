//! Targets: the one syntax every `gcl` command uses to name a hand, and opening a [`Link`]
//! to it.
//!
//! - `sim[:PROFILE]`: the reference model in-process, no I/O;
//! - `serial:PATH[?baud=N]`: a real port or a pty path;
//! - `tcp://HOST:PORT`;
//! - `exec:COMMAND ARGS`: a subprocess speaking GCL on stdin/stdout.

use std::fmt;
use std::str::FromStr;
use std::sync::Arc;
use std::time::Duration;

use gcl_model::params::NvMemory;
use gcl_model::{DeviceConfig, Fault, Profile, Scenario};

use crate::link::{Link, LinkError, SimLink};
use crate::links::{ExecLink, RateFollowingLink, SerialLink, StderrMode, TcpLink};

/// A parsed `--target`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Target {
    /// The in-process reference model with this profile (default `bh8-262`; see [`Target::sim_profile`]).
    Sim {
        /// The profile name, if given.
        profile: Option<String>,
    },
    /// A serial port or pty.
    Serial {
        /// The device path.
        path: String,
        /// The line rate, bit/s.
        baud: u32,
    },
    /// A TCP server.
    Tcp {
        /// `HOST:PORT`.
        addr: String,
    },
    /// A subprocess.
    Exec {
        /// The program and its arguments, split on whitespace.
        argv: Vec<String>,
    },
}

/// A `--target` that does not parse.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "bad target `{text}`: {reason} (expected sim[:PROFILE], serial:PATH[?baud=N], tcp://HOST:PORT or exec:COMMAND ARGS)"
)]
pub struct BadTarget {
    /// What was given.
    pub text: String,
    /// What is wrong with it.
    pub reason: String,
}

/// The line rates `gcl` accepts, bit/s: from the slowest POSIX rate (50) to 4 Mbit/s. Zero
/// or an absurd rate is refused when the command line is parsed, so no figure derived from
/// it (the wire-time bound) can be infinite or meaningless.
pub const BAUD_RANGE: std::ops::RangeInclusive<u32> = 50..=4_000_000;

/// Parses a line rate within [`BAUD_RANGE`] (also a clap value parser for `--baud`).
pub fn parse_baud(s: &str) -> Result<u32, String> {
    let baud: u32 = s.trim().parse().map_err(|_| format!("baud must be a whole number, not `{s}`"))?;
    if !BAUD_RANGE.contains(&baud) {
        return Err(format!("baud {baud} is outside {}..={} bit/s", BAUD_RANGE.start(), BAUD_RANGE.end()));
    }
    Ok(baud)
}

impl FromStr for Target {
    type Err = BadTarget;

    fn from_str(s: &str) -> Result<Target, BadTarget> {
        let bad = |reason: &str| BadTarget { text: s.to_string(), reason: reason.to_string() };
        if s == "sim" {
            return Ok(Target::Sim { profile: None });
        }
        if let Some(p) = s.strip_prefix("sim:") {
            if p.is_empty() {
                return Err(bad("empty profile"));
            }
            return Ok(Target::Sim { profile: Some(p.to_string()) });
        }
        if let Some(rest) = s.strip_prefix("serial:") {
            let (path, query) = match rest.split_once('?') {
                Some((p, q)) => (p, Some(q)),
                None => (rest, None),
            };
            if path.is_empty() {
                return Err(bad("empty port path"));
            }
            let mut baud = 9600;
            if let Some(q) = query {
                for kv in q.split('&') {
                    match kv.split_once('=') {
                        Some(("baud", v)) => baud = parse_baud(v).map_err(|e| bad(&e))?,
                        _ => return Err(bad(&format!("unknown option `{kv}`"))),
                    }
                }
            }
            return Ok(Target::Serial { path: path.to_string(), baud });
        }
        if let Some(addr) = s.strip_prefix("tcp://") {
            if !addr.contains(':') {
                return Err(bad("missing :PORT"));
            }
            return Ok(Target::Tcp { addr: addr.to_string() });
        }
        if let Some(cmd) = s.strip_prefix("exec:") {
            let argv: Vec<String> = cmd.split_whitespace().map(str::to_string).collect();
            if argv.is_empty() {
                return Err(bad("empty command"));
            }
            return Ok(Target::Exec { argv });
        }
        Err(bad("unknown scheme"))
    }
}

impl fmt::Display for Target {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Target::Sim { profile: None } => write!(f, "sim"),
            Target::Sim { profile: Some(p) } => write!(f, "sim:{p}"),
            Target::Serial { path, baud } => write!(f, "serial:{path}?baud={baud}"),
            Target::Tcp { addr } => write!(f, "tcp://{addr}"),
            Target::Exec { argv } => write!(f, "exec:{}", argv.join(" ")),
        }
    }
}

/// The profile `sim` opens when neither the target nor [`OpenOptions::profile`] names one.
pub const DEFAULT_SIM_PROFILE: &str = "bh8-262";

/// How to open a target, beyond what its text says.
#[derive(Debug, Clone)]
pub struct OpenOptions {
    /// The profile for `sim` when the target does not name one (`sim:PROFILE` wins).
    pub profile: Option<String>,
    /// `sim`: a profile already loaded (from a file given as `--profile FILE.toml`), used
    /// when the target names none; it wins over [`OpenOptions::profile`].
    pub loaded_profile: Option<Arc<Profile>>,
    /// `sim`: seed of the model's noise.
    pub seed: u64,
    /// `sim`: deliberate firmware bugs.
    pub faults: Vec<Fault>,
    /// `sim`: the world around the hand.
    pub scenario: Option<Scenario>,
    /// `sim`: the EEPROM at power-up.
    pub nv: Option<NvMemory>,
    /// `tcp`: how long to try to connect.
    pub connect_timeout: Duration,
    /// `exec`: what happens to the child's stderr.
    pub stderr: StderrMode,
    /// `serial`: the port follows the hand's line rate when a line the host sends changes it,
    /// and sets the hand back to the port's first rate before it closes
    /// ([`crate::links::RateFollowingLink`]; the profile is [`OpenOptions::loaded_profile`],
    /// else [`OpenOptions::profile`], else [`DEFAULT_SIM_PROFILE`]).
    pub follow_rate: bool,
}

impl Default for OpenOptions {
    fn default() -> OpenOptions {
        OpenOptions {
            profile: None,
            loaded_profile: None,
            seed: 0,
            faults: Vec::new(),
            scenario: None,
            nv: None,
            connect_timeout: Duration::from_secs(5),
            stderr: StderrMode::Inherit,
            follow_rate: false,
        }
    }
}

impl Target {
    /// The profile a `sim` target runs: its own, else `fallback`, else [`DEFAULT_SIM_PROFILE`].
    /// `None` for targets outside this process.
    pub fn sim_profile<'a>(&'a self, fallback: Option<&'a str>) -> Option<&'a str> {
        match self {
            Target::Sim { profile } => Some(profile.as_deref().or(fallback).unwrap_or(DEFAULT_SIM_PROFILE)),
            _ => None,
        }
    }

    /// The profile the model speaks with this target: `chosen` (a `--profile`), else a `sim`
    /// target's own, else [`DEFAULT_SIM_PROFILE`].
    pub fn model_profile<'a>(&'a self, chosen: Option<&'a str>) -> &'a str {
        chosen.or(self.sim_profile(None)).unwrap_or(DEFAULT_SIM_PROFILE)
    }
}

/// Opens a link to `target`.
pub fn open(target: &Target, opts: &OpenOptions) -> Result<Box<dyn Link>, LinkError> {
    match target {
        Target::Sim { profile: own } => {
            let profile = match (own, &opts.loaded_profile) {
                (None, Some(p)) => p.clone(),
                _ => {
                    let name = target.sim_profile(opts.profile.as_deref()).unwrap_or(DEFAULT_SIM_PROFILE);
                    crate::profiles::load(name)
                        .map_err(|e| LinkError::Open { target: target.to_string(), reason: e.to_string() })?
                }
            };
            let config = DeviceConfig {
                seed: opts.seed,
                scenario: opts.scenario.clone().unwrap_or_default(),
                nv: opts.nv.clone().unwrap_or_default(),
                faults: opts.faults.clone(),
                ..DeviceConfig::default()
            };
            Ok(Box::new(SimLink::new(profile, config)))
        }
        Target::Serial { path, baud } if opts.follow_rate => {
            let profile = match &opts.loaded_profile {
                Some(p) => p.clone(),
                None => crate::profiles::load(opts.profile.as_deref().unwrap_or(DEFAULT_SIM_PROFILE))
                    .map_err(|e| LinkError::Open { target: target.to_string(), reason: e.to_string() })?,
            };
            Ok(Box::new(RateFollowingLink::open(path, *baud, profile)?))
        }
        Target::Serial { path, baud } => Ok(Box::new(SerialLink::open(path, *baud)?)),
        Target::Tcp { addr } => Ok(Box::new(TcpLink::connect(addr, opts.connect_timeout)?)),
        Target::Exec { argv } => Ok(Box::new(ExecLink::spawn(argv, opts.stderr)?)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_scheme() {
        assert_eq!("sim".parse(), Ok(Target::Sim { profile: None }));
        assert_eq!("sim:seed".parse(), Ok(Target::Sim { profile: Some("seed".into()) }));
        assert_eq!(
            "serial:/dev/ttyUSB0?baud=38400".parse(),
            Ok(Target::Serial { path: "/dev/ttyUSB0".into(), baud: 38400 })
        );
        assert_eq!("tcp://127.0.0.1:5000".parse(), Ok(Target::Tcp { addr: "127.0.0.1:5000".into() }));
        assert_eq!(
            "exec:gcl sim --stdio".parse(),
            Ok(Target::Exec { argv: vec!["gcl".into(), "sim".into(), "--stdio".into()] })
        );
        assert!("bogus:x".parse::<Target>().is_err());
        assert!("serial:/dev/x?baud=fast".parse::<Target>().is_err());
        for absurd in ["0", "49", "4000001", "99999999999"] {
            let e = format!("serial:/dev/x?baud={absurd}").parse::<Target>().unwrap_err();
            assert!(e.to_string().contains("baud"), "{e}");
            assert!(parse_baud(absurd).is_err(), "{absurd}");
        }
        assert_eq!(parse_baud("9600"), Ok(9600));
        for t in ["sim", "sim:seed", "serial:/dev/x?baud=9600", "tcp://h:1", "exec:a b"] {
            assert_eq!(t.parse::<Target>().unwrap().to_string(), t);
        }
        // The model's profile: a chosen one, else the sim's own, else the default.
        let (sim, seed, tcp) = (
            Target::Sim { profile: None },
            "sim:seed".parse::<Target>().unwrap(),
            "tcp://h:1".parse::<Target>().unwrap(),
        );
        assert_eq!(seed.model_profile(Some("bh8-262-4.3")), "bh8-262-4.3");
        assert_eq!(seed.model_profile(None), "seed");
        assert_eq!(sim.model_profile(None), DEFAULT_SIM_PROFILE);
        assert_eq!(tcp.model_profile(None), DEFAULT_SIM_PROFILE);
    }

    #[test]
    fn opens_sim_and_reports_bad_targets() {
        let mut l = open(&"sim:seed".parse().unwrap(), &OpenOptions::default()).unwrap();
        assert_eq!(l.describe(), "sim:seed");
        let mut buf = Vec::new();
        l.recv(&mut buf, Duration::from_millis(10)).unwrap();
        assert!(String::from_utf8_lossy(&buf).contains("BarrettHand Firmware"));
        let l = open(&"sim".parse().unwrap(), &OpenOptions::default()).unwrap();
        assert!(l.describe().starts_with("sim:bh8-262"));
        let opts = OpenOptions { profile: Some("seed".into()), ..Default::default() };
        assert_eq!(open(&"sim".parse().unwrap(), &opts).unwrap().describe(), "sim:seed");
        for bad in ["sim:nonesuch", "serial:/nonexistent/tty", "exec:/nonexistent/program"] {
            assert!(matches!(open(&bad.parse().unwrap(), &opts), Err(LinkError::Open { .. })), "{bad}");
        }
    }
}
