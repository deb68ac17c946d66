"""Smoothing of the detected dock pose, as Nav2's opennav_docking ``PoseFilter`` does it, plus outlier rejection.

Each accepted detection moves the filtered pose a fraction ``coef`` of the way towards it: position by
exponential smoothing, yaw by spherical interpolation (for rotations about z, slerp with parameter
``coef`` is exactly a step of ``coef`` along the shortest arc). A detection more than ``timeout_s``
newer than the filtered pose restarts the filter from it, so a stale estimate never drags a fresh one.
Detections that jump further than the outlier limits are ignored, unless ``max_rejected_in_a_row`` of
them come in a row: then the dock really is somewhere else and the filter restarts there.
Time is passed in explicitly (seconds, any epoch).
"""

from __future__ import annotations

from dataclasses import dataclass

from shared.geometry import Pose2D, wrap_angle


@dataclass(frozen=True, slots=True)
class PoseFilterParams:
    """Filter tuning; ``coef`` and ``timeout_s`` defaults are Nav2's ``filter_coef`` and detection timeout."""

    coef: float = 0.1
    timeout_s: float = 1.0
    #: A detection further than this from the filtered pose is an outlier; None disables the test.
    outlier_distance_m: float | None = 0.25
    #: A detection whose yaw differs by more than this is an outlier; None disables the test.
    outlier_yaw_rad: float | None = 0.5
    max_rejected_in_a_row: int = 3

    def __post_init__(self) -> None:
        if not self.coef <= 1.0:
            raise ValueError(f"coef must be <= 1 (<= 0 disables filtering), got {self.coef}")
        if self.timeout_s <= 0.0:
            raise ValueError(f"timeout_s must be > 0, got {self.timeout_s}")
        if self.max_rejected_in_a_row < 1:
            raise ValueError(f"max_rejected_in_a_row must be >= 1, got {self.max_rejected_in_a_row}")


class DockPoseFilter:
    """Filters a stream of dock detections ``(pose, stamp_s)`` into one steady dock pose."""

    def __init__(self, params: PoseFilterParams | None = None) -> None:
        self.params = params or PoseFilterParams()
        self._pose: Pose2D | None = None
        self._stamp_s = float("-inf")
        self.rejected_in_a_row = 0

    @property
    def pose(self) -> Pose2D | None:
        """The filtered dock pose, or None before the first detection."""
        return self._pose

    @property
    def stamp_s(self) -> float:
        """Stamp of the last detection that updated the pose (-inf before any)."""
        return self._stamp_s

    def reset(self) -> None:
        self._pose = None
        self._stamp_s = float("-inf")
        self.rejected_in_a_row = 0

    def shift(self, transform: Pose2D) -> None:
        """Move the filtered pose with its frame: ``transform`` maps old frame coordinates to new ones."""
        if self._pose is not None:
            self._pose = transform.compose(self._pose)

    def is_fresh(self, now_s: float) -> bool:
        """True while the last accepted detection is at most ``timeout_s`` old."""
        return self._pose is not None and now_s - self._stamp_s <= self.params.timeout_s

    def is_outlier(self, measurement: Pose2D) -> bool:
        """Whether ``measurement`` jumps beyond the outlier limits from the filtered pose."""
        if self._pose is None:
            return False
        p = self.params
        far = p.outlier_distance_m is not None and self._pose.distance_to(measurement) > p.outlier_distance_m
        turned = (
            p.outlier_yaw_rad is not None
            and abs(wrap_angle(measurement.yaw - self._pose.yaw)) > p.outlier_yaw_rad
        )
        return far or turned

    def update(self, measurement: Pose2D, stamp_s: float) -> Pose2D:
        """Feed one detection; returns the filtered pose."""
        p = self.params
        if self._pose is None or p.coef <= 0.0 or stamp_s - self._stamp_s > p.timeout_s:
            return self._restart(measurement, stamp_s)
        if stamp_s < self._stamp_s:
            return self._pose  # older than what the filter already holds
        if self.is_outlier(measurement):
            self.rejected_in_a_row += 1
            if self.rejected_in_a_row >= p.max_rejected_in_a_row:
                return self._restart(measurement, stamp_s)
            return self._pose
        self.rejected_in_a_row = 0
        c = p.coef
        f = self._pose
        self._pose = Pose2D(
            (1.0 - c) * f.x + c * measurement.x,
            (1.0 - c) * f.y + c * measurement.y,
            wrap_angle(f.yaw + c * wrap_angle(measurement.yaw - f.yaw)),
        )
        self._stamp_s = stamp_s
        return self._pose

    def _restart(self, measurement: Pose2D, stamp_s: float) -> Pose2D:
        self._pose = Pose2D(measurement.x, measurement.y, wrap_angle(measurement.yaw))
        self._stamp_s = stamp_s
        self.rejected_in_a_row = 0
        return self._pose
