"""Global planning off the control thread: one worker thread, one request at a time.

A* can take longer than a control period, which would stall a 20 Hz control loop, so plans are computed here
on a read-only :class:`~services.planner.costmap.CostGrid` snapshot and handed back through ``deliver`` (the
node passes its ``post``, so the outcome is handled on its executor, never concurrently with its callbacks).
The worker owns its :class:`GlobalPlanner` (search arrays are reused between plans on the same snapshot).
"""

from __future__ import annotations

import logging
import queue
import threading
from collections.abc import Callable
from dataclasses import dataclass

from services.planner.astar import PlanningError
from services.planner.costmap import CostGrid
from services.planner.global_planner import GlobalPlanner, GlobalPlannerParams, PlannedPath
from shared.geometry import Pose2D

log = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class PlanRequest:
    #: Which navigation goal (and which attempt) asked: stale outcomes are recognised by it.
    generation: int
    grid: CostGrid
    start: Pose2D
    goal: Pose2D


@dataclass(frozen=True, eq=False)
class PlanOutcome:
    request: PlanRequest
    path: PlannedPath | None
    #: Why there is no path ("" when there is one).
    error: str = ""
    #: Which end the planner could not use: "start", "goal", or "" (unreachable, or an internal error).
    blocked_end: str = ""


def blocked_end_of(error: PlanningError) -> str:
    """Which end a :class:`PlanningError` names ("start ..." / "goal ..." messages), else ""."""
    text = str(error)
    for end in ("start", "goal"):
        if text.startswith(f"{end} "):
            return end
    return ""


class PlanningWorker:
    """Runs :meth:`GlobalPlanner.compute_path` for each submitted request, in order, on its own thread."""

    def __init__(self, params: GlobalPlannerParams, deliver: Callable[[PlanOutcome], None]) -> None:
        self._planner = GlobalPlanner(params)
        self._deliver = deliver
        self._requests: queue.SimpleQueue[PlanRequest | None] = queue.SimpleQueue()
        self._thread = threading.Thread(target=self._run, name="planner-worker", daemon=True)
        self._thread.start()

    def submit(self, request: PlanRequest) -> None:
        self._requests.put(request)

    def close(self, timeout_s: float = 2.0) -> None:
        self._requests.put(None)
        self._thread.join(timeout=timeout_s)

    def _run(self) -> None:
        while True:
            request = self._requests.get()
            if request is None:
                return
            self._deliver(self._plan(request))

    def _plan(self, request: PlanRequest) -> PlanOutcome:
        try:
            path = self._planner.compute_path(request.grid, request.start, request.goal)
        except PlanningError as exc:
            return PlanOutcome(request, None, str(exc), blocked_end_of(exc))
        except Exception as exc:  # a bug in planning must not kill the worker: report it as a failure
            log.exception("planning failed")
            return PlanOutcome(request, None, f"internal planning error: {type(exc).__name__}: {exc}")
        return PlanOutcome(request, path)
