"""The robot's pose in the map at any recent instant, from a slow unstamped map pose and stamped odometry.

The pose service publishes map -> base_link at 10 Hz without a stamp; odometry arrives at 50 Hz stamped,
with odom -> base_link and the measured twist. A localiser's map -> odom correction changes slowly, so
it is estimated at each map pose and the pose at time ``t`` is ``map->odom * odom->base_link(t)``, with
``odom->base_link(t)`` interpolated in the odometry history or extrapolated along the last twist: tf's
lookup at a stamp, in 2-D. Without it a lidar scan taken while turning at 1.5 rad/s would be placed with
up to 0.1 s of heading lag, smearing walls 0.4 m sideways at 3 m.

The map pose has no stamp, so which odometry sample it pairs with is a guess: of the newest few, the
one that moves the map -> odom estimate least (map -> odom is nearly constant between corrections).
Without odometry the tracker falls back to the last map pose as it came. Odometry that jumps (a
teleport restarts it) drops the history, the map -> odom estimate and the map pose measured before it:
the robot is placed again only once localisation has caught up.
"""

from __future__ import annotations

import bisect
import math
from collections import deque
from dataclasses import dataclass

from shared.frames import CLOCK_RESET_S
from shared.geometry import Pose2D, wrap_angle

#: How many of the newest odometry samples may pair with a map pose.
PAIRING_CANDIDATES = 5
#: Odometry that moves this much more between two samples than its twist allows has jumped (a reset, a
#: teleport): metres, radians.
ODOM_JUMP_M = 0.05
ODOM_JUMP_RAD = 0.2
#: After a jump, map poses are ignored this long: the localiser may still publish the pose from before it.
RELOCALISE_SETTLE_S = 1.0


@dataclass(frozen=True, slots=True)
class OdometrySample:
    stamp_s: float
    #: odom -> base_link.
    pose: Pose2D
    linear_mps: float
    angular_radps: float


def _jumped(last: OdometrySample, sample: OdometrySample) -> bool:
    """Whether odometry moved between two samples by more than its own twist can explain."""
    dt = sample.stamp_s - last.stamp_s
    speed = max(abs(last.linear_mps), abs(sample.linear_mps))
    turn = max(abs(last.angular_radps), abs(sample.angular_radps))
    moved = last.pose.distance_to(sample.pose)
    turned = abs(wrap_angle(sample.pose.yaw - last.pose.yaw))
    return moved > ODOM_JUMP_M + 2.0 * speed * dt or turned > ODOM_JUMP_RAD + 2.0 * turn * dt


def _pose_change(a: Pose2D, b: Pose2D) -> float:
    """A scalar size of the difference between two poses (metres, with 1 rad counted as 0.3 m)."""
    return math.hypot(b.x - a.x, b.y - a.y) + 0.3 * abs(wrap_angle(b.yaw - a.yaw))


class PoseTracker:
    """Keeps the odometry history and the map -> odom estimate; every time is on one clock per input.

    Odometry stamps and sensor stamps share the simulator's clock; ``received_s`` arguments are the
    node's clock when a message arrived, used for freshness and for extrapolating to "now".
    Extrapolation stops after ``max_extrapolation_s`` (a few odometry periods): further out, a robot
    that has since braked would be placed ahead of where it is.
    """

    def __init__(
        self, history_s: float = 2.0, max_extrapolation_s: float = 0.1, odom_timeout_s: float = 0.5
    ) -> None:
        self.history_s = history_s
        self.max_extrapolation_s = max_extrapolation_s
        self.odom_timeout_s = odom_timeout_s
        self._odom: deque[OdometrySample] = deque()
        self._odom_received_s = -math.inf
        self._map_pose: Pose2D | None = None
        self._map_received_s = -math.inf
        self._map_to_odom: Pose2D | None = None
        self._ignore_map_until_s = -math.inf

    # --- inputs ---------------------------------------------------------------------------------

    def add_odometry(self, sample: OdometrySample, received_s: float) -> None:
        if self._odom and sample.stamp_s < self._odom[-1].stamp_s - CLOCK_RESET_S:
            self.reset()
        if self._odom and sample.stamp_s <= self._odom[-1].stamp_s:
            return  # out of order or repeated: the history stays sorted
        if self._odom and _jumped(self._odom[-1], sample):
            # Odometry restarted (a teleport): neither the old map -> odom nor the map pose measured before
            # it places the robot now. Hold on until localisation has caught up.
            self._odom.clear()
            self._map_to_odom = None
            self._map_pose = None
            self._map_received_s = -math.inf
            self._ignore_map_until_s = received_s + RELOCALISE_SETTLE_S
        self._odom.append(sample)
        while self._odom and self._odom[0].stamp_s < sample.stamp_s - self.history_s:
            self._odom.popleft()
        self._odom_received_s = received_s

    def add_map_pose(self, pose: Pose2D, received_s: float) -> None:
        if received_s < self._ignore_map_until_s:
            return
        self._map_pose = pose
        self._map_received_s = received_s
        if not self._odom_fresh(received_s):
            self._map_to_odom = None
            return
        candidates = list(self._odom)[-PAIRING_CANDIDATES:]
        estimates = [pose.compose(sample.pose.inverse()) for sample in candidates]
        if self._map_to_odom is None:
            self._map_to_odom = estimates[-1]
            return
        previous = self._map_to_odom
        self._map_to_odom = min(reversed(estimates), key=lambda e: _pose_change(previous, e))

    def reset(self) -> None:
        """Forget everything (a clock reset, a teleport)."""
        self._odom.clear()
        self._odom_received_s = -math.inf
        self._map_pose = None
        self._map_received_s = -math.inf
        self._map_to_odom = None

    # --- queries --------------------------------------------------------------------------------

    def map_pose_age_s(self, now_s: float) -> float:
        """Time on the node's clock since the last map pose (``inf`` before the first)."""
        return now_s - self._map_received_s

    @property
    def has_pose(self) -> bool:
        return self._map_pose is not None

    def current_pose(self, now_s: float) -> Pose2D | None:
        """The pose now: the newest odometry carried forward by the time since it arrived."""
        if self._map_pose is None:
            return None
        if self._map_to_odom is None or not self._odom_fresh(now_s):
            return self._map_pose
        last = self._odom[-1]
        ahead_s = min(max(now_s - self._odom_received_s, 0.0), self.max_extrapolation_s)
        return self._map_to_odom.compose(last.pose.advance(last.linear_mps, last.angular_radps, ahead_s))

    def pose_at(self, stamp_s: float) -> Pose2D | None:
        """The pose at a sensor stamp (the odometry clock); the last map pose when that is all there is.

        ``None`` for a stamp from before the odometry history: after a teleport that is a reading taken
        where the robot was, and placing it where the robot is now would put what it saw in the wrong place.
        """
        if self._map_pose is None:
            return None
        if self._map_to_odom is None or not self._odom:
            return self._map_pose
        if stamp_s < self._odom[0].stamp_s:
            return None
        return self._map_to_odom.compose(self._odom_pose_at(stamp_s))

    def carried_by_odometry(self, now_s: float) -> bool:
        """Whether fresh odometry carries the last map pose forward (a map -> odom estimate exists)."""
        return self._map_to_odom is not None and self._odom_fresh(now_s)

    def velocity(self, now_s: float) -> tuple[float, float] | None:
        """The measured ``(linear, angular)`` twist, or ``None`` when odometry is stale."""
        if not self._odom_fresh(now_s):
            return None
        last = self._odom[-1]
        return last.linear_mps, last.angular_radps

    # --- internals ------------------------------------------------------------------------------

    def _odom_fresh(self, now_s: float) -> bool:
        return bool(self._odom) and now_s - self._odom_received_s <= self.odom_timeout_s

    def _odom_pose_at(self, stamp_s: float) -> Pose2D:
        samples = self._odom
        first, last = samples[0], samples[-1]
        if stamp_s >= last.stamp_s:
            ahead_s = min(stamp_s - last.stamp_s, self.max_extrapolation_s)
            return last.pose.advance(last.linear_mps, last.angular_radps, ahead_s)
        if stamp_s <= first.stamp_s:
            return first.pose
        stamps = [s.stamp_s for s in samples]
        i = bisect.bisect_right(stamps, stamp_s)
        before, after = samples[i - 1], samples[i]
        span = after.stamp_s - before.stamp_s
        return before.pose.interpolate(after.pose, (stamp_s - before.stamp_s) / span if span > 0 else 1.0)
