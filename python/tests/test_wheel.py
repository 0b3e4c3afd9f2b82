"""Tests of the installed wheel (run by .ci/run in a fresh venv that has only the wheel,
pytest, pyserial and PyYAML): the binary, the metadata, the packages, the Hand API, the pytest
plugin against examples/python-host, and the CI recipes in ci/.

python/gcl_vectors/ holds one symlink per module of vectors/python/gcl_vectors/, so there is
one copy; a module without its link fails here. The plugin runs over examples/python-host
(correct, and two planted bugs); its limits (bad values, a foreign or missing gcl, a user's
pytest-timeout) are in test_plugin_limits.py, and test_ci_recipes.py holds ci/*.yml to the
command lines of .ci/run. The venv also holds pytest-timeout."""

import importlib.metadata
import os
import re
import shutil
import subprocess
import sys
import sysconfig

import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SITE = sysconfig.get_paths()["purelib"]


def cargo_package():
    """(name, version) of the harness crate, the wheel's source."""
    text = open(os.path.join(ROOT, "harness", "Cargo.toml"), encoding="utf-8").read()
    name = re.search(r'^name = "([^"]+)"', text, re.M).group(1)
    ws = open(os.path.join(ROOT, "Cargo.toml"), encoding="utf-8").read()
    version = re.search(r'^version = "([^"]+)"', ws, re.M).group(1)
    return name, version


def test_the_wheel_puts_gcl_on_path_with_the_crates_version():
    gcl = shutil.which("gcl")
    assert gcl and gcl.startswith(sys.prefix), "gcl is not the venv's: {}".format(gcl)
    out = subprocess.run([gcl, "--version"], stdout=subprocess.PIPE, universal_newlines=True, check=True).stdout
    assert out.strip() == "gcl {}".format(cargo_package()[1])


def test_name_version_and_metadata_come_from_cargo_toml():
    name, version = cargo_package()
    meta = importlib.metadata.metadata(name)
    assert meta["Name"] == name
    assert meta["Version"] == version
    harness = open(os.path.join(ROOT, "harness", "Cargo.toml"), encoding="utf-8").read()
    assert meta["Summary"] == re.search(r'^description = "([^"]+)"', harness, re.M).group(1)
    entry = [e for e in importlib.metadata.entry_points(group="pytest11") if e.name == "gcl"]
    assert [e.value for e in entry] == ["gcl.pytest_plugin"]


def test_the_wheel_brings_pyserial_and_names_the_pytest_extra():
    # The host-library guide installs the wheel and pytest, and nothing else: its host
    # scenario (ci/host_scenario.py) and the example host library need pyserial.
    requires = importlib.metadata.requires(cargo_package()[0]) or []
    plain = [r for r in requires if "extra" not in r]
    assert any(r.replace(" ", "").startswith("pyserial>=") for r in plain), requires
    assert any(r.startswith("pytest") and "pytest" in r.split(";", 1)[-1] for r in requires if ";" in r), requires
    guide = open(os.path.join(ROOT, "docs", "src", "host-libraries.md"), encoding="utf-8").read()
    assert "pip install target/wheels/gcl_harness-*.whl 'pytest>=8'" in guide
    readme = open(os.path.join(ROOT, "python", "README.md"), encoding="utf-8").read()
    assert "gcl_harness-*.whl" in readme and "gcl-harness-*.whl" not in readme


def test_the_packages_come_from_the_wheel_and_gcl_vectors_is_the_source_trees():
    import gcl
    import gcl_vectors

    assert gcl.__file__.startswith(SITE)
    assert gcl_vectors.__file__.startswith(SITE)
    src = os.path.join(ROOT, "vectors", "python", "gcl_vectors")
    installed = os.path.dirname(gcl_vectors.__file__)
    want = sorted(f for f in os.listdir(src) if f.endswith(".py"))
    assert sorted(f for f in os.listdir(installed) if f.endswith(".py")) == want, \
        "python/gcl_vectors/ must link every module of vectors/python/gcl_vectors/"
    for f in want:
        with open(os.path.join(src, f), "rb") as a, open(os.path.join(installed, f), "rb") as b:
            assert a.read() == b.read(), f


def test_gcl_vectors_runs_a_golden_against_the_wheels_simulator():
    golden = os.path.join(ROOT, "vectors", "suite", "seed", "cmd-fget.gcl")
    out = subprocess.run(
        [sys.executable, "-m", "gcl_vectors", "replay", "--target", "exec:gcl sim --stdio --profile seed", golden],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True, cwd="/")
    assert out.returncode == 0, out.stdout


def talk(url, line_end, commands=1):
    """^C, then FGET DP `commands` times, each line ended by `line_end`."""
    import serial

    port = serial.serial_for_url(url, baudrate=9600, timeout=0.05)
    try:
        port.write(b"\x03")
        buf = b""
        for _ in range(100):
            buf += port.read(64)
            if buf.endswith(b"=> "):
                break
        for _ in range(commands):
            port.write(b"FGET DP" + line_end)
            buf = b""
            for _ in range(40):
                buf += port.read(64)
                if buf.endswith((b"=> ", b"=> \n")):
                    break
    finally:
        port.close()


@pytest.mark.parametrize("tcp", [False, True])
def test_a_hand_grades_its_session(tcp):
    from gcl import Hand

    with Hand(profile="seed", tcp=tcp) as good:
        assert good.url.startswith("socket://") == tcp
        talk(good.url, b"\r")
    assert good.verdict.passed, good.verdict.explain()
    with Hand(profile="seed", tcp=tcp) as bad:
        talk(bad.url, b"\r\n")
    assert not bad.verdict.passed
    assert [f.id for f in bad.verdict.failures] == ["host-line-ending"]
    assert "LF" in bad.verdict.failures[0].message
    assert 'send "FGET DP\\r\\n"' in bad.verdict.explain()


def test_a_hand_nobody_talks_to_judges_nothing():
    from gcl import Hand

    with Hand(profile="seed") as idle:
        pass
    assert not idle.verdict.passed
    assert idle.verdict.exit_code == 2
    assert [f.id for f in idle.verdict.failures] == ["host-session"]
    assert "nobody opened the port" in idle.verdict.failures[0].message


def test_a_verdict_prints_as_what_it_says():
    from gcl import Hand

    with Hand(profile="seed") as good:
        talk(good.url, b"\r")
    text = str(good.verdict)
    assert text.startswith("PASS: ") and " PASS" in text, text
    assert repr(good.verdict).startswith("Verdict(passed=True, exit_code=0, counts={"), repr(good.verdict)
    with Hand(profile="seed") as bad:
        talk(bad.url, b"\r\n")
    text = str(bad.verdict)
    assert text.startswith("FAIL: ") and "host-line-ending" in text, text
    assert "object at 0x" not in text + repr(bad.verdict)
    assert "failures=['host-line-ending']" in repr(bad.verdict), repr(bad.verdict)


def test_a_misbehaving_hand_plays_the_fuzzers_schedule():
    from gcl import Hand

    with Hand(profile="seed", misbehave=(3, 1), ops="truncate") as hand:
        # More answers than a schedule plans for (it plans within the first 10).
        talk(hand.url, b"\r", commands=12)
    assert hand.planned and all(p.startswith("truncate at answer") for p in hand.planned)
    assert hand.verdict.fired and all(f.startswith("truncate") for f in hand.verdict.fired)


def pytest_example(bug=None, command=None):
    env = dict(os.environ)
    env.pop("BH8HOST_BUG", None)
    if bug:
        env["BH8HOST_BUG"] = bug
    # The example runs as its author would: from its own folder, the plugin found by its
    # entry point; `python -m pytest` unless `command` says otherwise (the bare `pytest`).
    command = command or [sys.executable, "-m", "pytest"]
    return subprocess.run(command + ["-q", "-p", "no:cacheprovider", "-rA", "tests"],
                          cwd=os.path.join(ROOT, "examples", "python-host"), env=env,
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True)


def test_the_example_host_library_passes_its_suite():
    out = pytest_example()
    assert out.returncode == 0, out.stdout
    assert re.search(r"\b8 passed\b", out.stdout), out.stdout


def test_the_example_runs_with_the_bare_pytest_command_too():
    # `pytest` (the venv's script) puts no folder on sys.path by itself: the example's
    # pyproject.toml does (`pythonpath`), else `import bh8host` fails.
    bare = os.path.join(os.path.dirname(sys.executable), "pytest")
    out = pytest_example(command=[bare])
    assert out.returncode == 0, out.stdout
    assert re.search(r"\b8 passed\b", out.stdout), out.stdout


def test_the_lf_bug_fails_every_test_naming_the_clause():
    out = pytest_example("lf")
    assert out.returncode == 1, out.stdout
    assert re.search(r"\b8 failed\b", out.stdout), out.stdout
    # Each failure leads with the broken clause, then what the test raised, then the bytes.
    assert out.stdout.count("the host code broke GCL (host-line-ending)") >= 8, out.stdout
    assert 'send "VERS\\r\\n"' in out.stdout


def test_the_short_block_bug_fails_under_misbehaviour_with_what_fired():
    out = pytest_example("short-block")
    assert out.returncode == 1, out.stdout
    failed = re.findall(r"^FAILED (\S+)", out.stdout, re.M)
    assert failed and all("test_realtime_under_misbehaviour[" in f for f in failed), out.stdout
    assert "IndexError" in out.stdout
    assert "misbehaviours that fired:" in out.stdout
    assert re.search(r"(truncate|rt-block-length) at answer \d+ \(RealTime feedback\)", out.stdout), out.stdout


MARKER_SUITE = '''
import pytest
import serial


def ask(url, line):
    port = serial.serial_for_url(url, baudrate=38400, timeout=0.05)
    try:
        port.write(b"\\x03")
        buf = b""
        for _ in range(100):
            buf += port.read(64)
            if buf.endswith(b"=> "):
                break
        port.write(line + b"\\r")
        buf = b""
        for _ in range(100):
            buf += port.read(256)
            if buf.endswith(b"=> "):
                break
        return buf
    finally:
        port.close()


@pytest.mark.gcl(profile="bh8-262-4.3", tcp=True, baud=38400)
def test_profile_tcp_and_baud(gcl_hand):
    assert gcl_hand.url.startswith("socket://127.0.0.1:")
    assert b"4.3" in ask(gcl_hand.url, b"VERS")


@pytest.mark.gcl(profile="seed", fault="crlf")
def test_fault(gcl_hand):
    assert b"\\r\\n" in ask(gcl_hand.url, b"FGET DP")


@pytest.mark.gcl(profile="seed", schedules=2, seed=9)
def test_schedules(gcl_misbehaving_hand):
    assert gcl_misbehaving_hand.planned
    # A session nobody talks in judges nothing (an ERROR), nor does one of a lone ^C (no
    # clause is exercised by it): a command is talking.
    ask(gcl_misbehaving_hand.url, b"FGET DP")
'''


def test_marker_options_reach_the_hand(tmp_path):
    (tmp_path / "test_markers.py").write_text(MARKER_SUITE)
    out = subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-v", str(tmp_path)],
                         cwd=str(tmp_path), stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                         universal_newlines=True)
    assert out.returncode == 0, out.stdout
    assert "test_schedules[schedule-9:1]" in out.stdout and "test_schedules[schedule-9:2]" in out.stdout, out.stdout
    assert re.search(r"\b4 passed\b", out.stdout), out.stdout
