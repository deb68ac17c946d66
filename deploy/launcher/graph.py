"""The dependency graph of a stack: start order, cycles, and the services a selection pulls in."""

from __future__ import annotations

from collections.abc import Iterable, Mapping


def find_cycle(dependencies: Mapping[str, Iterable[str]]) -> list[str] | None:
    """One dependency cycle as ``[a, b, ..., a]``, or ``None``; edges to unknown names are ignored."""
    visiting: list[str] = []
    done: set[str] = set()

    def visit(name: str) -> list[str] | None:
        if name in done:
            return None
        if name in visiting:
            return [*visiting[visiting.index(name) :], name]
        visiting.append(name)
        for dependency in dependencies.get(name, ()):
            if dependency in dependencies:
                cycle = visit(dependency)
                if cycle:
                    return cycle
        visiting.pop()
        done.add(name)
        return None

    for name in dependencies:
        cycle = visit(name)
        if cycle:
            return cycle
    return None


def dependency_order(dependencies: Mapping[str, Iterable[str]]) -> list[str]:
    """Every name after all of its dependencies; ties keep the mapping's order (Kahn's algorithm).

    Raises ``ValueError`` on a cycle.
    """
    pending = {name: {d for d in deps if d in dependencies} for name, deps in dependencies.items()}
    order: list[str] = []
    while pending:
        ready = [name for name, deps in pending.items() if not deps]
        if not ready:
            cycle = find_cycle(dependencies) or list(pending)
            raise ValueError(f"dependency cycle: {' -> '.join(cycle)}")
        for name in ready:
            order.append(name)
            del pending[name]
        for deps in pending.values():
            deps.difference_update(ready)
    return order


def with_dependencies(names: Iterable[str], dependencies: Mapping[str, Iterable[str]]) -> set[str]:
    """``names`` and everything they depend on, transitively."""
    selected: set[str] = set()
    stack = list(names)
    while stack:
        name = stack.pop()
        if name not in selected:
            selected.add(name)
            stack.extend(dependencies.get(name, ()))
    return selected
