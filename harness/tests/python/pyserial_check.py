#!/usr/bin/env python3
"""Talks GCL to `gcl sim --profile seed` through pyserial, as a Python host would.

Usage: pyserial_check.py PORT_OR_URL
  PORT_OR_URL is a device path (gcl sim --pty) or socket://HOST:PORT (gcl sim --tcp).

Checks the echo, the "\\n\\r=> " prompt, "ERR n", and a RealTime exchange. Prints "ok" and
exits 0, or prints what went wrong and exits 1.
"""

import struct
import sys

import serial

PROMPT = b"\n\r=> "


def fail(msg):
    print("FAIL: " + msg)
    sys.exit(1)


def read_until(port, end, limit=4096):
    data = b""
    while not data.endswith(end):
        chunk = port.read(1)
        if not chunk:
            fail("timed out waiting for %r; got %r" % (end, data))
        data += chunk
        if len(data) > limit:
            fail("no %r in %r" % (end, data))
    return data


def read_exact(port, n):
    data = port.read(n)
    if len(data) != n:
        fail("wanted %d bytes, got %r" % (n, data))
    return data


def command(port, line):
    port.write(line + b"\r")
    reply = read_until(port, PROMPT)
    if not reply.startswith(line):
        fail("echo: sent %r, got %r" % (line, reply))
    return reply


def main():
    if len(sys.argv) != 2:
        fail("usage: pyserial_check.py PORT_OR_URL")
    port = serial.serial_for_url(sys.argv[1], baudrate=9600, timeout=5)
    port.reset_input_buffer()

    # A bare CR gets a fresh prompt; whatever was pending before it is discarded.
    port.write(b"\r")
    read_until(port, PROMPT)
    port.timeout = 0.2
    port.read(4096)
    port.timeout = 5

    # Echo, output line, prompt.
    reply = command(port, b"FGET DP")
    if reply != b"FGET DP\n\r1000 1000 1000 150" + PROMPT:
        fail("FGET DP: %r" % reply)

    # ERR n.
    reply = command(port, b"FSET DP 999999")
    if reply != b"FSET DP 999999\n\rERR 128" + PROMPT:
        fail("out of range: %r" % reply)
    reply = command(port, b"NONESUCH")
    if not reply.endswith(b"\n\rERR 32" + PROMPT):
        fail("unknown command: %r" % reply)

    # RealTime: the seed's RealTime example flags on F1-F3.
    command(port, b"HI")
    command(port, b"123FSET LCV 1 LCVC 1 LCPG 0 LFV 0 LFVC 1 LFS 0 LFAP 1 LFDP 0 LFDPC 1")
    port.write(b"123LOOP\r")
    ack = read_exact(port, len(b"123LOOP*"))
    if ack != b"123LOOP*":
        fail("LOOP: %r" % ack)
    positions = None
    for _ in range(20):
        port.write(b"C" + struct.pack(">bbb", 55, 0, 0))
        block = read_exact(port, 7)
        if block[:1] != b"*":
            fail("feedback header: %r" % block)
        positions = struct.unpack(">HHH", block[1:])
    if not positions[0] > 0 or positions[1] != 0:
        fail("F1 should move, F2 should not: %r" % (positions,))
    port.write(b"a")
    if read_exact(port, 1) != b"*":
        fail("'a' must be answered with '*' alone")
    port.write(b"\x03")
    if read_until(port, PROMPT) != PROMPT:
        fail("^C must leave the loop with a prompt")
    reply = command(port, b"1FGET P")
    if int(reply.split(b"\n\r")[1]) < positions[0]:
        fail("FGET P after the loop: %r" % reply)

    port.close()
    print("ok")


if __name__ == "__main__":
    main()
