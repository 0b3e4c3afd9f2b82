"""Mutant: ERR n is looked up in a table of the documented single bits.
Plausible bug: an ERR with an unexpected combination of bits raises KeyError.
Expected finding: crash (Python traceback)."""
import gclhost

STATUS = {0: "ok", 4: "motor not initialized", 32: "unknown command", 64: "unknown parameter",
          128: "invalid value", 256: "read-only", 1024: "too many arguments",
          2048: "invalid RealTime header", 4096: "no prefix allowed"}


def command(port, line, deadline=1.0):
    port.write(line.encode() + b"\r")
    answer = gclhost.read_until(port, gclhost.PROMPT, deadline)[:-3]
    body = [l for l in answer.split(gclhost.EOL)[1:] if l]
    if body and body[-1].startswith(b"ERR "):
        raise gclhost.HostError("%s: %s" % (line, STATUS[int(body[-1][4:])]))
    return body


gclhost.main(lambda port: gclhost.supervisory(port, command))
