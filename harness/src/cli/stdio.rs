//! The one way the `gcl` binary writes to stdout and stderr: [`out`], [`err`] and the macros
//! `outln!` and `errln!` built on them.
//!
//! Why: what a command prints is a courtesy to whoever reads it; its reports, findings and
//! exit code are its verdict. A reader that goes away (`gcl conform ... | head -2`, a CI step
//! piped into `true`) or a full disk behind `>` must not cut a command short, turn a failure
//! into exit 0, or panic (`println!` does on a closed pipe). So a write to stdout that fails is
//! dropped, and every write after it too: the command runs to its end, writes its files and
//! returns its verdict's code. `main` asks [`finish`] at the end: a closed pipe is the reader's
//! choice and changes nothing; another failure (`> /dev/full`) lost output that was asked for,
//! and `main` says so on stderr and exits 2 if the verdict was a pass.
//!
//! Stderr is treated the same way, silently: there is nowhere left to say it failed.
//!
//! `harness/tests/it/tidy.rs` (`the_binary_prints_through_one_door`) holds every other file of the
//! binary to these: no `println!`, `eprintln!`, `std::io::stdout()` or `std::io::stderr()`.

use std::io::{self, Write};
use std::sync::Mutex;

/// The first failure of a write to stdout, once one happened: later writes are dropped.
static STDOUT_LOST: Mutex<Option<io::Error>> = Mutex::new(None);

fn lost() -> std::sync::MutexGuard<'static, Option<io::Error>> {
    STDOUT_LOST.lock().unwrap_or_else(|e| e.into_inner())
}

/// Stdout for the commands: a write that fails is dropped and remembered, never returned (so a
/// summary written with `?` cannot end a command before its reports).
#[derive(Debug, Clone, Copy)]
pub struct Out;

/// Stdout, through [`Out`].
pub fn out() -> Out {
    Out
}

impl Write for Out {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let mut lost = lost();
        if lost.is_some() {
            return Ok(buf.len());
        }
        match io::stdout().write(buf) {
            Err(e) if e.kind() == io::ErrorKind::Interrupted => Err(e),
            Err(e) => {
                *lost = Some(e);
                Ok(buf.len())
            }
            Ok(n) => Ok(n),
        }
    }

    fn flush(&mut self) -> io::Result<()> {
        let mut lost = lost();
        if lost.is_some() {
            return Ok(());
        }
        if let Err(e) = io::stdout().flush() {
            *lost = Some(e);
        }
        Ok(())
    }
}

/// Whether stdout failed (its reader went away, or it could not be written): what is written
/// to it now goes nowhere.
pub fn stdout_lost() -> bool {
    lost().is_some()
}

/// Flushes stdout; the failure that lost output someone asked for, if one happened (a closed
/// pipe is not one: its reader chose to stop reading).
pub fn finish() -> Option<io::Error> {
    let _ = out().flush();
    lost().take().filter(|e| e.kind() != io::ErrorKind::BrokenPipe)
}

/// Stderr for the commands: a write that fails is dropped (there is nowhere to say so).
#[derive(Debug, Clone, Copy)]
pub struct ErrOut;

/// Stderr, through [`ErrOut`].
pub fn err() -> ErrOut {
    ErrOut
}

impl Write for ErrOut {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        match io::stderr().write(buf) {
            Err(e) if e.kind() == io::ErrorKind::Interrupted => Err(e),
            _ => Ok(buf.len()),
        }
    }

    fn flush(&mut self) -> io::Result<()> {
        let _ = io::stderr().flush();
        Ok(())
    }
}

/// Whether stderr is a terminal (where progress is a bar).
pub fn stderr_is_terminal() -> bool {
    use std::io::IsTerminal;
    io::stderr().is_terminal()
}

/// A line on stdout, through [`out`]: never fails, never panics.
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!($crate::cli::stdio::out(), $($arg)*);
    }};
}

/// A line on stderr, through [`err`]: never fails, never panics.
macro_rules! errln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!($crate::cli::stdio::err(), $($arg)*);
    }};
}

pub(crate) use {errln, outln};
