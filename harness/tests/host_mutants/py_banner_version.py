"""Mutant: after RESET, takes the firmware version from a fixed word of a fixed banner line.
Plausible bug: a banner variant (a line missing, a restart) gives IndexError.
Expected finding: crash (Python traceback)."""
import gclhost


def scenario(port):
    gclhost.sync(port)
    lines = gclhost.command(port, "RESET", deadline=2.0)
    version = lines[1].split()[3]
    if not version.startswith(b"(P"):
        raise gclhost.HostError("unknown firmware %r" % version)
    for line in gclhost.SCENARIO[:4]:
        gclhost.command(port, line)


gclhost.main(scenario)
