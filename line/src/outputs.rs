//! Writing output files without trusting what is already there: every file `gcl` writes
//! (reports, `results.jsonl`, certificates, findings, corpus entries, goldens and vectors,
//! recordings) goes through [`write_atomic`] or [`create_stream`], and every folder a
//! long-running command fills (`--out`, `--report`) is held with [`OutLock`].
//!
//! - A file is always a new file: a temporary beside the target, created with `O_EXCL |
//!   O_NOFOLLOW` (so a planted symbolic link or an old temporary is never written through),
//!   then renamed over the target. A symbolic link at the target's name is replaced, never
//!   followed: its target is left untouched.
//! - A write that fails (a full disk) removes its temporary and names the file it was writing.
//! - Nothing here deletes a file it did not create.
//!
//! Must never: write through a symbolic link, truncate an existing file in place, or leave a
//! temporary behind on an error.
//!
//! `create_stream` opens `results.jsonl` the same way; `write_unique` never replaces another
//! file (a second finding of the same name is `NAME-2.gcl`); `OutLock` holds `DIR/.gcl.lock`
//! with `flock` for the command filling the folder, so a second one is refused, and `held_by`
//! looks without taking it.

use std::fs::File;
use std::io::{self, Write};
use std::os::unix::fs::OpenOptionsExt;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// The folder `path` lives in (`.` for a bare name).
fn dir_of(path: &Path) -> &Path {
    path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."))
}

/// An I/O error that names the file it concerns (what a person needs on a full disk).
fn named(path: &Path, e: io::Error) -> io::Error {
    io::Error::new(e.kind(), format!("{}: {e}", path.display()))
}

/// Creates a fresh temporary beside `path`: `.NAME.tmpPID.N`, `O_EXCL | O_NOFOLLOW`, mode 0644.
fn create_temporary(path: &Path) -> io::Result<(PathBuf, File)> {
    static NEXT: AtomicU64 = AtomicU64::new(0);
    let dir = dir_of(path);
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("out");
    loop {
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        let tmp = dir.join(format!(".{name}.tmp{}.{n}", std::process::id()));
        match std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .mode(0o644)
            .custom_flags(nix::libc::O_NOFOLLOW)
            .open(&tmp)
        {
            Ok(f) => return Ok((tmp, f)),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(named(&tmp, e)),
        }
    }
}

/// Writes `bytes` to `path` atomically: a new temporary file in the same folder, synced, then
/// renamed over the target. A kill leaves the old file or the new one, never a torn one; a
/// symbolic link at `path` is replaced, never written through; an error (a full disk)
/// removes the temporary and names `path`.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let dir = dir_of(path);
    std::fs::create_dir_all(dir).map_err(|e| named(dir, e))?;
    let (tmp, mut f) = create_temporary(path)?;
    let result = f.write_all(bytes).and_then(|()| f.sync_all()).and_then(|()| std::fs::rename(&tmp, path));
    drop(f);
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(named(path, e));
    }
    Ok(())
}

/// Creates `path` afresh for streaming into it (`results.jsonl`): a new file renamed into
/// place at once, so an existing file or a symbolic link at `path` is replaced, never
/// truncated or followed.
pub fn create_stream(path: &Path) -> io::Result<File> {
    let dir = dir_of(path);
    std::fs::create_dir_all(dir).map_err(|e| named(dir, e))?;
    let (tmp, f) = create_temporary(path)?;
    if let Err(e) = std::fs::rename(&tmp, path) {
        let _ = std::fs::remove_file(&tmp);
        return Err(named(path, e));
    }
    Ok(f)
}

/// Writes `bytes` as a new file `DIR/STEM.EXT`, never replacing another file: when that name
/// holds different bytes (another finding, from an earlier campaign or another worker), the
/// next free `STEM-2.EXT`, `STEM-3.EXT`, ... is taken; when it holds the same bytes, that file
/// is the answer. The file appears whole (a temporary, hard-linked into place).
pub fn write_unique(dir: &Path, stem: &str, ext: &str, bytes: &[u8]) -> io::Result<PathBuf> {
    std::fs::create_dir_all(dir).map_err(|e| named(dir, e))?;
    for n in 1..=10_000u32 {
        let name = if n == 1 { format!("{stem}.{ext}") } else { format!("{stem}-{n}.{ext}") };
        let path = dir.join(name);
        if let Ok(old) = gcl_host::files::read_limited(&path, bytes.len() as u64) {
            if old == bytes {
                return Ok(path);
            }
            continue;
        }
        let (tmp, mut f) = create_temporary(&path)?;
        let written = f.write_all(bytes).and_then(|()| f.sync_all());
        drop(f);
        // A hard link fails on an existing name: nothing is ever replaced.
        let placed = written.and_then(|()| std::fs::hard_link(&tmp, &path));
        let _ = std::fs::remove_file(&tmp);
        match placed {
            Ok(()) => return Ok(path),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(named(&path, e)),
        }
    }
    Err(io::Error::new(io::ErrorKind::AlreadyExists, format!("{}: no free name for {stem}.{ext}", dir.display())))
}

/// The name of the lock file in a held output folder.
pub const LOCK_FILE: &str = ".gcl.lock";

/// A folder held by one running command: `DIR/.gcl.lock`, locked with `flock` for as long
/// as the value lives (the kernel drops the lock when the process ends, kill -9 included).
/// A second campaign or report on the same folder is refused instead of overwriting the
/// first one's files. When the value is dropped the lock file is removed (only if it is still
/// this lock's file), and so is the folder if `acquire` made it and it is left empty, and each
/// parent `acquire` made for it that is left empty too: a run that wrote nothing leaves
/// nothing behind.
#[derive(Debug)]
pub struct OutLock {
    lock: nix::fcntl::Flock<File>,
    path: PathBuf,
    /// The folders `acquire` made, `dir` first and then its parents it made.
    made_dirs: Vec<PathBuf>,
}

/// Device and inode of an open file or a path: the identity of a lock file.
fn identity(m: &std::fs::Metadata) -> (u64, u64) {
    use std::os::unix::fs::MetadataExt;
    (m.dev(), m.ino())
}

impl OutLock {
    /// Takes `dir` (creating it) for `what` (`fuzz device`, `conform --report`, ...), or says
    /// which process holds it.
    pub fn acquire(dir: &Path, what: &str) -> io::Result<OutLock> {
        let made_dirs: Vec<PathBuf> = dir
            .ancestors()
            .filter(|d| !d.as_os_str().is_empty())
            .take_while(|d| std::fs::symlink_metadata(d).is_err())
            .map(Path::to_path_buf)
            .collect();
        std::fs::create_dir_all(dir).map_err(|e| named(dir, e))?;
        let path = dir.join(LOCK_FILE);
        loop {
            let file = std::fs::OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false)
                .mode(0o644)
                // Never a link followed, never a wait on a FIFO or a device planted there.
                .custom_flags(nix::libc::O_NOFOLLOW | nix::libc::O_NONBLOCK | nix::libc::O_NOCTTY)
                .open(&path)
                .map_err(|e| named(&path, e))?;
            let ty = file.metadata().map_err(|e| named(&path, e))?.file_type();
            if !ty.is_file() {
                return Err(io::Error::new(
                    io::ErrorKind::InvalidInput,
                    format!(
                        "{}: {}, not a lock file; gcl makes its lock files regular files (remove it, or choose another folder)",
                        path.display(),
                        gcl_host::files::kind_of(&ty)
                    ),
                ));
            }
            let held = file.try_clone().map_err(|e| named(&path, e))?;
            let Ok(lock) = nix::fcntl::Flock::lock(held, nix::fcntl::FlockArg::LockExclusiveNonblock) else {
                let holder = holder_line(&path);
                return Err(io::Error::new(
                    io::ErrorKind::ResourceBusy,
                    format!("{} is in use by {holder}; wait for it to end or choose another folder", dir.display()),
                ));
            };
            // The holder before us may have removed the file between our open and our lock:
            // then the lock is on a file nobody else will find, and we start again.
            let ours = file.metadata().map(|m| identity(&m)).ok();
            if std::fs::symlink_metadata(&path).map(|m| identity(&m)).ok() != ours {
                continue;
            }
            // The whole line in one write at the start, then the rest of an older holder's line
            // cut: a reader never sees a part of it (see `holder_line`).
            let line = format!("gcl {what} (pid {})\n", std::process::id());
            std::os::unix::fs::FileExt::write_all_at(&file, line.as_bytes(), 0)?;
            file.set_len(line.len() as u64)?;
            return Ok(OutLock { lock, path, made_dirs });
        }
    }
}

/// Whether a running command holds `dir` (an [`OutLock`] on it), and which, without taking or
/// creating anything: for a folder another command is still writing (a campaign's `--out`)
/// that this one is about to replace or read.
pub fn held_by(dir: &Path) -> Option<String> {
    let path = dir.join(LOCK_FILE);
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(nix::libc::O_NOFOLLOW | nix::libc::O_NONBLOCK | nix::libc::O_NOCTTY)
        .open(&path)
        .ok()?;
    // Anything but a regular file is no lock of ours: nobody holds the folder with it.
    if !file.metadata().is_ok_and(|m| m.is_file()) {
        return None;
    }
    match nix::fcntl::Flock::lock(file, nix::fcntl::FlockArg::LockSharedNonblock) {
        // Free: a lock file a finished (or killed) command left.
        Ok(_free) => None,
        Err(_) => Some(holder_line(&path)),
    }
}

/// The line the holder of the lock file at `path` wrote of itself (`gcl fuzz merge --out (pid
/// N)`). A holder that has just taken the lock may not have written it yet: a line without its
/// end is read again, for up to 100 ms, before it is "another gcl". Read as a file from
/// anywhere is: no link followed, no wait on a FIFO, a few KiB at most.
fn holder_line(path: &Path) -> String {
    for _ in 0..50 {
        let text = match gcl_host::files::read_limited_no_follow(path, 4096) {
            Ok(bytes) => String::from_utf8_lossy(&bytes).into_owned(),
            Err(e) if e.kind() == io::ErrorKind::NotFound => String::new(),
            Err(e) => return format!("something that is not a gcl's lock ({}: {e})", path.display()),
        };
        if let Some((line, _)) = text.split_once('\n') {
            return line.chars().take(200).collect();
        }
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    "another gcl".to_string()
}

impl Drop for OutLock {
    fn drop(&mut self) {
        // Only our own lock file (another run may have made a new one since ours was removed).
        let ours = self.lock.metadata().map(|m| identity(&m)).ok();
        if ours.is_some() && std::fs::symlink_metadata(&self.path).map(|m| identity(&m)).ok() == ours {
            let _ = std::fs::remove_file(&self.path);
        }
        // Removes a folder only when empty: never a file somebody (or this run) wrote; and a
        // parent only once the folder in it is gone.
        for d in &self.made_dirs {
            if std::fs::remove_dir(d).is_err() {
                break;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::unix::fs::FileTypeExt;

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> =
            std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    }

    #[test]
    fn writes_replace_files_and_links_never_their_targets() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.json");
        write_atomic(&p, b"old").unwrap();
        write_atomic(&p, b"new").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"new");
        let victim = dir.path().join("victim");
        std::fs::write(&victim, b"precious").unwrap();
        let link = dir.path().join("b.json");
        std::os::unix::fs::symlink(&victim, &link).unwrap();
        write_atomic(&link, b"ours").unwrap();
        assert_eq!(std::fs::read(&victim).unwrap(), b"precious");
        assert_eq!(std::fs::read(&link).unwrap(), b"ours");
        let stream = dir.path().join("results.jsonl");
        std::os::unix::fs::symlink(&victim, &stream).unwrap();
        let mut f = create_stream(&stream).unwrap();
        f.write_all(b"line\n").unwrap();
        assert_eq!(std::fs::read(&victim).unwrap(), b"precious");
        assert_eq!(std::fs::read(&stream).unwrap(), b"line\n");
        assert_eq!(names(dir.path()), ["a.json", "b.json", "results.jsonl", "victim"]);
    }

    #[test]
    fn a_failed_write_leaves_no_temporary_and_names_the_file() {
        let dir = tempfile::tempdir().unwrap();
        // A folder where the file should be: the rename fails after the temporary is written.
        let p = dir.path().join("finding.json");
        std::fs::create_dir(&p).unwrap();
        std::fs::write(p.join("x"), b"x").unwrap();
        let e = write_atomic(&p, b"data").unwrap_err();
        assert!(e.to_string().contains("finding.json"), "{e}");
        assert_eq!(names(dir.path()), ["finding.json"]);
    }

    #[test]
    fn a_unique_write_never_replaces_another_file() {
        let dir = tempfile::tempdir().unwrap();
        let a = write_unique(dir.path(), "fuzz-pset-status", "gcl", b"bug A").unwrap();
        let b = write_unique(dir.path(), "fuzz-pset-status", "gcl", b"bug B").unwrap();
        let again = write_unique(dir.path(), "fuzz-pset-status", "gcl", b"bug A").unwrap();
        assert_eq!(a, dir.path().join("fuzz-pset-status.gcl"));
        assert_eq!(b, dir.path().join("fuzz-pset-status-2.gcl"));
        assert_eq!(again, a);
        assert_eq!(std::fs::read(&a).unwrap(), b"bug A");
        assert_eq!(std::fs::read(&b).unwrap(), b"bug B");
        assert_eq!(names(dir.path()), ["fuzz-pset-status-2.gcl", "fuzz-pset-status.gcl"]);
    }

    /// Issue 39 item 13: a FIFO planted as the lock file and held by another process hung
    /// `fuzz merge` (the holder's line was read from it, blocking for a writer for ever): it is
    /// refused at once as no lock file, and seen from outside as no lock.
    #[test]
    fn a_fifo_in_place_of_the_lock_file_is_refused_never_waited_on() {
        let dir = tempfile::tempdir().unwrap();
        let lock = dir.path().join(LOCK_FILE);
        nix::unistd::mkfifo(&lock, nix::sys::stat::Mode::from_bits_truncate(0o644)).unwrap();
        // Held by another open file (flock locks an open file, so this is another holder).
        let other =
            std::fs::OpenOptions::new().read(true).write(true).custom_flags(nix::libc::O_NONBLOCK).open(&lock).unwrap();
        let _held = nix::fcntl::Flock::lock(other, nix::fcntl::FlockArg::LockExclusiveNonblock).unwrap();
        let (tx, rx) = std::sync::mpsc::channel();
        let d = dir.path().to_path_buf();
        std::thread::spawn(move || {
            let _ = tx.send((OutLock::acquire(&d, "fuzz merge --out").map(|_| ()), held_by(&d)));
        });
        // A watchdog, not a timing claim: the old code never came back.
        let (acquired, seen) = rx.recv_timeout(std::time::Duration::from_secs(60)).expect("acquire hung on a FIFO");
        let e = acquired.unwrap_err();
        assert!(e.to_string().contains("a named pipe, not a lock file"), "{e}");
        assert_eq!(seen, None);
        assert!(std::fs::symlink_metadata(&lock).unwrap().file_type().is_fifo(), "left as it was");
    }

    #[test]
    fn a_held_folder_is_refused_until_its_holder_lets_go() {
        let dir = tempfile::tempdir().unwrap();
        let first = OutLock::acquire(dir.path(), "fuzz device").unwrap();
        let e = OutLock::acquire(dir.path(), "fuzz device").unwrap_err();
        assert!(e.to_string().contains("in use by gcl fuzz device (pid"), "{e}");
        drop(first);
        let second = OutLock::acquire(dir.path(), "conform --report").unwrap();
        drop(second);
        assert!(names(dir.path()).is_empty(), "the lock file is removed with the lock");
        // A folder the lock made is removed with it when nothing was written there.
        let made = dir.path().join("reports");
        drop(OutLock::acquire(&made, "conform --report").unwrap());
        assert!(!made.exists());
        // And the parents it made for it, up to the first that was there.
        drop(OutLock::acquire(&made.join("hand/now"), "conform --report").unwrap());
        assert!(!made.exists());
        // Seen from outside without taking it: held while held, free after.
        let looked = dir.path().join("looked");
        assert_eq!(held_by(&looked), None);
        let held = OutLock::acquire(&looked, "fuzz host --out").unwrap();
        assert!(held_by(&looked).is_some_and(|h| h.starts_with("gcl fuzz host --out (pid")), "{:?}", held_by(&looked));
        drop(held);
        assert_eq!(held_by(&looked), None);
        let kept = dir.path().join("kept");
        let held = OutLock::acquire(&kept, "conform --report").unwrap();
        std::fs::write(kept.join("report.json"), b"{}").unwrap();
        drop(held);
        assert_eq!(names(&kept), ["report.json"]);
    }
}
