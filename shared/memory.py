"""Keep a service's process lean: its resident memory near what it uses, its start free of work it never needs.

:func:`keep_openssl_out` spares every service OpenSSL, which none of them uses; :func:`keep_blas_single_threaded`
spares it OpenBLAS's thread pool, which none of them needs.

Image-sized temporaries (a camera frame's working arrays, made and dropped fifteen times a second) are
left to glibc's own rule: after the first one is freed they come from the heap and are reused. Returning
each to the system (a fixed ``mmap`` threshold) kept the simulator's steady RSS lower but not its peak,
and its page faults made every rendered frame dearer (measurement 61).
"""

from __future__ import annotations

import os
import sys


def keep_openssl_out() -> bool:
    """Make ``hashlib`` and ``hmac`` use the interpreter's own hashes instead of OpenSSL's; call it first thing.

    ``hashlib`` (the glass memory's digest, foxglove, ``secrets``) loads
    ``_hashlib``, which maps OpenSSL's libcrypto into the process (measurement 61), and no service hashes
    more than a few kB. Without ``_hashlib`` both modules fall back to the built-in md5, sha1, sha2, sha3 and
    blake2; what only OpenSSL has (``pbkdf2_hmac``, ``scrypt``) is then missing. True when it took effect:
    False once something has imported ``_hashlib`` already.
    """
    if "_hashlib" in sys.modules:
        return sys.modules["_hashlib"] is None
    sys.modules["_hashlib"] = None  # type: ignore[assignment]  # import raises ImportError from now on
    return True


def keep_blas_single_threaded() -> bool:
    """Let OpenBLAS, which numpy loads, start no threads of its own; call it before anything imports numpy.

    OpenBLAS starts a thread per core when numpy is imported, and they spin a while: on the 2-core machine
    ``import numpy`` took 0.21-0.24 s of CPU against 0.17-0.18 s with one thread, the other core's time taken
    from the services starting beside it. No service multiplies matrices larger than a few rows, where the
    threads never help. A user's own ``OPENBLAS_NUM_THREADS`` is kept. True when it took effect: False
    once numpy has been imported, or when the user set the variable."""
    if "numpy" in sys.modules or "OPENBLAS_NUM_THREADS" in os.environ:
        return False
    os.environ["OPENBLAS_NUM_THREADS"] = "1"
    return True


__all__ = ["keep_blas_single_threaded", "keep_openssl_out"]
