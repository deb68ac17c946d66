"""Keep a service's resident memory near what it uses, for services that make large short-lived arrays.

glibc serves allocations above a threshold with their own ``mmap`` and gives them back on ``free``, but it
raises that threshold each time such a block is freed (up to 32 MiB), after which image-sized numpy
temporaries come from the heap and stay resident. A camera frame's working arrays (a few MiB each, made
and dropped fifteen times a second) then hold tens of MiB for good. Fixing the threshold keeps them
returned. Elsewhere (another libc, another OS) this does nothing.
"""

from __future__ import annotations

import ctypes
import ctypes.util

_M_MMAP_THRESHOLD = -3  # glibc's mallopt parameter number


def return_large_blocks(threshold_bytes: int = 128 * 1024) -> bool:
    """Serve blocks of ``threshold_bytes`` or more by mmap for good; True when the C library agreed."""
    name = ctypes.util.find_library("c")
    if name is None:
        return False
    try:
        libc = ctypes.CDLL(name)
        return bool(libc.mallopt(_M_MMAP_THRESHOLD, ctypes.c_int(threshold_bytes)))
    except (OSError, AttributeError):  # not glibc: no mallopt
        return False


__all__ = ["return_large_blocks"]
