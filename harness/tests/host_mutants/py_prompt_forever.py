"""Mutant: the read loop waits for the prompt with no deadline and a blocking port.
Plausible bug: 'the hand always answers', so a lost prompt blocks the host for ever.
Expected finding: hang."""
import gclhost


def command(port, line, deadline=None):
    port.write(line.encode() + b"\r")
    buf = b""
    while not buf.endswith(gclhost.PROMPT):
        buf += port.read(1)  # the port has no timeout: blocks for ever
    return buf[:-3].split(gclhost.EOL)[1:]


def scenario(port):
    port.timeout = None
    port.write(b"\x03")
    gclhost.read_until(port, gclhost.PROMPT)
    for line in gclhost.SCENARIO:
        command(port, line)


gclhost.main(scenario)
