"""Golden transcripts (`gcl-transcript 1`), parsed from text as vectors/README.md section 1
describes them. Untrusted input: every problem is a TranscriptError with a line number."""

import re

MAX_FILE = 4 * 1024 * 1024
DEFAULT_STEP_TIMEOUT = 2.0  # seconds, for a step without `within`
MAX_DURATION = 24 * 3600.0
SLUG = re.compile(r"^[a-z0-9][a-z0-9._-]*$")
LEVELS = ("MUST", "SHOULD", "MAY", "INFO")
INT_LIMIT = 10**18 - 1  # 1 to 18 digits


class TranscriptError(Exception):
    """A transcript that does not follow the format."""

    def __init__(self, line, message):
        super().__init__("line %d: %s" % (line, message) if line else message)
        self.line = line


# Pieces of an expectation. A literal byte is an int; the others are tuples.
BYTE = ("byte",)
LINE = ("line",)
ANY = ("any",)
# One or more whole lines of text, none a status answer (README 1.5): at least one byte
# other than LF and CR, and no line among its bytes begins with `ERR`.
TEXT = ("text",)


def int_piece(lo=-INT_LIMIT, hi=INT_LIMIT):
    return ("int", lo, hi)


def bin_piece(width, signed, lo, hi):
    return ("bin", width, signed, lo, hi)


def value_piece(base, relation, capture):
    """An int or bin piece that is captured under a name, or held to a relation with a value
    captured before (relation = (name, num, den, percent)), or both."""
    return ("value", base, relation, capture)


NAME = re.compile(r"^[a-z][a-z0-9_]{0,31}$")
FACTOR = r"[1-9][0-9]{0,6}"


def relation_band(relation, v):
    """The values a relation accepts when its captured value is v: E = v * num / den exactly,
    the band E -+ |E| * percent / 100 rounded outward to whole numbers (vectors/README.md 1.5)."""
    _, num, den, pct = relation
    e = v * num
    d = den * 100
    a, b = e * (100 - pct), e * (100 + pct)
    lo, hi = (a, b) if e >= 0 else (b, a)
    return lo // d, -((-hi) // d)


class Step:
    def __init__(self, line):
        self.line = line  # the transcript line of the step's first directive
        self.pause = None  # seconds
        self.send = None  # bytes
        self.within = None  # seconds
        self.earliest = None  # seconds: a timing window's lower bound
        self.expect = []  # pieces
        self.expect_text = ""  # as written, for reports
        self.has_expect = False


class Transcript:
    def __init__(self):
        self.header = {}  # key -> list of values
        self.steps = []

    @property
    def id(self):
        return self.header["id"][0]

    @property
    def profiles(self):
        return [p.strip() for v in self.header.get("profile", []) for p in v.split(",") if p.strip()]

    @property
    def requires(self):
        return [p.strip() for v in self.header.get("requires", []) for p in v.split(",") if p.strip()]

    @property
    def setup(self):
        """The `setup:` lines as (kind, motor, position): ("object", 1, 8500)."""
        return [("object", int(v.split()[1]), int(v.split()[2])) for v in self.header.get("setup", [])]


MAX_OBJECT_POSITION = 1000000


def _check_setup(value, lineno):
    m = re.fullmatch(r"object[ \t]+([1-4])[ \t]+(0|[1-9][0-9]{0,6})", value)
    if not m or int(m.group(2)) > MAX_OBJECT_POSITION:
        raise TranscriptError(lineno, "bad setup `%s` (object MOTOR POSITION: motor 1..4, position 0..%d)" % (value, MAX_OBJECT_POSITION))
    return int(m.group(1))


def parse_duration(text, lineno):
    m = re.fullmatch(r"(\d+)(ms|s)", text)
    if not m:
        raise TranscriptError(lineno, "bad duration `%s` (a whole number then ms or s)" % text)
    v = int(m.group(1)) / (1000.0 if m.group(2) == "ms" else 1.0)
    if v > MAX_DURATION:
        raise TranscriptError(lineno, "duration `%s` is longer than 24 h" % text)
    return v


def _parse_range(text, lineno, lo_limit=-INT_LIMIT, hi_limit=INT_LIMIT):
    m = re.fullmatch(r"(-?\d+)\.\.(-?\d+)", text)
    if not m:
        raise TranscriptError(lineno, "bad range `%s` (A..B)" % text)
    lo, hi = int(m.group(1)), int(m.group(2))
    if lo > hi:
        raise TranscriptError(lineno, "range `%s` is not ordered" % text)
    if lo < lo_limit or hi > hi_limit:
        raise TranscriptError(lineno, "range `%s` does not fit the field" % text)
    return lo, hi


def _parse_relation(term, tol, lineno):
    m = re.fullmatch(r"([a-z][a-z0-9_]*)(?:\*(%s))?(?:/(%s))?" % (FACTOR, FACTOR), term)
    t = re.fullmatch(r"\+-(0|[1-9][0-9]{0,2})%", tol)
    if not m or not t or not NAME.match(m.group(1)) or int(t.group(1)) > 100:
        raise TranscriptError(lineno, "bad relation `%s %s` (NAME[*N][/D] +-P%%)" % (term, tol))
    num, den = int(m.group(2) or 1), int(m.group(3) or 1)
    if num > 1000000 or den > 1000000:
        raise TranscriptError(lineno, "a relation's factors are 1..1000000")
    return (m.group(1), num, den, int(t.group(1)))


def parse_elision(body, lineno):
    """The inside of `{...}` as a piece: KIND [CONSTRAINT] [as NAME]."""
    words = body.split(" ")
    if not words or not words[0]:
        raise TranscriptError(lineno, "empty elision {}")
    capture = None
    if len(words) >= 3 and words[-2] == "as":
        if not NAME.match(words[-1]):
            raise TranscriptError(lineno, "bad capture name `%s`" % words[-1])
        capture = words[-1]
        words = words[:-2]
    name, rest = words[0], words[1:]
    if name in ("line", "any", "text", "byte") and not rest and capture is None:
        return {"line": LINE, "any": ANY, "text": TEXT, "byte": BYTE}[name]
    relation = None
    if len(rest) == 2:
        relation = _parse_relation(rest[0], rest[1], lineno)
    if name == "int" and len(rest) != 2:
        if not rest:
            base = int_piece()
        elif len(rest) == 1:
            base = int_piece(*_parse_range(rest[0], lineno))
        else:
            raise TranscriptError(lineno, "unknown elision {%s}" % body)
    elif name == "int":
        base = int_piece()
    elif name in ("u8", "i8", "u16", "i16") and len(rest) <= 2:
        width = 1 if name.endswith("8") else 2
        signed = name[0] == "i"
        bits = width * 8
        lo_l, hi_l = (-(1 << (bits - 1)), (1 << (bits - 1)) - 1) if signed else (0, (1 << bits) - 1)
        if len(rest) == 1:
            lo, hi = _parse_range(rest[0], lineno, lo_l, hi_l)
        elif rest or capture is not None:
            lo, hi = lo_l, hi_l
        else:
            raise TranscriptError(lineno, "{%s} needs a range" % body)
        base = bin_piece(width, signed, lo, hi)
    else:
        raise TranscriptError(lineno, "unknown elision {%s}" % body)
    if relation is None and capture is None:
        return base
    return value_piece(base, relation, capture)


def _is_int(piece):
    return isinstance(piece, tuple) and (piece[0] == "int" or (piece[0] == "value" and piece[1][0] == "int"))


ESCAPES = {"n": 10, "r": 13, "t": 9, "\\": 92}


def _parse_string(text, i, lineno, allow_elisions):
    """A quoted string starting at text[i] == '"'; returns (pieces, next index)."""
    pieces = []
    i += 1
    while True:
        if i >= len(text):
            raise TranscriptError(lineno, "unterminated string")
        c = text[i]
        if c == '"':
            return pieces, i + 1
        if c == "\\":
            e = text[i + 1 : i + 2]
            if e in ESCAPES:
                pieces.append(ESCAPES[e])
                i += 2
            elif e == "x" and re.fullmatch(r"[0-9A-Fa-f]{2}", text[i + 2 : i + 4] or ""):
                pieces.append(int(text[i + 2 : i + 4], 16))
                i += 4
            else:
                raise TranscriptError(lineno, "bad escape `\\%s`" % e)
        elif c == "{":
            if not allow_elisions:
                raise TranscriptError(lineno, "`{` in a send string (write \\x7B)")
            end = text.find("}", i)
            if end < 0:
                raise TranscriptError(lineno, "unterminated elision")
            pieces.append(parse_elision(text[i + 1 : end], lineno))
            i = end + 1
        elif 0x20 <= ord(c) <= 0x7E:
            pieces.append(ord(c))
            i += 1
        else:
            raise TranscriptError(lineno, "unescaped character %r in a string" % c)


def parse_segments(text, lineno, allow_elisions):
    """Strings and hex segments, one after the other, as one list of pieces."""
    pieces = []
    i = 0
    n = len(text)
    while True:
        while i < n and text[i] == " ":
            i += 1
        if i >= n:
            return pieces
        if text[i] == '"':
            p, i = _parse_string(text, i, lineno, allow_elisions)
            pieces.extend(p)
        elif text.startswith("hex", i) and (i + 3 == n or text[i + 3] == " "):
            i += 3
            any_token = False
            while True:
                while i < n and text[i] == " ":
                    i += 1
                if i >= n or text[i] == '"' or (text.startswith("hex", i) and (i + 3 == n or text[i + 3] == " ")):
                    break
                if text[i] == "{":
                    end = text.find("}", i)
                    if end < 0 or not allow_elisions:
                        raise TranscriptError(lineno, "bad elision in a hex segment")
                    pieces.append(parse_elision(text[i + 1 : end], lineno))
                    i = end + 1
                else:
                    j = i
                    while j < n and text[j] != " ":
                        j += 1
                    tok = text[i:j]
                    if tok == "??" and allow_elisions:
                        pieces.append(BYTE)
                    elif re.fullmatch(r"[0-9A-Fa-f]{2}", tok):
                        pieces.append(int(tok, 16))
                    else:
                        raise TranscriptError(lineno, "bad hex token `%s`" % tok)
                    i = j
                any_token = True
            if not any_token:
                raise TranscriptError(lineno, "empty hex segment")
        else:
            raise TranscriptError(lineno, "expected a string or `hex`, found `%s`" % text[i:])


def parse(data):
    """Parses transcript bytes (or text) into a Transcript."""
    if isinstance(data, str):
        data = data.encode("utf-8")
    if len(data) > MAX_FILE:
        raise TranscriptError(0, "file larger than 4 MiB")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as e:
        raise TranscriptError(0, "not UTF-8: %s" % e)
    t = Transcript()
    seen_version = False
    in_header = True
    step = None
    captured = set()  # names captured so far, for the relations of later pieces
    for lineno, raw in enumerate(text.split("\n"), start=1):
        if raw.endswith("\r"):
            raw = raw[:-1]
        line = raw.strip(" ")
        if not line or line.startswith("#"):
            continue
        if not seen_version:
            if line != "gcl-transcript 1":
                raise TranscriptError(lineno, "the first line must be `gcl-transcript 1`")
            seen_version = True
            continue
        word = line.split(" ", 1)[0]
        rest = line[len(word) :].strip(" ")
        if in_header and word not in ("pause", "send", "expect"):
            m = re.fullmatch(r"([a-z][a-z0-9-]*):(.*)", line)
            if not m:
                raise TranscriptError(lineno, "expected a header line `key: value` or a step")
            key, value = m.group(1), m.group(2).strip()
            if key not in ("id", "title", "clause", "level", "profile", "requires", "setup", "note") and not key.startswith("x-"):
                raise TranscriptError(lineno, "unknown header key `%s`" % key)
            if not value or any(ord(c) < 0x20 or ord(c) == 0x7F for c in value):
                raise TranscriptError(lineno, "empty value or control characters in `%s`" % key)
            if key == "setup":
                motor = _check_setup(value, lineno)
                if any(m == motor for _, m, _ in t.setup):
                    raise TranscriptError(lineno, "motor %d already has an object" % motor)
            t.header.setdefault(key, []).append(value)
            continue
        in_header = False
        if word == "pause":
            if step is not None:
                t.steps.append(step)
            step = Step(lineno)
            step.pause = parse_duration(rest, lineno)
        elif word == "send":
            if step is not None and step.send is not None:
                t.steps.append(step)
                step = None
            if step is None:
                step = Step(lineno)
            pieces = parse_segments(rest, lineno, allow_elisions=False)
            step.send = bytes(pieces)
        elif word == "expect":
            if step is None:
                step = Step(lineno)
            m = re.match(r"within +(\S+) *(.*)$", rest)
            if m:
                window = m.group(1)
                if ".." in window:
                    # A timing window: no sooner than its lower bound, no later than its upper.
                    lower, upper = window.split("..", 1)
                    step.earliest = parse_duration(lower, lineno)
                    step.within = parse_duration(upper, lineno)
                    if step.earliest > step.within:
                        raise TranscriptError(lineno, "timing window `%s`: its lower bound is above its upper" % window)
                else:
                    step.within = parse_duration(window, lineno)
                rest = m.group(2)
            step.expect = parse_segments(rest, lineno, allow_elisions=True)
            if step.expect and (step.expect[-1] in (LINE, ANY, TEXT) or _is_int(step.expect[-1])):
                raise TranscriptError(lineno, "an expect must not end with {int}, {line}, {any} or {text}")
            for k, piece in enumerate(step.expect):
                # {text} stands for whole lines: a line break before it (unless it begins the
                # expectation) and after it.
                if piece == TEXT and not (
                    (k == 0 or step.expect[k - 1] in (10, 13)) and k + 1 < len(step.expect) and step.expect[k + 1] in (10, 13)
                ):
                    raise TranscriptError(lineno, "{text} must stand between line breaks")
            for piece in step.expect:
                if isinstance(piece, tuple) and piece[0] == "value":
                    _, _, relation, capture = piece
                    if relation is not None and relation[0] not in captured:
                        raise TranscriptError(lineno, "`%s` is not captured before it is used" % relation[0])
                    if capture is not None:
                        if capture in captured:
                            raise TranscriptError(lineno, "`%s` is captured twice" % capture)
                        captured.add(capture)
            step.expect_text = rest
            step.has_expect = True
            t.steps.append(step)
            step = None
        else:
            raise TranscriptError(lineno, "unknown directive `%s` (header lines come before the first step)" % word)
    if step is not None:
        t.steps.append(step)
    if not seen_version:
        raise TranscriptError(0, "empty file: no `gcl-transcript 1` line")
    for key in ("id", "title", "level"):
        if len(t.header.get(key, [])) != 1:
            raise TranscriptError(0, "the header needs exactly one `%s`" % key)
    for key in ("clause", "profile"):
        if not t.header.get(key):
            raise TranscriptError(0, "the header needs at least one `%s`" % key)
    if not SLUG.match(t.id) or len(t.id) > 100:
        raise TranscriptError(0, "bad id `%s`" % t.id)
    if t.header["level"][0].upper() not in LEVELS:
        raise TranscriptError(0, "bad level `%s`" % t.header["level"][0])
    if t.setup and "object" not in t.requires:
        raise TranscriptError(0, "a case with a setup requires `object` (add it to `requires:`)")
    return t
