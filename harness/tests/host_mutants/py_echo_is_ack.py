"""Mutant: takes the echo line as the acknowledgement and sends the next command as soon as
it has it, while the rest of the answer (values, prompt) is still crossing the line; it reads
what is left at the end. Unnoticed on an unpaced line, where a whole answer arrives at once.
Expected finding, on a paced line: violation of host-waits-for-answer. It opens the port at
1200 bit/s (the hand paced at 1200): the rest of an answer then takes some 200 ms to cross.
"""
import time

import gclhost

LINES = ["FGET DP", "FGET P", "FGET DP"]


def scenario(port):
    port.baudrate = 1200
    gclhost.sync(port)
    seen = b""
    at = 0
    stop = time.monotonic() + 5.0

    def more():
        if time.monotonic() > stop:
            raise gclhost.HostError("answers incomplete: %r" % seen[-40:])
        return port.read(max(1, port.in_waiting))

    for line in LINES:
        port.write(line.encode() + b"\r")
        echo = line.encode() + gclhost.EOL
        while seen.find(echo, at) < 0:
            seen += more()
        at = seen.find(echo, at) + len(echo)
    while seen.count(gclhost.PROMPT) < len(LINES):
        seen += more()


gclhost.main(scenario)
