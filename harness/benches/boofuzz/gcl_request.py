"""A GCL request for boofuzz, run against a hand on a serial port for a fixed time.

Usage: gcl_request.py PORT BAUD SECONDS [best|plain|reset|fresh|logged]

The setup (default `best`) is boofuzz configured at its best for a serial hand: one
connection reused for every case, a content checker that ends a receive at the prompt `=> `
(no waiting for a quiet line), no sleep between cases, no web UI, and before each case a ^C
whose prompt is awaited, so a case that left the hand in RealTime mode or mid-line does not
spoil the next one. Two other setups a boofuzz user might pick:

- `plain`: no content checker. boofuzz's serial receive then ends at its timeout (1 s here)
  once any byte came, or after `message_separator_time` (0.3 s) if none did: in boofuzz
  0.4.2 `SerialConnection.recv` refreshes its last-byte time on every pass once it holds
  data, so the separator time never ends a receive that has begun.
- `reset`: the content checker, and before each case a RESET whose banner and prompt are
  awaited instead of the ^C: the way a boofuzz user gets the same known state for every
  case (boofuzz itself has no notion of one).
- `logged`: as `best`, with boofuzz's default loggers (every case written as text to
  stdout) and its web UI on port 26000.
- `fresh`: as `best`, but the port is closed and opened again for every case (boofuzz's
  default, `reuse_target_connection=False`).

boofuzz has no model of the hand, so it judges an answer by what needs none: the answer must
end with the prompt (a hand that went silent, or stayed in a loop, does not), and must not
hold the power-up banner unless the line was RESET (a restart).

Prints one summary line of `key=value` fields (cases, seconds, cases/s, bytes sent and
received, CR-ended lines sent, failures by kind), counted at the connection, so every byte
that crossed the line is counted once, the ^C or RESET before each case included.
"""

import os
import sys
import time

from boofuzz import (
    Delim,
    Group,
    Request,
    Session,
    Static,
    String,
    Target,
)
from boofuzz.connections import SerialConnection

PROMPT = b"=> "
BANNER = b"BarrettHand Firmware"

# Command words of the BH8-262 firmware (supervisory mode), prefixes a user would try.
WORDS = [
    "FGET", "FSET", "FLIST", "FLISTV", "FLISTA", "FLISTAV", "FDEF", "FLOAD", "FSAVE",
    "PGET", "PSET", "PLIST", "PLISTV", "PDEF", "PLOAD", "PSAVE",
    "HI", "HOME", "M", "C", "O", "IC", "IO", "T", "TC", "TO", "LOOP", "RESET", "ERR", "VERS",
]
PREFIXES = ["", "1", "2", "3", "4", "S", "G", "12", "123", "1234"]


def prompt_end(data: bytes) -> int:
    """Content checker: the length up to and including the first prompt, 0 until it came."""
    i = data.find(PROMPT)
    return i + len(PROMPT) if i >= 0 else 0


class CountingSerial(SerialConnection):
    """boofuzz's serial connection, counting what crosses the line each way."""

    sent = 0
    received = 0
    lines = 0

    def send(self, data):
        n = super().send(data)
        self.sent += len(data)
        self.lines += data.count(b"\r")
        return n

    def recv(self, max_bytes):
        data = super().recv(max_bytes)
        self.received += len(data)
        return data


def main() -> None:
    port, baud, seconds = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
    mode = sys.argv[4] if len(sys.argv) > 4 else "best"
    if mode not in ("best", "plain", "reset", "fresh", "logged"):
        sys.exit(f"unknown setup {mode!r} (best, plain, reset, fresh, logged)")
    conn = CountingSerial(
        port=port,
        baudrate=baud,
        timeout=1.0,
        message_separator_time=0.3,
        content_checker=None if mode == "plain" else prompt_end,
    )
    started = time.monotonic()
    failures: dict[str, int] = {}
    cases = 0

    def to_known_state(target, fuzz_data_logger, session, sock, *args, **kwargs):
        if mode == "reset":
            target.send(b"RESET\r")
            # The echo and banner come before the prompt; a receive ends at the prompt.
            target.recv(10000)
        else:
            target.send(b"\x03")
            target.recv(10000)

    def summary(elapsed: float, note: str = "") -> None:
        kinds = ",".join(f"{k.replace(' ', '-')}:{v}" for k, v in sorted(failures.items())) or "none"
        print(
            f"boofuzz setup={mode} cases={cases} seconds={elapsed:.1f} "
            f"cases_per_s={cases / max(elapsed, 1e-3):.2f} sent={conn.sent} received={conn.received} "
            f"lines={conn.lines} failures={kinds}{note}"
        )
        sys.stdout.flush()

    def judge(target, fuzz_data_logger, session, *args, **kwargs):
        nonlocal cases
        cases += 1
        got = session.last_recv or b""
        sent = session.last_send or b""
        kind = None
        if not got.endswith(PROMPT):
            kind = "no prompt (silent, or not idle)"
        elif BANNER in got and b"RESET" not in sent.upper():
            kind = "restart (banner)"
        if kind:
            failures[kind] = failures.get(kind, 0) + 1
            fuzz_data_logger.log_fail(kind)
        else:
            fuzz_data_logger.log_pass("prompt")
        elapsed = time.monotonic() - started
        if elapsed >= seconds:
            summary(elapsed)
            os._exit(0)

    session = Session(
        target=Target(connection=conn),
        sleep_time=0,
        web_port=26000 if mode == "logged" else None,
        keep_web_open=False,
        fuzz_loggers=None if mode == "logged" else [],
        reuse_target_connection=mode != "fresh",
        receive_data_after_fuzz=True,
        pre_send_callbacks=[to_known_state],
        post_test_case_callbacks=[judge],
        db_filename=os.path.join(os.getcwd(), "boofuzz-results.db"),
        restart_sleep_time=0,
    )
    req = Request(
        "gcl-line",
        children=(
            Group(name="prefix", values=PREFIXES),
            Group(name="word", values=WORDS),
            Delim(name="space", default_value=" "),
            String(name="args", default_value="P", max_len=128),
            Static(name="cr", default_value="\r"),
        ),
    )
    session.connect(req)
    session.fuzz()
    summary(time.monotonic() - started, " (ran out of mutations)")


if __name__ == "__main__":
    main()
