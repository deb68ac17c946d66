"""The msgpack codec writes what msgpack-python writes, byte for byte, so the wire the contracts document
is unchanged; and garbage is still refused with a MessageError."""

from __future__ import annotations

import math
import random

import msgpack
import numpy as np
import pytest

from shared import schema
from shared.messages import Image, LaserScan
from shared.schema import MessageError, registered_types, unpack


def _value(rng: random.Random, depth: int = 0) -> object:
    kind = rng.randrange(9 if depth < 3 else 6)
    if kind == 0:
        return rng.choice(
            [
                0,
                1,
                -1,
                127,
                128,
                -32,
                -33,
                255,
                256,
                65535,
                65536,
                -(2**31),
                2**32,
                2**63 - 1,
                -(2**63),
                2**64 - 1,
            ]
        )
    if kind == 1:
        return rng.choice([0.0, -0.0, 1.5, 1e-310, 1e308, math.inf, -math.inf, math.nan, 0.1])
    if kind == 2:
        return "x" * rng.choice([0, 1, 31, 32, 255, 256, 65535, 65536]) + rng.choice(["", "é", "漢"])
    if kind == 3:
        return bytes(rng.randrange(256) for _ in range(rng.choice([0, 1, 255, 256, 70000])))
    if kind == 4:
        return rng.choice([True, False, None])
    if kind == 5:
        return rng.uniform(-1e6, 1e6)
    if kind == 6:
        return [_value(rng, depth + 1) for _ in range(rng.choice([0, 1, 15, 16, 17]))]
    return {f"k{i}": _value(rng, depth + 1) for i in range(rng.choice([0, 1, 15, 16, 17]))}


@pytest.mark.parametrize("seed", range(40))
def test_the_codec_writes_msgpack_pythons_bytes(seed: int) -> None:
    value = _value(random.Random(seed))
    assert schema._PACK(value) == msgpack.packb(value, use_bin_type=True)


def test_every_message_type_encodes_as_before() -> None:
    scan = LaserScan(
        ranges=np.linspace(0.1, 5.0, 360, dtype=np.float32), intensities=np.zeros(0, dtype=np.float32)
    )
    image = Image(height=2, width=100, encoding="mono8", step=100, data=np.arange(200, dtype=np.uint8))
    messages = [cls() for cls in registered_types().values()] + [scan, image]
    for msg in messages:
        assert msg.encode() == msgpack.packb(msg.to_dict(), use_bin_type=True), type(msg).TYPE_NAME
        assert type(msg).decode(msg.encode()).encode() == msg.encode()


@pytest.mark.parametrize(
    "payload",
    [
        b"",
        b"\xc1",
        b"\x92\x01",
        b"\x81\x01\x02\x03",
        b"\xd9\x05ab",
        b"\x81\x91\x01\x02",
        msgpack.packb({1: 2}),
        msgpack.packb({"data": 1}) + b"\x00",
    ],
)
def test_garbage_is_refused_with_a_message_error(payload: bytes) -> None:
    with pytest.raises(MessageError):
        LaserScan.decode(payload)


def test_garbage_that_is_msgpack_names_the_problem() -> None:
    with pytest.raises(MessageError, match="not valid msgpack"):
        unpack(b"\xc1", "sensor_msgs/msg/LaserScan")
