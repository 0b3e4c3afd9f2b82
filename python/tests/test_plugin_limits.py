"""The pytest plugin and ``gcl.Hand`` against what a user gets wrong and what a machine throws
at them (issue 32, item 8): a user's own test timeout (pytest-timeout) is kept, values out of
range are refused by name, a missing or foreign ``gcl`` and a hand that writes no report are a
``HandError`` at once, and no failed start leaves a ``gcl-hand-*`` folder behind. Issue 39,
item 15: Ctrl-C stops the session (it was a failed test, and the session ran on), a test that
skips or xfails itself is reported so, SIGTERM leaves no ``gcl-hand-*`` folder.

Run by .ci/run in the venv that holds the wheel (with pytest-timeout); in a checkout, with
``GCL_BIN`` naming a built gcl and the plugin on ``PYTEST_PLUGINS``. Each pytest run here is
bounded (``RUN_LIMIT``)."""

import os
import re
import signal
import subprocess
import sys
import tempfile
import textwrap
import time

import pytest

from gcl import Hand, HandError

#: The wall-clock bound of each pytest run these tests make, seconds.
RUN_LIMIT = 120


def run_pytest(tmp_path, files, *args):
    """pytest over ``files`` ({name: source}) in ``tmp_path``, as a user runs it."""
    for name, source in files.items():
        (tmp_path / name).write_text(textwrap.dedent(source))
    return subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-rA", *args],
                          cwd=str(tmp_path), stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          universal_newlines=True, timeout=RUN_LIMIT)


def outcome(out, test):
    """What pytest's summary says of ``test``: PASSED, FAILED, ERROR (a body that passed and a
    teardown that failed: both)."""
    return sorted(set(re.findall(r"^(PASSED|FAILED|ERROR) \S*::{}\b".format(re.escape(test)), out, re.M)))


TIMEOUTS = '''
import os
import select
import time
import pytest


def talk(hand):
    """The host code asks the hand one command, reads its answer for at most a second, and
    leaves (a session that exercised no clause judges nothing, and fails as such; a lone ^C
    exercises none: these tests are about the timers)."""
    fd = os.open(hand.port, os.O_RDWR | os.O_NOCTTY)
    os.write(fd, b"FGET DP\\r")
    got, end = b"", time.monotonic() + 1.0
    while not got.endswith(b"=> ") and time.monotonic() < end:
        ready, _, _ = select.select([fd], [], [], max(0.0, end - time.monotonic()))
        if not ready:
            break
        got += os.read(fd, 256)
    os.close(fd)


@pytest.mark.timeout(3)
@pytest.mark.gcl(profile="seed", schedules=1)
def test_body_overruns(gcl_misbehaving_hand):
    talk(gcl_misbehaving_hand)
    time.sleep(12)


@pytest.fixture
def slow_teardown():
    yield
    time.sleep(10)


@pytest.mark.timeout(4)
@pytest.mark.gcl(profile="seed", schedules=1)
def test_teardown_overruns(slow_teardown, gcl_misbehaving_hand):
    talk(gcl_misbehaving_hand)


@pytest.mark.timeout(60)
@pytest.mark.gcl(profile="seed", schedules=1, timeout=2)
def test_host_hangs(gcl_misbehaving_hand):
    talk(gcl_misbehaving_hand)
    time.sleep(30)
'''


def test_a_users_pytest_timeout_is_kept_under_a_misbehaving_hand(tmp_path):
    """pytest-timeout's timer (SIGALRM) still fails a body that overruns it, is re-armed for the
    teardown after the body, and the hand's own hang timer still fires when it comes first
    (before, the plugin took SIGALRM and disarmed the user's timer: all passed)."""
    try:
        import pytest_timeout  # noqa: F401
    except ImportError:
        assert os.environ.get("CI") != "true", "CI: pytest-timeout is missing (.ci/run installs it)"
        pytest.skip("pytest-timeout is missing (pip install pytest-timeout)")
    out = run_pytest(tmp_path, {"test_timeouts.py": TIMEOUTS}).stdout
    assert outcome(out, "test_body_overruns") == ["FAILED"], out
    assert "ERROR" in outcome(out, "test_teardown_overruns"), out
    assert out.count("Timeout (>") >= 2, out
    assert outcome(out, "test_host_hangs") == ["FAILED"], out
    assert "the host code hung: no return within 2 s under misbehaviour" in out, out


def test_values_out_of_range_are_refused_by_name(tmp_path):
    """``schedules=0`` or ``-2`` ran no schedule (SKIPPED, "got empty parameter set"),
    ``timeout=-1`` left the plugin's SIGALRM handler installed for the session, ``timeout=0``
    turned the hang timer off: each is now an error naming the value, and SIGALRM is left as
    it was."""
    bad = {
        "test_schedules_0.py": "schedules=0",
        "test_schedules_neg.py": "schedules=-2",
        "test_timeout_neg.py": "timeout=-1",
        "test_timeout_0.py": "timeout=0",
    }
    files = {
        name: '''
            import pytest

            @pytest.mark.gcl(profile="seed", {})
            def test_it(gcl_misbehaving_hand):
                pass
            '''.format(value)
        for name, value in bad.items()
    }
    files["test_zz_after.py"] = '''
        import signal

        def test_sigalrm_is_as_it_was():
            assert signal.getsignal(signal.SIGALRM) == signal.SIG_DFL
        '''
    # Not whole numbers as Python reads digits: a superscript two (whose int() failed naming
    # nothing), a schedule count past the bound (a billion tests collected), a negative seed.
    named = {
        "test_schedules_sup.py": ('schedules="\u00b2"', "schedules='\u00b2'"),
        "test_schedules_huge.py": ("schedules=10**9", "schedules=1000000000"),
        "test_seed_neg.py": ("seed=-1", "seed=-1"),
        "test_seed_sup.py": ('seed="\u00b2"', "seed='\u00b2'"),
    }
    for name, (source, _) in named.items():
        files[name] = files["test_schedules_0.py"].replace("schedules=0", source)
    out = run_pytest(tmp_path, files, "--continue-on-collection-errors").stdout
    assert "empty parameter set" not in out and "SKIPPED" not in out, out
    for name, value in bad.items():
        assert "ERROR collecting {}".format(name) in out, (value, out)
        assert "gcl: {}::test_it: {}: give".format(name, value) in out, (value, out)
    for name, (_, shown) in named.items():
        assert "ERROR collecting {}".format(name) in out, (shown, out)
        assert "gcl: {}::test_it: {}: give".format(name, shown) in out, (shown, out)
    assert outcome(out, "test_sigalrm_is_as_it_was") == ["PASSED"], out
    # On the command line too.
    usage = run_pytest(tmp_path, {}, "--gcl-schedules", "0", "test_zz_after.py")
    assert usage.returncode == 4 and "schedules='0'" in usage.stdout, usage.stdout


@pytest.fixture
def own_tmp(tmp_path, monkeypatch):
    """A temporary folder of the test's own, where the hand makes its report folder."""
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(tmp))
    return tmp


def fake_gcl(tmp_path, version, serve):
    """A program named gcl: ``version`` is what ``--version`` prints, ``serve`` the shell code
    that runs for anything else."""
    path = tmp_path / "bin" / "gcl"
    path.parent.mkdir(exist_ok=True)
    path.write_text('#!/bin/sh\nif [ "$1" = --version ]; then echo "{}"; exit 0; fi\n{}\n'.format(version, serve))
    path.chmod(0o755)
    return str(path)


def test_a_missing_binary_is_a_hand_error_and_leaves_no_folder(own_tmp, tmp_path, monkeypatch):
    missing = str(tmp_path / "no-such-gcl")
    monkeypatch.setenv("GCL_BIN", missing)
    with pytest.raises(HandError, match=re.escape(missing)):
        Hand(profile="seed").start()
    assert os.listdir(str(own_tmp)) == []


def test_a_hand_that_writes_no_report_is_a_hand_error_and_leaves_no_folder(own_tmp, tmp_path, monkeypatch):
    monkeypatch.setenv("GCL_BIN", fake_gcl(tmp_path, "gcl 0.1.0",
                                           "echo port /dev/null; echo url x; echo ready; cat >/dev/null"))
    hand = Hand(profile="seed").start()
    with pytest.raises(HandError, match="without a readable .*report.json"):
        hand.stop()
    assert os.listdir(str(own_tmp)) == []


def test_a_hand_that_fails_to_start_leaves_no_folder(own_tmp, tmp_path, monkeypatch):
    monkeypatch.setenv("GCL_BIN", fake_gcl(tmp_path, "gcl 0.1.0", "echo 'gcl: error: no such profile' >&2; exit 2"))
    with pytest.raises(HandError, match=r"ended \(2\) before it said where it listens: gcl: error: no such profile"):
        Hand(profile="seed").start()
    assert os.listdir(str(own_tmp)) == []


def test_a_hand_that_closes_its_output_and_then_fails_is_said_to_have_ended(own_tmp, tmp_path, monkeypatch):
    """Its output ends a moment before it can be waited for (so on a loaded machine, once):
    it ended with its code, not "did not say where it listens within 30 s"."""
    monkeypatch.setenv("GCL_BIN", fake_gcl(tmp_path, "gcl 0.1.0",
                                           "exec >&-; echo 'gcl: error: no such profile' >&2; sleep 1; exit 2"))
    with pytest.raises(HandError, match=r"ended \(2\) before it said where it listens: gcl: error: no such profile"):
        Hand(profile="seed").start()
    assert os.listdir(str(own_tmp)) == []


def test_another_program_named_gcl_is_refused_at_once(own_tmp, tmp_path, monkeypatch):
    """GNU Common Lisp is also `gcl`: its --version is asked first, so the hand is not waited
    for (before: 30 s, then "did not say where it listens")."""
    monkeypatch.setenv("GCL_BIN", fake_gcl(tmp_path, "GCL (GNU Common Lisp) 2.6.12", "sleep 60"))
    with pytest.raises(HandError, match=r"is not the gcl of gcl-harness: its --version says 'GCL \(GNU Common Lisp\)"):
        Hand(profile="seed").start()
    assert os.listdir(str(own_tmp)) == []


def run_pytest_until(tmp_path, files, started, act):
    """pytest over ``files`` in ``tmp_path``, in a session of its own with ``TMPDIR`` a folder of
    its own; once the file ``started`` exists (the first test is running), ``act(process)``;
    then its output, exit code and the ``gcl-hand-*`` folders left in its ``TMPDIR``."""
    for name, source in files.items():
        (tmp_path / name).write_text(textwrap.dedent(source))
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    env = dict(os.environ, TMPDIR=str(tmp))
    proc = subprocess.Popen([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-rA"], cwd=str(tmp_path),
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True, env=env,
                            start_new_session=True)
    try:
        deadline = time.monotonic() + RUN_LIMIT
        while not (tmp_path / started).exists():
            assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()[0]
            time.sleep(0.05)
        act(proc)
        out = proc.communicate(timeout=RUN_LIMIT)[0]
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    return out, proc.returncode, sorted(n for n in os.listdir(str(tmp)) if n.startswith("gcl-hand-"))


SLOW_TESTS = '''
import time
import pytest


@pytest.mark.gcl(profile="seed")
@pytest.mark.parametrize("n", [1, 2, 3])
def test_slow(gcl_hand, n):
    open("started-{}".format(n), "w").close()
    time.sleep(6)
'''


def test_ctrl_c_stops_the_session_and_fails_no_test(tmp_path):
    """Ctrl-C (SIGINT to pytest's process group, the hands' gcl too) during the first of three
    gcl_hand tests stops the session as pytest stops it (exit 2, "KeyboardInterrupt"); the test
    is not FAILED, the others never start, and no hand folder is left (before: the test, whose
    hand judged nothing yet, FAILED with the KeyboardInterrupt in its message, the two others
    ran, exit 1)."""
    out, code, left = run_pytest_until(tmp_path, {"test_slow.py": SLOW_TESTS}, "started-1",
                                       lambda p: os.killpg(p.pid, signal.SIGINT))
    assert code == 2 and "KeyboardInterrupt" in out, out
    assert "FAILED" not in out and "PASSED" not in out, out
    assert not (tmp_path / "started-2").exists(), out
    assert left == [], out


def test_sigterm_leaves_no_hand_folder_and_ends_pytest_by_it(tmp_path):
    """SIGTERM to pytest (as CI runners and ``timeout`` send it) while a hand runs: the hand is
    stopped, its folder removed, and pytest ends by SIGTERM (before: it died at once and its
    hand, reading the end of its input, wrote a report into a gcl-hand-* folder left behind)."""
    out, code, left = run_pytest_until(tmp_path, {"test_slow.py": SLOW_TESTS}, "started-1",
                                       lambda p: p.send_signal(signal.SIGTERM))
    assert code == -signal.SIGTERM, (code, out)
    assert left == [], out
    assert not (tmp_path / "started-2").exists(), out


def test_skip_and_xfail_inside_a_gcl_hand_test_are_reported_as_such(tmp_path):
    """``pytest.skip()`` and ``pytest.xfail()`` in a gcl_hand test, before it talks to the hand
    or after: SKIPPED and XFAIL, as without the plugin (they were FAILED: "nothing of the host
    code was judged ... the test then failed with Skipped")."""
    out = run_pytest(tmp_path, {"test_outcomes.py": '''
        import os
        import time
        import pytest


        def talk(hand):
            fd = os.open(hand.port, os.O_RDWR | os.O_NOCTTY)
            os.write(fd, b"\\x03")
            time.sleep(0.2)
            os.close(fd)


        @pytest.mark.gcl(profile="seed")
        def test_skips_at_once(gcl_hand):
            pytest.skip("no hand today")


        @pytest.mark.gcl(profile="seed")
        def test_skips_after_talking(gcl_hand):
            talk(gcl_hand)
            pytest.skip("seen enough")


        @pytest.mark.gcl(profile="seed")
        def test_xfails(gcl_hand):
            pytest.xfail("a known bug")


        @pytest.mark.gcl(profile="seed", schedules=1)
        def test_xfails_misbehaving(gcl_misbehaving_hand):
            talk(gcl_misbehaving_hand)
            pytest.xfail("a known bug")
        '''}, "-v").stdout
    got = dict(re.findall(r"^test_outcomes.py::(test_\S+) (\w+)", out, re.M))
    assert got == {"test_skips_at_once": "SKIPPED", "test_skips_after_talking": "SKIPPED", "test_xfails": "XFAIL",
                   "test_xfails_misbehaving[schedule-0:1]": "XFAIL"}, out


def test_a_verdict_shows_what_the_host_sent_escaped():
    """A host's bytes quoted in a verdict (its unknown command word, here an OSC that retitles
    the window, a screen clear and a right-to-left override) are shown escaped by ``str()``
    and ``explain()``, which the plugin's failures print: they reached the terminal raw."""
    hostile = b"A\x00\x1b]0;PWNED\x07\x1b[2J\xe2\x80\xae"
    hand = Hand(profile="seed").start()
    fd = os.open(hand.port, os.O_RDWR | os.O_NOCTTY)
    try:
        os.write(fd, b"\x03")
        time.sleep(0.3)
        os.write(fd, hostile + b"\r")
        time.sleep(0.5)
    finally:
        os.close(fd)
    verdict = hand.stop()
    assert [f.id for f in verdict.failures] == ["host-valid-commands"], verdict
    obeyed = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f\u061c\u200e\u200f\u202a-\u202e\u2066-\u2069]")
    for text in (str(verdict), verdict.explain(), str(verdict.failures[0])):
        assert not obeyed.search(text), repr(text)
    assert "]0;PWNED\\x07" in str(verdict.failures[0]), str(verdict.failures[0])
    from gcl._hand import printable

    assert printable("a\tb\nc\r\x1b\x9b\u202e") == "a\tb\nc\\r\\x1B\\u{009B}\\u{202E}"


def test_pytest_exit_inside_a_gcl_hand_test_ends_the_session(tmp_path):
    """``pytest.exit()`` in a gcl_hand test ends the session with its code (before: the test
    FAILED, "nothing of the host code was judged", and the session ran on)."""
    run = run_pytest(tmp_path, {"test_exit.py": '''
        import pytest


        @pytest.mark.gcl(profile="seed")
        def test_a(gcl_hand):
            pytest.exit("enough", returncode=7)


        @pytest.mark.gcl(profile="seed")
        def test_b(gcl_hand):
            pass
        '''})
    assert run.returncode == 7 and "Exit: enough" in run.stdout, run.stdout
    assert "FAILED" not in run.stdout and "PASSED" not in run.stdout, run.stdout
