"""Matching a hand's answer against an expectation, byte by byte (vectors/README.md 1.5, 1.6).

The answer is the shortest prefix of the bytes received that matches; a byte that cannot
continue any match is where the answer parts from the expectation."""

from .transcript import INT_LIMIT, relation_band

ALIVE, COMPLETE, DEAD = "alive", "complete", "dead"
DIGITS = b"0123456789"


def _int_reachable(s):
    """The closed intervals of values an integer whose text starts with `s` can take (GCL
    integers: 0, or an optional minus then 1 to 18 digits without a leading zero)."""
    neg = s.startswith(b"-")
    digits = s[1:] if neg else s
    if not digits:
        return [(-INT_LIMIT, -1)] if neg else [(-INT_LIMIT, INT_LIMIT)]
    if len(digits) > 18 or any(c not in DIGITS for c in digits):
        return []
    if digits[0:1] == b"0":
        return [] if neg or len(digits) > 1 else [(0, 0)]
    d = int(digits)
    out = []
    for j in range(0, 18 - len(digits) + 1):
        lo, hi = d * 10**j, d * 10**j + 10**j - 1
        out.append((-hi, -lo) if neg else (lo, hi))
    return out


def _int_viable(s, lo, hi):
    return any(a <= hi and b >= lo for a, b in _int_reachable(s))


def _int_complete(s, lo, hi):
    neg = s.startswith(b"-")
    digits = s[1:] if neg else s
    if not digits or len(digits) > 18 or any(c not in DIGITS for c in digits):
        return False
    if digits[0:1] == b"0" and (neg or len(digits) > 1):
        return False
    v = -int(digits) if neg else int(digits)
    return lo <= v <= hi


def _signed(v, width):
    top = 1 << (width * 8 - 1)
    return v - 2 * top if v >= top else v


class Matcher:
    """Feed bytes one at a time; `feed` says ALIVE, COMPLETE (the shortest match ends at this
    byte) or DEAD (this byte parts from the expectation). `known` holds the values earlier
    steps captured, by name; `captures()` gives them with this answer's, once complete."""

    def __init__(self, pieces, known=None):
        self.pieces = pieces
        self.known = dict(known or {})
        # For each value piece: its ordinal among this expectation's captures, and the
        # ordinal (or the known value) its relation is measured against.
        self.names = []
        self.slots = []
        for p in pieces:
            slot = (None, None)
            if isinstance(p, tuple) and p[0] == "value":
                _, _, relation, capture = p
                base = None
                if relation is not None:
                    if relation[0] in self.names:
                        base = ("local", self.names.index(relation[0]))
                    elif relation[0] in self.known:
                        base = ("known", self.known[relation[0]])
                    else:
                        base = ("unknown", None)
                if capture is not None:
                    self.names.append(capture)
                slot = (len(self.names) - 1 if capture is not None else None, base)
            self.slots.append(slot)
        self.states = self._closure({(0, None, ())})
        self.fed = 0

    def _reads(self, i, caps):
        """The int or bin piece that piece i reads for a state with captures `caps`, or None
        when nothing can match (a relation to a name nobody captured, a band outside a field)."""
        p = self.pieces[i]
        if p[0] != "value":
            return p
        _, base, relation, _ = p
        ref = self.slots[i][1]
        if ref is None:
            return base
        if ref[0] == "unknown":
            return None
        x = caps[ref[1]] if ref[0] == "local" else ref[1]
        lo, hi = relation_band(relation, x)
        if base[0] == "int":
            return ("int", lo, hi)
        _, width, signed, blo, bhi = base
        lo, hi = max(lo, blo), min(hi, bhi)
        return ("bin", width, signed, lo, hi) if lo <= hi else None

    def _next(self, i, caps, value):
        if self.slots[i][0] is not None:
            caps = caps + (value,)
        return (i + 1, None, caps)

    def _closure(self, states):
        out = set(states)
        todo = list(states)
        n = len(self.pieces)
        while todo:
            i, aux, caps = todo.pop()
            if i >= n:
                continue
            p = self.pieces[i]
            nxt = None
            if p in (("line",), ("any",)):
                nxt = (i + 1, None, caps)
            elif p == ("text",):
                if (aux or 0) & _TEXT_SEEN:
                    nxt = (i + 1, None, caps)
            elif isinstance(p, tuple) and p[0] in ("int", "value", "bin"):
                r = self._reads(i, caps)
                if r is not None and r[0] == "int" and aux is not None and _int_complete(aux, r[1], r[2]):
                    nxt = self._next(i, caps, int(aux))
                elif r is not None and r[0] == "bin" and isinstance(aux, tuple):
                    nxt = self._next(i, caps, aux[0])
            if nxt is not None and nxt not in out:
                out.add(nxt)
                todo.append(nxt)
        return out

    def is_complete(self):
        return any(i >= len(self.pieces) for i, _, _ in self.states)

    def captures(self):
        """Once complete: the values known before and those this answer captured."""
        for i, _, caps in sorted(self.states, key=lambda s: s[2]):
            if i >= len(self.pieces):
                out = dict(self.known)
                out.update(zip(self.names, caps))
                return out
        return None

    def feed(self, b):
        self.fed += 1
        new = set()
        n = len(self.pieces)
        for i, aux, caps in self.states:
            if i >= n:
                continue
            p = self.pieces[i]
            if isinstance(p, int):
                if b == p:
                    new.add((i + 1, None, caps))
            elif p == ("byte",):
                new.add((i + 1, None, caps))
            elif p == ("any",):
                new.add((i, None, caps))
            elif p == ("line",):
                if b not in (10, 13):
                    new.add((i, None, caps))
            elif p == ("text",):
                t = _text_step(aux or 0, b)
                if t is not None:
                    new.add((i, t, caps))
            else:
                r = self._reads(i, caps)
                if r is None or isinstance(aux, tuple):
                    continue
                if r[0] == "int":
                    s = (aux or b"") + bytes([b])
                    if _int_viable(s, r[1], r[2]):
                        new.add((i, s, caps))
                    continue
                _, width, signed, lo, hi = r
                if width == 1:
                    v = _signed(b, 1) if signed else b
                    if lo <= v <= hi:
                        # A whole field: its value waits in `aux` for the closure to capture.
                        new.add((i, (v,), caps))
                elif aux is None:
                    h = _signed(b, 1) if signed else b
                    if h * 256 <= hi and h * 256 + 255 >= lo:
                        new.add((i, b, caps))
                else:
                    v = aux * 256 + b
                    if signed:
                        v = _signed(v, 2)
                    if lo <= v <= hi:
                        new.add((i, (v,), caps))
        self.states = self._closure(new)
        if not self.states:
            return DEAD
        return COMPLETE if self.is_complete() else ALIVE


# A {text} state in `aux`: _TEXT_SEEN once a byte other than LF and CR came; in the low bits,
# 0 to 2 while the present line is so far the start of `ERR`, _TEXT_FREE once it is not.
_TEXT_SEEN = 8
_TEXT_FREE = 3


def _text_step(aux, b):
    """A {text}'s next byte: a line break starts a new line; a line that begins with `ERR` (a
    status answer) is where the text parts (None)."""
    if b in (10, 13):
        return aux & _TEXT_SEEN
    line = aux & 7
    if line == 0 and b == 0x45:
        line = 1
    elif line == 1 and b == 0x52:
        line = 2
    elif line == 2 and b == 0x52:
        return None
    else:
        line = _TEXT_FREE
    return _TEXT_SEEN | line


def match_prefix(pieces, data, known=None):
    """(COMPLETE, length) for the shortest matching prefix of `data`, (DEAD, offset) where it
    parts, or (ALIVE, len(data)) when more bytes are needed."""
    m = Matcher(pieces, known)
    if m.is_complete():
        return COMPLETE, 0
    for k, b in enumerate(data):
        r = m.feed(b)
        if r == DEAD:
            return DEAD, k
        if r == COMPLETE:
            return COMPLETE, k + 1
    return ALIVE, len(data)
