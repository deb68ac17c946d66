"""Nav2's reasons for a failed path, from the planner's own."""

from __future__ import annotations

import numpy as np

from services.planner.costmap import CostGrid
from services.planner.grid_frame import GridFrame
from services.planner.path_server import outcome_code
from services.planner.planning_worker import PlanOutcome, PlanRequest
from shared.geometry import Pose2D
from shared.interfaces.navigation import ComputePathErrorCode, through_poses_code

REQUEST = PlanRequest(
    1,
    CostGrid(GridFrame(0.05, (0.0, 0.0, 0.0), 4, 4), np.zeros((4, 4), np.uint8)),
    Pose2D(0, 0, 0),
    Pose2D(1, 1, 0),
)


def _failed(error: str, end: str) -> PlanOutcome:
    return PlanOutcome(REQUEST, None, error, end)


def test_each_planner_failure_has_nav2s_code() -> None:
    cases = {
        ("start (9.00, 0.00) is outside the map", "start"): ComputePathErrorCode.START_OUTSIDE_MAP,
        ("goal (9.00, 0.00) is outside the map", "goal"): ComputePathErrorCode.GOAL_OUTSIDE_MAP,
        (
            "start (0.10, 0.10) is in an obstacle or its inscribed zone",
            "start",
        ): ComputePathErrorCode.START_OCCUPIED,
        ("goal (0.10, 0.10) is in unknown space", "goal"): ComputePathErrorCode.GOAL_OCCUPIED,
        (
            "no path from (0.00, 0.00) to (1.00, 1.00): the goal is not reachable",
            "",
        ): ComputePathErrorCode.NO_VALID_PATH,
        ("internal error: RuntimeError", ""): ComputePathErrorCode.UNKNOWN,
    }
    for (error, end), code in cases.items():
        assert outcome_code(_failed(error, end)) is code, error


def test_through_poses_codes_are_a_hundred_higher() -> None:
    assert through_poses_code(ComputePathErrorCode.GOAL_OCCUPIED) == 306
    assert through_poses_code(ComputePathErrorCode.NO_VALID_PATH) == 308
    assert through_poses_code(ComputePathErrorCode.NONE) == 0
