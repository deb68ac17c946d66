"""Telling a module loaded from its bytecode cache from one compiled from source on import."""

from __future__ import annotations

import importlib
import os
import py_compile
import sys
from pathlib import Path

import pytest

from deploy.bench.bytecode import bytecode_is_fresh, compiled_from_source, own_modules


def _write(path: Path, text: str, mtime: int) -> Path:
    path.write_text(text)
    os.utime(path, (mtime, mtime))
    return path


def test_a_source_is_fresh_only_with_a_cache_file_of_its_own_mtime_and_size(tmp_path: Path) -> None:
    source = _write(tmp_path / "fresh_mod.py", "X = 1\n", 1_700_000_000)
    assert not bytecode_is_fresh(source)  # no cache file at all
    py_compile.compile(str(source))
    assert bytecode_is_fresh(source)
    _write(source, "X = 2\n", 1_700_000_100)  # edited after the cache was written
    assert not bytecode_is_fresh(source)
    py_compile.compile(str(source))
    assert bytecode_is_fresh(source)
    _write(source, "X = 22\n", 1_700_000_100)  # same mtime, another size
    assert not bytecode_is_fresh(source)


def test_a_truncated_or_foreign_cache_file_does_not_count(tmp_path: Path) -> None:
    source = _write(tmp_path / "odd_mod.py", "X = 1\n", 1_700_000_000)
    cached = Path(py_compile.compile(str(source)))
    cached.write_bytes(b"\x00" * 16)  # another interpreter's magic number
    assert not bytecode_is_fresh(source)
    cached.write_bytes(b"")
    assert not bytecode_is_fresh(source)


def test_the_processs_own_modules_under_a_root_are_counted_with_those_compiled(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    package = tmp_path / "bytecode_probe_pkg"
    package.mkdir()
    _write(package / "__init__.py", "", 1_700_000_000)
    cached = _write(package / "cached.py", "A = 1\n", 1_700_000_000)
    _write(package / "compiled.py", "B = 2\n", 1_700_000_000)
    py_compile.compile(str(package / "__init__.py"))
    py_compile.compile(str(cached))
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setattr(sys, "dont_write_bytecode", True)  # the import must not write the missing cache
    try:
        importlib.import_module("bytecode_probe_pkg.cached")
        importlib.import_module("bytecode_probe_pkg.compiled")
        assert [p.name for p in own_modules(tmp_path)] == ["__init__.py", "cached.py", "compiled.py"]
        assert compiled_from_source(tmp_path) == (3, 1)
    finally:
        for name in ("bytecode_probe_pkg", "bytecode_probe_pkg.cached", "bytecode_probe_pkg.compiled"):
            sys.modules.pop(name, None)
