"""A message class compiles its codec on first use, and the result is the one compiled at once."""

from __future__ import annotations

import importlib
import pkgutil

import pytest

import shared.interfaces
from shared import schema
from shared.schema import Message, compile_all, message, registered_types


def _fresh_class(type_name: str) -> type[Message]:
    @message(type_name)
    class Sample(Message):
        x: float = 0.0
        label: str = ""

    return Sample


def test_a_class_is_not_compiled_until_it_is_used() -> None:
    cls = _fresh_class("zendock_test/msg/LazySample")
    assert not isinstance(cls.__dict__["_FIELDS"], tuple)
    payload = cls(1.5, "a").encode()
    assert isinstance(cls.__dict__["_FIELDS"], tuple)
    assert [name for name, _, _ in cls._FIELDS] == ["x", "label"]
    assert cls.decode(payload) == cls(1.5, "a")


def test_first_and_later_decodes_agree() -> None:
    cls = _fresh_class("zendock_test/msg/LazyAgree")
    payload = cls(2.0, "b").to_dict()
    first = cls.from_dict(payload)  # the general path, which compiles
    later = cls.from_dict(payload)  # the generated fast path
    assert first == later == cls(2.0, "b")


def test_an_unsupported_annotation_is_named_when_compiled() -> None:
    @message("zendock_test/msg/LazyBroken")
    class Broken(Message):
        size: complex = 0j

    try:
        with pytest.raises(TypeError, match="field 'size'"):
            Broken().encode()
    finally:
        del schema._REGISTRY[Broken.TYPE_NAME]  # a broken class must not stay for compile_all


def test_every_shipped_message_compiles() -> None:
    for module in pkgutil.iter_modules(shared.interfaces.__path__):
        importlib.import_module(f"shared.interfaces.{module.name}")
    importlib.import_module("shared.messages")
    compile_all()
    for name, cls in registered_types().items():
        assert isinstance(cls.__dict__["_FIELDS"], tuple), name
