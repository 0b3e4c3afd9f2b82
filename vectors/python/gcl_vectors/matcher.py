"""Matching a hand's answer against an expectation, byte by byte (vectors/README.md 1.5, 1.6).

The answer is the shortest prefix of the bytes received that matches; a byte that cannot
continue any match is where the answer parts from the expectation."""

from .transcript import INT_LIMIT

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
    byte) or DEAD (this byte parts from the expectation)."""

    def __init__(self, pieces):
        self.pieces = pieces
        self.states = self._closure({(0, None)})
        self.fed = 0

    def _closure(self, states):
        out = set(states)
        todo = list(states)
        n = len(self.pieces)
        while todo:
            i, aux = todo.pop()
            if i >= n:
                continue
            p = self.pieces[i]
            nxt = None
            if p in (("line",), ("any",)):
                nxt = (i + 1, None)
            elif isinstance(p, tuple) and p[0] == "int" and aux is not None and _int_complete(aux, p[1], p[2]):
                nxt = (i + 1, None)
            if nxt is not None and nxt not in out:
                out.add(nxt)
                todo.append(nxt)
        return out

    def is_complete(self):
        return any(i >= len(self.pieces) for i, _ in self.states)

    def feed(self, b):
        self.fed += 1
        new = set()
        n = len(self.pieces)
        for i, aux in self.states:
            if i >= n:
                continue
            p = self.pieces[i]
            if isinstance(p, int):
                if b == p:
                    new.add((i + 1, None))
            elif p == ("byte",):
                new.add((i + 1, None))
            elif p == ("any",):
                new.add((i, None))
            elif p == ("line",):
                if b not in (10, 13):
                    new.add((i, None))
            elif p[0] == "int":
                s = (aux or b"") + bytes([b])
                if _int_viable(s, p[1], p[2]):
                    new.add((i, s))
            elif p[0] == "bin":
                _, width, signed, lo, hi = p
                if width == 1:
                    v = _signed(b, 1) if signed else b
                    if lo <= v <= hi:
                        new.add((i + 1, None))
                elif aux is None:
                    h = _signed(b, 1) if signed else b
                    if h * 256 <= hi and h * 256 + 255 >= lo:
                        new.add((i, b))
                else:
                    v = aux * 256 + b
                    if signed:
                        v = _signed(v, 2)
                    if lo <= v <= hi:
                        new.add((i + 1, None))
        self.states = self._closure(new)
        if not self.states:
            return DEAD
        return COMPLETE if self.is_complete() else ALIVE


def match_prefix(pieces, data):
    """(COMPLETE, length) for the shortest matching prefix of `data`, (DEAD, offset) where it
    parts, or (ALIVE, len(data)) when more bytes are needed."""
    m = Matcher(pieces)
    if m.is_complete():
        return COMPLETE, 0
    for k, b in enumerate(data):
        r = m.feed(b)
        if r == DEAD:
            return DEAD, k
        if r == COMPLETE:
            return COMPLETE, k + 1
    return ALIVE, len(data)
