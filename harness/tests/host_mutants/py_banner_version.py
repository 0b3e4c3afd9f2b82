"""Mutant: after RESET, unpacks the first banner line into exactly two words.
Plausible bug: a banner variant (a version suffix, a line missing) raises ValueError.
Expected finding: crash (Python traceback)."""
import gclhost


def scenario(port):
    gclhost.sync(port)
    lines = gclhost.command(port, "RESET", deadline=2.0)
    vendor, kind = lines[0].split()
    if kind != b"Firmware":
        raise gclhost.HostError("not a BarrettHand: %r" % lines[0])
    for line in gclhost.SCENARIO[:4]:
        gclhost.command(port, line)


gclhost.main(scenario)
