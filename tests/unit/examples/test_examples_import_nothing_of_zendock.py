"""The examples prove a user can replace a zendock service from its contracts alone, so their code must not
lean on zendock: no import of ``shared``, ``services`` or ``deploy``, and nothing beyond eclipse-zenoh,
msgpack, numpy, OpenCV, PyYAML (the world file a dock database is) and the standard library (plus the
examples' own modules, such as ``wire``).

A user's tests under ``examples/tests/`` drive a zendock stack through zendock's pytest plugin, so they may
import ``deploy.testing`` (and pytest), nothing else of zendock: it is the replacement services that must
stand alone.
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[3] / "examples"
ZENDOCK_PACKAGES = {"shared", "services", "deploy"}
ALLOWED_THIRD_PARTY = {"zenoh", "msgpack", "numpy", "cv2", "yaml"}
#: What a user's tests may import of zendock: its pytest plugin.
TEST_PLUGIN = "deploy.testing"


def _is_test(path: Path) -> bool:
    return "tests" in path.relative_to(EXAMPLES).parts[:-1]


def _service_sources() -> list[Path]:
    return sorted(p for p in EXAMPLES.rglob("*.py") if not _is_test(p))


def _zendock_import(path: Path, module: str) -> bool:
    if module.split(".")[0] not in ZENDOCK_PACKAGES:
        return False
    return not (_is_test(path) and (module == TEST_PLUGIN or module.startswith(TEST_PLUGIN + ".")))


def _imported_modules(path: Path) -> list[tuple[int, str]]:
    """``(line, module)`` of every import in a file, including ``importlib.import_module("...")`` and
    ``__import__("...")`` with a literal name; relative imports are the examples' own."""
    found: list[tuple[int, str]] = []
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            found += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            found.append((node.lineno, node.module))
        elif isinstance(node, ast.Call) and node.args and isinstance(node.args[0], ast.Constant):
            name = node.func.attr if isinstance(node.func, ast.Attribute) else getattr(node.func, "id", "")
            if name in ("import_module", "__import__") and isinstance(node.args[0].value, str):
                found.append((node.lineno, node.args[0].value))
    return found


def test_there_are_examples_to_check() -> None:
    names = {p.relative_to(EXAMPLES).as_posix() for p in _service_sources()}
    assert {"battery/battery.py", "docking/docking.py"} <= names, names


def test_no_example_imports_zendock() -> None:
    offences = [
        f"{path.relative_to(EXAMPLES.parent)}:{line}: imports {module}"
        for path in sorted(EXAMPLES.rglob("*.py"))
        for line, module in _imported_modules(path)
        if _zendock_import(path, module)
    ]
    assert not offences, "examples must not import zendock's packages:\n" + "\n".join(offences)


def test_examples_use_only_zenoh_msgpack_numpy_and_the_standard_library() -> None:
    own = {p.stem for p in EXAMPLES.rglob("*.py")}
    allowed = set(sys.stdlib_module_names) | ALLOWED_THIRD_PARTY | own | {"__future__"}
    offences = [
        f"{path.relative_to(EXAMPLES.parent)}:{line}: imports {module}"
        for path in _service_sources()
        for line, module in _imported_modules(path)
        if module.split(".")[0] not in allowed
    ]
    assert not offences, (
        "examples may use only zenoh, msgpack, numpy and the standard library:\n" + "\n".join(offences)
    )


@pytest.mark.parametrize(
    "source",
    [
        "from shared.node import Node",
        "import services.battery",
        "import importlib\nimportlib.import_module('deploy.cli')",
    ],
)
def test_the_check_sees_an_import_of_zendock(tmp_path: Path, source: str) -> None:
    path = tmp_path / "bad.py"
    path.write_text(source + "\n")
    assert any(module.split(".")[0] in ZENDOCK_PACKAGES for _, module in _imported_modules(path))


def test_only_tests_may_import_the_pytest_plugin() -> None:
    assert not _zendock_import(EXAMPLES / "tests" / "test_x.py", "deploy.testing")
    assert _zendock_import(EXAMPLES / "tests" / "test_x.py", "deploy.cli")
    assert _zendock_import(EXAMPLES / "docking" / "docking.py", "deploy.testing")
