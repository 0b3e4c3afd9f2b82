//! The EEPROM file: the hand's `NvMemory` as JSON, loaded at start and rewritten atomically
//! (temporary file in the same directory, fsync, rename) whenever a command changed it.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use gcl_model::params::NvMemory;

use super::SimError;

/// Wear counters (odometer, powered time, peak temperature) change all the time; on their
/// own they are written at most this often, and at exit.
const COUNTER_PERIOD: Duration = Duration::from_secs(5);

/// A persisted EEPROM.
#[derive(Debug)]
pub struct EepromFile {
    path: PathBuf,
    saved: NvMemory,
    saved_at: Instant,
}

fn err(path: &Path, reason: impl std::fmt::Display) -> SimError {
    SimError::Eeprom { path: path.to_path_buf(), reason: reason.to_string() }
}

/// Whether two memories differ in what a host put there (saved parameters, serial number,
/// write count), as opposed to the counters the hand keeps by itself.
fn contents_differ(a: &NvMemory, b: &NvMemory) -> bool {
    a.motor != b.motor || a.global != b.global || a.serial_number != b.serial_number || a.writes != b.writes
}

impl EepromFile {
    /// Opens `path`: removes temporary files a killed simulator left beside it, loads it if it
    /// exists, and proves it writable by writing it back (an absent file is created holding an
    /// empty memory).
    pub fn open(path: &Path) -> Result<(EepromFile, NvMemory), SimError> {
        remove_stale_temporaries(path);
        let nv = match gcl_host::files::read_input(path) {
            Ok(bytes) => serde_json::from_slice::<NvMemory>(&bytes)
                .map_err(|e| err(path, format!("not an EEPROM image (JSON of NvMemory): {e}")))?,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => NvMemory::default(),
            Err(e) => return Err(err(path, e)),
        };
        let mut file = EepromFile { path: path.to_path_buf(), saved: nv.clone(), saved_at: Instant::now() };
        file.write(&nv)?;
        Ok((file, nv))
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Writes `nv` if a command changed its contents, or if only counters changed and the
    /// last write is a while ago. Returns whether it wrote.
    pub fn update(&mut self, nv: &NvMemory) -> Result<bool, SimError> {
        if contents_differ(nv, &self.saved) || (*nv != self.saved && self.saved_at.elapsed() >= COUNTER_PERIOD) {
            self.write(nv)?;
            return Ok(true);
        }
        Ok(false)
    }

    /// Writes `nv` if it differs at all from what the file holds (at exit).
    pub fn flush(&mut self, nv: &NvMemory) -> Result<(), SimError> {
        if *nv != self.saved {
            self.write(nv)?;
        }
        Ok(())
    }

    fn write(&mut self, nv: &NvMemory) -> Result<(), SimError> {
        let dir = dir_of(&self.path);
        let name = self.path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let tmp = dir.join(format!(".{name}.tmp{}", std::process::id()));
        let result = (|| -> std::io::Result<()> {
            let mut f = std::fs::File::create(&tmp)?;
            let mut text = serde_json::to_vec_pretty(nv).map_err(std::io::Error::other)?;
            text.push(b'\n');
            f.write_all(&text)?;
            f.sync_all()?;
            std::fs::rename(&tmp, &self.path)?;
            // The rename itself is durable once the directory is synced.
            if let Ok(d) = std::fs::File::open(&dir) {
                let _ = d.sync_all();
            }
            Ok(())
        })();
        if let Err(e) = result {
            let _ = std::fs::remove_file(&tmp);
            return Err(err(&self.path, format!("cannot write: {e}")));
        }
        self.saved = nv.clone();
        self.saved_at = Instant::now();
        Ok(())
    }
}

/// The directory `path` lives in (`.` for a bare name).
fn dir_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Removes `.NAME.tmpPID` files beside `path` whose process is gone (a kill during a write
/// leaves one); a live process's temporary file is left alone.
fn remove_stale_temporaries(path: &Path) {
    let Some(name) = path.file_name().map(|n| n.to_string_lossy().into_owned()) else { return };
    let prefix = format!(".{name}.tmp");
    let Ok(entries) = std::fs::read_dir(dir_of(path)) else { return };
    for e in entries.flatten() {
        let file = e.file_name();
        let Some(pid) = file.to_str().and_then(|f| f.strip_prefix(&prefix)) else { continue };
        let Ok(pid) = pid.parse::<u32>() else { continue };
        if pid != std::process::id() && !Path::new(&format!("/proc/{pid}")).exists() {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_and_rejects_garbage() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("hand.json");
        let (mut f, nv) = EepromFile::open(&path).unwrap();
        assert_eq!(nv, NvMemory::default());
        let mut changed = nv.clone();
        changed.motor.insert("DP".into(), [1234, 1000, 1000, 150]);
        assert!(f.update(&changed).unwrap());
        assert!(!f.update(&changed).unwrap());
        let (_, again) = EepromFile::open(&path).unwrap();
        assert_eq!(again, changed);
        std::fs::write(&path, b"{ not json").unwrap();
        assert!(matches!(EepromFile::open(&path), Err(SimError::Eeprom { .. })));
        let missing_dir = dir.path().join("no/such/dir/hand.json");
        assert!(EepromFile::open(&missing_dir).is_err());
    }

    #[test]
    fn temporaries_of_dead_processes_are_removed_at_start() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("hand.json");
        // PID 0x7FFFFFFE is above any pid_max: no such process.
        let stale = dir.path().join(".hand.json.tmp2147483646");
        let other = dir.path().join(".other.json.tmp2147483646");
        for f in [&stale, &other] {
            std::fs::write(f, b"{").unwrap();
        }
        EepromFile::open(&path).unwrap();
        assert!(!stale.exists(), "a dead writer's temporary file is removed");
        assert!(other.exists(), "another file's temporaries are not touched");
    }
}
