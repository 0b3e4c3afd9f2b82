"""The gcl pytest plugin (entry point ``pytest11``): simulated hands that grade your host
code.

``gcl_hand``: a running ``gcl check-host --serve`` for the test, on a pty (or a loopback TCP
port with ``tcp=True``); ``gcl_hand.port`` is the port's path (or ``127.0.0.1:N``),
``gcl_hand.url`` a pyserial URL for it. When the test body ends, the hand grades the traffic
clause by clause, as ``gcl check-host`` does, and a test whose host code broke a clause
fails with the clause, what was wrong and the session.

``gcl_misbehaving_hand``: the same under misbehaviours; the test runs once per seeded
schedule (``schedules``, default 3: the schedules an unguided ``gcl fuzz host --seed SEED``
campaign draws for its runs 1..N, planned within the first 10 answers). Wrap what may meet a broken answer in ``gcl_misbehaving_hand.tolerate(MyError)``:
a host that reports a broken hand with its own error is doing its job; any other exception,
a hang past ``timeout`` seconds, or a broken clause fails the test, with the misbehaviours
that fired.

Options, per test with ``@pytest.mark.gcl(...)`` or for the run on the command line:
``profile`` (``--gcl-profile``, default bh8-262), ``baud``, ``time`` ("fast" or "real"),
``fault`` (a deliberate firmware bug, or a list), ``tcp``, ``seed`` (``--gcl-seed``, a whole
number from 0 to 2^64 - 1), ``schedules`` (``--gcl-schedules``, a whole number from 1 to
10000), ``ops`` (which
misbehaviours, as ``gcl fuzz host --ops``), ``timeout`` (seconds, more than 0, default 20,
misbehaving hands only), ``allow`` (clause ids a test breaks on purpose, such as
``["host-valid-commands"]`` for a test that sends an unknown command to see it refused). A
value out of range fails the test at collection (``schedules``, ``seed``, ``timeout``) or at setup,
naming it; it is never taken as "no schedule" or "no timer".

The hang timer is SIGALRM's real-time timer, shared: a timer already running when the test
body starts (``pytest-timeout``'s, or your own) keeps its deadline and its handler, which
runs when that deadline comes first; the timer is re-armed for what is left of it when the
body ends.

A ``pytest_runtest_call`` wrapper grades the hand when the test body ends, so a broken clause
fails the test itself, not its teardown; it runs the hang timer alongside a timer already
there, never in place of it. A test that skips or xfails itself (``pytest.skip()``,
``pytest.xfail()``) is reported so, ungraded; Ctrl-C (or ``pytest.exit()``) stops the hand and
the session as pytest stops it, never as a failed test.

While a hand runs, SIGTERM (what CI runners and ``timeout`` send) stops the session as Ctrl-C
does, so that every hand is stopped and its temporary folder removed; pytest then ends by
SIGTERM, as it was asked to. Only where SIGTERM had no handler of its own (yours is left
alone), and a second SIGTERM ends the process at once.
"""

import contextlib
import math
import os
import re
import signal
import threading
import time

import pytest

from ._hand import Hand, HandError

FIXTURES = ("gcl_hand", "gcl_misbehaving_hand")
HAND_OPTIONS = ("profile", "baud", "time", "fault", "tcp", "seed")


class HostHang(Exception):
    """The host code neither returned nor failed within the test's timeout."""


class Terminated(KeyboardInterrupt):
    """SIGTERM came while a hand ran: the session stops as at Ctrl-C (see the module's notes)."""


#: The most schedules a test runs under (each is a run of the test).
MAX_SCHEDULES = 10000


def _whole(value, name, least, most, what):
    """``value`` as a whole number from ``least`` to ``most`` (an int, or a string of ASCII
    digits), else a ValueError naming ``name``."""
    text = str(value).strip() if isinstance(value, (int, str)) and not isinstance(value, bool) else ""
    if not re.fullmatch(r"[0-9]{1,20}", text) or not least <= int(text) <= most:
        raise ValueError("{}={!r}: give {}".format(name, value, what))
    return int(text)


def _schedules(value):
    """``schedules``: a whole number of at least 1 (0 would run the test under no schedule)."""
    return _whole(value, "schedules", 1, MAX_SCHEDULES,
                  "a whole number of schedules, at least 1 (at most {})".format(MAX_SCHEDULES))


def _seed(value):
    """``seed``: what ``gcl fuzz host --seed`` takes, a whole number from 0 to 2^64 - 1."""
    return _whole(value, "seed", 0, 2 ** 64 - 1, "a whole number from 0 to 2^64 - 1")


def _timeout(value):
    """``timeout``: seconds, more than 0 (0 would turn the hang timer off)."""
    try:
        seconds = float(value)
    except (TypeError, ValueError):
        seconds = float("nan")
    if isinstance(value, bool) or not (seconds > 0) or math.isinf(seconds):
        raise ValueError("timeout={!r}: give the hang timeout in seconds, more than 0".format(value))
    return seconds


def _option_type(check):
    def parse(text):
        try:
            return check(text)
        except ValueError as e:
            import argparse
            raise argparse.ArgumentTypeError(str(e)) from None
    parse.__name__ = check.__name__.strip("_")
    return parse


def pytest_addoption(parser):
    group = parser.getgroup("gcl", "gcl simulated hands")
    group.addoption("--gcl-profile", default=None, help="profile of gcl_hand (default bh8-262)")
    group.addoption("--gcl-seed", type=_option_type(_seed), default=None,
                    help="seed of the misbehaviour schedules (default 0)")
    group.addoption("--gcl-schedules", type=_option_type(_schedules), default=None,
                    help="schedules each gcl_misbehaving_hand test runs under (default 3, at least 1)")


def pytest_configure(config):
    config.addinivalue_line(
        "markers",
        "gcl(profile=, baud=, time=, fault=, tcp=, seed=, schedules=, ops=, timeout=, allow=): "
        "options of the gcl_hand and gcl_misbehaving_hand fixtures")


def _marker(node):
    m = node.get_closest_marker("gcl")
    return dict(m.kwargs) if m else {}


def _setting(config, marker, name, default):
    if name in marker:
        return marker[name]
    value = config.getoption("--gcl-" + name, None)
    return default if value is None else value


def pytest_generate_tests(metafunc):
    if "gcl_misbehaving_hand" not in metafunc.fixturenames:
        return
    marker = _marker(metafunc.definition)
    refused = None
    try:
        n = _schedules(_setting(metafunc.config, marker, "schedules", 3))
        _timeout(marker.get("timeout", 20))
        seed = _seed(_setting(metafunc.config, marker, "seed", 0))
    except ValueError as e:
        refused = "gcl: {}: {}".format(metafunc.definition.nodeid, e)
    if refused:
        pytest.fail(refused, pytrace=False)
    metafunc.parametrize("gcl_misbehaving_hand", [(seed, i) for i in range(1, n + 1)], indirect=True,
                         ids=["schedule-{}:{}".format(seed, i) for i in range(1, n + 1)])


def _hand(request, misbehave=None):
    marker = _marker(request.node)
    options = {k: marker[k] for k in HAND_OPTIONS if k in marker}
    options["profile"] = _setting(request.config, marker, "profile", "bh8-262")
    if misbehave is not None:
        options["misbehave"] = misbehave
        options["ops"] = marker.get("ops")
    try:
        timeout, refused = _timeout(marker.get("timeout", 20)), None
    except ValueError as e:
        refused = "gcl: {}".format(e)
    if refused:
        pytest.fail(refused, pytrace=False)
    hand = Hand(name=request.node.nodeid, **options)
    hand.timeout = timeout
    hand.start()
    return hand


class _Sigterm:
    """SIGTERM as :class:`Terminated` while hands run (see the module's notes)."""

    hands = 0
    installed = False
    received = False

    @classmethod
    def on_sigterm(cls, signum, frame):
        if cls.received:
            # A second one: at once.
            signal.signal(signal.SIGTERM, signal.SIG_DFL)
            os.kill(os.getpid(), signal.SIGTERM)
            return
        cls.received = True
        raise Terminated("SIGTERM")

    @classmethod
    @contextlib.contextmanager
    def while_a_hand_runs(cls):
        main = threading.current_thread() is threading.main_thread()
        if main and cls.hands == 0 and signal.getsignal(signal.SIGTERM) == signal.SIG_DFL:
            signal.signal(signal.SIGTERM, cls.on_sigterm)
            cls.installed = True
        cls.hands += 1
        try:
            yield
        finally:
            cls.hands -= 1
            if cls.hands == 0 and cls.installed and not cls.received:
                signal.signal(signal.SIGTERM, signal.SIG_DFL)
                cls.installed = False


def pytest_unconfigure(config):
    """After a SIGTERM the session stopped for: the process ends by it, once pytest is done."""
    if _Sigterm.received:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        os.kill(os.getpid(), signal.SIGTERM)


@pytest.fixture
def gcl_hand(request):
    """A graded simulated hand (see the module's notes)."""
    with _Sigterm.while_a_hand_runs():
        hand = _hand(request)
        try:
            yield hand
        finally:
            hand.stop()


@pytest.fixture
def gcl_misbehaving_hand(request):
    """A graded simulated hand that misbehaves by a seeded schedule (see the module's notes)."""
    with _Sigterm.while_a_hand_runs():
        hand = _hand(request, misbehave=request.param)
        try:
            yield hand
        finally:
            hand.stop()


def _graded_hand(item):
    funcargs = getattr(item, "funcargs", {})
    for name in FIXTURES:
        if name in funcargs:
            return funcargs[name]
    return None


def _verdict(item, hand):
    """Stops the hand; its verdict without the clauses the test allows itself to break."""
    verdict = hand.stop()
    if verdict is not None:
        allowed = set(_marker(item).get("allow", ()))
        verdict.failures = [f for f in verdict.failures if f.id not in allowed]
    return verdict


class _HangTimer:
    """The hang timer on SIGALRM's real-time timer, sharing it with whoever had it: the timer
    goes off at the earlier of the two deadlines; at the host's, :class:`HostHang` is raised; at
    the other, the handler that was there runs (``pytest-timeout`` fails the test) and the
    hang timer goes on. When the body ends the handler is put back, and a timer that was
    running is re-armed for what is left of it."""

    def __init__(self, seconds):
        self.previous = signal.getsignal(signal.SIGALRM)
        remaining, self.interval = signal.getitimer(signal.ITIMER_REAL)
        now = time.monotonic()
        self.deadline = now + seconds
        self.theirs = now + remaining if remaining > 0 else None
        signal.signal(signal.SIGALRM, self._on_alarm)
        self._arm(now)

    def _arm(self, now):
        left = [d - now for d in (self.deadline, self.theirs) if d is not None]
        signal.setitimer(signal.ITIMER_REAL, max(min(left), 1e-6))

    def _on_alarm(self, signum, frame):
        now = time.monotonic()
        if now >= self.deadline:
            raise HostHang()
        if self.theirs is not None and now >= self.theirs:
            # Theirs came first: their handler runs, as if nothing stood between.
            self.theirs = None
            self._arm(now)
            if callable(self.previous):
                self.previous(signum, frame)
            elif self.previous == signal.SIG_DFL:
                self.restore()
                os.kill(os.getpid(), signal.SIGALRM)
            return
        self._arm(now)

    def restore(self):
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, self.previous)
        if self.theirs is not None:
            signal.setitimer(signal.ITIMER_REAL, max(self.theirs - time.monotonic(), 1e-6), self.interval)
            self.theirs = None


def _what_failed(verdict):
    """How a failing verdict begins: the clauses the host code broke, or, for a session in
    which nobody talked to the hand (its ``host-session`` ERROR), that nothing was judged."""
    ids = [f.id for f in verdict.failures]
    if ids == ["host-session"]:
        return "nothing of the host code was judged: it never talked to the hand (host-session)"
    return "the host code broke GCL ({})".format(", ".join(ids))


@pytest.hookimpl(wrapper=True)
def pytest_runtest_call(item):
    """Runs the test body (under a hang timer for a misbehaving hand), then stops its hand and
    fails the test on a broken clause."""
    hand = _graded_hand(item)
    if hand is None:
        return (yield)
    timer = None
    if hand.misbehave is not None and threading.current_thread() is threading.main_thread():
        timer = _HangTimer(hand.timeout)
    try:
        result = yield
    except (pytest.skip.Exception, pytest.xfail.Exception, pytest.exit.Exception, KeyboardInterrupt):
        # The test chose its outcome (skip, xfail), or the run is being stopped (Ctrl-C,
        # SIGTERM, pytest.exit()): ungraded, and what was raised goes on as it is (it was made
        # a failure, and the session ran on after Ctrl-C). The hand is stopped; a hand that
        # was interrupted too (Ctrl-C reaches the whole process group) says nothing more.
        try:
            hand.stop()
        except HandError:
            pass
        raise
    except HostHang:
        verdict = _verdict(item, hand)
        raise pytest.fail.Exception("the host code hung: no return within {:.0f} s{}\n{}".format(
            hand.timeout, " under misbehaviour" if hand.misbehave else "", verdict.explain()), pytrace=False) from None
    except BaseException as e:
        verdict = _verdict(item, hand)
        if verdict is not None and verdict.failures:
            # The broken clause is the root cause; what the test raised followed from it.
            raise pytest.fail.Exception("{}; the test then failed with {}: {}\n{}".format(
                _what_failed(verdict), type(e).__name__, e, verdict.explain()), pytrace=False) from None
        if verdict is not None and verdict.fired:
            item.add_report_section("call", "gcl hand", verdict.explain())
        raise
    finally:
        if timer:
            timer.restore()
    verdict = _verdict(item, hand)
    if verdict.failures:
        pytest.fail("{}:\n{}".format(_what_failed(verdict), verdict.explain()), pytrace=False)
    return result
