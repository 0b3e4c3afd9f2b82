"""Start and stop graded simulated hands (``gcl check-host --serve``).

``Hand`` starts ``gcl check-host --serve``, reads where it listens, and at ``stop()`` closes
its stdin and reads its ``report.json`` into a ``Verdict``."""

import contextlib
import json
import os
import re
import shutil
import subprocess
import sysconfig
import tempfile
import threading

__all__ = ["Failure", "Hand", "HandError", "Verdict", "binary"]

#: How long a hand may take to say where it listens, seconds.
START_TIMEOUT = 30.0
#: How long a stopped hand may take to grade and exit, seconds.
STOP_TIMEOUT = 30.0
#: How long ``gcl --version`` may take, seconds.
VERSION_TIMEOUT = 10.0


#: What a terminal would obey rather than show: the C0 controls but newline and tab, DEL, the
#: C1 controls, the bidirectional controls (U+202E reorders what follows it) and U+FFFE/U+FFFF.
_HIDDEN = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f\u061c\u200e\u200f\u202a-\u202e\u2066-\u2069\ufffe\uffff]")


def _shown(match):
    c = match.group(0)
    if c == "\r":
        return "\\r"
    if c <= "\x7f":
        return "\\x{:02X}".format(ord(c))
    return "\\u{{{:04X}}}".format(ord(c))


def printable(text):
    """``text`` with what a terminal would obey written out, as ``gcl`` shows text for people
    (its ``escape::printable``): a report's messages quote what the host sent, which may be
    an escape sequence (``ESC]0;`` retitling the window) or a right-to-left override. Newline
    and tab stay; ``\\r`` is written ``\\r``, other C0 controls and DEL ``\\xHH``, the rest
    ``\\u{HHHH}``."""
    return _HIDDEN.sub(_shown, text)


class HandError(RuntimeError):
    """The simulated hand could not be started or stopped (not a verdict on the host)."""


def binary():
    """The ``gcl`` binary: ``$GCL_BIN``, else the one this wheel installed beside the
    interpreter's scripts, else the first on PATH."""
    env = os.environ.get("GCL_BIN")
    if env:
        return env
    exe = "gcl.exe" if os.name == "nt" else "gcl"
    for scheme in (None, "posix_user"):
        try:
            scripts = sysconfig.get_path("scripts", scheme) if scheme else sysconfig.get_path("scripts")
        except KeyError:
            continue
        candidate = os.path.join(scripts, exe)
        if os.path.isfile(candidate) and os.access(candidate, os.X_OK):
            return candidate
    found = shutil.which(exe)
    if found:
        return found
    raise HandError("no gcl binary: install the gcl wheel (pip install gcl-harness) or set GCL_BIN")


_checked = {}


def check_binary(path):
    """``path`` if it is this kit's ``gcl`` (its ``--version`` says ``gcl X.Y.Z``), else
    :class:`HandError` at once: a missing file, one that cannot run, or another program named
    ``gcl`` is not waited for. Asked once per path."""
    if path in _checked:
        return _checked[path]
    try:
        out = subprocess.run([path, "--version"], stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                             stderr=subprocess.STDOUT, timeout=VERSION_TIMEOUT, universal_newlines=True,
                             errors="replace").stdout
    except subprocess.TimeoutExpired:
        raise HandError("{} --version did not answer within {:.0f} s: it is not the gcl of gcl-harness "
                        "(install the wheel, or set GCL_BIN to its gcl)".format(path, VERSION_TIMEOUT)) from None
    except OSError as e:
        raise HandError("cannot run gcl at {}: {} (install the wheel, or set GCL_BIN to its gcl)".format(
            path, e.strerror or e)) from None
    if not re.match(r"gcl \d+\.\d+\.\d+\s*$", out):
        raise HandError("{} is not the gcl of gcl-harness: its --version says {!r} (install the wheel, or set "
                        "GCL_BIN to its gcl)".format(path, out.strip()[:200]))
    _checked[path] = path
    return path


class Failure:
    """One clause the host broke: its id (``host-line-ending``), title, message and the
    session as a transcript."""

    def __init__(self, case):
        self.id = case.get("id", "")
        self.title = case.get("title", "")
        self.clauses = case.get("clauses", [])
        self.verdict = case.get("verdict", "")
        self.message = case.get("message") or ""
        self.diff = case.get("diff")
        self.transcript = case.get("transcript") or ""

    def __str__(self):
        text = "{} {}: {}\n  {}".format(self.verdict, self.id, self.title, self.message)
        if self.diff:
            text += "\n  expected: {}\n  actual:   {}".format(self.diff.get("expected"), self.diff.get("actual"))
        return printable(text)

    def __repr__(self):
        return "Failure({!r}, {!r})".format(self.id, self.message)


class Verdict:
    """What ``gcl check-host --serve`` said of a session: its report (``report.json``), the
    misbehaviours that fired, and its exit code (0 pass, 1 a clause failed, 2 nothing judged:
    nobody opened the port, or nobody sent the hand a byte; its ``host-session`` case says so)."""

    def __init__(self, report, fired, exit_code, output):
        self.report = report
        self.fired = fired
        self.exit_code = exit_code
        self.output = output
        self.failures = [Failure(c) for c in report.get("cases", []) if c.get("verdict") not in ("PASS", "SKIP", "XFAIL")]

    @property
    def passed(self):
        return self.exit_code == 0 and not self.failures

    def counts(self):
        """Cases per verdict, as the report counts them (``{"PASS": 9, "SKIP": 2}``)."""
        return {v: n for v, n in sorted(self.report.get("summary", {}).items()) if n}

    def __str__(self):
        """``PASS: 9 PASS, 2 SKIP``, or ``FAIL: ...`` followed by what :meth:`explain` says."""
        if self.passed:
            head = "PASS"
        elif self.exit_code in (0, 1):
            head = "FAIL"
        else:
            head = "ERROR (gcl exited {})".format(self.exit_code)
        counts = ", ".join("{} {}".format(n, v) for v, n in self.counts().items()) or "no clause graded"
        text = "{}: {}".format(head, counts)
        if not self.passed:
            detail = self.explain()
            if detail:
                text += "\n" + detail
        return text

    def __repr__(self):
        return "Verdict(passed={!r}, exit_code={!r}, counts={!r}, failures={!r})".format(
            self.passed, self.exit_code, self.counts(), [f.id for f in self.failures])

    def explain(self):
        """The failing clauses, the misbehaviours that fired, and the session, for people."""
        lines = []
        for f in self.failures:
            lines.append(str(f))
        if self.fired:
            lines.append("misbehaviours that fired:")
            lines.extend("  " + f for f in self.fired)
        transcript = next((f.transcript for f in self.failures if f.transcript), "")
        if transcript:
            lines.append("the session (what the host sent and the hand answered):")
            lines.extend("  " + t for t in transcript.splitlines())
        # What the host sent is quoted: shown, never obeyed.
        return printable("\n".join(lines))


class Hand:
    """A simulated hand on a fresh pty (or a loopback TCP port with ``tcp=True``) that grades
    whoever talks to it; ``stop()`` (or leaving the ``with`` block) ends it and returns the
    :class:`Verdict`.

    ``profile``: seed, bh8-262-4.3, bh8-262-4.4 (alias bh8-262) or a spec TOML file.
    ``baud``: pace both directions at this rate (default: unpaced in fast time, the hand's
    BAUD in real time). ``time``: "fast" (default) or "real". ``fault``: a deliberate firmware
    bug or a list of them (``gcl sim --help`` lists them). ``misbehave``: (seed, run) plays
    the schedule an unguided ``gcl fuzz host --seed seed`` campaign draws for run ``run``;
    ``ops``: which misbehaviours (``"delay-above,truncate=5"``). ``name``: the session's
    name in the report. ``report``: a folder for report.json, junit.xml and report.html
    (default: a temporary folder, removed on stop).
    """

    def __init__(self, profile="bh8-262", baud=None, time=None, fault=None, tcp=False, misbehave=None,
                 ops=None, name=None, report=None, seed=0):
        self.profile = profile
        self.baud = baud
        self.time = time
        self.faults = [fault] if isinstance(fault, str) else list(fault or [])
        self.tcp = tcp
        self.misbehave = misbehave
        self.ops = ops
        self.name = name
        self.seed = seed
        self._report_dir = report
        self._tmp = None
        self._proc = None
        self.port = None
        self.url = None
        self.planned = []
        self.tolerated = []
        self.verdict = None

    @contextlib.contextmanager
    def tolerate(self, *errors):
        """Inside the block, the host code's own errors (a broken hand reported cleanly, as a
        host should under misbehaviour) end the block without failing; they are kept in
        ``tolerated``."""
        try:
            yield
        except errors as e:
            self.tolerated.append(e)

    def command(self):
        """The ``gcl check-host --serve`` command line this hand runs."""
        cmd = [check_binary(binary()), "check-host", "--serve", "--stop-on-eof", "--profile", str(self.profile),
               "--seed", str(self.seed), "--report", self._report_dir or "REPORT"]
        cmd.append("--tcp" if self.tcp else "--pty")
        if self.baud is not None:
            cmd += ["--baud", str(self.baud)]
        if self.time is not None:
            cmd += ["--time", str(self.time)]
        for f in self.faults:
            cmd += ["--fault", str(f)]
        if self.misbehave is not None:
            cmd += ["--misbehave", "{}:{}".format(*self.misbehave)]
            if self.ops:
                cmd += ["--ops", str(self.ops)]
        if self.name:
            cmd += ["--name", str(self.name)]
        return cmd

    def start(self):
        """Starts the hand; returns once it listens (``port`` and ``url`` are set)."""
        if self._proc is not None:
            raise HandError("the hand is already running")
        # A binary that is not ours is refused before anything is made.
        check_binary(binary())
        if self._report_dir is None:
            self._tmp = tempfile.mkdtemp(prefix="gcl-hand-")
            self._report_dir = self._tmp
        command = self.command()
        try:
            self._proc = subprocess.Popen(command, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                          stderr=subprocess.PIPE, universal_newlines=True, errors="replace")
        except OSError as e:
            self._remove_tmp()
            raise HandError("cannot run {}: {}".format(command[0], e.strerror or e)) from None
        try:
            self._read_header()
        except BaseException:
            # Ctrl-C or SIGTERM (as KeyboardInterrupt) while it starts: nothing is left behind.
            self._kill()
            self._remove_tmp()
            raise
        return self

    def _read_header(self):
        """Reads where the started hand listens; :class:`HandError` when it does not say."""
        # The first lines: port, url, planned misbehaviours, ready (read by a thread, so that
        # a hand that never gets there cannot hold the caller past START_TIMEOUT).
        lines = []

        def read_header(stream=self._proc.stdout):
            for line in stream:
                lines.append(line.rstrip("\n"))
                if line.startswith("ready"):
                    return

        reader = threading.Thread(target=read_header, daemon=True)
        reader.start()
        reader.join(START_TIMEOUT)
        if reader.is_alive() or not lines or lines[-1] != "ready":
            code = self._proc.poll()
            why = "did not say where it listens within {:.0f} s".format(START_TIMEOUT)
            if code is None and not reader.is_alive():
                # Its output ended: it is exiting, and can be waited for a moment after its
                # output closed (on a loaded machine, poll() alone said "still running").
                why = "closed its output before it said where it listens"
                try:
                    code = self._proc.wait(timeout=5)
                except subprocess.TimeoutExpired:
                    pass
            if code is not None:
                why = "ended ({}) before it said where it listens: {}".format(code, self._proc.stderr.read().strip())
            self._kill()
            self._remove_tmp()
            raise HandError("gcl check-host --serve " + why)
        for line in lines:
            key, _, value = line.partition(" ")
            if key == "port":
                self.port = value
            elif key == "url":
                self.url = value
            elif key == "planned":
                self.planned.append(value)

    def stop(self):
        """Stops the hand and grades the session; returns the :class:`Verdict`."""
        if self._proc is None:
            return self.verdict
        proc, self._proc = self._proc, None
        try:
            try:
                out, err = proc.communicate(input="", timeout=STOP_TIMEOUT)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.communicate()
                raise HandError("gcl check-host --serve did not stop within {:.0f} s".format(STOP_TIMEOUT)) from None
            except BaseException:
                # Interrupted while it grades (Ctrl-C, SIGTERM): it goes before its folder does,
                # so that it writes nothing there afterwards.
                proc.kill()
                proc.wait()
                raise
            # 2 is also a session that judged nothing: a verdict (its ERROR case), not a failure to run.
            judged_nothing = proc.returncode == 2 and any(
                line.startswith("ERROR") and " host-session " in line for line in out.splitlines())
            if proc.returncode not in (0, 1) and not judged_nothing:
                raise HandError("gcl check-host --serve failed ({}): {}".format(proc.returncode, err.strip()))
            path = os.path.join(self._report_dir, "report.json")
            try:
                with open(path, encoding="utf-8") as f:
                    report = json.load(f)
            except (OSError, ValueError) as e:
                raise HandError("gcl check-host --serve ended ({}) without a readable {}: {}".format(
                    proc.returncode, path, e)) from None
            fired = [line[len("fired "):] for line in out.splitlines() if line.startswith("fired ")]
            self.verdict = Verdict(report, fired, proc.returncode, out)
            return self.verdict
        finally:
            self._remove_tmp()

    def _remove_tmp(self):
        """The temporary report folder goes, whatever became of the hand."""
        if self._tmp:
            shutil.rmtree(self._tmp, ignore_errors=True)
            self._tmp = None
            self._report_dir = None

    def _kill(self):
        if self._proc is not None:
            self._proc.kill()
            self._proc.communicate()
            self._proc = None

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.stop()
        return False

    def __repr__(self):
        return "Hand(profile={!r}, port={!r})".format(self.profile, self.port)

