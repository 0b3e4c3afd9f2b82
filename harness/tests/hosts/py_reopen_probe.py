"""The reopen probe (stdlib only): writes FGET P, closes the port without reading, waits 1 s,
reopens it, sends nothing and reports on stderr what it reads in the next second.

A serial port behaves so: what the host left unread when it closed is gone, so the probe
reads nothing. Usage: py_reopen_probe.py [PORT] (default: $GCL_PORT).
"""
import os
import select
import sys
import termios
import time


def open_port(path):
    fd = os.open(path, os.O_RDWR | os.O_NOCTTY)
    attrs = termios.tcgetattr(fd)
    attrs[0] = 0  # iflag
    attrs[1] = 0  # oflag
    attrs[3] = 0  # lflag
    attrs[2] |= termios.CREAD | termios.CLOCAL
    termios.tcsetattr(fd, termios.TCSANOW, attrs)
    return fd


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else os.environ["GCL_PORT"]
    fd = open_port(path)
    os.write(fd, b"FGET P\r")
    time.sleep(0.2)
    os.close(fd)
    time.sleep(1.0)
    fd = open_port(path)
    got = b""
    end = time.monotonic() + 1.0
    while time.monotonic() < end:
        r, _, _ = select.select([fd], [], [], max(0.0, end - time.monotonic()))
        if r:
            got += os.read(fd, 4096)
    os.close(fd)
    sys.stderr.write("probe read: %r\n" % (got,))


try:
    main()
except OSError as e:
    # The port went away (the hand hung up): a host reports it and exits 1.
    print("probe: %s" % e, file=sys.stderr)
    sys.exit(1)
