"""Mutant: command lines end in CR LF, as on a modem or a terminal.
Expected finding: violation of host-line-ending (check-host flags it too)."""
import gclhost


def command(port, line, deadline=1.0):
    port.write(line.encode() + b"\r\n")
    gclhost.read_until(port, gclhost.PROMPT, deadline)


gclhost.main(lambda port: gclhost.supervisory(port, command))
