"""Whether a process's own modules came from their bytecode cache or were compiled from source.

Python compiles a module's source each time it imports it unless a ``__pycache__`` file as new as the
source exists; it writes that file on the first import unless ``PYTHONDONTWRITEBYTECODE`` is set. With
it set and no cache (a fresh clone on a machine that sets it), every service start compiles every zendock
module it imports (what that costs: measurement 107). ``make`` writes the cache (``compileall``), and
``zendock bench startup`` says how many modules a service compiled, so a start-up figure is never read
without knowing which of the two it measured.
"""

from __future__ import annotations

import importlib.util
import os
import sys
from pathlib import Path

#: A cache file starts with the magic number, flags, then (timestamp-based) the source's mtime and size.
_HEADER_BYTES = 16


def bytecode_is_fresh(source: Path) -> bool:
    """Whether the import system would load ``source`` from its cache file rather than compile it."""
    cached = Path(importlib.util.cache_from_source(str(source)))
    try:
        with cached.open("rb") as handle:
            header = handle.read(_HEADER_BYTES)
        stat = source.stat()
    except OSError:
        return False
    if len(header) < _HEADER_BYTES or header[:4] != importlib.util.MAGIC_NUMBER:
        return False
    flags = int.from_bytes(header[4:8], "little")
    if flags & 0b1:  # hash-based: checked against the source's hash on import, or not at all
        return True
    mtime = int.from_bytes(header[8:12], "little")
    size = int.from_bytes(header[12:16], "little")
    return mtime == int(stat.st_mtime) & 0xFFFFFFFF and size == stat.st_size & 0xFFFFFFFF


def own_modules(root: Path) -> list[Path]:
    """The source files under ``root`` of the modules imported in this process so far."""
    prefix = str(root.resolve()) + os.sep
    files = {getattr(module, "__file__", None) for module in list(sys.modules.values())}
    return sorted(Path(f) for f in files if f and f.endswith(".py") and f.startswith(prefix))


def compiled_from_source(root: Path) -> tuple[int, int]:
    """``(modules, compiled)``: how many of this process's modules under ``root`` there are, and how many
    of them had no fresh cache file, so that their import compiled the source."""
    files = own_modules(root)
    return len(files), sum(not bytecode_is_fresh(f) for f in files)
