"""The perception kit's look from round the dock judges each detection by the frame it came from.

On a loaded machine detections of frames taken before the robot was moved arrive after the move; counted
against the new viewpoint they read as a flipped solution a metre off (seen once in a suite run on two
workers). A fake probe plays that: the first window after each move brings only the previous viewpoint's
detections, stamped before it. Frames taken after the move but before the robot's pose reads it are judged
by the old pose too (a mirror view settled the wrong way), so the move counts from when the pose reads it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from deploy.contracts import checks
from deploy.contracts.probe import Samples
from shared.geometry import Pose2D
from shared.messages import Float64MultiArray, Header, Pose, PoseStamped, Time
from shared.world import load_world

SEED_ROOM = Path(__file__).resolve().parents[3] / "deploy" / "worlds" / "seed_room.yaml"


def _detection(dock_in_base: Pose2D, stamp_s: float) -> PoseStamped:
    sec = math.floor(stamp_s)
    header = Header(stamp=Time(sec=sec, nanosec=int((stamp_s - sec) * 1e9)), frame_id="base_link")
    return PoseStamped(header=header, pose=Pose.from_pose2d(dock_in_base))


@dataclass
class _LaggingProbe:
    """Sim time that moves only when the check waits; each move's first window is the last viewpoint's."""

    dock: Pose2D
    late_windows: int
    sim_s: float = 100.0
    robot: Pose2D | None = None
    previous: Pose2D | None = None
    windows_since_move: int = 0
    moved_at: float = 0.0
    #: How long (sim) the robot's pose takes to read a move; frames taken meanwhile are judged by the old one.
    pose_lag_s: float = 0.0

    def moved(self, robot: Pose2D) -> None:
        self.previous, self.robot, self.windows_since_move = self.robot, robot, 0
        self.sim_s += 0.05
        self.moved_at = self.sim_s

    def wait_for(self, key: str, msg_type: Any, predicate: Any, timeout_s: float) -> Float64MultiArray | None:
        """The robot's pose reads the move ``pose_lag_s`` after it."""
        assert key.endswith("map_to_base_link_pose2d") and self.robot is not None
        self.sim_s = max(self.sim_s, self.moved_at + self.pose_lag_s)
        msg = Float64MultiArray(data=np.array([self.robot.x, self.robot.y, self.robot.yaw]))
        return msg if predicate(msg) else None

    def sim_now(self) -> float:
        return self.sim_s

    def pass_time(self, span_s: float, sim: bool, wall_limit_s: float) -> None:
        self.sim_s += span_s

    def key(self, name: str, namespace: str | None = None) -> str:
        return f"{namespace}/{name}"

    def collect(
        self,
        key: str,
        msg_type: Any,
        span_s: float,
        sim: bool,
        wall_limit_s: float,
        keep_messages: bool = False,
    ) -> Samples:
        start = self.sim_s
        self.sim_s += span_s
        self.windows_since_move += 1
        assert self.robot is not None
        if self.windows_since_move <= self.late_windows and self.previous is not None:
            seen_from, stamp = self.previous, self.moved_at - 0.3  # a frame from before the move
        elif self.windows_since_move == 1 and self.pose_lag_s > 0.0:
            # Frames taken after the move but before the pose read it: the mirror solution, a radian off.
            dock_in_base = self.dock.relative_to(self.robot)
            flipped = Pose2D(dock_in_base.x, dock_in_base.y, dock_in_base.yaw + 1.0)
            frames = [_detection(flipped, self.moved_at + 0.15 + 0.05 * i) for i in range(3)]
            frames.append(_detection(dock_in_base, self.moved_at + self.pose_lag_s + 0.3))
            return Samples(key=key, received=4, decoded=4, messages=frames)
        else:
            seen_from, stamp = self.robot, start + 0.2
        dock_in_base = self.dock.relative_to(seen_from)
        messages = [_detection(dock_in_base, stamp + 0.07 * i) for i in range(4)]
        return Samples(key=key, received=4, decoded=4, messages=messages)


def _context(probe: _LaggingProbe, world: Any) -> Any:
    return checks.Context(
        contract=None,  # type: ignore[arg-type]
        candidate=None,  # type: ignore[arg-type]
        probe=probe,  # type: ignore[arg-type]
        world=world,
        namespace="r1",
        robot_namespace="r1",
        sim=True,
    )


def _look_round(probe: _LaggingProbe, world: Any, monkeypatch: pytest.MonkeyPatch) -> tuple[bool, str]:
    """The look from round the dock, with ``probe`` playing the bus and its teleports."""
    monkeypatch.setattr(checks, "_teleport", lambda _ctx, pose: probe.moved(pose))
    sees_round = {c.name: c for c in checks.perception_behaviour(_context(probe, world))}[
        "sees the dock from 0.4 to 3 m and 40 degrees aside"
    ]
    return sees_round.body()


@pytest.mark.parametrize("late_windows", [0, 1, 2])
def test_detections_of_frames_from_before_the_move_are_not_judged_against_it(
    late_windows: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    world = load_world(SEED_ROOM)
    probe = _LaggingProbe(dock=world.docks[0].pose2d, late_windows=late_windows)
    passed, evidence = _look_round(probe, world, monkeypatch)
    assert passed, evidence
    assert "worst median 0 mm" in evidence, evidence


def test_only_detections_from_before_the_move_say_so(monkeypatch: pytest.MonkeyPatch) -> None:
    world = load_world(SEED_ROOM)
    probe = _LaggingProbe(dock=world.docks[0].pose2d, late_windows=checks.ROUND_WINDOWS)
    passed, evidence = _look_round(probe, world, monkeypatch)
    assert not passed
    assert (
        "no detection in 4.5 s of a frame taken after the move (12 of frames from before it)" in evidence
    ), evidence


def test_frames_taken_before_the_pose_reads_the_move_are_not_judged_against_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A loaded pose service reads a teleport late; perception meanwhile settles mirror views by the old pose."""
    world = load_world(SEED_ROOM)
    probe = _LaggingProbe(dock=world.docks[0].pose2d, late_windows=0, pose_lag_s=0.4)
    passed, evidence = _look_round(probe, world, monkeypatch)
    assert passed, evidence
    assert "worst median 0 mm and 0.000 rad" in evidence, evidence
