"""Keep a service's resident memory near what it uses.

:func:`keep_openssl_out` spares every service OpenSSL, which none of them uses.

Image-sized temporaries (a camera frame's working arrays, made and dropped fifteen times a second) are
left to glibc's own rule: after the first one is freed they come from the heap and are reused. Returning
each to the system (a fixed ``mmap`` threshold) kept the simulator's steady RSS 5 MB lower but not its
peak, and its page faults made a rendered frame cost 35 % more CPU (measurement 61).
"""

from __future__ import annotations

import sys


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


__all__ = ["keep_openssl_out"]
