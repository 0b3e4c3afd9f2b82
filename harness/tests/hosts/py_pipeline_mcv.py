"""BUG (modelled on a real host script): writes `1FGET MCV` and then, without reading its
answer, `GC`. On a serial line the G arrives while the FGET answer is still coming.

Finding: violation host-waits-for-answer, at any line speed, fast or real time.
Usage: py_pipeline_mcv.py [PORT] [BAUD] (default: $GCL_PORT, 9600). Needs pyserial.
"""
import os
import sys

import serial


def main():
    port = sys.argv[1] if len(sys.argv) > 1 else os.environ["GCL_PORT"]
    baud = int(sys.argv[2]) if len(sys.argv) > 2 else 9600
    s = serial.serial_for_url(port, baudrate=baud, timeout=2)
    s.write(b"1FGET MCV\r")
    s.write(b"GC\r")
    got = s.read_until(b"=> ")
    got += s.read_until(b"=> ")
    s.close()
    sys.stderr.write("read %r\n" % (got,))


try:
    main()
except (serial.SerialException, OSError) as e:
    print("host: %s" % e, file=sys.stderr)
    sys.exit(1)
