"""zendock's session defaults: explicit endpoints, no multicast, and its transport settings unless a file decides."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from shared.session import TX_QUEUE_BATCHES, SessionSpec, make_config


def _get(spec: SessionSpec, path: str) -> object:
    return json.loads(make_config(spec).get_json(path))


def test_default_sessions_queue_sixteen_data_batches_without_shared_memory() -> None:
    spec = SessionSpec(connect=("tcp/127.0.0.1:7447",))
    assert _get(spec, "transport/link/tx/queue/size/data") == TX_QUEUE_BATCHES
    assert _get(spec, "transport/shared_memory/enabled") is False
    assert _get(spec, "scouting/multicast/enabled") is False
    assert _get(spec, "connect/endpoints") == ["tcp/127.0.0.1:7447"]


def test_a_config_file_decides_the_transport_itself(tmp_path: Path) -> None:
    path = tmp_path / "client.json5"
    path.write_text("{ transport: { link: { tx: { queue: { size: { data: 3 } } } } } }")
    spec = SessionSpec(config_file=str(path))
    assert _get(spec, "transport/link/tx/queue/size/data") == 3
    assert _get(spec, "scouting/multicast/enabled") is False  # never multicast, file or not


def test_a_missing_config_file_is_named() -> None:
    with pytest.raises(ValueError, match="does not exist"):
        make_config(SessionSpec(config_file="/nonexistent/zenoh.json5"))
