"""A message class becomes a dataclass and compiles its codec on first use, and the result is the one
made at once."""

from __future__ import annotations

import concurrent.futures
import dataclasses
import importlib
import pkgutil
import threading
from collections.abc import Callable

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


def test_a_class_becomes_a_dataclass_on_first_use() -> None:
    cls = _fresh_class("zendock_test/msg/LazyDataclass")
    assert "__dataclass_params__" not in cls.__dict__
    made = cls(1.0, label="a")
    assert "__dataclass_params__" in cls.__dict__
    assert made == cls(1.0, "a") and made != cls(2.0, "a")
    assert repr(made).endswith("Sample(x=1.0, label='a')")
    assert cls.__hash__ is None  # as any dataclass with eq and without frozen


@pytest.mark.parametrize(
    "first_use",
    [
        lambda cls: [f.name for f in dataclasses.fields(cls)],
        lambda cls: dataclasses.is_dataclass(cls) and [f.name for f in dataclasses.fields(cls)],
        lambda cls: list(dataclasses.asdict(cls(3.0, "c"))),
    ],
    ids=["fields", "is_dataclass", "asdict"],
)
def test_reading_the_fields_first_gives_the_dataclass_too(
    first_use: Callable[[type[Message]], object],
) -> None:
    cls = _fresh_class("zendock_test/msg/LazyFields")
    assert first_use(cls) == ["x", "label"]
    assert cls(3.0) == cls(x=3.0, label="")


def test_an_instance_made_without_init_still_compares_and_prints() -> None:
    cls = _fresh_class("zendock_test/msg/LazyNew")
    bare = cls.__new__(cls)  # as pickle and copy make one
    bare.x, bare.label = 1.0, "n"
    assert bare == cls(1.0, "n")
    assert repr(bare).endswith("Sample(x=1.0, label='n')")


def test_a_subclass_of_a_deferred_class_keeps_the_base_fields() -> None:
    base = _fresh_class("zendock_test/msg/LazyBase")

    @message("zendock_test/msg/LazyDerived")
    class Derived(base):  # type: ignore[valid-type,misc]
        extra: int = 0

    assert Derived(1.0, "d", 5) == Derived(x=1.0, label="d", extra=5)
    assert [f.name for f in dataclasses.fields(base)] == ["x", "label"]


def test_threads_that_first_use_a_class_at_once_all_get_one_dataclass() -> None:
    cls = _fresh_class("zendock_test/msg/LazyThreads")
    barrier = threading.Barrier(8)

    def make(i: int) -> Message:
        barrier.wait()
        return cls(float(i), "t")

    with concurrent.futures.ThreadPoolExecutor(8) as pool:
        made = list(pool.map(make, range(8)))
    assert made == [cls(float(i), "t") for i in range(8)]


def test_a_class_whose_fields_cannot_make_a_dataclass_says_so_at_first_use() -> None:
    @message("zendock_test/msg/LazyBadOrder")
    class BadOrder(Message):
        first: float = 0.0
        second: float  # a field without a default after one with a default

    try:
        with pytest.raises(TypeError, match="second"):
            BadOrder(1.0, 2.0)
    finally:
        del schema._REGISTRY[BadOrder.TYPE_NAME]  # a broken class must not stay for compile_all


def test_a_message_made_while_another_thread_makes_its_class_a_dataclass_waits_for_it() -> None:
    """The window between the stand-ins' removal and the dataclass's own methods: a second thread
    making a message there waits for the first instead of finding no ``__init__``."""
    cls = _fresh_class("zendock_test/msg/LazyWindow")
    made: list[Message] = []
    with schema._DEFERRED_LOCK:  # this thread is the one converting the class
        schema._DEFERRED.discard(cls)
        for name in (*schema._DATACLASS_METHODS, "__dataclass_fields__"):
            delattr(cls, name)
        other = threading.Thread(target=lambda: made.append(cls(3.0, "c")))
        other.start()
        other.join(timeout=0.2)
        assert other.is_alive(), "the message was made before its class was a dataclass"
        dataclasses.dataclass(cls)
    other.join(timeout=5.0)
    assert made == [cls(3.0, "c")]


def test_a_codec_compiled_while_another_thread_makes_its_class_a_dataclass_waits_for_it() -> None:
    """The same window for the codec: a second thread decoding the class's first message there (reading
    ``_FIELDS``) waits for the dataclass instead of finding no ``__dataclass_fields__``."""
    cls = _fresh_class("zendock_test/msg/LazyCodecWindow")
    payload = {"x": 4.0, "label": "d"}
    decoded: list[Message] = []
    failed: list[BaseException] = []

    def decode() -> None:
        try:
            decoded.append(cls.from_dict(payload))
        except BaseException as exc:  # the test reports whatever the thread met
            failed.append(exc)

    with schema._DEFERRED_LOCK:  # this thread is the one converting the class
        schema._DEFERRED.discard(cls)
        for name in (*schema._DATACLASS_METHODS, "__dataclass_fields__"):
            delattr(cls, name)
        other = threading.Thread(target=decode)
        other.start()
        other.join(timeout=0.2)
        assert other.is_alive() and not failed, f"the codec was compiled too early: {failed}"
        dataclasses.dataclass(cls)
    other.join(timeout=5.0)
    assert not failed and decoded == [cls(4.0, "d")]


def test_the_fields_read_while_another_thread_makes_the_class_a_dataclass_wait_for_it() -> None:
    """The same window for anyone reading the fields (``dataclasses.fields``, ``is_dataclass``, ``asdict``:
    the ROS 2 conversions, the Foxglove view): they wait for the dataclass, and a class that is no
    dataclass still has no fields."""
    cls = _fresh_class("zendock_test/msg/LazyFieldsWindow")
    names: list[list[str]] = []
    with schema._DEFERRED_LOCK:  # this thread is the one converting the class
        schema._DEFERRED.discard(cls)
        for name in (*schema._DATACLASS_METHODS, "__dataclass_fields__"):
            delattr(cls, name)
        other = threading.Thread(target=lambda: names.append([f.name for f in dataclasses.fields(cls)]))
        other.start()
        other.join(timeout=0.2)
        assert other.is_alive(), "the fields were read before the class was a dataclass"
        dataclasses.dataclass(cls)
    other.join(timeout=5.0)
    assert names == [["x", "label"]]
    assert not dataclasses.is_dataclass(Message) and dataclasses.is_dataclass(cls)
