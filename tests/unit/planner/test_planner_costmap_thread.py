"""The costmap worker: updates run on its thread and come back as snapshots; changes wait for an update."""

from __future__ import annotations

import logging
import queue
import threading
from collections.abc import Iterator

import numpy as np
import pytest

from services.planner.costmap_thread import CostmapThread, LockedPoseTrack
from services.planner.costmap_updater import CostmapUpdater
from services.planner.occupancy_map import OCC_FREE, OCC_OCCUPIED, OccupancyMap
from services.planner.params import Params
from services.planner.recovery import GlassClearing
from shared.geometry import Pose2D
from shared.pose_tracking import PoseTrack

WAIT_S = 5.0
Worker = tuple[CostmapThread, "queue.Queue[tuple[float, str]]"]


def _room() -> OccupancyMap:
    data = np.full((40, 60), OCC_FREE, dtype=np.int8)
    data[:, 30] = OCC_OCCUPIED  # a wall across the room
    return OccupancyMap(0.05, (0.0, 0.0, 0.0), data)


@pytest.fixture
def worker() -> Iterator[Worker]:
    track = LockedPoseTrack(PoseTrack())
    with track.lock:
        track.track.add_pose(0.0, Pose2D(0.5, 1.0, 0.0))
    layers = CostmapUpdater(Params(), track, logging.getLogger("test"))
    updated: queue.Queue[tuple[float, str]] = queue.Queue()
    costmap = CostmapThread(
        layers, lambda now: updated.put((now, threading.current_thread().name)), logging.getLogger("test")
    )
    yield costmap, updated
    costmap.close()


def test_an_update_runs_on_the_worker_and_reports_its_time(worker: Worker) -> None:
    costmap, updated = worker
    assert costmap.grid is None, "no snapshot before a map"
    costmap.change(costmap.layers.set_map, _room())
    first = costmap.grid
    assert first is not None and first.costs[20, 30] == 254, "the map's wall is in the first snapshot"
    costmap.request_update(1.5)
    now, thread = updated.get(timeout=WAIT_S)
    assert (now, thread) == (1.5, "costmap-worker")
    assert costmap.grid is not None


def test_requests_made_while_one_runs_fold_into_one_update_as_of_the_newest(worker: Worker) -> None:
    costmap, updated = worker
    costmap.change(costmap.layers.set_map, _room())
    with costmap.lock:  # an update cannot start while a change holds the lock
        costmap.request_update(1.0)
        costmap.request_update(2.0)
        costmap.request_update(3.0)
        with pytest.raises(queue.Empty):
            updated.get(timeout=0.2)
    times = [updated.get(timeout=WAIT_S)[0]]
    while True:
        try:
            times.append(updated.get(timeout=0.3)[0])
        except queue.Empty:
            break
    assert times[-1] == 3.0, times
    assert len(times) <= 2, f"three requests ran {len(times)} updates: {times}"


def test_a_change_publishes_a_new_snapshot(worker: Worker) -> None:
    costmap, _ = worker
    costmap.change(costmap.layers.set_map, _room())
    moved = _room()
    moved.data[:, 30] = OCC_FREE
    moved.data[:, 10] = OCC_OCCUPIED
    costmap.change(costmap.layers.set_map, moved)
    assert costmap.grid is not None
    assert costmap.grid.costs[20, 10] == 254 and costmap.grid.costs[20, 30] == 0, (
        "the snapshot shows the new map"
    )
    costmap.change(costmap.layers.clear, GlassClearing.ALL)
    assert costmap.heard_glass_xy.shape == (0, 2), "nothing heard: no glass cells"


def test_a_failing_update_is_reported_and_the_worker_goes_on(
    worker: Worker, caplog: pytest.LogCaptureFixture
) -> None:
    costmap, updated = worker
    costmap.change(costmap.layers.set_map, _room())
    real_update = costmap.layers.update
    calls = []

    def fails_once(now: float) -> None:
        calls.append(now)
        if len(calls) == 1:
            raise RuntimeError("broken update")
        real_update(now)

    costmap.layers.update = fails_once  # type: ignore[method-assign]
    with caplog.at_level(logging.ERROR):
        costmap.request_update(1.0)
        with pytest.raises(queue.Empty):
            updated.get(timeout=0.5)
        costmap.request_update(2.0)
        assert updated.get(timeout=WAIT_S)[0] == 2.0
    assert "costmap update failed" in caplog.text


def test_close_ends_the_thread(worker: Worker) -> None:
    costmap, _ = worker
    costmap.close()
    assert not costmap._thread.is_alive()
