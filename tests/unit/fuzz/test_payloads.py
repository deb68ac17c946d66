"""Malformed payloads: every one is refused by its type's decoder (with a MessageError, nothing else)."""

from __future__ import annotations

import math
import random
from collections import Counter

import msgpack
import pytest

from deploy.fuzz.payloads import (
    MSGPACK,
    TYPED_KINDS,
    UNTYPED_KINDS,
    PayloadFactory,
    refused,
    rich_example,
)
from deploy.keys.types import known_types
from shared.interface_types import UUID
from shared.messages import TFMessage, Twist
from shared.schema import MessageError

TYPES = known_types()


@pytest.mark.parametrize("type_name", sorted(TYPES))
def test_every_payload_for_every_type_is_refused(type_name: str) -> None:
    msg_type = TYPES[type_name]
    factory = PayloadFactory(random.Random(type_name), TYPES, huge_budget=1)
    for _ in range(150):
        malformed = factory.typed(msg_type, empty_request=b"\x80")
        try:
            msg_type.decode(malformed.payload if malformed.payload is not None else b"\x80")
        except MessageError:
            continue
        pytest.fail(f"{type_name} accepted a {malformed.kind} payload: {malformed.payload!r:.200}")


def test_untyped_payloads_are_not_messages_of_any_type() -> None:
    factory = PayloadFactory(random.Random(1), TYPES)
    kinds = Counter()
    for _ in range(300):
        malformed = factory.untyped()
        kinds[malformed.kind] += 1
        assert malformed.encoding == MSGPACK
        assert all(refused(t, malformed.payload) for t in (Twist, TFMessage, UUID))
    assert set(kinds) == set(UNTYPED_KINDS)


def test_the_same_seed_makes_the_same_payloads() -> None:
    def run(seed: int) -> list[tuple[str, bytes | None, str]]:
        factory = PayloadFactory(random.Random(seed), TYPES)
        return [(m.kind, m.payload, m.encoding) for m in (factory.typed(Twist) for _ in range(50))]

    assert run(3) == run(3)
    assert run(3) != run(4)


def test_every_kind_turns_up_and_huge_arrays_stay_within_budget() -> None:
    factory = PayloadFactory(random.Random(5), TYPES, huge_budget=2)
    kinds = Counter(factory.typed(TFMessage, empty_request=b"\x80").kind for _ in range(2000))
    assert set(TYPED_KINDS) | set(UNTYPED_KINDS) | {"no_payload"} == set(kinds)
    assert kinds["huge_array"] == 2


def test_nested_messages_are_reachable() -> None:
    """Lists of nested messages get items, so a mutation can land inside them."""
    example = rich_example(TFMessage)
    assert len(example["transforms"]) == 2 and "header" in example["transforms"][0]
    factory = PayloadFactory(random.Random(0), TYPES)
    inside = 0
    for _ in range(400):
        malformed = factory.typed(TFMessage)
        if malformed.kind in ("missing_field", "wrong_type", "non_finite", "out_of_range"):
            data = msgpack.unpackb(malformed.payload, strict_map_key=False)
            items = data.get("transforms") if isinstance(data, dict) else None
            inside += isinstance(items, list) and len(items) == 2 and items != example["transforms"]
    assert inside > 10


def test_integer_arrays_refuse_nan_and_64_bit_overflow() -> None:
    """Found by this fuzzer: these used to escape the decoder as OverflowError / ValueError."""
    for item in (math.nan, 2**64 - 1, 2**63):
        with pytest.raises(MessageError, match="uuid"):
            UUID.decode(msgpack.packb({"uuid": [item]}))
