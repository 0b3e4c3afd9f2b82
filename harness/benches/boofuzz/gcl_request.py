"""A GCL request for boofuzz, run against a hand on a serial port for a fixed time.

Usage: gcl_request.py PORT BAUD SECONDS [plain]

With `plain`, boofuzz runs without the content checker (each receive ends after 0.3 s of
quiet, its default), for comparison with boofuzz as first configured.

boofuzz is configured at its best for a serial hand: one connection reused for every case,
a content checker that ends a receive at the prompt `=> ` (no waiting for a quiet line), no
sleep between cases, no web UI, and before each case a ^C whose prompt is awaited, so a case
that left the hand in RealTime mode or mid-line does not spoil the next one.

boofuzz has no model of the hand, so it judges an answer by what needs none: the answer must
end with the prompt (a hand that went silent, or stayed in a loop, does not), and must not
hold the power-up banner unless the line was RESET (a restart). Prints one summary line:
cases, cases/s, failures by kind.
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


def main() -> None:
    port, baud, seconds = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
    plain = len(sys.argv) > 4 and sys.argv[4] == "plain"
    conn = SerialConnection(
        port=port,
        baudrate=baud,
        timeout=1.0,
        message_separator_time=0.3,
        content_checker=None if plain else prompt_end,
    )
    started = time.monotonic()
    failures: dict[str, int] = {}
    cases = 0
    wire = 0  # bytes both ways, the ^C before each case included

    def to_idle(target, fuzz_data_logger, session, sock, *args, **kwargs):
        nonlocal wire
        target.send(b"\x03")
        wire += 1 + len(target.recv(10000))

    def judge(target, fuzz_data_logger, session, *args, **kwargs):
        nonlocal cases, wire
        cases += 1
        got = session.last_recv or b""
        sent = session.last_send or b""
        wire += len(got) + len(sent)
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
            kinds = ", ".join(f"{k}: {v}" for k, v in sorted(failures.items())) or "none"
            print(
                f"boofuzz: {cases} cases in {elapsed:.1f} s = {cases / elapsed:.2f} cases/s, "
                f"{wire / elapsed:.0f} wire bytes/s; failures: {kinds}"
            )
            sys.stdout.flush()
            os._exit(0)

    session = Session(
        target=Target(connection=conn),
        sleep_time=0,
        web_port=None,
        keep_web_open=False,
        fuzz_loggers=[],
        reuse_target_connection=True,
        receive_data_after_fuzz=True,
        pre_send_callbacks=[to_idle],
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
    elapsed = time.monotonic() - started
    print(f"boofuzz: {cases} cases in {elapsed:.1f} s = {cases / max(elapsed, 1e-3):.2f} cases/s (ran out of mutations)")


if __name__ == "__main__":
    main()
