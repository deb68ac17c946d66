"""``shared.node`` keeps exporting what services, tools and tests import from it, wherever it now lives."""

from __future__ import annotations

import shared.node


def test_node_exports_its_public_names() -> None:
    assert set(shared.node.__all__) == {
        "ANSWERING_ATTACHMENT_SIZE",
        "ATTACHMENT_SIZE",
        "BLOCKING",
        "ENCODING_PREFIX",
        "MAX_PAYLOAD_BYTES",
        "RELIABLE",
        "SENSOR_DATA",
        "TIMER_TOLERANCE_S",
        "Node",
        "NodeStats",
        "Publisher",
        "QoS",
        "ServiceError",
        "ServiceServer",
        "ServiceType",
        "ServiceUnavailable",
        "Subscription",
        "Timer",
        "answered_tick_s",
        "call_service",
        "encoding_for",
        "publisher_gid",
        "publisher_id",
        "schema_of",
        "sequence_attachment",
        "sequence_number",
    }
    assert all(hasattr(shared.node, name) for name in shared.node.__all__)
