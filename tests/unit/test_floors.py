"""The three floors hold: ``shared`` imports neither services nor deploy, a service imports no other service,
and ``deploy`` starts services as processes instead of importing them."""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _imports(path: Path) -> Iterator[tuple[int, str]]:
    """Every module a file imports (absolute imports; the project uses no relative ones)."""
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            yield from ((node.lineno, alias.name) for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            yield node.lineno, node.module


def _files(package: str) -> list[Path]:
    return sorted((ROOT / package).rglob("*.py"))


def _crossings(package: str) -> list[str]:
    """Imports from ``package``'s files of a floor above, or of another service."""
    found = []
    for path in _files(package):
        where = path.relative_to(ROOT)
        own_service = where.parts[1] if package == "services" and len(where.parts) > 2 else None
        for line, module in _imports(path):
            head, _, rest = module.partition(".")
            if package == "shared" and head in ("services", "deploy"):
                found.append(f"{where}:{line} imports {module}")
            elif package == "deploy" and head == "services":
                found.append(f"{where}:{line} imports {module}")
            elif package == "services" and head == "deploy":
                found.append(f"{where}:{line} imports {module}")
            elif package == "services" and head == "services" and rest.split(".")[0] not in ("", own_service):
                found.append(f"{where}:{line} imports {module} (another service)")
    return found


@pytest.mark.parametrize("package", ["shared", "services", "deploy"])
def test_no_floor_reaches_up_and_no_service_into_another(package: str) -> None:
    assert _files(package), f"no Python files under {package}/"
    assert _crossings(package) == []
