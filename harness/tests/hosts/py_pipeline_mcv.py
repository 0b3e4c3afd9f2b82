"""BUG (modelled on a real host script): writes `1FGET MCV` and then, without reading its
answer, `GC`. On a serial line the G arrives while the FGET answer is still coming.

Finding: violation host-waits-for-answer, at any line speed, fast or real time, over a pty
or TCP, however long the host takes between its two writes (the answer may then be there
whole, unread, when the G comes).
Usage: py_pipeline_mcv.py [PORT] [BAUD] [PAUSE] [READ_PAUSE] (default: $GCL_PORT, 9600, 0 s
between the two writes, 0 s between the second write and the first read). Needs pyserial.
"""
import os
import sys
import time

import serial


def main():
    port = sys.argv[1] if len(sys.argv) > 1 else os.environ["GCL_PORT"]
    baud = int(sys.argv[2]) if len(sys.argv) > 2 else 9600
    pause = float(sys.argv[3]) if len(sys.argv) > 3 else 0.0
    read_pause = float(sys.argv[4]) if len(sys.argv) > 4 else 0.0
    s = serial.serial_for_url(port, baudrate=baud, timeout=2)
    s.write(b"1FGET MCV\r")
    time.sleep(pause)
    s.write(b"GC\r")
    time.sleep(read_pause)
    got = s.read_until(b"=> ")
    got += s.read_until(b"=> ")
    s.close()
    sys.stderr.write("read %r\n" % (got,))


try:
    main()
except (serial.SerialException, OSError) as e:
    print("host: %s" % e, file=sys.stderr)
    sys.exit(1)
