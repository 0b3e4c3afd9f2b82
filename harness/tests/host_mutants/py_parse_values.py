"""Mutant: reads FGET answers by splitting on LF and converting the second line to integers,
and only catches its own errors.
Plausible bug: CR LF line ends, garbage or a restart give a ValueError nobody catches.
Expected finding: crash (Python traceback)."""
import gclhost


def command(port, line, deadline=1.0):
    port.write(line.encode() + b"\r")
    answer = gclhost.read_until(port, gclhost.PROMPT, deadline)
    lines = [l.strip() for l in answer.split(b"\n")]
    if "GET" in line:
        return [int(v) for v in lines[1].split()]
    return []


gclhost.main(lambda port: gclhost.supervisory(port, command))
