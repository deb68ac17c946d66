"""Infrared docking closed in a loop with the simulator's beacon model: Kobuki's states find the axis and dock."""

from __future__ import annotations

import math
import random

import numpy as np
import pytest

from services.docking.ir_drive import FAR_LEFT, FAR_RIGHT, NEAR_LEFT, IrDockDrive, IrState
from services.docking.ir_run import within_beacon_reach
from shared.geometry import Pose2D
from shared.models.infrared import InfraredParams, receiver_readings
from shared.models.raycast import SegmentSet
from shared.world import ROBOT_FRONT_M, parse_world

WORLD = parse_world(
    {
        "name": "ir",
        "bounds": [-5, -5, 5, 5],
        "docks": [{"id": "home", "pose": [0, 0, 0]}],
        "robot": {"start": [-1, 0, 0]},
    }
)
DOCK = WORLD.docks[0].pose2d
FACE = DOCK.compose(Pose2D(ROBOT_FRONT_M, 0.0, math.pi))


def _dock_from(
    start: Pose2D, seed: int, max_time_s: float = 150.0
) -> tuple[float | None, Pose2D, list[IrState]]:
    """Kinematic unicycle at 20 Hz until the robot's front reaches the dock's face (or time runs out)."""
    rng = np.random.default_rng(seed)
    segments = SegmentSet(WORLD.opaque_segments())
    drive, pose, t, dt, turn = IrDockDrive(), start, 0.0, 0.05, 0.0
    states: list[IrState] = []
    while t < max_time_s:
        at_dock = pose.relative_to(DOCK)
        if at_dock.x >= -0.002:
            return t, at_dock, states
        command = drive.step(receiver_readings(pose, WORLD.docks, segments, InfraredParams(), rng), turn * dt)
        if not states or states[-1] is not command.state:
            states.append(command.state)
        if command.state is IrState.LOST:
            return None, at_dock, states
        turn = command.angular_radps
        pose = Pose2D(
            pose.x + command.linear_mps * dt * math.cos(pose.yaw),
            pose.y + command.linear_mps * dt * math.sin(pose.yaw),
            pose.yaw + turn * dt,
        )
        t += dt
    return None, pose.relative_to(DOCK), states


@pytest.mark.parametrize("seed", range(12))
def test_from_anywhere_in_reach_facing_anywhere_the_robot_reaches_the_dock_square(seed: int) -> None:
    rnd = random.Random(seed)
    distance, bearing = rnd.uniform(0.7, 2.0), rnd.uniform(-math.radians(45), math.radians(45))
    spot = FACE.compose(Pose2D(distance * math.cos(bearing), distance * math.sin(bearing), 0.0))
    start = Pose2D(spot.x, spot.y, rnd.uniform(-math.pi, math.pi))
    assert within_beacon_reach(start, DOCK)
    took, at_dock, states = _dock_from(start, seed)
    assert took is not None, f"not docked from {start}: {[s.value for s in states]}"
    assert abs(at_dock.y) < 0.04 and abs(at_dock.yaw) < math.radians(20), (at_dock, [s.value for s in states])


def test_with_no_beacon_in_sight_the_scan_gives_up() -> None:
    drive = IrDockDrive()
    command = drive.step((0, 0, 0), 0.0)
    for _ in range(2000):
        command = drive.step((0, 0, 0), command.angular_radps * 0.05)
        if command.state is IrState.LOST:
            break
    assert command.state is IrState.LOST and command.linear_mps == 0.0 and command.angular_radps == 0.0


def test_beside_or_behind_the_dock_is_out_of_the_beacons_reach() -> None:
    assert not within_beacon_reach(FACE.compose(Pose2D(1.0, 1.5, 0.0)), DOCK)  # far off the axis
    assert not within_beacon_reach(DOCK.compose(Pose2D(1.0, 0.0, 0.0)), DOCK)  # behind the dock
    assert not within_beacon_reach(FACE.compose(Pose2D(2.5, 0.0, 0.0)), DOCK)  # too far


def test_a_blocked_way_to_the_axis_homes_in_on_the_first_field_seen() -> None:
    drive = IrDockDrive()
    drive.state, drive.dock_detector = IrState.GET_STREAM, 1  # on the dock's right, driving for the axis
    assert drive.step((0, 0, FAR_RIGHT), 0.0).state is IrState.GET_STREAM
    turn = drive.obstacle_ahead()
    assert turn is not None and turn.state is IrState.SCAN and turn.linear_mps == 0.0
    command = drive.step((0, FAR_RIGHT, 0), 0.02)
    assert command.state is IrState.ALIGNED_FAR  # not the centre, but followed: side corrections bring it in
    for _ in range(drive.params.filter_window):  # the left receiver's last sight of the beacon filtered out
        command = drive.step((0, FAR_RIGHT, 0), 0.0)
    assert command.angular_radps < 0  # on the dock's right: turn right, to the axis
    assert IrDockDrive().obstacle_ahead() is None  # scanning on the spot: nothing to avoid


def test_turning_for_the_axis_stops_while_the_emitter_already_stands_to_the_other_side() -> None:
    drive = IrDockDrive()
    drive.state = IrState.ALIGNED_FAR
    for _ in range(drive.params.filter_window):
        command = drive.step((0, FAR_RIGHT, 0), 0.0)
    assert command.angular_radps < 0  # on the dock's right: turn right, towards the axis
    for _ in range(drive.params.filter_window):  # the left receiver now sees the emitter: turned far enough
        command = drive.step((0, FAR_RIGHT, FAR_RIGHT), 0.0)
    assert command.state is IrState.ALIGNED_FAR and command.angular_radps == 0.0 and command.linear_mps > 0


def test_a_beacon_lost_from_the_central_receiver_is_turned_back_to_not_scanned_for() -> None:
    far = IrDockDrive()
    far.state = IrState.ALIGNED_FAR
    for _ in range(far.params.filter_window):
        command = far.step((0, 0, FAR_RIGHT), 0.0)
    assert command.state is IrState.ALIGNED_FAR and command.linear_mps == 0.0 and command.angular_radps > 0
    near = IrDockDrive()
    near.state = IrState.ALIGNED_NEAR
    for _ in range(near.params.filter_window):
        command = near.step((NEAR_LEFT | FAR_LEFT, 0, 0), 0.0)
    assert command.state is IrState.BACK_OFF and command.linear_mps < 0 and command.angular_radps < 0
