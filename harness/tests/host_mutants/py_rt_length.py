"""Mutant: in RealTime, reads a feedback block with a timeout and indexes it at the length
the layout promises.
Plausible bug: a short block (or ERR instead of '*') raises IndexError.
Expected finding: crash (Python traceback)."""
import gclhost

FLAGS = "123FSET LCV 1 LCVC 1 LCPG 0 LFV 1 LFVC 1 LFS 0 LFAP 1 LFDP 0"
FEEDBACK = 10  # '*' + 3 x (velocity, position high, position low)


def scenario(port):
    gclhost.sync(port)
    gclhost.command(port, "HI")
    gclhost.command(port, FLAGS)
    port.write(b"123LOOP\r")
    gclhost.read_until(port, b"*")
    for _ in range(8):
        port.write(b"C\x14\x14\x14")
        block = port.read(FEEDBACK)
        if block[0:1] != b"*":
            raise gclhost.HostError("bad feedback header %r" % block[:1])
        positions = [block[3 * m + 2] * 256 + block[3 * m + 3] for m in range(3)]
        assert all(0 <= p < 65536 for p in positions)
    port.write(b"\x03")
    gclhost.read_until(port, gclhost.PROMPT)


def main():
    port = None
    try:
        port = gclhost.open_port(timeout=0.3)
    except Exception as e:  # noqa: BLE001
        raise SystemExit("host: %s" % e)
    try:
        scenario(port)
    except gclhost.HostError as e:
        raise SystemExit("host: %s" % e)


main()
