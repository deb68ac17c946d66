"""Every zendock sample's attachment: sequence number then publisher id, read back by any client."""

from __future__ import annotations

import math
import struct

import pytest

from shared.node import (
    ANSWERING_ATTACHMENT_SIZE,
    ATTACHMENT_SIZE,
    answered_tick_s,
    publisher_id,
    sequence_attachment,
    sequence_number,
)


def test_attachment_carries_the_sequence_number_then_the_publisher_id() -> None:
    gid = bytes(range(20))
    raw = sequence_attachment(7, gid)
    assert len(raw) == ATTACHMENT_SIZE == 28
    assert struct.unpack_from("<Q", raw)[0] == 7  # a plain client reads the first 8 bytes
    assert sequence_number(raw) == 7
    assert publisher_id(raw) == gid


def test_a_bare_sequence_number_is_still_read_and_names_no_publisher() -> None:
    raw = struct.pack("<Q", 42)
    assert sequence_number(raw) == 42
    assert publisher_id(raw) is None


def test_other_attachments_are_not_mistaken_for_sequence_numbers() -> None:
    for raw in (b"", b"abc", bytes(12), bytes(29), bytes(37)):
        assert sequence_number(raw) is None
        assert publisher_id(raw) is None
    assert sequence_number(None) is None and publisher_id(None) is None


def test_a_command_says_which_control_tick_it_answers_after_the_publisher_id() -> None:
    gid = bytes(range(20))
    raw = sequence_attachment(9, gid, answers_s=133.55)
    assert len(raw) == ANSWERING_ATTACHMENT_SIZE == 36
    assert struct.unpack_from("<q", raw, 28)[0] == 133_550_000_000  # sim time in nanoseconds
    assert answered_tick_s(raw) == pytest.approx(133.55)
    assert sequence_number(raw) == 9 and publisher_id(raw) == gid  # readers of the 28 bytes still read them


def test_a_sample_that_does_not_say_answers_no_tick() -> None:
    gid = bytes(20)
    assert answered_tick_s(sequence_attachment(1, gid)) is None
    assert answered_tick_s(None) is None and answered_tick_s(struct.pack("<Q", 1)) is None
    # no tick yet (a stop before the first): nothing is claimed
    assert len(sequence_attachment(1, gid, answers_s=-math.inf)) == ATTACHMENT_SIZE
