"""Keep a service's process lean: its resident memory near what it uses, its start free of work it never needs.

:func:`keep_openssl_out` spares every service OpenSSL, which none of them uses;
:func:`skip_pydantic_plugin_scan` spares it pydantic's search of every installed package for plugins.

Image-sized temporaries (a camera frame's working arrays, made and dropped fifteen times a second) are
left to glibc's own rule: after the first one is freed they come from the heap and are reused. Returning
each to the system (a fixed ``mmap`` threshold) kept the simulator's steady RSS lower but not its peak,
and its page faults made every rendered frame dearer (measurement 61).
"""

from __future__ import annotations

import os
import sys

#: pydantic's switch for its plugins: ``__all__`` turns them all off (an empty value turns them back on).
PYDANTIC_PLUGINS_ENV = "PYDANTIC_DISABLE_PLUGINS"


def keep_openssl_out() -> bool:
    """Make ``hashlib`` and ``hmac`` use the interpreter's own hashes instead of OpenSSL's; call it first thing.

    pydantic imports ``secrets``, hence ``hmac`` and ``hashlib``, whose ``_hashlib`` maps OpenSSL's libcrypto
    into every service's memory (measurement 61), and none of them hashes more than a few kB (the glass
    memory's digest). Without ``_hashlib`` both modules fall back to the built-in md5, sha1, sha2, sha3 and
    blake2; what only OpenSSL has (``pbkdf2_hmac``, ``scrypt``) is then missing. True when it took effect:
    False once something has imported ``_hashlib`` already.
    """
    if "_hashlib" in sys.modules:
        return sys.modules["_hashlib"] is None
    sys.modules["_hashlib"] = None  # type: ignore[assignment]  # import raises ImportError from now on
    return True


def skip_pydantic_plugin_scan() -> None:
    """Turn pydantic's plugins off unless the environment says otherwise; call it before the first model.

    The first pydantic model a process defines makes pydantic read the entry points of every installed
    distribution, looking for plugins, a cost that grows with what is installed (measurement 97). zendock
    uses no pydantic plugin. Setting the variable (to an empty
    value, say) keeps whatever the user chose.
    """
    os.environ.setdefault(PYDANTIC_PLUGINS_ENV, "__all__")


__all__ = ["PYDANTIC_PLUGINS_ENV", "keep_openssl_out", "skip_pydantic_plugin_scan"]
