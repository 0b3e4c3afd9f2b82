#!/usr/bin/env python3
"""A Python host (pyserial) behaving as BH8-262 host libraries do at the port, against
`gcl sim --pty --profile bh8-262` with its defaults (real time, paced at the hand's BAUD).

Usage: host_compat.py PTY_PATH

1. connect with ^C and read exactly one prompt; the first command gets its own answer;
2. RESET: the answer holds b"BarrettHand Firmware\\n" (what Barrett's C++ API searches for);
3. PSET BAUD 384, close without reading, reopen at 38400, wait, CR: exactly one prompt.
Prints "ok" and exits 0, or prints what went wrong and exits 1.
"""

import sys
import time

import serial

PROMPT = b"\n\r=> "


def fail(msg):
    print("FAIL: " + msg)
    sys.exit(1)


def read_until(port, end):
    data = b""
    while not data.endswith(end):
        chunk = port.read(1)
        if not chunk:
            fail("timed out waiting for %r; got %r" % (end, data))
        data += chunk
    return data


def main():
    path = sys.argv[1]
    # No reset_input_buffer(): the port must hold nothing stale when a host opens it.
    port = serial.Serial(path, baudrate=9600, timeout=5)
    port.write(b"\x03")
    if read_until(port, PROMPT) != PROMPT:
        fail("^C: more than one prompt")
    port.write(b"FGET DP\r")
    got = read_until(port, PROMPT)
    if got != b"FGET DP\n\r8500 8500 8500 1575" + PROMPT:
        fail("first command answered %r" % got)
    port.write(b"RESET\r")
    got = read_until(port, PROMPT)
    if b"BarrettHand Firmware\n" not in got:
        fail("RESET banner %r" % got)
    port.write(b"PSET BAUD 384\r")
    time.sleep(0.1)
    port.close()
    time.sleep(0.5)
    port = serial.Serial(path, baudrate=38400, timeout=0.5)
    port.write(b"\r")
    got = port.read(100)
    if got != PROMPT:
        fail("after the reopen: %r, not one fresh prompt" % got)
    port.timeout = 5
    port.write(b"PGET BAUD\r")
    got = read_until(port, PROMPT)
    if got != b"PGET BAUD\n\r384" + PROMPT:
        fail("PGET BAUD answered %r" % got)
    print("ok")


if __name__ == "__main__":
    main()
