"""A small, correct pyserial host for GCL, the base the Python host mutants change.

The port comes from GCL_PORT_URL (a pty path or socket://127.0.0.1:N), set by
`gcl fuzz host` and `gcl check-host`. Every wait has a deadline; anything the hand does
wrong becomes HostError, reported on one line with exit code 1.
"""
import os
import sys
import time

import serial

PROMPT = b"=> "
EOL = b"\n\r"


class HostError(Exception):
    """The hand broke the protocol, refused a command, or went away."""


def open_port(timeout=0.05):
    return serial.serial_for_url(os.environ["GCL_PORT_URL"], baudrate=9600, timeout=timeout)


def read_until(port, end, deadline=1.0):
    buf = b""
    stop = time.monotonic() + deadline
    while not buf.endswith(end):
        if time.monotonic() > stop:
            raise HostError("no %r after %r" % (end, buf[-40:]))
        buf += port.read(max(1, port.in_waiting))
    return buf


def command(port, line, deadline=1.0):
    """Sends one command line; returns the answer's lines between echo and prompt."""
    port.write(line.encode() + b"\r")
    answer = read_until(port, PROMPT, deadline)[: -len(PROMPT)]
    lines = answer.split(EOL)
    if lines[0] != line.encode():
        raise HostError("echo %r for %r" % (lines[0], line))
    body = [l for l in lines[1:] if l]
    if body and body[-1].startswith(b"ERR "):
        raise HostError("%s refused: %s" % (line, body[-1].decode(errors="replace")))
    return body


def sync(port):
    """^C, then whatever the hand had to say is dropped."""
    port.write(b"\x03")
    read_until(port, PROMPT)


SCENARIO = ["HI", "FGET DP", "1M 5000", "1FGET P", "C", "O", "FGET P", "2M 1000", "123FGET P"]


def supervisory(port, ask=command):
    sync(port)
    for line in SCENARIO:
        ask(port, line)


def main(scenario=supervisory):
    try:
        port = open_port()
        scenario(port)
        port.close()
    except (HostError, serial.SerialException, OSError) as e:
        print("host: %s" % e, file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()
