"""Time to goal with the real stack: simulator, pose and planner as processes on a private router.

Each world gets a fresh stack; its routes run one after another from wherever the last one ended. A
route records the sim time from sending the goal to its result, the distance the robot really drove
(ground truth), collisions and recoveries, and the yardstick: the shortest collision-free path from the
actual start (``services.planner.shortest_path``, glass included) divided by the speed limit. The ratio
``time_s / lower_bound_s`` is what the rotations, the slow-downs near obstacles and the final approach
cost, and in the glass room what discovering the glass costs.
"""

from __future__ import annotations

import math
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path

from deploy.bench.processes import ServiceGroup, free_port
from deploy.paths import REPO_ROOT
from deploy.service_tools import run_tool
from deploy.trials.time_over_bound import BOUND_MAX_LINEAR_MPS
from shared.action import spin_in_background
from shared.endpoints import ServiceError
from shared.geometry import Pose2D
from shared.interfaces.simulator import SIM_STATE, SimStateRequest, SimStateResponse
from shared.messages import PoseStamped
from shared.navigation import NavigationClient, TaskResult
from shared.node import RELIABLE, Node, call_service
from shared.session import SessionSpec, open_session
from shared.world import load_world

#: Routes per world: goals ``(x, y, yaw)`` driven in order from the world's start pose.
ROUTES: dict[str, tuple[tuple[float, float, float], ...]] = {
    "deploy/worlds/seed_room.yaml": ((2.2, 2.5, 0.0), (0.0, 2.0, -math.pi / 2)),
    "deploy/worlds/glass_room.yaml": ((0.5, 1.5, 0.0),),
}


@dataclass(frozen=True)
class RouteResult:
    world: str
    start: Pose2D
    goal: tuple[float, float, float]
    outcome: str
    time_s: float
    driven_m: float
    shortest_m: float
    collisions: int
    recoveries: int

    @property
    def lower_bound_s(self) -> float:
        return self.shortest_m / BOUND_MAX_LINEAR_MPS

    def as_dict(self) -> dict[str, float | str]:
        return {
            "outcome": self.outcome,
            "time_s": round(self.time_s, 2),
            "lower_bound_s": round(self.lower_bound_s, 2),
            "time_ratio": round(self.time_s / self.lower_bound_s, 2) if self.lower_bound_s > 0 else math.nan,
            "driven_m": round(self.driven_m, 2),
            "shortest_m": round(self.shortest_m, 2),
            "length_ratio": round(self.driven_m / self.shortest_m, 2) if self.shortest_m > 0 else math.nan,
            "collisions": self.collisions,
            "recoveries": self.recoveries,
        }


class _Odometer:
    """Sums the ground-truth distance driven while ``running``."""

    def __init__(self, node: Node) -> None:
        self._lock = threading.Lock()
        self._last: tuple[float, float] | None = None
        self.running = False
        self.distance_m = 0.0
        node.create_subscription(PoseStamped, "ground_truth_pose", self._on_pose, RELIABLE)

    def _on_pose(self, msg: PoseStamped) -> None:
        xy = (msg.pose.position.x, msg.pose.position.y)
        with self._lock:
            if self.running and self._last is not None:
                self.distance_m += math.hypot(xy[0] - self._last[0], xy[1] - self._last[1])
            self._last = xy

    def start(self) -> None:
        with self._lock:
            self.running, self.distance_m = True, 0.0

    def stop(self) -> float:
        with self._lock:
            self.running = False
            return self.distance_m


def _shortest_path_length_m(world_file: str, start: Pose2D, goal: tuple[float, float, float]) -> float:
    """The planner's own shortest collision-free path (glass included), run as a tool process."""
    argv = [
        "--world",
        str(REPO_ROOT / world_file),
        "--start",
        *map(str, start.as_tuple()),
        "--goal",
        *map(str, goal),
    ]
    return float(run_tool("services.planner.lower_bound", argv).last_json()["path_length_m"])


def _drive_world(
    world_file: str,
    goals: tuple[tuple[float, float, float], ...],
    rtf: float,
    timeout_s: float,
    log_dir: Path,
) -> list[RouteResult]:
    world = load_world(REPO_ROOT / world_file)
    endpoint, namespace = f"tcp/127.0.0.1:{free_port()}", "bench"
    results = []
    with open_session(SessionSpec(mode="router", connect=(), listen=(endpoint,))):
        world_path = str(REPO_ROOT / world_file)
        stack = ServiceGroup(
            endpoint,
            namespace,
            {
                "simulator": ["--world", world_path, "-p", f"rtf={rtf}"],
                "pose": ["-p", "use_sim_time=true"],
                "planner": ["-p", "use_sim_time=true", "-p", f"world={world_path}"],
            },
            log_dir,
        )
        try:
            with open_session(SessionSpec(mode="client", connect=(endpoint,))) as session:
                node = Node("bench_navigation", session, namespace)
                spin_in_background(node)
                odometer = _Odometer(node)
                nav = NavigationClient(node)
                if not nav.wait_until_active(60.0):
                    raise RuntimeError(f"no navigation server came up:\n{stack.tails()}")

                def state(wait_s: float = 5.0) -> SimStateResponse:
                    """The simulator's state, asked every half second for up to ``wait_s``: a request sent before
                    its service is declared finds no one, however long it waits."""
                    deadline = time.monotonic() + wait_s
                    while True:
                        try:
                            return call_service(
                                session, f"{namespace}/simulator/state", SIM_STATE, SimStateRequest(), 0.5
                            )
                        except ServiceError as exc:
                            if time.monotonic() < deadline:
                                continue
                            raise RuntimeError(f"{exc}; the services' logs end:\n{stack.tails()}") from None

                state(wait_s=60.0)  # the navigation server can be up before the simulator answers

                for goal in goals:
                    before = state()
                    start = before.pose.to_pose2d()
                    odometer.start()
                    nav.go_to_pose(Pose2D(*goal))
                    deadline = time.monotonic() + timeout_s
                    while not nav.is_task_complete() and time.monotonic() < deadline:
                        time.sleep(0.02)
                    if not nav.is_task_complete():
                        nav.cancel_task()
                    after = state()
                    feedback = nav.get_feedback()
                    outcome = nav.get_result()
                    results.append(
                        RouteResult(
                            world=world.name,
                            start=start,
                            goal=goal,
                            outcome=outcome.name if outcome is not TaskResult.UNKNOWN else "TIMEOUT",
                            time_s=after.stamp.to_sec() - before.stamp.to_sec(),
                            driven_m=odometer.stop(),
                            shortest_m=_shortest_path_length_m(world_file, start, goal),
                            collisions=after.collisions - before.collisions,
                            recoveries=feedback.number_of_recoveries if feedback is not None else 0,
                        )
                    )
                node.shutdown()
                node.close()
        finally:
            stack.close()
    return results


def run_navigation_bench(
    rtf: float = 5.0,
    timeout_s: float = 120.0,
    routes: dict[str, tuple[tuple[float, float, float], ...]] | None = None,
) -> list[RouteResult]:
    """Drive every route at ``rtf`` times real time; ``timeout_s`` (wall) per goal."""
    results: list[RouteResult] = []
    with tempfile.TemporaryDirectory(prefix="zendock-bench-nav-") as tmp:
        for world_file, goals in (routes or ROUTES).items():
            log_dir = Path(tmp) / Path(world_file).stem
            log_dir.mkdir()
            results += _drive_world(world_file, goals, rtf, timeout_s, log_dir)
    return results
