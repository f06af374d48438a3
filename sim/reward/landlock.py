"""Linux Landlock through ctypes: a process gives up, for good, the files it does not need.

Landlock (Linux 5.13 and later) lets an unprivileged process restrict itself and every
process it starts: after `restrict`, opening a file is allowed only beneath the folders (or
for the files) given, with the rights given, and nothing else; files already open stay
usable. racer-tui uses it around a racer's reward function (sim.reward.sandbox). No
library wraps it for Python in the standard library, so the three system calls are made
directly (their numbers are the same on every Linux architecture).

Where the kernel lacks Landlock (another OS, an old kernel, Landlock not enabled at boot)
`restrict` changes nothing and says why; the caller records that and goes on.
"""

from __future__ import annotations

import ctypes
import os
import sys
from collections.abc import Iterable
from pathlib import Path

_CREATE_RULESET = 444
_ADD_RULE = 445
_RESTRICT_SELF = 446
_CREATE_RULESET_VERSION = 1
_RULE_PATH_BENEATH = 1
_RULE_NET_PORT = 2
_PR_SET_NO_NEW_PRIVS = 38

# Filesystem rights (include/uapi/linux/landlock.h) and the ABI that brought each.
EXECUTE = 1 << 0
WRITE_FILE = 1 << 1
READ_FILE = 1 << 2
READ_DIR = 1 << 3
_WRITE_TREE = sum(1 << bit for bit in range(4, 13))  # remove, make dir/file/node/link
REFER = 1 << 13  # ABI 2
TRUNCATE = 1 << 14  # ABI 3
IOCTL_DEV = 1 << 15  # ABI 5
_FS_BY_ABI = {
    1: EXECUTE | WRITE_FILE | READ_FILE | READ_DIR | _WRITE_TREE,
    2: REFER,
    3: TRUNCATE,
    5: IOCTL_DEV,
}
_FILE_ONLY = EXECUTE | WRITE_FILE | READ_FILE | TRUNCATE | IOCTL_DEV
READ = READ_FILE | READ_DIR
READ_WRITE = READ | WRITE_FILE | _WRITE_TREE | REFER | TRUNCATE
# Network (ABI 4): with these handled and no port allowed, no TCP bind or connect.
_NET_BIND_TCP = 1 << 0
_NET_CONNECT_TCP = 1 << 1
# Scopes (ABI 6): no abstract unix socket, no signal, to a process outside the sandbox.
_SCOPE_ABSTRACT_UNIX_SOCKET = 1 << 0
_SCOPE_SIGNAL = 1 << 1


class _PathBeneath(ctypes.Structure):
    _pack_ = 1
    _fields_ = (("allowed_access", ctypes.c_uint64), ("parent_fd", ctypes.c_int32))


class _RulesetAttr(ctypes.Structure):
    _fields_ = (
        ("handled_access_fs", ctypes.c_uint64),
        ("handled_access_net", ctypes.c_uint64),
        ("scoped", ctypes.c_uint64),
    )


def _libc() -> ctypes.CDLL:
    libc = ctypes.CDLL(None, use_errno=True)
    libc.syscall.restype = ctypes.c_long
    return libc


def abi_version() -> int:
    """The kernel's Landlock ABI version; 0 when there is none to use."""
    if not sys.platform.startswith("linux"):
        return 0
    try:
        version = _libc().syscall(
            _CREATE_RULESET, None, ctypes.c_size_t(0), _CREATE_RULESET_VERSION
        )
    except (OSError, AttributeError):
        return 0
    return max(0, int(version))


def _handled_fs(abi: int) -> int:
    return sum(rights for since, rights in _FS_BY_ABI.items() if abi >= since)


def restrict(
    read: Iterable[Path], read_write: Iterable[Path] = (), *, scope_signals: bool = True
) -> str | None:
    """From now on this process (and what it starts) may open only the files beneath `read`
    for reading, and beneath `read_write` for reading and writing, may not run programs,
    and (where the kernel can) may not use TCP, abstract unix sockets, or, with
    `scope_signals`, signal a process outside it. Paths that do not exist are left out.
    Returns None when applied, else why not (nothing was changed)."""
    abi = abi_version()
    if abi < 1:
        return "this system has no Landlock (Linux 5.13 or later with Landlock enabled)"
    handled = _handled_fs(abi)
    attr = _RulesetAttr(handled_access_fs=handled)
    size = 8
    if abi >= 4:
        attr.handled_access_net = _NET_BIND_TCP | _NET_CONNECT_TCP
        size = 16
    if abi >= 6:
        attr.scoped = _SCOPE_ABSTRACT_UNIX_SOCKET | (_SCOPE_SIGNAL if scope_signals else 0)
        size = 24
    libc = _libc()
    ruleset = libc.syscall(_CREATE_RULESET, ctypes.byref(attr), ctypes.c_size_t(size), 0)
    if ruleset < 0:
        return f"Landlock refused a ruleset ({os.strerror(ctypes.get_errno())})"
    try:
        for paths, rights in ((read, READ), (read_write, READ_WRITE)):
            for path in paths:
                problem = _allow(libc, int(ruleset), path, rights & handled)
                if problem is not None:
                    return problem
        if libc.prctl(_PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0:
            return f"no_new_privs could not be set ({os.strerror(ctypes.get_errno())})"
        if libc.syscall(_RESTRICT_SELF, int(ruleset), 0) != 0:
            return f"Landlock could not be applied ({os.strerror(ctypes.get_errno())})"
    finally:
        os.close(int(ruleset))
    return None


def _allow(libc: ctypes.CDLL, ruleset: int, path: Path, rights: int) -> str | None:
    try:
        fd = os.open(path, os.O_PATH | os.O_CLOEXEC)
    except OSError:
        return None  # nothing there to allow
    try:
        if not os.path.isdir(path):
            rights &= _FILE_ONLY  # a file takes only a file's rights
        rule = _PathBeneath(allowed_access=rights, parent_fd=fd)
        if libc.syscall(_ADD_RULE, ruleset, _RULE_PATH_BENEATH, ctypes.byref(rule), 0) != 0:
            return f"Landlock refused a rule for {path} ({os.strerror(ctypes.get_errno())})"
    finally:
        os.close(fd)
    return None
