"""Every zendock sample's attachment: sequence number then publisher id, read back by any client."""

from __future__ import annotations

import struct

from shared.node import ATTACHMENT_SIZE, publisher_id, sequence_attachment, sequence_number


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
    for raw in (b"", b"abc", bytes(12), bytes(29)):
        assert sequence_number(raw) is None
        assert publisher_id(raw) is None
    assert sequence_number(None) is None and publisher_id(None) is None
