"""BUG: a pyserial host whose port has no timeout: `read_answer` blocks for ever when an
answer is cut or its prompt never comes, whichever command it answers.

Expected: `gcl fuzz host` reports ONE hang, whose signature names py_read_forever.py:read_answer.
"""
import os
import sys

import serial

PROMPT = b"=> "


def read_answer(port):
    buf = b""
    while not buf.endswith(PROMPT):
        buf += port.read(1)  # no timeout: blocks for ever
    return buf


def main():
    port = serial.serial_for_url(os.environ["GCL_PORT_URL"], baudrate=9600, timeout=None)
    for line in [b"\x03", b"HI\r", b"FGET DP\r", b"1M 5000\r", b"FGET P\r", b"C\r", b"O\r"]:
        port.write(line)
        read_answer(port)
    port.close()


try:
    main()
except (serial.SerialException, OSError) as e:
    print("host: %s" % e, file=sys.stderr)
    sys.exit(1)
