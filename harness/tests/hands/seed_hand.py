"""An independent minimal GCL hand for the `seed` profile, written from the seed document
(shared/seed/gcl-seed.md) and the fact tables (shared/facts/bh8-facts.md) only, without
reading the reference model. Where the seed is silent it decides on its own, so it differs
from the model there: that is the point (issue 19, "on a hand that already differs, new bugs
hide"). It speaks GCL on stdin/stdout: `exec:python3 seed_hand.py [--bug NAME]`.

Motions take simulated wall time (a quarter count per ms per unit of MCV/MOV), so ^C can land
mid-motion. `--bug NAME` plants a bug (repeatable): lcvc-scaling, extra-args-ignored,
fsave-noop, full-block-for-c, lfdpc-ignored, fget-reversed, lcvc-ignored (the control velocity
is the datum alone), lfv-zero (the feedback velocity always reads 0). `--decide NAME` takes an
open point otherwise than the hand does by default (repeatable): lfdp-counts-from-home (LFDP
counts from the last position reported by FGET P, or from home, 0, where HI or RESET put it:
LOOP does not set it; the seed names only "the last reported position").
"""
import os
import select
import sys
import time

BUGS = {"lcvc-scaling", "extra-args-ignored", "fsave-noop", "full-block-for-c", "lfdpc-ignored", "fget-reversed",
        "lcvc-ignored", "lfv-zero"}
DECISIONS = {"lfdp-counts-from-home"}


def flags(name, known):
    out = set()
    for i, a in enumerate(sys.argv[:-1]):
        if a == name:
            v = sys.argv[i + 1]
            if v not in known:
                sys.stderr.write("seed_hand: unknown %s %s (one of %s)\n" % (name, v, ", ".join(sorted(known))))
                sys.exit(2)
            out.add(v)
    return out


PLANTED = flags("--bug", BUGS)
DECIDED = flags("--decide", DECISIONS)

NL = b"\n\r"
PROMPT = b"\n\r=> "
BOOL = (0, 1)
# name: (range, finger default, spread default); the saved set is every one but BAUD.
PARAMS = {
    "MOV": ((0, 255), 55, 35), "MCV": ((0, 255), 65, 35), "MSG": ((0, 256), 256, 256),
    "DS": ((0, 20000), 1200, 150), "DP": ((0, 20000), 1000, 150), "LCV": (BOOL, 1, 1),
    "LCVC": ((0, 255), 1, 1), "LCPG": (BOOL, 0, 0), "LFV": (BOOL, 1, 1), "LFVC": ((0, 255), 1, 1),
    "LFS": (BOOL, 1, 1), "LFAP": (BOOL, 1, 1), "LFDP": (BOOL, 0, 0), "LFDPC": ((0, 255), 1, 1),
    "FPG": ((0, 255), 200, 100), "FIP": ((0, 255), 66, 66), "FDZ": ((0, 255), 221, 221),
    "ACCEL": ((0, 32767), 1, 1), "MPE": ((0, 30000), 25, 25), "TSTOP": ((0, 32767), 30, 30),
    "HOLD": (BOOL, 0, 1), "SGFLIP": (BOOL, 0, 0), "EN": (BOOL, 1, 1),
}
FSET_NAMES = list(PARAMS) + ["BAUD"]
FGET_NAMES = FSET_NAMES + ["S", "P", "SG"]
READ_ONLY = {"S", "P", "SG"}
BAUDS = (6, 12, 24, 48, 96, 192, 384)
CODES = {1: "No motor board found", 2: "No motor found", 4: "Motor not initialized", 8: "not used",
         16: "Couldn't reach position", 32: "Unknown command", 64: "Unknown parameter name",
         128: "Invalid value", 256: "Tried to write a read only parameter", 512: "Timeout",
         1024: "Too many arguments for this command", 2048: "Invalid RealTime control block header",
         4096: "Command can't have motor prefix"}
NO_PREFIX = {"ERR", "FLISTA", "FLISTAV", "PGET", "RESET", "VERS", "?"}
MOTION = {"C", "O", "M", "IC", "IO", "HI", "T", "LOOP"}
COMMANDS = ["C", "ERR", "FDEF", "FGET", "FLISTA", "FLISTAV", "FLOAD", "FSAVE", "FSET", "HI", "IC",
            "IO", "LOOP", "M", "O", "PGET", "RESET", "T", "VERS"]
CLOSED = (17000, 17000, 17000, 3150)
SPEED = 0.25  # counts per ms per unit of velocity


def defaults():
    return [{n: (d[2] if m == 3 else d[1]) for n, d in PARAMS.items()} for m in range(4)]


class Hand:
    def __init__(self):
        self.eeprom = defaults()
        self.reset()
        self.inbuf = bytearray()
        self.line = bytearray()
        self.state = "idle"

    def reset(self):
        self.par = [dict(p) for p in self.eeprom]
        self.baud = 96
        self.init = [False] * 4
        self.pos = [0, 0, 0, 0]
        self.reported = [0, 0, 0, 0]  # R of the LFDP algorithm
        self.moves = {}

    def out(self, b):
        os.write(1, b)

    # ---- supervisory -------------------------------------------------------------------
    def execute(self, text):
        text = text.decode("latin-1").upper().strip()
        if not text:
            return self.out(PROMPT)
        i = 0
        while i < len(text) and text[i] in "1234GS":
            i += 1
        prefix, rest = text[:i], text[i:]
        if rest.startswith("?"):
            word, args = "?", rest[1:].split()
        else:
            parts = rest.split()
            word, args = (parts[0], parts[1:]) if parts else ("", [])
        motors = sorted({m for c in prefix for m in ({"G": (0, 1, 2), "S": (3,)}.get(c) or (int(c) - 1,))})
        if word not in COMMANDS and word != "?":
            return self.err(32)
        if prefix and word in NO_PREFIX:
            return self.err(4096)
        if not prefix:
            motors = [m for m in range(4) if self.par[m]["EN"]] if word in MOTION else [0, 1, 2, 3]
        handler = getattr(self, "cmd_" + ("HELP" if word == "?" else word))
        handler(motors, args)

    def err(self, code):
        self.out(NL + b"ERR %d" % code + PROMPT)

    def lines(self, rows, code=0):
        self.out(b"".join(NL + r.encode() for r in rows) + (NL + b"ERR %d" % code if code else b"") + PROMPT)

    def no_args(self, args):
        if args and "extra-args-ignored" not in PLANTED:
            self.err(1024)
            return False
        return True

    def cmd_FSET(self, motors, args):
        code, i = 0, 0
        if not args:
            code = 128
        while i < len(args) and not code:
            name = args[i]
            if name in READ_ONLY:
                code = 256
            elif name not in FSET_NAMES:
                code = 64
            elif i + 1 >= len(args) or not is_int(args[i + 1]):
                code = 128
            else:
                v = int(args[i + 1])
                if name == "BAUD":
                    if v not in BAUDS:
                        code = 128
                    else:
                        self.baud = v
                else:
                    lo_hi = PARAMS[name][0]
                    if not lo_hi[0] <= v <= lo_hi[1]:
                        code = 128
                    else:
                        for m in motors:
                            self.par[m][name] = v
            i += 2
        self.err(code) if code else self.out(PROMPT)

    def value(self, m, name):
        if name == "BAUD":
            return self.baud
        if name == "P":
            self.reported[m] = self.pos[m]
            return self.pos[m]
        if name == "S":
            return 0 if self.init[m] else 1
        if name == "SG":
            return 0
        return self.par[m][name]

    def cmd_FGET(self, motors, args):
        rows = []
        order = list(reversed(motors)) if "fget-reversed" in PLANTED else motors
        for name in args:
            if name not in FGET_NAMES:
                return self.lines(rows, 64)
            rows.append(" ".join(str(self.value(m, name)) for m in order))
        self.lines(rows)

    def cmd_PGET(self, motors, args):
        rows = []
        for name in args:
            if name not in ("TEMP", "TMP"):
                return self.lines(rows, 64)
            rows.append("250")
        self.lines(rows)

    def cmd_FDEF(self, motors, args):
        self.copy(motors, args, defaults(), self.par)

    def cmd_FLOAD(self, motors, args):
        self.copy(motors, args, self.eeprom, self.par)

    def cmd_FSAVE(self, motors, args):
        self.copy(motors, args, self.par, self.eeprom if "fsave-noop" not in PLANTED else defaults())

    def copy(self, motors, args, src, dst):
        if self.no_args(args):
            for m in motors:
                dst[m].update(src[m])
            self.out(PROMPT)

    def cmd_FLISTA(self, motors, args):
        if self.no_args(args):
            self.lines(["%s %s" % (n, "RO" if n in READ_ONLY else "RW") for n in FGET_NAMES])

    def cmd_FLISTAV(self, motors, args):
        if self.no_args(args):
            self.lines([" ".join(str(self.value(m, n)) for m in range(4)) for n in FGET_NAMES])

    def cmd_RESET(self, motors, args):
        if self.no_args(args):
            self.reset()
            self.lines(["BarrettHand Firmware, GCL seed hand"])

    def cmd_VERS(self, motors, args):
        if self.no_args(args):
            self.lines(["GCL seed hand 0.1, Barrett Technology"])

    def cmd_ERR(self, motors, args):
        if len(args) > 1:
            return self.err(1024)
        if args and not is_int(args[0]):
            return self.err(128)
        n = int(args[0]) if args else sum(CODES)
        self.lines(["%d %s" % (b, CODES[b]) for b in sorted(CODES) if n & b])

    def cmd_HELP(self, motors, args):
        if not args:
            return self.lines(COMMANDS)
        if args[0] not in COMMANDS or len(args) > 1:
            return self.err(32 if args[0] not in COMMANDS else 1024)
        self.lines(["%s: see the GCL seed" % args[0]])

    def cmd_T(self, motors, args):
        if self.no_args(args):
            self.err(1) if not all(self.init[m] for m in motors) else self.out(PROMPT)

    def cmd_HI(self, motors, args):
        if self.no_args(args):
            self.start({m: 0 for m in motors}, "HI", 100)

    def motion(self, motors, args, target, maxargs=0):
        if len(args) > maxargs and "extra-args-ignored" not in PLANTED:
            return self.err(1024)
        if not all(self.init[m] for m in motors):
            return self.err(4)
        goals = {}
        for m in motors:
            goals[m] = max(0, min(20000, target(m)))
        self.start(goals, "POS", 0)

    def cmd_C(self, motors, args):
        self.motion(motors, args, lambda m: CLOSED[m])

    def cmd_O(self, motors, args):
        self.motion(motors, args, lambda m: 0)

    def cmd_IC(self, motors, args):
        self.motion(motors, args, lambda m: self.pos[m] + self.par[m]["DS"])

    def cmd_IO(self, motors, args):
        self.motion(motors, args, lambda m: self.pos[m] - self.par[m]["DS"])

    def cmd_M(self, motors, args):
        if args and (not is_int(args[0]) or not 0 <= int(args[0]) <= 20000) and len(args) == 1:
            return self.err(128)
        self.motion(motors, args, lambda m: int(args[0]) if args else self.par[m]["DP"], 1)

    def start(self, goals, kind, extra_ms):
        now = time.monotonic()
        self.moves = {}
        end = now + extra_ms / 1000.0
        for m, g in goals.items():
            v = self.par[m]["MCV" if g > self.pos[m] else "MOV"] if kind == "POS" else 40
            rate = v * SPEED if v else 0
            dur = abs(g - self.pos[m]) / rate / 1000.0 if rate else self.par[m]["TSTOP"] / 1000.0
            self.moves[m] = (self.pos[m], g if rate else self.pos[m], now, dur)
            end = max(end, now + dur)
        self.kind, self.deadline, self.state = kind, end, "busy"

    def settle(self, now):
        for m, (p0, g, t0, dur) in self.moves.items():
            f = 1.0 if dur <= 0 else min(1.0, (now - t0) / dur)
            self.pos[m] = int(round(p0 + (g - p0) * f))

    def finish(self, aborted):
        self.settle(time.monotonic())
        if self.kind == "HI" and not aborted:
            for m in self.moves:
                self.init[m], self.pos[m] = True, 0
                if "lfdp-counts-from-home" in DECIDED:
                    self.reported[m] = 0
        code = 0
        if not aborted and self.kind == "POS":
            if any(abs(self.pos[m] - g) > self.par[m]["MPE"] for m, (_, g, _, _) in self.moves.items()):
                code = 16
        self.moves, self.state = {}, "idle"
        self.err(code) if code else self.out(PROMPT)

    def cmd_LOOP(self, motors, args):
        if not self.no_args(args):
            return
        if not all(self.init[m] for m in motors):
            return self.err(4)
        self.loop = motors
        self.vel = {m: 0 for m in motors}
        self.t = time.monotonic()
        if "lfdp-counts-from-home" not in DECIDED:
            for m in motors:
                self.reported[m] = self.pos[m]
        self.state = "loop"
        self.out(b"*")

    # ---- RealTime ----------------------------------------------------------------------
    def advance(self):
        now = time.monotonic()
        dt = (now - self.t) * 1000.0
        self.t = now
        for m in self.loop:
            p = self.pos[m] + self.vel[m] * SPEED * dt
            self.pos[m] = int(round(max(0, min(20000, p))))

    def feedback(self):
        out = bytearray(b"*")
        for m in self.loop:
            p = self.par[m]
            if p["LFV"]:
                v = 0 if "lfv-zero" in PLANTED else int(self.vel[m] / max(1, p["LFVC"]))
                out += (max(-128, min(127, v)) & 0xFF).to_bytes(1, "big")
            if p["LFS"]:
                out.append(255 if p["SGFLIP"] else 0)
            if p["LFAP"]:
                out += self.pos[m].to_bytes(2, "big")
            if p["LFDP"]:
                c = 1 if "lfdpc-ignored" in PLANTED else max(1, p["LFDPC"])
                d = self.pos[m] - self.reported[m]
                q = max(-128, min(127, int(d / c)))
                self.reported[m] += q * c
                out += (q & 0xFF).to_bytes(1, "big")
        return bytes(out)

    def realtime(self):
        h = self.inbuf[0]
        if h == 3:
            del self.inbuf[:1]
            self.advance()
            self.state = "idle"
            return self.out(PROMPT)
        if h not in b"CcAa":
            del self.inbuf[:1]
            self.state = "idle"
            return self.err(2048)
        data = h in b"Cc"
        need = 1 + (sum(self.par[m]["LCV"] + self.par[m]["LCPG"] for m in self.loop) if data else 0)
        if len(self.inbuf) < need:
            return "wait"
        block = bytes(self.inbuf[1:need])
        del self.inbuf[:need]
        self.advance()
        full = h in b"CA" or (h == ord("c") and "full-block-for-c" in PLANTED)
        self.out(self.feedback() if full else b"*")
        i = 0
        for m in self.loop if data else ():
            if self.par[m]["LCV"]:
                datum = block[i] - 256 if block[i] > 127 else block[i]
                lcvc = 1 if "lcvc-ignored" in PLANTED else self.par[m]["LCVC"]
                # the planted bug divides by LCVC where the seed multiplies (the same at 1)
                self.vel[m] = int(datum / max(1, lcvc)) if "lcvc-scaling" in PLANTED else datum * lcvc
                i += 1
            if self.par[m]["LCPG"]:
                i += 1

    # ---- the byte pump -----------------------------------------------------------------
    def pump(self):
        while True:
            if self.state == "busy":
                if 3 in self.inbuf:
                    del self.inbuf[: self.inbuf.index(3) + 1]  # ^C clears the input buffer
                    self.finish(True)
                elif time.monotonic() >= self.deadline:
                    self.finish(False)
                else:
                    return
            elif self.state == "loop":
                if not self.inbuf or self.realtime() == "wait":
                    return
            else:
                if not self.inbuf:
                    return
                b = self.inbuf.pop(0)
                if b == 3:
                    self.line = bytearray()
                    self.out(PROMPT)
                elif b == 13:
                    line, self.line = bytes(self.line), bytearray()
                    self.execute(line)
                elif b != 10:
                    self.out(bytes([b]))
                    self.line.append(b)


def is_int(s):
    return s.lstrip("-").isdigit()


def main():
    hand = Hand()
    hand.out(b"BarrettHand Firmware, GCL seed hand" + PROMPT)
    while True:
        timeout = max(0.0, hand.deadline - time.monotonic()) if hand.state == "busy" else None
        ready, _, _ = select.select([0], [], [], timeout)
        if ready:
            data = os.read(0, 4096)
            if not data:
                return
            hand.inbuf += data
        hand.pump()


if __name__ == "__main__":
    main()
