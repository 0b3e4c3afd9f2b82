"""Command line: `replay` and `check`. Exit codes: 0 pass, 1 failures, 2 usage or
infrastructure errors (as gcl's)."""

import argparse
import glob
import os
import sys

from . import loader
from .files import read_limited
from .links import TargetError, open_target, parse_target
from .replay import replay, wait_banner
from .schema import SchemaError
from .transcript import TranscriptError, parse

EXIT_OK, EXIT_FAIL, EXIT_ERROR = 0, 1, 2


def cmd_replay(args):
    try:
        spec = parse_target(args.target)
    except TargetError as e:
        print("gcl_vectors: error: %s" % e, file=sys.stderr)
        return EXIT_ERROR
    transcripts = []
    for f in args.files:
        try:
            transcripts.append((f, parse(read_limited(f))))
        except (OSError, ValueError, TranscriptError) as e:
            print("gcl_vectors: error: %s: %s" % (f, e), file=sys.stderr)
            return EXIT_ERROR
    try:
        link = open_target(spec)
    except TargetError as e:
        print("gcl_vectors: error: opening %s: %s" % (args.target, e), file=sys.stderr)
        return EXIT_ERROR
    code = EXIT_OK
    tally = {"passed": 0, "failed": 0, "skipped": 0, "errors": 0}
    try:
        if spec[0] == "exec":
            wait_banner(link)
        for f, t in transcripts:
            if t.setup and "object" not in args.fixture:
                # This runner drives no simulator of its own: it cannot place an object.
                what = " and ".join("object %d %d" % (m, at) for _, m, at in t.setup)
                print("SKIP %s: needs %s in place, which this runner cannot place; put it there and pass --fixture object" % (f, what))
                tally["skipped"] += 1
                continue
            out = replay(t, link, default_timeout=args.timeout / 1000.0, resync=args.resync)
            if out.verdict == "PASS":
                tally["passed"] += 1
                if not args.quiet:
                    print("PASS %s (%d steps)" % (f, out.steps))
            elif out.verdict in ("FAIL", "TIMEOUT"):
                tally["failed"] += 1
                print("%s %s: %s" % (out.verdict, f, out.detail))
                code = max(code, EXIT_FAIL)
            else:
                tally["errors"] += 1
                print("ERROR %s: %s" % (f, out.detail))
                code = EXIT_ERROR
            sys.stdout.flush()
    except Exception as e:  # a link that breaks outside a step (the banner wait)
        print("gcl_vectors: error: %s" % e, file=sys.stderr)
        return EXIT_ERROR
    finally:
        link.close()
    print(summary(tally))
    return code


def summary(tally):
    """The last line of a replay: how many transcripts passed, failed (FAIL or TIMEOUT) and
    were skipped (SKIP), and the errors (ERROR) when there were any."""
    line = "%d passed, %d failed, %d skipped" % (tally["passed"], tally["failed"], tally["skipped"])
    if tally["errors"]:
        line += ", %d errors" % tally["errors"]
    return line


def cmd_check(args):
    files = args.files or sorted(glob.glob(os.path.join(loader.VECTORS, "json", "*", "*.json")))
    bad = 0
    for f in files:
        try:
            vf = loader.load(f)
            if not args.quiet:
                print("ok %s: %s of %s, %d tests" % (f, vf.kind, vf.profile, len(vf.tests)))
        except (OSError, ValueError, SchemaError) as e:
            print("BAD %s: %s" % (f, e))
            bad += 1
    return EXIT_FAIL if bad else EXIT_OK


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python3 -m gcl_vectors", description=__doc__)
    sub = ap.add_subparsers(dest="command", required=True)
    r = sub.add_parser("replay", help="run golden transcripts against a hand")
    r.add_argument("files", nargs="+", metavar="FILE")
    r.add_argument("--target", required=True, help="serial:PATH?baud=N, tcp://HOST:PORT or exec:COMMAND ARGS")
    r.add_argument("--timeout", type=int, default=2000, metavar="MS", help="wait of a step without `within`")
    r.add_argument("--resync", action="store_true", help="send ^C and drain before each transcript")
    r.add_argument("-q", "--quiet", action="store_true", help="print only failures")
    r.add_argument(
        "--fixture",
        action="append",
        default=[],
        choices=["object"],
        help="declare a transcript's set-up in place (the objects its `setup:` lines name); without it such transcripts are SKIP",
    )
    c = sub.add_parser("check", help="load JSON vector files with their schema check")
    c.add_argument("files", nargs="*", metavar="FILE")
    c.add_argument("-q", "--quiet", action="store_true")
    args = ap.parse_args(argv)
    try:
        return cmd_replay(args) if args.command == "replay" else cmd_check(args)
    except BrokenPipeError:
        return EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
