"""Every run gets a directory of its own, even when two start in the same second."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from deploy.paths import new_run_dir


def test_runs_started_in_the_same_second_get_directories_of_their_own(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(time, "strftime", lambda _format: "20261202-031917")
    made = [new_run_dir(tmp_path / "runs", "trials-", "-seed_room") for _ in range(3)]
    assert [d.name for d in made] == [
        "trials-20261202-031917-seed_room",
        "trials-20261202-031917-seed_room-2",
        "trials-20261202-031917-seed_room-3",
    ]
    assert all(d.is_dir() and not any(d.iterdir()) for d in made)
