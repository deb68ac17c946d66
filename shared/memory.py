"""Keep a service's resident memory near what it uses.

:func:`keep_openssl_out` spares every service OpenSSL, which it never uses. :func:`return_large_blocks`
is for services that make large short-lived arrays: glibc serves allocations above a threshold with their own ``mmap`` and gives them back on ``free``, but it
raises that threshold each time such a block is freed (up to 32 MiB), after which image-sized numpy
temporaries come from the heap and stay resident. A camera frame's working arrays (a few MiB each, made
and dropped fifteen times a second) then hold tens of MiB for good. Fixing the threshold keeps them
returned. Elsewhere (another libc, another OS) this does nothing.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import sys

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


def keep_openssl_out() -> bool:
    """Make ``hashlib`` and ``hmac`` use the interpreter's own hashes instead of OpenSSL's; call it first thing.

    pydantic imports ``secrets``, hence ``hmac`` and ``hashlib``, whose ``_hashlib`` maps OpenSSL's
    libcrypto: 3.5 MB of RSS in each service, none of which hashes more than a few kB (the glass memory's
    digest). Without ``_hashlib`` both modules fall back to the built-in md5, sha1, sha2, sha3 and blake2;
    what only OpenSSL has (``pbkdf2_hmac``, ``scrypt``) is then missing. True when it took effect: False
    once something has imported ``_hashlib`` already.
    """
    if "_hashlib" in sys.modules:
        return sys.modules["_hashlib"] is None
    sys.modules["_hashlib"] = None  # type: ignore[assignment]  # import raises ImportError from now on
    return True


__all__ = ["keep_openssl_out", "return_large_blocks"]
