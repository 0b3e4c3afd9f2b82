//! Reading input files without trusting them: every file `gcl` and this crate read
//! (transcripts, scripts, suite files, known-failures lists, scenarios, EEPROM images, profile
//! TOML, keys, certificate bundles) goes through [`read_limited`] or [`open_regular`]; what
//! comes from somewhere untrusted whose links must not be followed (the shards `gcl fuzz merge`
//! folds) through [`read_limited_no_follow`], or [`read_head_no_follow`] where the beginning of
//! a file too long is kept (the sanitizer logs a host under test writes).
//!
//! - Only regular files are accepted. A FIFO is opened without blocking and refused, so a
//!   named pipe called `x.gcl` in a suite directory cannot hang a run; `/dev/zero`, a
//!   directory or a terminal is refused the same way.
//! - The size is checked while reading: at most `limit + 1` bytes are ever read, so a 1 GB
//!   file, or one that grows while it is read, costs no more memory than the limit.
//!
//! Errors are `std::io::Error`s (kind `InvalidInput` for a file that is not regular,
//! `FileTooLarge` beyond the limit), so callers keep telling a missing file from others.

use std::fs::File;
use std::io::{self, Read};
use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
use std::path::Path;

/// The size limit of an input file a person writes or a tool generates: transcripts,
/// scripts, suite files, known-failures lists, scenarios, EEPROM images, profile TOML. It is
/// the transcript crate's `MAX_FILE_BYTES` (this crate does not depend on that one;
/// `gcl-harness` asserts the two agree at compile time).
pub const MAX_INPUT_BYTES: u64 = 4 << 20;

/// What a file that is not a regular file is, for people: `a directory`, `a named pipe`...
pub fn kind_of(ft: &std::fs::FileType) -> &'static str {
    if ft.is_dir() {
        "a directory"
    } else if ft.is_fifo() {
        "a named pipe"
    } else if ft.is_char_device() {
        "a character device"
    } else if ft.is_block_device() {
        "a block device"
    } else if ft.is_socket() {
        "a socket"
    } else {
        "not a file"
    }
}

/// Opens `path` for reading if it is a regular file (after following symbolic links).
/// Never blocks on a FIFO, and never makes a terminal the controlling one.
pub fn open_regular(path: &Path) -> io::Result<File> {
    open_with(path, 0)
}

/// [`open_regular`] for a file from somewhere untrusted (a CI artifact, a shard's folder): a
/// symbolic link at `path` is refused, never followed, so a link planted in place of a file
/// (to `/etc/shadow`, to a 3 GB file) is never read.
pub fn open_regular_no_follow(path: &Path) -> io::Result<File> {
    // O_NOFOLLOW refuses a link at the last component with ELOOP.
    open_with(path, nix::libc::O_NOFOLLOW)
        .map_err(|e| if e.raw_os_error() == Some(nix::libc::ELOOP) { not_followed() } else { e })
}

/// Opens a regular file without blocking or taking a terminal, with `flags` added.
fn open_with(path: &Path, flags: i32) -> io::Result<File> {
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(nix::libc::O_NONBLOCK | nix::libc::O_NOCTTY | flags)
        .open(path)?;
    let ft = file.metadata()?.file_type();
    if !ft.is_file() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("not a regular file ({}); expected a file", kind_of(&ft)),
        ));
    }
    Ok(file)
}

fn not_followed() -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, "a symbolic link, not followed; expected a file")
}

/// Reads a whole regular file of at most `limit` bytes, counting while it reads.
pub fn read_limited(path: &Path, limit: u64) -> io::Result<Vec<u8>> {
    read_whole(open_regular(path)?, limit)
}

/// [`read_limited`] through [`open_regular_no_follow`]: a symbolic link is refused.
pub fn read_limited_no_follow(path: &Path, limit: u64) -> io::Result<Vec<u8>> {
    read_whole(open_regular_no_follow(path)?, limit)
}

/// The first `limit` bytes of a regular file from somewhere untrusted (a log a program under
/// test wrote), through [`open_regular_no_follow`], and whether there was more: for text whose
/// beginning is worth keeping when the whole is too long (a sanitizer's report).
pub fn read_head_no_follow(path: &Path, limit: u64) -> io::Result<(Vec<u8>, bool)> {
    let mut bytes = Vec::new();
    open_regular_no_follow(path)?.take(limit.saturating_add(1)).read_to_end(&mut bytes)?;
    let more = bytes.len() as u64 > limit;
    bytes.truncate(usize::try_from(limit).unwrap_or(usize::MAX));
    Ok((bytes, more))
}

fn read_whole(file: File, limit: u64) -> io::Result<Vec<u8>> {
    let hint = file.metadata().map(|m| m.len().min(limit)).unwrap_or(0);
    let mut bytes = Vec::with_capacity(usize::try_from(hint).unwrap_or(0));
    file.take(limit.saturating_add(1)).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(too_large(limit));
    }
    Ok(bytes)
}

/// [`read_limited`] for UTF-8 text.
pub fn read_text_limited(path: &Path, limit: u64) -> io::Result<String> {
    String::from_utf8(read_limited(path, limit)?)
        .map_err(|e| io::Error::new(io::ErrorKind::InvalidData, format!("not UTF-8 text: {e}")))
}

/// [`read_limited`] with [`MAX_INPUT_BYTES`].
pub fn read_input(path: &Path) -> io::Result<Vec<u8>> {
    read_limited(path, MAX_INPUT_BYTES)
}

/// [`read_text_limited`] with [`MAX_INPUT_BYTES`].
pub fn read_input_text(path: &Path) -> io::Result<String> {
    read_text_limited(path, MAX_INPUT_BYTES)
}

/// The error of a file beyond `limit` bytes.
pub fn too_large(limit: u64) -> io::Error {
    io::Error::new(io::ErrorKind::FileTooLarge, format!("larger than the limit of {limit} bytes"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_small_files_and_refuses_large_ones_without_reading_them_whole() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.gcl");
        std::fs::write(&p, b"hello").unwrap();
        assert_eq!(read_limited(&p, 5).unwrap(), b"hello");
        let e = read_limited(&p, 4).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::FileTooLarge);
        // A sparse 1 GiB file: refused after reading the limit, not 1 GiB.
        let big = dir.path().join("big.gcl");
        File::create(&big).unwrap().set_len(1 << 30).unwrap();
        assert_eq!(read_input(&big).unwrap_err().kind(), io::ErrorKind::FileTooLarge);
        assert_eq!(read_text_limited(&p, 10).unwrap(), "hello");
        assert_eq!(read_input(&dir.path().join("none")).unwrap_err().kind(), io::ErrorKind::NotFound);
    }

    #[test]
    fn refuses_what_is_not_a_regular_file_without_blocking() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("x.gcl");
        nix::unistd::mkfifo(&fifo, nix::sys::stat::Mode::from_bits_truncate(0o600)).unwrap();
        // Nobody writes to the FIFO: a blocking open or read would hang this test.
        let e = read_input(&fifo).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
        assert!(e.to_string().contains("named pipe"), "{e}");
        let e = read_input(Path::new("/dev/zero")).unwrap_err();
        assert!(e.to_string().contains("character device"), "{e}");
        assert!(read_input(dir.path()).unwrap_err().to_string().contains("directory"));
    }

    #[test]
    fn the_no_follow_reader_refuses_links_and_reads_files() {
        let dir = tempfile::tempdir().unwrap();
        let secret = dir.path().join("secret");
        std::fs::write(&secret, b"root:x").unwrap();
        let link = dir.path().join("stderr.txt");
        std::os::unix::fs::symlink(&secret, &link).unwrap();
        let e = read_limited_no_follow(&link, 100).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
        assert!(e.to_string().contains("symbolic link"), "{e}");
        assert_eq!(read_limited(&link, 100).unwrap(), b"root:x", "the following reader follows");
        assert_eq!(read_limited_no_follow(&secret, 100).unwrap(), b"root:x");
        let fifo = dir.path().join("fifo");
        nix::unistd::mkfifo(&fifo, nix::sys::stat::Mode::from_bits_truncate(0o600)).unwrap();
        assert!(read_limited_no_follow(&fifo, 100).unwrap_err().to_string().contains("named pipe"));
        let big = dir.path().join("big");
        File::create(&big).unwrap().set_len(1 << 30).unwrap();
        assert_eq!(read_limited_no_follow(&big, 100).unwrap_err().kind(), io::ErrorKind::FileTooLarge);
        // The head reader: the same refusals, and the beginning of a file too long.
        assert_eq!(read_head_no_follow(&big, 100).unwrap(), (vec![0; 100], true));
        assert_eq!(read_head_no_follow(&secret, 6).unwrap(), (b"root:x".to_vec(), false));
        assert!(read_head_no_follow(&link, 100).unwrap_err().to_string().contains("symbolic link"));
        assert!(read_head_no_follow(&fifo, 100).unwrap_err().to_string().contains("named pipe"));
    }
}
