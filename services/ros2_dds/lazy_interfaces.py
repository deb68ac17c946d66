"""Load a ROS 2 interface package's classes one at a time, as the face first asks for each.

A generated ``<pkg>/msg/__init__.py`` (and ``srv``, ``action``) is nothing but one ``from
<pkg>.msg._snake_name import Name`` line per interface, so ``from nav2_msgs.action import NavigateToPose``
executes every action module of the package: code, class objects and metaclasses the face never uses
(``nav2_msgs.action`` alone is 15 modules and 1.3 MB of bytecode). :func:`load_interfaces_on_use` puts a
finder ahead of the path finder that gives such a package a module whose attributes are imported on first
access (PEP 562's module ``__getattr__``), from the same ``from ... import ...`` lines read as text.

A package whose ``__init__`` holds anything else is loaded the ordinary way; so is every other module.
The classes are the same objects an eager import makes: only the moment each is imported changes.
"""

from __future__ import annotations

import ast
import importlib
import importlib.machinery
import importlib.util
import sys
import threading
from collections.abc import Sequence
from pathlib import Path
from types import ModuleType
from typing import Any

#: The sub-packages rosidl generates, one per kind of interface.
INTERFACE_KINDS = frozenset({"msg", "srv", "action"})


def interface_index(init_source: str, package: str) -> dict[str, str] | None:
    """``{Name: module}`` from a generated ``__init__``'s text; None when it is anything else.

    Generated means: each statement is ``from <package>._snake import Name`` (one name, no alias, an
    absolute import of a direct submodule). Docstrings or other statements make it not generated.
    """
    try:
        tree = ast.parse(init_source)
    except SyntaxError:
        return None
    index: dict[str, str] = {}
    for statement in tree.body:
        if not (
            isinstance(statement, ast.ImportFrom)
            and statement.level == 0
            and statement.module is not None
            and statement.module.rpartition(".")[0] == package
            and len(statement.names) == 1
            and statement.names[0].asname is None
        ):
            return None
        index[statement.names[0].name] = statement.module
    return index or None


class _OnUseLoader:
    """Executes nothing at import: the module's ``__getattr__`` imports each class when it is first read.

    (The loader and finder protocols are met without ``importlib.abc``, which imports ``tempfile`` and
    ``shutil`` through ``importlib.resources``: 1.3 MB of RSS when imported on their own.)
    """

    def __init__(self, index: dict[str, str]) -> None:
        self._index = index

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType | None:
        return None  # the default module object

    def exec_module(self, module: ModuleType) -> None:
        index = self._index

        def __getattr__(name: str) -> Any:
            submodule = index.get(name)
            if submodule is None:
                raise AttributeError(f"module {module.__name__!r} has no attribute {name!r}")
            value = getattr(importlib.import_module(submodule), name)
            setattr(module, name, value)  # later reads skip __getattr__
            return value

        def __dir__() -> list[str]:
            return sorted(set(module.__dict__) | set(index))

        module.__getattr__ = __getattr__  # type: ignore[method-assign]
        module.__dir__ = __dir__  # type: ignore[method-assign]
        module.__all__ = sorted(index)  # type: ignore[attr-defined]


class OnUseInterfaceFinder:
    """Finds ``<pkg>.msg`` / ``.srv`` / ``.action`` with a generated ``__init__`` and loads it on use."""

    def find_spec(
        self, fullname: str, path: Sequence[str] | None, target: ModuleType | None = None
    ) -> importlib.machinery.ModuleSpec | None:
        package, _, kind = fullname.rpartition(".")
        if kind not in INTERFACE_KINDS or not package or "." in package:
            return None
        spec = importlib.machinery.PathFinder.find_spec(fullname, path)
        if spec is None or spec.origin is None or not spec.origin.endswith("__init__.py"):
            return None
        try:
            source = Path(spec.origin).read_text(encoding="utf-8")
        except OSError:
            return None
        index = interface_index(source, fullname)
        if index is None:
            return None
        loader: Any = _OnUseLoader(index)  # a loader by protocol (see _OnUseLoader)
        on_use = importlib.machinery.ModuleSpec(fullname, loader, origin=spec.origin, is_package=True)
        on_use.submodule_search_locations = spec.submodule_search_locations
        on_use.has_location = True
        return on_use


def load_interfaces_on_use() -> bool:
    """Install the finder (once); call it before the first message import. True when it is in place."""
    if not any(isinstance(finder, OnUseInterfaceFinder) for finder in sys.meta_path):
        sys.meta_path.insert(0, OnUseInterfaceFinder())
    return True


#: The packages :func:`load_on_first_use` stood in for.
_STOOD_IN: set[str] = set()


class _MadeByItsPackage:
    """``import pkg.sub`` under a stood-in package: reading the stand-in's ``__path__`` imported the package,
    whose own import may have made ``pkg.sub`` already. Python would run ``pkg.sub`` a second time (two
    copies of its classes, one of them the package's); this finder hands over the one the package made."""

    def find_spec(
        self, fullname: str, path: Sequence[str] | None, target: ModuleType | None = None
    ) -> importlib.machinery.ModuleSpec | None:
        made = sys.modules.get(fullname)
        if made is None or fullname.rpartition(".")[0] not in _STOOD_IN:
            return None
        loader: Any = _AlreadyMade(made)  # a loader by protocol (see _OnUseLoader)
        return importlib.machinery.ModuleSpec(fullname, loader)


class _AlreadyMade:
    """Loads a module that is already made: the same object, its own spec kept."""

    def __init__(self, module: ModuleType) -> None:
        self._module = module
        self._spec = module.__spec__

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType:
        return self._module

    def exec_module(self, module: ModuleType) -> None:
        module.__spec__ = self._spec  # the import machinery set ours


#: One module stood in for is imported at a time: two threads reading it first must not both swap it.
_STAND_IN_LOCK = threading.RLock()


class _OnFirstUse(ModuleType):
    """Stands in for a module until an attribute is read, then imports it and hands every read on to it."""

    def __getattr__(self, attr: str) -> Any:
        name = self.__name__
        with _STAND_IN_LOCK:
            if sys.modules.get(name) is self:
                sys.modules.pop(name)
            real = importlib.import_module(name)
            self.__dict__.update(real.__dict__)  # later reads find the real attributes directly
        return getattr(real, attr)


def load_on_first_use(name: str) -> bool:
    """Let ``import name`` succeed now and import the module only when one of its attributes is first read.

    For a module a library imports at its top only for a function the face never calls: rclpy's
    ``parameter`` imports ``yaml`` (0.8 MB with libyaml) to parse parameter strings and files.
    (``importlib.util.LazyLoader`` does not serve here: on Python 3.11 the import statement's own read of
    ``__spec__`` loads the module.) True when it took effect: False when ``name`` is imported already or
    cannot be found.
    """
    if name in sys.modules:
        return False
    spec = importlib.util.find_spec(name)
    if spec is None:
        return False
    placeholder = _OnFirstUse(name)
    placeholder.__spec__ = spec
    sys.modules[name] = placeholder
    if spec.submodule_search_locations is not None:
        _STOOD_IN.add(name)
        if not any(isinstance(finder, _MadeByItsPackage) for finder in sys.meta_path):
            sys.meta_path.insert(0, _MadeByItsPackage())
    return True
