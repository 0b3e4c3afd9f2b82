"""A host that installs a seccomp filter with a user-notification listener of its own (as a
sandboxing host or test runner might), then writes the errno of the attempt (0: it worked)
to OUT (argv[1]) and exits. Linux only; x86-64 or aarch64.

Expected: over `--tcp` the attempt fails with EBUSY (16): `gcl` watches the host's writes
with such a listener, and a process tree has one at most (README). Over `--pty` it works.
"""
import ctypes
import platform
import struct
import sys

SYS_SECCOMP = {"x86_64": 317, "aarch64": 277}[platform.machine()]
PR_SET_NO_NEW_PRIVS = 38
SECCOMP_SET_MODE_FILTER = 1
SECCOMP_FILTER_FLAG_NEW_LISTENER = 8
SECCOMP_RET_ALLOW = 0x7FFF0000
BPF_RET_K = 0x06


class SockFprog(ctypes.Structure):
    _fields_ = [("len", ctypes.c_ushort), ("filter", ctypes.c_void_p)]


libc = ctypes.CDLL(None, use_errno=True)
libc.syscall.restype = ctypes.c_long
program = ctypes.create_string_buffer(struct.pack("HBBI", BPF_RET_K, 0, 0, SECCOMP_RET_ALLOW))
prog = SockFprog(1, ctypes.addressof(program))
libc.prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0)
r = libc.syscall(SYS_SECCOMP, SECCOMP_SET_MODE_FILTER, SECCOMP_FILTER_FLAG_NEW_LISTENER, ctypes.byref(prog))
with open(sys.argv[1], "w") as f:
    f.write(str(0 if r >= 0 else ctypes.get_errno()))
