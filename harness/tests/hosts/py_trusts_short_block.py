"""BUG (Barrett's API accepted a RealTime block two bytes short and returned success): in
RealTime, reads a feedback block with a timeout and decodes whatever arrived, a short block
padded with zeros, and publishes the positions it decoded. It says what it believes with the
observation protocol: `gcl-observe: P MOTOR VALUE WHERE` lines on the descriptor
GCL_OBSERVE_FD, WHERE naming the code that decoded the value.

Expected: `gcl fuzz host` reports a silent wrong value (a position the hand never sent),
`silent wrong value: P at py_trusts_short_block.py:scenario`; no crash, no hang, exit 0.
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "host_mutants"))
import gclhost  # noqa: E402
import serial  # noqa: E402

FLAGS = "123FSET LCV 1 LCVC 1 LCPG 0 LFV 1 LFVC 1 LFS 0 LFAP 1 LFDP 0"
FEEDBACK = 10  # '*' + 3 x (velocity, position high, position low)
OBSERVE = int(os.environ.get("GCL_OBSERVE_FD", "2"))


def observe(text):
    os.write(OBSERVE, ("gcl-observe: %s\n" % text).encode())


def scenario(port):
    gclhost.sync(port)
    gclhost.command(port, "HI")
    gclhost.command(port, FLAGS)
    port.write(b"123LOOP\r")
    gclhost.read_until(port, b"*")
    for _ in range(6):
        port.write(b"C\x14\x14\x14")
        block = port.read(FEEDBACK).ljust(FEEDBACK, b"\0")  # trusts a short block
        for m in range(3):
            # WHERE (optional): the code that formed the belief, named in the finding.
            observe("P %d %d py_trusts_short_block.py:scenario" % (m + 1, block[3 * m + 2] * 256 + block[3 * m + 3]))
    port.write(b"\x03")
    port.read(100)


def main():
    try:
        port = gclhost.open_port(timeout=0.3)
        scenario(port)
    except (gclhost.HostError, serial.SerialException, OSError) as e:
        print("host: %s" % e, file=sys.stderr)
        sys.exit(1)


main()
