"""Runtime parameters: which of a service's parameters may change while it runs, and changing them.

A service's parameters are one record (:class:`ServiceParams`, a msgspec ``Struct``), validated at
start-up (:func:`shared.structs.validate`). A field marked with :func:`runtime_settable` may also change
while the service runs (``zendock param set``); every other field is read once, at start-up, and a change
to it is refused.
:class:`ParameterTable` is the contract, pure (no bus, no clock):

- names are the start-up names: ``field``, or ``group.field`` for a nested group (``-p`` spells them so);
- a new value is validated by the same record type as at start-up (the field's bounds and the record's
  cross-field checks), on a copy; a refused value changes nothing and the reason names the parameter;
- an accepted value is written into the live record the service was built with, so code that reads its
  parameters when it starts something (a docking run, a navigation goal) picks it up then; then the
  listeners run (:meth:`ParameterTable.on_set`), to apply it at once where that is wanted. A listener
  raising ``ValueError`` undoes the change and refuses it with its message.

:mod:`shared.parameter_server` answers ``<ns>/<node>/_param/{list,get,set}`` with a table.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Iterable, Iterator
from typing import Any

import msgspec

from shared import structs
from shared.suggestions import did_you_mean

#: The ``Meta(extra=...)`` key that marks a field settable at runtime.
DYNAMIC_KEY = "dynamic"
#: The key of the text that says when a change takes effect.
APPLIES_KEY = "applies"
AT_ONCE = "at once"


class ServiceParams(msgspec.Struct, forbid_unknown_fields=True, kw_only=True):
    """Base of every service's parameters: strict (unknown names are errors). Pure, so a service's
    parameter model (and the logic built from it) loads without the bus."""

    use_sim_time: bool = False


def runtime_settable(applies: str = AT_ONCE) -> dict[str, Any]:
    """``Meta(extra=...)`` for a field ``zendock param set`` may change while the service runs.

    ``applies`` says when a change takes effect, in the user's words: "at once", "next docking run"."""
    return {DYNAMIC_KEY: True, APPLIES_KEY: applies}


class ParameterRefused(ValueError):
    """A get or set the table refuses; the message names the parameter and the reason."""


class ParameterInfo(msgspec.Struct, frozen=True):
    """One parameter as ``param list`` shows it; ``value`` is JSON-ready (tuples are lists)."""

    name: str
    value: Any
    settable: bool
    applies: str = ""
    description: str = ""

    @property
    def value_json(self) -> str:
        return json.dumps(self.value)


#: Called with the parameter's name and its new (validated) value; ``ValueError`` refuses the change.
Listener = Callable[[str, Any], None]


def _leaves(model: type[msgspec.Struct], prefix: str = "") -> Iterator[tuple[str, str, bool, str]]:
    """``(dotted name, description, settable, applies)`` of every leaf parameter, groups flattened."""
    for spec in structs.fields(model):
        if spec.group is not None:
            yield from _leaves(spec.group, f"{prefix}{spec.name}.")
            continue
        settable = bool(spec.extra.get(DYNAMIC_KEY, False))
        applies = str(spec.extra.get(APPLIES_KEY, AT_ONCE)) if settable else ""
        yield f"{prefix}{spec.name}", spec.description, settable, applies


def _reason(name: str, value: Any, error: msgspec.ValidationError, record: type) -> str:
    """``name: reason (got value)``; a cross-field check that names another field says which."""
    where, reason = structs.explain(error, record)
    leaf = name.rpartition(".")[2]
    if where and where != leaf:
        reason = f"{where}: {reason}"
    return f"{name}: {reason} (got {value!r})"


class ParameterTable:
    """A service's live parameters, read and changed by name (see the module docstring)."""

    def __init__(self, params: msgspec.Struct) -> None:
        self._params = params
        self._fields = {
            name: (description, settable, applies)
            for name, description, settable, applies in _leaves(type(params))
        }
        self._listeners: list[tuple[frozenset[str], Listener]] = []

    @property
    def params(self) -> msgspec.Struct:
        return self._params

    def settable_names(self) -> list[str]:
        return sorted(name for name, (_d, settable, _a) in self._fields.items() if settable)

    def on_set(self, names: str | Iterable[str], listener: Listener) -> None:
        """Call ``listener(name, value)`` after any of ``names`` changes (each must be runtime-settable)."""
        wanted = frozenset([names] if isinstance(names, str) else names)
        wrong = sorted(n for n in wanted if not self._fields.get(n, ("", False, ""))[1])
        if wrong:
            raise ValueError(f"not runtime-settable parameters: {', '.join(wrong)}")
        self._listeners.append((wanted, listener))

    def describe(self) -> list[ParameterInfo]:
        """Every parameter, sorted by name."""
        return [self._info(name) for name in sorted(self._fields)]

    def get(self, name: str) -> ParameterInfo:
        self._check_known(name)
        return self._info(name)

    def set(self, name: str, value: Any) -> ParameterInfo:
        """Validate ``value`` as at start-up, write it, run the listeners; :class:`ParameterRefused` says why not."""
        self._check_known(name)
        if not self._fields[name][1]:
            raise ParameterRefused(
                f"{name}: read at start-up only, cannot change while running "
                f"(settable: {', '.join(self.settable_names()) or 'none'})"
            )
        parent_path, _, leaf = name.rpartition(".")
        live_parent = self._walk(self._params, parent_path)
        values = {**msgspec.structs.asdict(live_parent), leaf: value}
        try:
            candidate = msgspec.convert(values, type(live_parent), strict=False)
        except msgspec.ValidationError as exc:
            raise ParameterRefused(_reason(name, value, exc, type(live_parent))) from None
        new_value, old_value = getattr(candidate, leaf), getattr(live_parent, leaf)
        if isinstance(new_value, float) and not math.isfinite(new_value):
            raise ParameterRefused(f"{name}: must be a finite number (got {value!r})")
        setattr(live_parent, leaf, new_value)
        try:
            for names, listener in self._listeners:
                if name in names:
                    listener(name, new_value)
        except ValueError as exc:
            setattr(live_parent, leaf, old_value)
            raise ParameterRefused(f"{name}: {exc}") from None
        except BaseException:
            setattr(live_parent, leaf, old_value)  # a listener's own fault: the old value stays in force
            raise
        return self._info(name)

    # --- helpers ---------------------------------------------------------------------------------

    def _check_known(self, name: str) -> None:
        if name not in self._fields:
            settable = self.settable_names()
            raise ParameterRefused(
                f"{name}: no such parameter{did_you_mean(name, settable)} (settable: {', '.join(settable) or 'none'})"
            )

    @staticmethod
    def _walk(model: msgspec.Struct, dotted: str) -> msgspec.Struct:
        for part in dotted.split(".") if dotted else ():
            model = getattr(model, part)
        return model

    def _value(self, name: str) -> Any:
        parent_path, _, leaf = name.rpartition(".")
        return structs.plain(getattr(self._walk(self._params, parent_path), leaf))

    def _info(self, name: str) -> ParameterInfo:
        description, settable, applies = self._fields[name]
        return ParameterInfo(name, self._value(name), settable, applies, description)
