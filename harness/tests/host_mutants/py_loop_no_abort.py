"""Mutant: leaves RealTime by closing the port, without ^C.
Plausible bug: the destructor closes the port but never ends the loop, so the next program
finds the hand deaf to commands.
Expected finding: violation of host-leaves-cleanly (check-host flags it too)."""
import gclhost


def scenario(port):
    gclhost.sync(port)
    gclhost.command(port, "HI")
    gclhost.command(port, "123FSET LCV 1 LCVC 1 LCPG 0 LFV 1 LFVC 1 LFS 0 LFAP 1 LFDP 0")
    port.write(b"123LOOP\r")
    gclhost.read_until(port, b"*")
    for _ in range(4):
        port.write(b"C\x14\x14\x14")
        gclhost.read_until(port, b"*")
        port.read(9)


gclhost.main(scenario)
