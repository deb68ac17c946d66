import math

import pytest

from services.docking.approach import line_approach
from services.docking.kinematics import simulate_approach
from services.docking.seed_controller import (
    LineApproachController,
    LineApproachParams,
    LinePhase,
    LowBatteryTrigger,
)
from shared.geometry import Pose2D

SEED_DOCK = Pose2D(-1.0, 0.83, -math.pi / 2)


class Recorder:
    """Wraps the controller and records (goal_idx, phase, command) at each tick."""

    def __init__(self, controller: LineApproachController) -> None:
        self.controller = controller
        self.ticks: list[tuple[int, LinePhase, tuple[float, float]]] = []

    def step(self, x: float, y: float, yaw: float) -> tuple[float, float]:
        command = self.controller.step(x, y, yaw)
        self.ticks.append((self.controller.goal_idx, self.controller.phase, command))
        return command


def test_turns_towards_the_goal_then_drives() -> None:
    controller = LineApproachController([Pose2D(1.0, 0.0, 0.0)])
    assert controller.step(0.0, 0.0, 0.3) == (0.0, -0.1)  # goal is to the right: turn right
    assert controller.step(0.0, 0.0, -0.3) == (0.0, 0.1)
    assert controller.step(0.0, 0.0, 0.04) == (0.08, 0.0)  # within heading tolerance: drive
    assert controller.phase is LinePhase.SEEK_POSITION


def test_aligns_yaw_at_the_goal_then_moves_on_and_stays_idle() -> None:
    goals = [Pose2D(1.0, 0.0, math.pi / 2), Pose2D(1.0, 1.0, math.pi / 2)]
    controller = LineApproachController(goals)
    assert controller.step(0.98, 0.0, 0.0) == (0.0, 0.1)  # at the position, yaw short of the goal yaw
    assert controller.reached_distance_goal and controller.phase is LinePhase.ALIGN_YAW
    # Having started to align, it keeps aligning even if it drifted out of the distance tolerance.
    assert controller.step(0.9, 0.0, 0.5) == (0.0, 0.1)
    assert controller.step(0.9, 0.0, math.pi / 2) == (0.0, 0.0)  # aligned: next goal
    assert controller.goal_idx == 1 and not controller.reached_distance_goal
    assert controller.step(1.0, 0.99, math.pi / 2) == (0.0, 0.0)  # last goal reached at once
    assert controller.is_idle and controller.phase is LinePhase.IDLE
    assert controller.reached_distance_goal  # the last goal leaves the flag set
    assert controller.step(5.0, 5.0, 0.0) == (0.0, 0.0)
    controller.reset()
    assert controller.goal_idx == 0 and controller.phase is LinePhase.SEEK_POSITION


def test_goal_yaw_error_is_not_wrapped_unless_asked() -> None:
    goal = [Pose2D(0.0, 0.0, -math.pi / 2)]
    # At yaw 3.0 the short way to -pi/2 is positive; the seed behaviour turns negative (the long way).
    assert LineApproachController(goal).step(0.0, 0.0, 3.0) == (0.0, -0.1)
    wrapped = LineApproachController(goal, LineApproachParams(wrap_yaw_goal_error=True))
    assert wrapped.step(0.0, 0.0, 3.0) == (0.0, 0.1)


def test_drives_through_all_three_goals_from_the_staging_goal_and_ends_idle() -> None:
    approach = line_approach(SEED_DOCK)
    recorder = Recorder(LineApproachController(approach.goals))
    result = simulate_approach(
        recorder, approach.staging_goal, SEED_DOCK, 0.1, stop_at_contact=False, timeout_s=200.0
    )

    goal_sequence = [
        idx for i, (idx, _, _) in enumerate(recorder.ticks) if i == 0 or recorder.ticks[i - 1][0] != idx
    ]
    assert goal_sequence == [0, 1, 2, 3]
    for goal_idx in (0, 1, 2):
        phases = {phase for idx, phase, _ in recorder.ticks if idx == goal_idx}
        assert LinePhase.SEEK_POSITION in phases
    # From the staging goal (facing east) the robot ends goal 0 facing west and must turn to face the dock.
    assert LinePhase.ALIGN_YAW in {phase for idx, phase, _ in recorder.ticks if idx == 0}
    assert recorder.ticks[-1][1] is LinePhase.IDLE and recorder.ticks[-1][2] == (0.0, 0.0)
    # Bang-bang: every command is a pure turn at 0.1 rad/s, a straight drive at 0.08 m/s, or zero.
    assert {cmd for _, _, cmd in recorder.ticks} <= {(0.0, 0.1), (0.0, -0.1), (0.08, 0.0), (0.0, 0.0)}
    assert result.contact and result.mated
    final = result.final_pose
    assert final.distance_to(SEED_DOCK) <= 0.06
    assert abs(math.remainder(final.yaw - SEED_DOCK.yaw, 2 * math.pi)) <= 0.06


def test_trigger_fires_when_crossing_below_threshold() -> None:
    trigger = LowBatteryTrigger(0.25)
    assert [trigger.update(p) for p in (0.5, 0.3, 0.25, 0.2499, 0.2, 0.1)] == [
        False,
        False,
        False,
        True,
        False,
        False,
    ]


def test_trigger_fires_when_the_first_reading_is_already_low() -> None:
    trigger = LowBatteryTrigger(0.25)
    assert trigger.update(0.1) is True
    assert trigger.update(0.09) is False


def test_trigger_rearms_above_threshold_or_on_charging() -> None:
    trigger = LowBatteryTrigger(0.25)
    assert trigger.update(0.2)
    assert not trigger.update(0.3)  # re-armed, no fire
    assert trigger.update(0.24)
    assert not trigger.update(0.22, charging=True)  # never fires while charging, but re-arms
    assert trigger.update(0.22)  # left the dock still low: fires again
    assert not trigger.update(float("nan"))
    assert not trigger.armed
    trigger.reset()
    assert trigger.armed and trigger.update(0.1)


def test_trigger_rejects_bad_threshold() -> None:
    with pytest.raises(ValueError):
        LowBatteryTrigger(0.0)
    with pytest.raises(ValueError):
        LowBatteryTrigger(1.5)
