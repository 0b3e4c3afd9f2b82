"""Replaying golden transcripts against a hand, as vectors/README.md describes: the same
verdicts (PASS, FAIL, TIMEOUT, ERROR) and exit codes (0, 1, 2) as `gcl replay`."""

import time

from .links import Disconnected
from .matcher import ALIVE, COMPLETE, DEAD, Matcher

DRAIN_QUIET = 0.1
DRAIN_LIMIT = 5.0
TRAILING = 0.05
EXEC_BANNER_WAIT = 5.0
# The most bytes one step's answer may hold before the hand counts as flooding (FAIL), and
# the most of an answer a message shows: a flood costs neither memory nor a screenful.
MAX_ANSWER = 1 << 20
SHOWN = 200


def escape(data):
    out = []
    for b in data:
        if b == 10:
            out.append("\\n")
        elif b == 13:
            out.append("\\r")
        elif b == 9:
            out.append("\\t")
        elif b == 92:
            out.append("\\\\")
        elif 0x20 <= b <= 0x7E and b not in (0x22, 0x7B):
            out.append(chr(b))
        else:
            out.append("\\x%02X" % b)
    return "".join(out)


def show(data, hex_form):
    """Bytes as a report shows them: hex pairs for a hex expectation, else an escaped string;
    at most SHOWN bytes, then a count of the rest."""
    more = " and %d more bytes" % (len(data) - SHOWN) if len(data) > SHOWN else ""
    data = data[:SHOWN]
    if hex_form:
        return " ".join("%02X" % b for b in data) + more
    return '"%s"' % escape(data) + more


def aligned(golden, got, at):
    """The golden as written and the actual answer, both from byte 0, with a caret under the
    parting byte of the actual one (`at`; None: nothing more came): the notation `gcl replay`,
    `gcl conform` and the reports use."""
    hex_form = golden.startswith("hex")
    lines = "  golden:   %s\n  actual:   %s" % (golden, show(got, hex_form))
    if at is None:
        return lines + "  (nothing more came)"
    if hex_form:
        col = len(show(got[:at], True)) + (1 if at > 0 else 0)
    else:
        col = len(show(got[:at], False)) - 1
    return lines + "\n            %s^ byte %d" % (" " * col, at)


def drain(link, quiet=DRAIN_QUIET, limit=DRAIN_LIMIT):
    """Reads and discards until the hand has been quiet for `quiet` seconds (at most `limit`)."""
    end = time.monotonic() + limit
    while time.monotonic() < end:
        if not link.recv(min(quiet, max(end - time.monotonic(), 0))):
            return


def wait_banner(link):
    """A freshly started process prints its banner when ready: wait for it, then drain."""
    link.recv(EXEC_BANNER_WAIT)
    drain(link)


class Outcome:
    def __init__(self, verdict, steps, detail=""):
        self.verdict = verdict  # PASS, FAIL, TIMEOUT, ERROR
        self.steps = steps
        self.detail = detail


def _where(i, step):
    return "step %d (line %d)" % (i + 1, step.line)


def replay(t, link, default_timeout=2.0, resync=False):
    """Runs one transcript over `link` and returns its Outcome."""
    try:
        if resync:
            link.send(b"\x03")
        drain(link)
        buf = b""
        captured = {}  # values the answers captured, for the relations of later answers
        for i, step in enumerate(t.steps):
            if step.pause:
                time.sleep(step.pause)
            if step.send:
                link.send(step.send)
            timeout = step.within if step.within is not None else default_timeout
            started = time.monotonic()
            deadline = started + timeout
            m = Matcher(step.expect, captured)
            fed = 0
            while not m.is_complete():
                r = ALIVE
                while fed < len(buf) and r == ALIVE:
                    r = m.feed(buf[fed])
                    fed += 1
                if r == COMPLETE:
                    break
                if r == DEAD:
                    return Outcome(
                        "FAIL",
                        i,
                        "%s: the answer parts from the expectation at byte %d\n%s"
                        % (_where(i, step), fed - 1, aligned(step.expect_text, buf, fed - 1)),
                    )
                left = deadline - time.monotonic()
                if left <= 0:
                    return Outcome(
                        "TIMEOUT",
                        i,
                        "%s: no complete answer within %gs (%d bytes so far)\n%s"
                        % (_where(i, step), timeout, len(buf), aligned(step.expect_text, buf, None)),
                    )
                if len(buf) > MAX_ANSWER:
                    return Outcome(
                        "FAIL",
                        i,
                        "%s: the hand sent more than %d bytes without completing its answer (a flood)\n  expected: %s\n  actual:   %s"
                        % (_where(i, step), MAX_ANSWER, step.expect_text, show(buf, step.expect_text.startswith("hex"))),
                    )
                buf += link.recv(left)
            took = time.monotonic() - started
            if step.earliest is not None and took < step.earliest:
                return Outcome(
                    "FAIL",
                    i,
                    "%s: the answer was complete after %gs, sooner than its window's %gs\n  expected: %s\n  actual:   %s"
                    % (_where(i, step), took, step.earliest, step.expect_text, show(buf[:fed], step.expect_text.startswith("hex"))),
                )
            captured = m.captures() or captured
            buf = buf[fed:]
        buf += link.recv(TRAILING)
        if buf:
            last = len(t.steps) - 1
            return Outcome(
                "FAIL", last, "after the last step the hand sent more: %s" % show(buf, False)
            )
        return Outcome("PASS", len(t.steps))
    except Disconnected as e:
        return Outcome("ERROR", 0, "the link failed: %s" % e)
