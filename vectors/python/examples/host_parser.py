"""An example for Python host authors: a tiny parser of what a BH8 hand sends back, tested
offline against the host vectors (vectors/json/<profile>/host.json) by
tests/test_host_example.py. Copy it and grow it; it is deliberately small.

parse(request, stream) returns the outcome a host must reach, in the vectors' terms:
  {"kind": "lines", "lines": [...]}           a command's output lines
  {"kind": "refusal", "status": n, "lines": []} ERR n
  {"kind": "loop-started"} / {"kind": "ack"}   `*` after LOOP, or after an `a`/`c` block
  {"kind": "feedback", "values": [...]}        a feedback block, one value per field
  {"kind": "prompt", "lines": [...]}           the prompt after ^C
  {"kind": "violation", "violation": "echo" | "framing"}
  {"kind": "incomplete"}                       not (yet) a whole answer: keep reading
each with "length", the bytes it took to decide (a host reading byte by byte)."""

EOL = b"\n\r"
PROMPT = b"=> "


def _lines(buf, start):
    """Output lines from `start`, each introduced by LF CR, up to LF CR `=> `.
    Returns ("done", lines, end) | ("more",) | ("bad",)."""
    pos, lines = start, []
    while True:
        rest = buf[pos:]
        if len(rest) < len(EOL):
            return ("more",) if EOL.startswith(rest) else ("bad",)
        if not rest.startswith(EOL):
            return ("bad",)
        body = rest[len(EOL):]
        if body.startswith(PROMPT):
            return ("done", lines, pos + len(EOL) + len(PROMPT))
        i = body.find(EOL)
        if i < 0:
            return ("more",)
        lines.append(body[:i].decode("latin-1"))
        pos += len(EOL) + i


def _status(lines):
    """("refusal", code) when the last line is `ERR n`, ("bad",) for `ERR` without a number,
    None when there is no status line."""
    if not lines or not lines[-1].startswith("ERR "):
        return None
    number = lines[-1][4:].strip()
    return ("refusal", int(number)) if number.isdigit() else ("bad",)


def _field(block, f):
    raw = block[f["offset"]:f["offset"] + f["size"]]
    return int.from_bytes(raw, "big", signed=f["signed"])


def _decide(request, buf):
    """The outcome for a whole buffer, or None when more bytes are needed."""
    kind = request["kind"]
    if kind in ("command", "loop"):
        echo = request["line"].encode("latin-1")
        if not echo.startswith(buf[:len(echo)]):
            return {"kind": "violation", "violation": "echo"}
        if len(buf) < len(echo):
            return None
        if kind == "loop" and buf[len(echo):len(echo) + 1] == b"*":
            return {"kind": "loop-started"}
        start = len(echo)
    elif kind == "block":
        if not buf:
            return None
        if buf[:1] == b"*":
            if request["header"] in ("a", "c"):
                return {"kind": "ack"}
            fb = request["layout"]["feedback"]
            if len(buf) < fb["size"]:
                return None
            return {"kind": "feedback", "values": [_field(buf, f) for f in fb["fields"]]}
        if buf[:1] != EOL[:1]:
            return {"kind": "violation", "violation": "framing"}
        start = 0
    else:  # abort, abort-loop: a prompt, maybe after lines such as ERR 16384
        start = 0
    r = _lines(buf, start)
    if r[0] == "more":
        return None
    if r[0] == "bad":
        return {"kind": "violation", "violation": "framing"}
    lines = r[1]
    if kind in ("abort", "abort-loop"):
        return {"kind": "prompt", "lines": lines}
    st = _status(lines)
    if st is not None and st[0] == "bad":
        return {"kind": "violation", "violation": "framing"}
    if st is not None:
        return {"kind": "refusal", "status": st[1], "lines": lines[:-1]}
    if kind == "command":
        return {"kind": "lines", "lines": lines}
    # LOOP answered with lines but no `*` and no ERR, or a loop that ended without ERR.
    return {"kind": "violation", "violation": "framing"}


def parse(request, stream):
    """Reads `stream` as a host reading byte by byte would: the first prefix that decides."""
    for k in range(1, len(stream) + 1):
        out = _decide(request, stream[:k])
        if out is not None:
            out["length"] = k
            return out
    return {"kind": "incomplete", "length": len(stream)}
