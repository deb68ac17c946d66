"""A kinematic diff-drive robot for testing and tuning docking controllers without a simulator.

The robot is a unicycle whose wheel speeds follow the commanded body velocity within acceleration
limits; the controller is stepped at its control period and sees the pose ``latency_s`` late with
Gaussian noise, as the real stack delivers it. An approach ends at contact (the robot is within the
contacts' reach of the dock pose along the dock axis), when the robot has stopped for good, or at a
timeout.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from services.docking.approach import DockFrameError, dock_frame_error
from shared.geometry import Pose2D, wrap_angle


class DockingController(Protocol):
    """What the simulator steps: a map pose in, ``(linear_x m/s, angular_z rad/s)`` out."""

    def step(self, pose_x: float, pose_y: float, pose_yaw: float) -> tuple[float, float]: ...


@dataclass(frozen=True, slots=True)
class RobotLimits:
    """Velocity and acceleration limits of the base (the simulator's ``DiffDriveParams`` defaults).

    Braking is harder than speeding up, as on the simulated base: a controller that plans its stop at
    the plate with more than the acceleration limit must see that the base can follow it. Unlike the
    simulator's drive, the wheels' own speed limit (which slows a fast turn) is not modelled.
    """

    v_max_mps: float = 0.5
    w_max_radps: float = 1.5
    a_max_mps2: float = 1.0
    alpha_max_radps2: float = 3.0
    a_decel_mps2: float = 2.5
    alpha_decel_radps2: float = 6.0

    def next_twist(
        self, v_mps: float, w_radps: float, target_v_mps: float, target_w_radps: float, dt_s: float
    ) -> tuple[float, float]:
        """The twist after ``dt_s`` of steering ``(v, w)`` towards the (clamped) target within the limits;
        a non-finite target counts as a stop, as on the simulated base."""
        target_v = (
            min(max(target_v_mps, -self.v_max_mps), self.v_max_mps) if math.isfinite(target_v_mps) else 0.0
        )
        target_w = (
            min(max(target_w_radps, -self.w_max_radps), self.w_max_radps)
            if math.isfinite(target_w_radps)
            else 0.0
        )
        return (
            _rate_limited(v_mps, target_v, self.a_max_mps2, self.a_decel_mps2, dt_s),
            _rate_limited(w_radps, target_w, self.alpha_max_radps2, self.alpha_decel_radps2, dt_s),
        )


def _rate_limited(previous: float, target: float, accel: float, decel: float, dt_s: float) -> float:
    """One step from ``previous`` towards ``target``: ``decel`` while slowing in the same direction."""
    slowing = abs(target) < abs(previous) and target * previous >= 0.0
    step = (decel if slowing else accel) * dt_s
    return previous + min(max(target - previous, -step), step)


@dataclass(frozen=True, slots=True)
class PoseSensing:
    """How the controller sees the robot's pose: late by ``latency_s``, with Gaussian noise (std devs)."""

    latency_s: float = 0.0
    position_noise_m: float = 0.0
    yaw_noise_rad: float = 0.0
    seed: int = 0


@dataclass(frozen=True, slots=True)
class MatingTolerance:
    """When the contacts mate: the contacts reach the plate with lateral and yaw errors within these."""

    contact_reach_m: float = 0.05
    lateral_m: float = 0.04
    yaw_rad: float = 0.1


class DiffDriveModel:
    """Unicycle with acceleration-limited velocities; ``step`` integrates the exact arc."""

    def __init__(self, pose: Pose2D, limits: RobotLimits | None = None) -> None:
        self.limits = limits or RobotLimits()
        self.x, self.y, self.yaw = pose.x, pose.y, pose.yaw
        self.v_mps = 0.0
        self.w_radps = 0.0

    @property
    def pose(self) -> Pose2D:
        return Pose2D(self.x, self.y, wrap_angle(self.yaw))

    def step(self, cmd_v_mps: float, cmd_w_radps: float, dt_s: float) -> None:
        self.v_mps, self.w_radps = self.limits.next_twist(
            self.v_mps, self.w_radps, cmd_v_mps, cmd_w_radps, dt_s
        )
        moved = Pose2D(self.x, self.y, self.yaw).advance(self.v_mps, self.w_radps, dt_s)
        self.x, self.y, self.yaw = moved.x, moved.y, moved.yaw


@dataclass(frozen=True)
class ApproachResult:
    """How one simulated approach went.

    ``time_s`` and ``error`` (the robot pose in the dock frame) are taken at the first contact, or at the
    end of the run when the contacts never touched. ``trajectory`` has one row ``(t, x, y, yaw, v, w)``
    per physics step from ``t = 0`` to the end of the run.
    """

    contact: bool
    mated: bool
    time_s: float
    error: DockFrameError
    trajectory: np.ndarray

    @property
    def lateral_error_m(self) -> float:
        return self.error.lateral_m

    @property
    def yaw_error_rad(self) -> float:
        return self.error.yaw_rad

    @property
    def contact_speed_mps(self) -> float:
        """Speed at contact (at the end of the run when there was none)."""
        row = int(np.searchsorted(self.trajectory[:, 0], self.time_s - 1e-9))
        return float(self.trajectory[min(row, len(self.trajectory) - 1), 4])

    @property
    def final_pose(self) -> Pose2D:
        t, x, y, yaw, _, _ = self.trajectory[-1]
        return Pose2D(float(x), float(y), wrap_angle(float(yaw)))


def simulate_approach(
    controller: DockingController,
    start_pose: Pose2D,
    dock_pose: Pose2D,
    dt: float = 0.1,
    *,
    limits: RobotLimits | None = None,
    sensing: PoseSensing | None = None,
    mating: MatingTolerance | None = None,
    physics_dt_s: float = 0.005,
    timeout_s: float = 120.0,
    stopped_for_s: float = 1.0,
    stop_at_contact: bool = True,
) -> ApproachResult:
    """Drive ``controller`` (stepped every ``dt`` seconds) from ``start_pose`` towards ``dock_pose``.

    The run ends at the first contact (unless ``stop_at_contact`` is False: then the plate is not there
    and the run goes on), once the controller has commanded zero with the robot at rest for
    ``stopped_for_s``, or at ``timeout_s``.
    """
    sensing = sensing or PoseSensing()
    mating = mating or MatingTolerance()
    robot = DiffDriveModel(start_pose, limits)
    rng = np.random.default_rng(sensing.seed)
    substeps = max(1, round(dt / physics_dt_s))
    h = dt / substeps
    times: list[float] = [0.0]
    rows: list[tuple[float, float, float, float, float, float]] = [
        (0.0, robot.x, robot.y, robot.yaw, 0.0, 0.0)
    ]
    t = 0.0
    tick = 0
    stopped_since: float | None = None
    contact_time_s: float | None = None
    contact_error: DockFrameError | None = None
    while t < timeout_s:
        seen = rows[max(0, bisect.bisect_right(times, t - sensing.latency_s + 1e-12) - 1)]
        mx = seen[1] + (rng.normal(0.0, sensing.position_noise_m) if sensing.position_noise_m > 0 else 0.0)
        my = seen[2] + (rng.normal(0.0, sensing.position_noise_m) if sensing.position_noise_m > 0 else 0.0)
        myaw = seen[3] + (rng.normal(0.0, sensing.yaw_noise_rad) if sensing.yaw_noise_rad > 0 else 0.0)
        cmd_v, cmd_w = controller.step(mx, my, wrap_angle(myaw))
        if not (math.isfinite(cmd_v) and math.isfinite(cmd_w)):
            raise ValueError(f"controller returned a non-finite command ({cmd_v}, {cmd_w}) at t={t:.3f} s")
        tick_start_s = tick * dt
        tick += 1
        for k in range(1, substeps + 1):
            robot.step(cmd_v, cmd_w, h)
            t = tick_start_s + k * h
            times.append(t)
            rows.append((t, robot.x, robot.y, robot.yaw, robot.v_mps, robot.w_radps))
            if contact_time_s is None:
                error = dock_frame_error(robot.pose, dock_pose)
                if error.along_m >= -mating.contact_reach_m:
                    contact_time_s, contact_error = t, error
                    if stop_at_contact:
                        break
        if contact_time_s is not None and stop_at_contact:
            break
        if cmd_v == 0.0 and cmd_w == 0.0 and robot.v_mps == 0.0 and robot.w_radps == 0.0:
            stopped_since = t if stopped_since is None else stopped_since
            if t - stopped_since >= stopped_for_s:
                break
        else:
            stopped_since = None
    if contact_time_s is None or contact_error is None:
        return ApproachResult(False, False, t, dock_frame_error(robot.pose, dock_pose), np.array(rows))
    mated = abs(contact_error.lateral_m) <= mating.lateral_m and abs(contact_error.yaw_rad) <= mating.yaw_rad
    return ApproachResult(True, mated, contact_time_s, contact_error, np.array(rows))
