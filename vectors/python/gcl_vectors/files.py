"""Reading input files without trusting them, with the limits of the Rust reader
(host/src/files.rs): only regular files (a FIFO is opened without blocking and refused, as
are /dev/zero, directories and terminals), and at most MAX_INPUT_BYTES read, counted while
reading, so a huge or growing file costs no more memory than the limit. Stdlib only."""

import os
import stat

# The transcript format's MAX_FILE_BYTES, as in the Rust reader.
MAX_INPUT_BYTES = 4 << 20


class FileError(ValueError):
    """A file that is not a regular file, or larger than the limit."""


def _kind(mode):
    if stat.S_ISDIR(mode):
        return "a directory"
    if stat.S_ISFIFO(mode):
        return "a named pipe"
    if stat.S_ISCHR(mode):
        return "a character device"
    if stat.S_ISBLK(mode):
        return "a block device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "not a file"


def read_limited(path, limit=MAX_INPUT_BYTES):
    """The bytes of the regular file `path` (symbolic links followed), at most `limit` of them.
    Raises FileError for anything else, OSError when it cannot be opened."""
    fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOCTTY", 0))
    try:
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):
            raise FileError("not a regular file (%s); expected a file" % _kind(mode))
        os.set_blocking(fd, True)
        chunks, total = [], 0
        while total <= limit:
            b = os.read(fd, min(1 << 16, limit + 1 - total))
            if not b:
                break
            chunks.append(b)
            total += len(b)
        if total > limit:
            raise FileError("larger than the limit of %d bytes" % limit)
        return b"".join(chunks)
    finally:
        os.close(fd)


def read_text_limited(path, limit=MAX_INPUT_BYTES):
    """read_limited as UTF-8 text."""
    try:
        return read_limited(path, limit).decode("utf-8")
    except UnicodeDecodeError as e:
        raise FileError("not UTF-8 text: %s" % e)
