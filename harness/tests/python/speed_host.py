#!/usr/bin/env python3
"""A pyserial host that may open the port at the wrong speed, started before the simulator.

Usage: speed_host.py BAUD [THEN_BAUD]
  Prints "ready", then reads the port's path from stdin (the simulator's first line of stdout,
  so it opens the port the moment the path is announced), opens it at BAUD and sends a CR.
  It reads what comes until the line has been quiet for half a second, and prints it as hex
  on a line "first HEX". With THEN_BAUD it then sets that speed, as a host that found the
  right one, sends ^C and reads until a prompt (or 5 s): "then HEX".
"""

import sys

import serial

PROMPT = b"\n\r=> "


def read_quiet(port):
    got = b""
    while True:
        chunk = port.read(64)
        if not chunk:
            return got
        got += chunk


def main():
    baud = int(sys.argv[1])
    then = int(sys.argv[2]) if len(sys.argv) > 2 else None
    print("ready", flush=True)
    path = sys.stdin.readline().strip()
    port = serial.Serial(path, baud, timeout=0.5)
    port.write(b"\r")
    print("first " + read_quiet(port).hex(), flush=True)
    if then is not None:
        port.baudrate = then
        port.timeout = 5
        port.write(b"\x03")
        got = port.read_until(PROMPT)
        print("then " + got.hex(), flush=True)
    port.close()


main()
