"""The fleet monitor's tracks: a point every 10 cm of ground truth, kept compact and bounded, copied whole."""

from __future__ import annotations

from collections.abc import Callable
from types import SimpleNamespace
from typing import Any

import pytest

from deploy.fleet.monitor import TRACK_POINTS_MAX, TRACK_STEP_M, FleetMonitor, Track
from shared.messages import Clock, Point, Pose, PoseStamped, Time


class _Session:
    """Records each subscriber's callback by key, as a Zenoh session would call it."""

    def __init__(self) -> None:
        self.callbacks: dict[str, Callable[[Any], None]] = {}

    def declare_subscriber(self, key: str, callback: Callable[[Any], None]) -> SimpleNamespace:
        self.callbacks[key] = callback
        return SimpleNamespace(undeclare=lambda: None)

    def put(self, key: str, payload: bytes) -> None:
        self.callbacks[key](SimpleNamespace(payload=SimpleNamespace(to_bytes=lambda: payload)))


def _truth(x: float, y: float) -> bytes:
    return PoseStamped(pose=Pose(position=Point(x=x, y=y))).encode()


def test_a_track_keeps_its_points_in_order_and_a_copy_is_its_own() -> None:
    track = Track([(0.0, 1.0), (0.5, 1.5)])
    twin = track.copy()
    track.add(2.0, 2.5)
    assert list(track) == [(0.0, 1.0), (0.5, 1.5), (2.0, 2.5)] and track.last() == (2.0, 2.5)
    assert list(twin) == [(0.0, 1.0), (0.5, 1.5)] and len(twin) == 2
    assert not Track()
    with pytest.raises(IndexError):
        Track().last()


def test_a_track_costs_sixteen_bytes_a_point() -> None:
    track = Track((float(i), float(i)) for i in range(TRACK_POINTS_MAX))
    assert track.xs.itemsize + track.ys.itemsize == 16
    assert len(track.xs) == len(track.ys) == TRACK_POINTS_MAX


def test_a_track_takes_its_memory_once_and_keeps_it() -> None:
    """Its arrays are allocated whole when it is made and never grow, move or shrink: the run's length does
    not change what a track costs."""
    track = Track()
    where = (track.xs.buffer_info(), track.ys.buffer_info())
    assert where[0][1] == where[1][1] == TRACK_POINTS_MAX
    for i in range(5 * TRACK_POINTS_MAX):
        track.add(float(i), float(-i))
    assert (track.xs.buffer_info(), track.ys.buffer_info()) == where
    assert track.last() == (float(5 * TRACK_POINTS_MAX - 1), float(1 - 5 * TRACK_POINTS_MAX))


def test_a_track_past_its_cap_thins_itself_and_doubles_its_step() -> None:
    track = Track()
    for i in range(TRACK_POINTS_MAX):
        track.follow(float(i), 0.0)
    assert len(track) == TRACK_POINTS_MAX and track.step == TRACK_STEP_M
    track.follow(float(TRACK_POINTS_MAX), 0.0)
    assert len(track) == TRACK_POINTS_MAX // 2 + 1 and track.step == 2 * TRACK_STEP_M
    xs = [x for x, _ in track]
    assert xs[:3] == [0.0, 2.0, 4.0] and xs[-2:] == [float(TRACK_POINTS_MAX - 2), float(TRACK_POINTS_MAX)]
    assert xs == sorted(xs), "every other point kept, still in order, the newest last"
    for i in range(TRACK_POINTS_MAX + 1, 20 * TRACK_POINTS_MAX):
        track.follow(float(i), 0.0)
    assert len(track) <= TRACK_POINTS_MAX, "however long the run, the track stays under its cap"
    assert track.copy().step == track.step


def test_the_monitor_adds_a_point_once_the_robot_has_moved_a_track_step() -> None:
    session = _Session()
    monitor = FleetMonitor(session, ["r1"])  # type: ignore[arg-type]
    for x in (0.0, 0.05, 0.09, 0.1, 0.25, 0.3):
        session.put("r1/ground_truth_pose", _truth(x, 0.0))
    _, (tally,), _, _ = monitor.snapshot()
    assert list(tally.track) == [(0.0, 0.0), (0.1, 0.0), (0.25, 0.0)]
    assert all(b[0] - a[0] >= TRACK_STEP_M for a, b in zip(tally.track, list(tally.track)[1:], strict=False))
    assert tally.distance_m == pytest.approx(0.3)
    session.put("r1/ground_truth_pose", _truth(0.5, 0.0))
    assert len(tally.track) == 3, "a snapshot's track is a copy, not the live one"
    assert len(monitor.snapshot()[1][0].track) == 4


def test_a_snapshot_for_progress_copies_no_track() -> None:
    session = _Session()
    monitor = FleetMonitor(session, ["r1"])  # type: ignore[arg-type]
    for x in (0.0, 0.2, 0.4):
        session.put("r1/ground_truth_pose", _truth(x, 0.0))
    _, (light,), _, _ = monitor.snapshot(tracks=False)
    assert len(light.track) == 0 and light.distance_m == pytest.approx(0.4)
    assert len(monitor.snapshot()[1][0].track) == 3, "the live track is untouched"


def test_the_clock_is_read_without_a_snapshot() -> None:
    session = _Session()
    monitor = FleetMonitor(session, ["r1"])  # type: ignore[arg-type]
    assert monitor.sim_time() != monitor.sim_time()  # NaN before the first tick
    session.put("r1/clock", Clock(clock=Time(sec=12, nanosec=500_000_000)).encode())
    assert monitor.sim_time() == 12.5
