"""Mutant: builds RealTime control blocks for a hard-coded two-motor layout while the loop
runs three motors (the flags were set for 123).
Plausible bug: the block layout is not computed from the flags; every block is one byte short.
Expected finding: violation of host-realtime-blocks (check-host flags it too)."""
import gclhost


def scenario(port):
    gclhost.sync(port)
    gclhost.command(port, "HI")
    gclhost.command(port, "123FSET LCV 1 LCVC 1 LCPG 0 LFV 1 LFVC 1 LFS 0 LFAP 1 LFDP 0")
    port.write(b"123LOOP\r")
    gclhost.read_until(port, b"*")
    for _ in range(4):
        port.write(b"C\x14\x14")  # header and two velocities: the layout wants three
        port.read(10)
    port.write(b"\x03")
    port.read(16)


gclhost.main(scenario)
