"""BUG, deep: the Python twin of c_deep_parser.c, instrumented with python-afl.

The host asks `1FGET P` ten times, the same commands whatever it reads, and keeps a recovery
state across answers: an `ERR` answer, then an answer with a byte no GCL answer has, then a
line longer than 80 bytes; in that state the next `ERR n` whose value passes a check
(n > 1000000) is taken as an index into a 16-entry list: an IndexError nobody catches.
Expected finding, only with err-bits, garbage, overlong-line and err-bits (of 2^31, 2^32-1 or
20 digits) in that order: one crash, a traceback in `retry_slot`. With python-afl
(`afl.init()`), or run through `python -m gcl.afl_cov` (whose stand-in `afl` it then imports),
each state reached is new lines in the map of __AFL_SHM_ID; without either the host runs the
same, uninstrumented. Every read has a 1 s deadline; it exits 0 at the end.
"""
import os
import sys
import time

import serial

TABLE = [0] * 16


def read_answer(port):
    buf = b""
    stop = time.monotonic() + 1.0
    while not buf.endswith(b"=> ") and time.monotonic() < stop:
        buf += port.read(max(1, port.in_waiting))
    return buf


def err_code(answer):
    at = answer.find(b"ERR ")
    if at < 0:
        return -1
    digits = answer[at + 4 :].split(b"\n")[0].strip()
    try:
        return int(digits)
    except ValueError:
        return -1


def has_foreign_byte(answer):
    return any((c < 0x20 and c not in (0x0A, 0x0D)) or c > 0x7E for c in answer)


def has_long_line(answer):
    return any(len(line) > 80 for line in answer.replace(b"\r", b"\n").split(b"\n"))


def retry_slot(code):
    TABLE[code] = 1


def main():
    port = serial.serial_for_url(os.environ["GCL_PORT_URL"], baudrate=9600, timeout=0.05)
    state = "idle"
    port.write(b"\x03")
    read_answer(port)
    for _ in range(10):
        port.write(b"1FGET P\r")
        answer = read_answer(port)
        code = err_code(answer)
        if state == "idle":
            if code >= 0:
                state = "recovering"
        elif state == "recovering":
            if has_foreign_byte(answer):
                state = "resyncing"
        elif state == "resyncing":
            if has_long_line(answer):
                state = "buffered"
        elif state == "buffered":
            if code > 1000000:
                retry_slot(code)
    return 0


if __name__ == "__main__":
    try:
        import afl
    except ImportError:
        afl = None
    if afl is not None:
        afl.init()
    sys.exit(main())
