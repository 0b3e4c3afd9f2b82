//! Targets: the one syntax every `gcl` command uses to name a hand, and opening a [`Link`]
//! to it.
//!
//! - `sim[:PROFILE]`: the reference model in-process, no I/O;
//! - `serial:PATH[?baud=N]`: a real port or a pty path;
//! - `tcp://HOST:PORT`;
//! - `exec:COMMAND ARGS`: a subprocess speaking GCL on stdin/stdout.

use std::fmt;
use std::str::FromStr;

/// A parsed `--target`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Target {
    /// The in-process reference model with this profile (default `bh8-262`... see [`Target::profile`]).
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
                        Some(("baud", v)) => baud = v.parse().map_err(|_| bad("baud must be a whole number"))?,
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
        for t in ["sim", "sim:seed", "serial:/dev/x?baud=9600", "tcp://h:1", "exec:a b"] {
            assert_eq!(t.parse::<Target>().unwrap().to_string(), t);
        }
    }
}
