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
``fault`` (a deliberate firmware bug, or a list), ``tcp``, ``seed`` (``--gcl-seed``),
``schedules`` (``--gcl-schedules``, a whole number, at least 1), ``ops`` (which
misbehaviours, as ``gcl fuzz host --ops``), ``timeout`` (seconds, more than 0, default 20,
misbehaving hands only), ``allow`` (clause ids a test breaks on purpose, such as
``["host-valid-commands"]`` for a test that sends an unknown command to see it refused). A
value out of range fails the test at collection (``schedules``, ``timeout``) or at setup,
naming it; it is never taken as "no schedule" or "no timer".

The hang timer is SIGALRM's real-time timer, shared: a timer already running when the test
body starts (``pytest-timeout``'s, or your own) keeps its deadline and its handler, which
runs when that deadline comes first; the timer is re-armed for what is left of it when the
body ends.

A ``pytest_runtest_call`` wrapper grades the hand when the test body ends, so a broken clause
fails the test itself, not its teardown; it runs the hang timer alongside a timer already
there, never in place of it.
"""

import math
import os
import signal
import threading
import time

import pytest

from ._hand import Hand

FIXTURES = ("gcl_hand", "gcl_misbehaving_hand")
HAND_OPTIONS = ("profile", "baud", "time", "fault", "tcp", "seed")


class HostHang(Exception):
    """The host code neither returned nor failed within the test's timeout."""


def _schedules(value):
    """``schedules``: a whole number of at least 1 (0 would run the test under no schedule)."""
    if isinstance(value, bool) or not isinstance(value, (int, str)) or not str(value).strip().isdigit() \
            or int(value) < 1:
        raise ValueError("schedules={!r}: give a whole number of schedules, at least 1".format(value))
    return int(value)


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
    group.addoption("--gcl-seed", type=int, default=None, help="seed of the misbehaviour schedules (default 0)")
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
    except ValueError as e:
        refused = "gcl: {}: {}".format(metafunc.definition.nodeid, e)
    if refused:
        pytest.fail(refused, pytrace=False)
    seed = int(_setting(metafunc.config, marker, "seed", 0))
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


@pytest.fixture
def gcl_hand(request):
    """A graded simulated hand (see the module's notes)."""
    hand = _hand(request)
    yield hand
    hand.stop()


@pytest.fixture
def gcl_misbehaving_hand(request):
    """A graded simulated hand that misbehaves by a seeded schedule (see the module's notes)."""
    hand = _hand(request, misbehave=request.param)
    yield hand
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
