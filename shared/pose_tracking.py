"""The robot's map pose at any recent instant, from slow unstamped localisation and stamped odometry.

``map_to_base_link_pose2d`` arrives at a few hertz without a stamp; odometry arrives faster (50 Hz),
stamped at capture, with odom -> base_link and the measured twist. The pose at time ``t`` is the
localiser's map -> odom correction of the newest localisation sample taken at or before ``t``, applied
to the odometry at ``t`` (REP 105; tf's lookup at a stamp, in 2-D). A sample's correction comes from
pairing it with the odometry sample it was computed from: of those stamped shortly before it (or after),
the one that moves the correction least -- the correction changes slowly, and the pose service composes
it with the very odometry the topic carries -- so a sample that arrives late (a busy machine) neither
delays nor shakes the pose. Without it a lidar scan taken while turning at 1.5 rad/s would be placed with
up to 0.1 s of heading lag, smearing walls 0.4 m sideways at 3 m.

Without odometry the samples are interpolated. An odometry jump (a reset, a teleport) drops the history,
since poses from before it cannot be carried across it, and localisation arriving in the next
``relocalise_settle_s`` is ignored: the localiser may still report where the robot was. Times are on one
clock, the one odometry is stamped on (the services run on sim time); ``received_s`` of odometry is
when it arrived on that clock (its stamp unless told), which decides freshness and extrapolation.

The planner places scans and steers with it, the docking service places dock detections and controls
the approach with it.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass

from shared.frames import CLOCK_RESET_S
from shared.geometry import Pose2D, wrap_angle

#: How much history is kept, seconds.
HISTORY_S = 3.0
#: Odometry may be extrapolated with its last twist at most this far past its newest sample (default).
MAX_EXTRAPOLATION_S = 0.2
#: Without odometry, a localisation sample stands for the robot's pose at most this long after it.
MAX_HOLD_S = 0.5
#: A localisation sample pairs with odometry stamped at most this long before the time it describes (or later).
PAIRING_WINDOW_S = 0.3
#: Pose change that counts as much as 1 rad of heading change, when choosing the pairing.
PAIRING_METRES_PER_RAD = 0.3
#: After an odometry jump, localisation is ignored this long (default).
RELOCALISE_SETTLE_S = 1.0


@dataclass(frozen=True, slots=True)
class OdometrySample:
    """odom -> base_link at ``stamp_s`` and the body twist measured then."""

    stamp_s: float
    pose: Pose2D
    linear_mps: float
    angular_radps: float


class PoseTrack:
    """Map poses (time they describe, pose) and odometry samples, a few seconds of each."""

    def __init__(
        self,
        odom_jump_m: float = 0.05,
        odom_jump_rad: float = 0.2,
        max_extrapolation_s: float = MAX_EXTRAPOLATION_S,
        relocalise_settle_s: float = RELOCALISE_SETTLE_S,
    ) -> None:
        self.odom_jump_m = odom_jump_m
        self.odom_jump_rad = odom_jump_rad
        self.max_extrapolation_s = max_extrapolation_s
        self.relocalise_settle_s = relocalise_settle_s
        #: When the newest odometry arrived (-inf before any).
        self._odom_received_s = -math.inf
        self._ignore_poses_until_s = -math.inf
        self._pose_times: list[float] = []
        self._poses: list[Pose2D] = []
        #: map -> odom of each localisation sample (None when there was no odometry to pair it with).
        self._corrections: list[Pose2D | None] = []
        self._odom_times: list[float] = []
        self._odom: list[OdometrySample] = []
        #: Clock time at which the newest localisation sample arrived (-inf before any).
        self.last_pose_received_s = -math.inf
        self.odom_resets = 0

    def clear(self) -> None:
        self._pose_times.clear()
        self._poses.clear()
        self._corrections.clear()
        self._odom_times.clear()
        self._odom.clear()
        self.last_pose_received_s = -math.inf
        self._odom_received_s = -math.inf
        self._ignore_poses_until_s = -math.inf

    def snapshot(self) -> PoseTrack:
        """A copy that later samples do not change: readings placed with it in one pass share one
        map -> odom correction, however localisation arrives meanwhile."""
        copy = PoseTrack.__new__(PoseTrack)
        copy.__dict__.update(self.__dict__)
        for name in ("_pose_times", "_poses", "_corrections", "_odom_times", "_odom"):
            setattr(copy, name, list(getattr(self, name)))
        return copy

    # --- input -------------------------------------------------------------------------------------

    def add_pose(self, received_s: float, pose: Pose2D, latency_s: float = 0.0) -> None:
        """A localisation sample received at ``received_s`` describing the robot ``latency_s`` earlier.

        Ignored for ``relocalise_settle_s`` after an odometry jump (it may place the robot where it was).
        """
        if received_s < self._ignore_poses_until_s:
            return
        t = received_s - latency_s
        if self._pose_times and t < self._pose_times[-1] - CLOCK_RESET_S:
            self.clear()
        if self._pose_times and t <= self._pose_times[-1]:
            t = self._pose_times[-1] + 1e-6  # keep times increasing
        # Paired now if the odometry of its time is here, else when it comes (see add_odom).
        correction = self._pair(pose, t) if self._odom and self._odom_times[-1] >= t else None
        self._pose_times.append(t)
        self._poses.append(pose)
        self._corrections.append(correction)
        self.last_pose_received_s = received_s
        self._forget(t, self._pose_times, self._poses, self._corrections)

    def _pair(self, pose: Pose2D, t: float) -> Pose2D | None:
        """The map -> odom correction of a localisation sample: see the module docstring."""
        candidates = self._odom[bisect.bisect_left(self._odom_times, t - PAIRING_WINDOW_S) :]
        if not candidates:
            return None
        estimates = [pose.compose(sample.pose.inverse()) for sample in candidates]
        previous = self.map_to_odom
        if previous is None:
            return estimates[min(range(len(candidates)), key=lambda i: abs(candidates[i].stamp_s - t))]

        def change(estimate: Pose2D) -> float:
            turn = abs(wrap_angle(estimate.yaw - previous.yaw))
            return previous.distance_to(estimate) + PAIRING_METRES_PER_RAD * turn

        return min(reversed(estimates), key=change)

    def add_odom(self, sample: OdometrySample, received_s: float | None = None) -> None:
        """An odometry sample (odom -> base_link and the body twist), stamped at capture, arrived at
        ``received_s`` (its stamp when not given)."""
        received_s = sample.stamp_s if received_s is None else received_s
        if self._odom:
            last = self._odom[-1]
            if sample.stamp_s < last.stamp_s - CLOCK_RESET_S:
                self.clear()
            elif sample.stamp_s <= last.stamp_s:
                return  # out of order or repeated
            elif self._is_jump(last, sample):
                self.odom_resets += 1
                # Poses from before the jump cannot be carried across it.
                self._odom_times.clear()
                self._odom.clear()
                self._pose_times.clear()
                self._poses.clear()
                self._corrections.clear()
                self._ignore_poses_until_s = received_s + self.relocalise_settle_s
        self._odom_received_s = received_s
        self._odom_times.append(sample.stamp_s)
        self._odom.append(sample)
        self._forget(sample.stamp_s, self._odom_times, self._odom)
        if self._corrections and self._corrections[-1] is None and sample.stamp_s >= self._pose_times[-1]:
            # The newest localisation sample came before the odometry of its time.
            self._corrections[-1] = self._pair(self._poses[-1], self._pose_times[-1])

    def _is_jump(self, last: OdometrySample, sample: OdometrySample) -> bool:
        dt = sample.stamp_s - last.stamp_s
        speed = max(abs(last.linear_mps), abs(sample.linear_mps))
        turn = max(abs(last.angular_radps), abs(sample.angular_radps))
        moved = last.pose.distance_to(sample.pose)
        turned = abs(wrap_angle(sample.pose.yaw - last.pose.yaw))
        return moved > self.odom_jump_m + 2.0 * speed * dt or turned > self.odom_jump_rad + 2.0 * turn * dt

    @staticmethod
    def _forget(newest_s: float, times: list[float], *items: list) -> None:  # type: ignore[type-arg]
        keep_from = bisect.bisect_left(times, newest_s - HISTORY_S)
        if keep_from > 0:
            del times[:keep_from]
            for item in items:
                del item[:keep_from]

    # --- queries -----------------------------------------------------------------------------------

    @property
    def has_pose(self) -> bool:
        return bool(self._poses)

    @property
    def map_to_odom(self) -> Pose2D | None:
        """The newest map -> odom correction (None without odometry to pair localisation with)."""
        return self._correction_at(len(self._corrections) - 1)

    def _correction_at(self, index: int) -> Pose2D | None:
        """The correction of localisation sample ``index``, or of the newest one before it that has one."""
        for correction in reversed(self._corrections[: index + 1]):
            if correction is not None:
                return correction
        return None

    def pose_fresh(self, now_s: float, max_age_s: float, carried_age_s: float = 0.0) -> bool:
        """Whether a localisation sample arrived within ``max_age_s`` of ``now_s`` -- or within
        ``carried_age_s`` while odometry no older than ``max_age_s`` carries it forward (map -> odom
        changes slowly: a localiser running late does not make the robot's pose stale)."""
        if not self.has_pose:
            return False
        age = self.pose_age_s(now_s)
        if age <= max_age_s:
            return True
        return self.carried_by_odometry(now_s, max_age_s) and age <= carried_age_s

    @property
    def latest_odom(self) -> OdometrySample | None:
        return self._odom[-1] if self._odom else None

    def twist(self, now_s: float, max_age_s: float) -> tuple[float, float] | None:
        """The measured body velocity ``(v, w)``, or None when odometry arrived more than ``max_age_s`` ago."""
        odom = self.latest_odom
        if odom is None or not self.odom_fresh(now_s, max_age_s):
            return None
        return (odom.linear_mps, odom.angular_radps)

    def odom_fresh(self, now_s: float, max_age_s: float) -> bool:
        """Whether odometry arrived within ``max_age_s`` of ``now_s``."""
        return bool(self._odom) and now_s - self._odom_received_s <= max_age_s

    def carried_by_odometry(self, now_s: float, max_age_s: float) -> bool:
        """Whether fresh odometry carries the localisation forward (a map -> odom correction exists)."""
        return self.map_to_odom is not None and self.odom_fresh(now_s, max_age_s)

    def pose_age_s(self, now_s: float) -> float:
        """Time since the newest localisation sample arrived (``inf`` before the first)."""
        return now_s - self.last_pose_received_s

    def current_pose(self, now_s: float, max_odom_age_s: float) -> Pose2D | None:
        """The pose now: the newest odometry through the newest correction, carried forward along its
        twist by the time since it arrived (at most ``max_extrapolation_s``: further out, a robot that has
        since braked would be placed ahead of where it is). The newest localisation sample as it came when
        odometry is older than ``max_odom_age_s`` or there is no correction."""
        if not self._poses:
            return None
        odom, correction = self.latest_odom, self.map_to_odom
        if odom is None or correction is None or not self.odom_fresh(now_s, max_odom_age_s):
            return self._poses[-1]
        ahead_s = min(max(now_s - self._odom_received_s, 0.0), self.max_extrapolation_s)
        return correction.compose(odom.pose.advance(odom.linear_mps, odom.angular_radps, ahead_s))

    def odom_at(self, t_s: float) -> Pose2D | None:
        """The odometry pose at ``t_s``: interpolated, or extrapolated a little past the newest sample."""
        if not self._odom or t_s < self._odom_times[0]:
            return None
        i = bisect.bisect_right(self._odom_times, t_s)
        if i >= len(self._odom):
            last = self._odom[-1]
            ahead = t_s - last.stamp_s
            if ahead > self.max_extrapolation_s:
                return None
            return last.pose.advance(last.linear_mps, last.angular_radps, ahead)
        a, b = self._odom[i - 1], self._odom[i]
        return a.pose.interpolate(b.pose, (t_s - a.stamp_s) / (b.stamp_s - a.stamp_s))

    def pose_at(self, t_s: float) -> Pose2D | None:
        """The robot's map pose at ``t_s``, or None when the history does not reach that far."""
        if not self._poses:
            return None
        i = bisect.bisect_right(self._pose_times, t_s)
        k = max(0, i - 1)  # the newest sample at or before t (or the oldest one)
        anchor_t, anchor, correction = self._pose_times[k], self._poses[k], self._correction_at(k)
        odom_t = self.odom_at(t_s)
        if correction is not None and odom_t is not None:
            return correction.compose(odom_t)
        if i == 0:
            return anchor if anchor_t - t_s <= self.max_extrapolation_s else None
        if i < len(self._poses):
            t1 = self._pose_times[i]
            return anchor.interpolate(self._poses[i], (t_s - anchor_t) / (t1 - anchor_t))
        return anchor if t_s - anchor_t <= MAX_HOLD_S else None

    def pose_now_at(self, t_s: float) -> Pose2D | None:
        """The odometry pose at ``t_s`` through the newest correction (what the robot's pose now is
        made of), or :meth:`pose_at` without odometry."""
        correction, odom_t = self.map_to_odom, self.odom_at(t_s)
        if correction is not None and odom_t is not None:
            return correction.compose(odom_t)
        return self.pose_at(t_s)

    def latest(self) -> tuple[float, Pose2D] | None:
        """``(time, pose)`` of the newest pose this track knows: the newest odometry through the newest
        correction when it has them (as :meth:`pose_now_at` places detections), else the newest sample."""
        if not self._poses:
            return None
        odom, correction = self.latest_odom, self.map_to_odom
        if odom is not None and correction is not None:
            return (odom.stamp_s, correction.compose(odom.pose))
        return (self._pose_times[-1], self._poses[-1])
