//! What the hand had saved in its EEPROM before a campaign, and putting it back after it
//! (issue 37 item 2).
//!
//! A case that saves parameters ends by saving the factory values back (its own restore:
//! defaults, then save, for the motors and the globals). On a hand whose saved values were not
//! the factory ones, that is a change the team did not ask for. So on a hand outside this
//! process, before the first case of a campaign that may write the EEPROM, the saved values are
//! read: the load commands (FLOAD, PLOAD) bring them into RAM and the get commands read them,
//! which changes nothing saved. After a campaign that wrote, they are set and saved again
//! and read back the same way, and the report says what it found.
//!
//! Read: the parameters the profile's load commands cover (`persist`), writable, stored (not
//! live, not an alias, not kept by the hand itself). Not written back: the line-rate parameter
//! (`[hand] baud`) when its saved value is not the rate the campaign talks at: setting it moves
//! the line at once (see [`gcl_conformance::actions::Allowed::keep_rate`]); that is said.

use std::sync::Arc;
use std::time::Duration;

use gcl_host::client::{ClientError, Hand, Timeouts};
use gcl_host::link::Link;
use gcl_model::Profile;
use gcl_model::spec::{CommandKind, ParamSpec, Scope};

/// The saved values, as read before the campaign.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Saved {
    /// Per motor parameter, the value of each motor (motor order).
    pub motors: Vec<(String, Vec<i64>)>,
    /// The global parameters.
    pub globals: Vec<(String, i64)>,
}

/// The motors a saved per-motor value is read and written for, one at a time.
const MOTORS: [&str; 4] = ["1", "2", "3", "4"];

/// How long each command of the reading and the restore may take.
const REPLY: Duration = Duration::from_secs(5);

/// The parameters of `scope` that `load` (a load command's name) brings back from the EEPROM.
fn stored<'p>(p: &'p Profile, scope: Scope, load: &'p str) -> impl Iterator<Item = &'p ParamSpec> + 'p {
    p.params.iter().filter(move |s| {
        s.scope == scope
            && s.persist.iter().any(|c| c == load)
            && !s.read_only
            && !s.live
            && !s.self_stored
            && s.alias_of.is_none()
    })
}

fn name_of(p: &Profile, kind: CommandKind) -> Option<String> {
    p.command_of_kind(kind).map(|id| p.command(id).name.clone())
}

fn client(link: Box<dyn Link>, p: &Arc<Profile>) -> Hand {
    let mut c = Hand::new(link, p.clone());
    let t = c.timeouts();
    c.set_timeouts(Timeouts { reply: REPLY, ..t });
    c
}

/// Reads the saved values over `link` (see the module doc); gives the link back.
pub fn read(link: Box<dyn Link>, p: &Arc<Profile>) -> (Box<dyn Link>, Result<Saved, String>) {
    let mut c = client(link, p);
    let saved = read_trusted(&mut c, p).map_err(|e| e.to_string()).and_then(|r| r);
    (c.into_link(), saved)
}

/// Reads the values the load commands bring back (see the module doc). First the same reading
/// after the default commands, held to the profile's defaults: a hand that reads them otherwise
/// (another order, another scale) would have its saved values written back wrong, so nothing
/// is trusted to be written back.
fn read_trusted(c: &mut Hand, p: &Profile) -> Result<Result<Saved, String>, ClientError> {
    c.resync()?;
    let defaults = read_with(c, p, CommandKind::MotorDefaults, CommandKind::GlobalDefaults)?;
    let mut wrong = Vec::new();
    for (n, v) in &defaults.motors {
        let Some(s) = p.param_id(n).map(|id| p.param(id)) else { continue };
        let want: Vec<Option<i64>> =
            (0..4).map(|i| if i == 3 { s.default_spread.or(s.default) } else { s.default }).collect();
        if v.iter().zip(&want).any(|(v, w)| w.is_some_and(|w| w != *v)) {
            wrong.push(format!("{n} {}", join(v)));
        }
    }
    for (n, v) in &defaults.globals {
        if p.param_id(n).and_then(|id| p.param(id).default).is_some_and(|d| d != *v) {
            wrong.push(format!("{n} {v}"));
        }
    }
    if !wrong.is_empty() {
        return Ok(Err(format!(
            "after the default commands the hand reads values other than the profile's defaults ({}), so its \
             readings are not trusted to be saved back",
            wrong.join(", ")
        )));
    }
    Ok(Ok(read_with(c, p, CommandKind::MotorLoad, CommandKind::GlobalLoad)?))
}

/// The stored parameters' values after the commands of `motor` and `global` kinds (the load
/// or the default commands).
fn read_with(c: &mut Hand, p: &Profile, motor: CommandKind, global: CommandKind) -> Result<Saved, ClientError> {
    let mut saved = Saved { motors: Vec::new(), globals: Vec::new() };
    let (Some(mload), Some(gload)) = (name_of(p, CommandKind::MotorLoad), name_of(p, CommandKind::GlobalLoad)) else {
        return Ok(saved);
    };
    if let Some(cmd) = name_of(p, motor) {
        let load = mload;
        c.command(&cmd)?;
        let names: Vec<&str> = stored(p, Scope::Motor, &load).map(|s| s.name.as_str()).collect();
        // (as many names to a line as fit the hand's longest line)
        let mut chunks: Vec<Vec<&str>> = vec![Vec::new()];
        let mut len = "1FGET".len();
        for n in &names {
            if len + 1 + n.len() > p.framing.max_line && chunks.last().is_some_and(|c| !c.is_empty()) {
                chunks.push(Vec::new());
                len = "1FGET".len();
            }
            len += 1 + n.len();
            chunks.last_mut().into_iter().for_each(|c| c.push(n));
        }
        let mut values: Vec<Vec<i64>> = Vec::new();
        for chunk in &chunks {
            let mut per_name: Vec<Vec<i64>> = vec![Vec::new(); chunk.len()];
            for m in MOTORS {
                for (i, v) in c.get_many(m, chunk)?.into_iter().enumerate() {
                    // (one value: the motor asked)
                    per_name[i].push(v.first().copied().unwrap_or_default());
                }
            }
            values.extend(per_name);
        }
        saved.motors = names.iter().map(|n| n.to_string()).zip(values).collect();
    }
    if let Some(cmd) = name_of(p, global) {
        let load = gload;
        c.command(&cmd)?;
        for s in stored(p, Scope::Global, &load) {
            saved.globals.push((s.name.clone(), c.pget(&s.name)?));
        }
    }
    Ok(saved)
}

/// The line-rate parameter's name and the value that keeps the line at `rate` bit/s, if the
/// profile names one (`None` for the value: no value keeps it).
fn rate_param(p: &Profile, rate: Option<u32>) -> Option<(String, Option<i64>)> {
    let gcl_model::spec::ValueSource::Param(id) = p.hand_sources().baud else { return None };
    let keep = rate.map(i64::from).filter(|r| r % 100 == 0).map(|r| r / 100);
    Some((p.param(id).name.clone(), keep))
}

/// Sets and saves `saved` again over `link`, then reads it back; `rate`: the line's rate on a
/// serial line. Says what was left as found, for the report's EEPROM line.
pub fn restore(link: Box<dyn Link>, p: &Arc<Profile>, saved: &Saved, rate: Option<u32>) -> (Box<dyn Link>, String) {
    let mut c = client(link, p);
    let said = match restore_with(&mut c, p, saved, rate) {
        Ok(s) => s,
        Err(e) => format!("the values saved before the campaign could not be saved back: {e}"),
    };
    (c.into_link(), said)
}

fn restore_with(c: &mut Hand, p: &Profile, saved: &Saved, rate: Option<u32>) -> Result<String, ClientError> {
    c.resync()?;
    let guarded = rate_param(p, rate).filter(|_| rate.is_some());
    let mut kept_out = Vec::new();
    if let Some(save) = name_of(p, CommandKind::MotorSave) {
        for (i, m) in MOTORS.iter().enumerate() {
            let pairs: Vec<(&str, i64)> =
                saved.motors.iter().filter_map(|(n, v)| v.get(i).map(|v| (n.as_str(), *v))).collect();
            c.set_many(m, &pairs)?;
        }
        c.command(&save)?;
    }
    if let Some(save) = name_of(p, CommandKind::GlobalSave) {
        for (n, v) in &saved.globals {
            if let Some((g, keep)) = &guarded
                && g == n
                && Some(*v) != *keep
            {
                kept_out.push(format!("{n} {v}"));
                continue;
            }
            c.pset(n, *v)?;
        }
        c.command(&save)?;
    }
    let again = read_with(c, p, CommandKind::MotorLoad, CommandKind::GlobalLoad)?;
    let mut differ = Vec::new();
    for ((n, was), (_, now)) in saved.motors.iter().zip(&again.motors) {
        if was != now {
            differ.push(format!("{n} {} (was {})", join(now), join(was)));
        }
    }
    for ((n, was), (_, now)) in saved.globals.iter().zip(&again.globals) {
        if was != now && !kept_out.iter().any(|k| k.split(' ').next() == Some(n.as_str())) {
            differ.push(format!("{n} {now} (was {was})"));
        }
    }
    let count = saved.motors.len() + saved.globals.len();
    let mut said = if differ.is_empty() {
        format!(
            "the {count} values saved before the campaign (read at its start) were saved back and read back as found"
        )
    } else {
        format!(
            "the {count} values saved before the campaign (read at its start) were saved back, but read back otherwise: {}",
            differ.join(", ")
        )
    };
    if !kept_out.is_empty() {
        said.push_str(&format!(
            "; not saved back, since setting it moves the line off the rate the campaign talks at: {}",
            kept_out.join(", ")
        ));
    }
    Ok(said)
}

fn join(v: &[i64]) -> String {
    v.iter().map(|x| x.to_string()).collect::<Vec<_>>().join(" ")
}
