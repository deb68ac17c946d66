"""Robot pose estimate for the docking loop: dead reckoning corrected by late, noisy pose measurements.

The graceful law divides by the distance to its target, so near the dock a few millimetres of pose noise
become large steering commands, and a pose that is 50 ms old makes it steer for where the robot was.
This complementary filter (a fixed-gain observer) predicts the pose forward with the body velocities
the base is following (the commands, passed through the base's acceleration limits, or measured
odometry), and nudges the prediction towards each measurement by ``correction_gain`` of the
*innovation*, the difference between the measurement and the prediction for the moment the
measurement was taken (its age, by default ``latency_s``). The whole stored track is shifted by the same correction so
an innovation is never counted twice.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass

from services.docking.kinematics import RobotLimits
from shared.geometry import Pose2D, wrap_angle

_SUBSTEPS = 5
#: How much past track is kept to look up late measurements.
_HISTORY_S = 1.0


@dataclass(frozen=True, slots=True)
class PoseEstimatorParams:
    """Filter tuning: how much a measurement moves the estimate, and how late measurements arrive."""

    correction_gain: float = 0.12
    latency_s: float = 0.05
    #: Model the base's acceleration limits when propagating with commanded (not measured) velocities.
    command_limits: RobotLimits | None = RobotLimits()

    def __post_init__(self) -> None:
        if not 0.0 < self.correction_gain <= 1.0:
            raise ValueError(f"correction_gain must be in (0, 1], got {self.correction_gain}")
        if self.latency_s < 0.0:
            raise ValueError(f"latency_s must be >= 0, got {self.latency_s}")


class RobotPoseEstimator:
    """Fixed-gain observer of the robot's map pose; time advances only through :meth:`propagate`."""

    def __init__(self, params: PoseEstimatorParams | None = None) -> None:
        self.params = params or PoseEstimatorParams()
        self._times: list[float] = []
        self._track: list[tuple[float, float, float]] = []
        self._v_mps = 0.0
        self._w_radps = 0.0

    @property
    def initialised(self) -> bool:
        return bool(self._track)

    @property
    def pose(self) -> Pose2D:
        if not self._track:
            raise RuntimeError("no pose yet: call reset() or correct() first")
        x, y, yaw = self._track[-1]
        return Pose2D(x, y, wrap_angle(yaw))

    @property
    def velocity(self) -> tuple[float, float]:
        """The body velocity ``(v m/s, w rad/s)`` the estimate currently moves with."""
        return (self._v_mps, self._w_radps)

    def reset(self, pose: Pose2D | None = None) -> None:
        """Forget everything; with ``pose``, start there at rest."""
        self._times = []
        self._track = []
        self._v_mps = 0.0
        self._w_radps = 0.0
        if pose is not None:
            self._times.append(0.0)
            self._track.append((pose.x, pose.y, pose.yaw))

    def propagate(self, v_mps: float, w_radps: float, dt_s: float, measured_velocity: bool = False) -> Pose2D:
        """Advance the estimate by ``dt_s`` following the body velocity ``(v, w)``.

        ``(v, w)`` is a command, reached within ``command_limits``; with ``measured_velocity`` it is what
        the base did (odometry) and is followed as is.
        """
        if not self._track:
            raise RuntimeError("no pose yet: call reset() or correct() first")
        if dt_s <= 0.0:
            return self.pose
        limits = None if measured_velocity else self.params.command_limits
        h = dt_s / _SUBSTEPS
        x, y, yaw = self._track[-1]
        for _ in range(_SUBSTEPS):
            if limits is None:
                self._v_mps, self._w_radps = v_mps, w_radps
            else:
                self._v_mps, self._w_radps = limits.next_twist(self._v_mps, self._w_radps, v_mps, w_radps, h)
            mid_yaw = yaw + 0.5 * self._w_radps * h
            x += self._v_mps * h * math.cos(mid_yaw)
            y += self._v_mps * h * math.sin(mid_yaw)
            yaw += self._w_radps * h
        self._times.append(self._times[-1] + dt_s)
        self._track.append((x, y, yaw))
        self._forget_old()
        return self.pose

    def correct(self, measured: Pose2D, age_s: float | None = None) -> Pose2D:
        """Blend in a pose measured ``age_s`` ago (default ``latency_s``); the first one initialises the estimate."""
        if not self._track:
            self.reset(measured)
            return self.pose
        age = self.params.latency_s if age_s is None else max(0.0, age_s)
        px, py, pyaw = self._estimate_at(self._times[-1] - age)
        g = self.params.correction_gain
        dx = g * (measured.x - px)
        dy = g * (measured.y - py)
        dyaw = g * wrap_angle(measured.yaw - pyaw)
        self._track = [(x + dx, y + dy, yaw + dyaw) for x, y, yaw in self._track]
        return self.pose

    def _estimate_at(self, t: float) -> tuple[float, float, float]:
        i = bisect.bisect_right(self._times, t)
        if i == 0:
            return self._track[0]
        if i >= len(self._times):
            return self._track[-1]
        t0, t1 = self._times[i - 1], self._times[i]
        a = (t - t0) / (t1 - t0)
        (x0, y0, yaw0), (x1, y1, yaw1) = self._track[i - 1], self._track[i]
        return (x0 + a * (x1 - x0), y0 + a * (y1 - y0), yaw0 + a * (yaw1 - yaw0))

    def _forget_old(self) -> None:
        horizon = self._times[-1] - max(self.params.latency_s, _HISTORY_S)
        keep_from = max(0, bisect.bisect_left(self._times, horizon) - 1)
        if keep_from > 0:
            del self._times[:keep_from]
            del self._track[:keep_from]
