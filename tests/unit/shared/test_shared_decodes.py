"""A process decodes each payload on a key once: its other subscriptions on that key share the message."""

from __future__ import annotations

import pytest

from shared.endpoints import SHARED_DECODE_MAX_BYTES, SHARED_DECODE_MAX_KEYS, SharedDecodes
from shared.messages import Clock, Float64MultiArray, LaserScan, Time
from shared.schema import MessageError


def test_the_same_bytes_on_the_same_key_decode_once() -> None:
    decodes = SharedDecodes()
    payload = Clock(Time(12, 5)).encode()
    first = decodes.decode(Clock, "r1/clock", payload)
    assert decodes.decode(Clock, "r1/clock", bytes(payload)) is first, (
        "equal bytes: the decoded message is shared"
    )
    newer = decodes.decode(Clock, "r1/clock", Clock(Time(12, 6)).encode())
    assert newer is not first and newer.clock.nanosec == 6
    assert decodes.decode(Clock, "r2/clock", payload) is not first, "another key decodes on its own"


def test_the_type_is_part_of_what_is_shared() -> None:
    decodes = SharedDecodes()
    payload = Float64MultiArray(data=[1.0, 2.0, 3.0]).encode()
    pose = decodes.decode(Float64MultiArray, "r1/x", payload)
    with pytest.raises(MessageError):
        decodes.decode(LaserScan, "r1/x", payload)
    assert decodes.decode(Float64MultiArray, "r1/x", payload) is pose


def test_a_bad_payload_is_refused_every_time_and_never_kept() -> None:
    decodes = SharedDecodes()
    for _ in range(2):
        with pytest.raises(MessageError):
            decodes.decode(Clock, "r1/clock", b"\xc1")


def test_large_payloads_are_decoded_each_time() -> None:
    decodes = SharedDecodes()
    big = Float64MultiArray(data=[0.5] * (SHARED_DECODE_MAX_BYTES // 9 + 10)).encode()
    assert len(big) > SHARED_DECODE_MAX_BYTES
    assert decodes.decode(Float64MultiArray, "k", big) is not decodes.decode(Float64MultiArray, "k", big)


def test_many_keys_start_the_memory_afresh_instead_of_growing() -> None:
    decodes = SharedDecodes()
    payload = Clock(Time(1, 0)).encode()
    for i in range(SHARED_DECODE_MAX_KEYS + 5):
        decodes.decode(Clock, f"robot{i}/clock", payload)
    assert len(decodes._last) <= SHARED_DECODE_MAX_KEYS
