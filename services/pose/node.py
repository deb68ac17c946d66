"""The pose service's wiring: ``tf`` and ``tf_static`` in, ``map_to_base_link_pose2d`` and ``amcl_pose`` out.

Every ``1 / publish_rate_hz`` seconds on the node's clock it looks up ``reference_frame ->
target_frame`` at the latest common time and publishes std_msgs/Float64MultiArray ``[x, y, yaw]``
(metres, radians in [-pi, pi)) with the layout ``dim = [{label: pose2d, size: 3, stride: 3}]``.
While the lookup fails, or the newest transform is older than ``max_transform_age_s`` on the node's
clock, it publishes nothing and says why (rate-limited). The simulator republishes ``tf_static``
every second, so a late joiner has the static links within a second.

It also stands in for Nav2's ``amcl`` (:mod:`shared.nav2_stand_ins`): ``amcl_pose``
(geometry_msgs/PoseWithCovarianceStamped in ``reference_frame``) when the robot has moved
``amcl_update_min_d_m`` or turned ``amcl_update_min_a_rad`` since the last one, as AMCL publishes it
(its ``update_min_d`` and ``update_min_a``), and, unlike AMCL, at least every ``amcl_pose_period_s``, so
a Nav2 script's ``waitUntilNav2Active()`` hears one soon after its ``/initialpose``. The covariance is all zeros: the
stand-in does not estimate its uncertainty.
"""

from __future__ import annotations

from typing import Annotated

import numpy as np
from msgspec import Meta

from shared import topics
from shared.frames import CLOCK_RESET_S, clock_went_back
from shared.geometry import Pose2D, wrap_angle
from shared.messages import (
    Float64MultiArray,
    Header,
    MultiArrayDimension,
    MultiArrayLayout,
    Pose,
    PoseWithCovariance,
    PoseWithCovarianceStamped,
    TFMessage,
)
from shared.node import RELIABLE, Node, QoS
from shared.parameters import ServiceParams
from shared.ratelimit import RateLimitedLogger
from shared.runtime import ServiceSpec
from shared.tf_buffer import StampedTransform, TfBuffer, TransformError

#: tf is a high-rate stream: keep a deep queue so a busy moment loses no history.
TF_QOS = QoS(reliable=False, depth=100)
#: tf_static is state: reliable, every message kept.
TF_STATIC_QOS = QoS(reliable=True, depth=20)
#: How often the same complaint may be logged.
LOG_INTERVAL_S = 2.0
#: A clock reading this much earlier than the previous tick is a reset.


class Params(ServiceParams):
    """Parameters of ``python -m services.pose`` (``-p name=value`` or a YAML file)."""

    target_frame: Annotated[str, Meta(description="frame whose pose is published (e.g. lidar_link)")] = (
        "base_link"
    )
    reference_frame: Annotated[str, Meta(description="frame the pose is expressed in")] = "map"
    publish_rate_hz: Annotated[
        float, Meta(gt=0.0, le=100.0, description="publication rate on the node's clock")
    ] = 10.0
    cache_time_s: Annotated[
        float, Meta(gt=0.0, description="how much tf history is kept for interpolation")
    ] = 10.0
    max_transform_age_s: Annotated[
        float,
        Meta(
            ge=0.0, description="publish nothing when the newest transform is older than this (0: no limit)"
        ),
    ] = 1.0
    amcl_pose_period_s: Annotated[
        float, Meta(gt=0.0, description="amcl_pose at least this often (node's clock)")
    ] = 1.0
    amcl_update_min_d_m: Annotated[
        float, Meta(gt=0.0, description="amcl_pose when moved this far since the last")
    ] = 0.25
    amcl_update_min_a_rad: Annotated[
        float, Meta(gt=0.0, description="amcl_pose when turned this far since the last")
    ] = 0.2

    def __post_init__(self) -> None:
        for field_name in ("target_frame", "reference_frame"):
            frame = getattr(self, field_name).strip().lstrip("/")
            if not frame:
                raise ValueError(f"{field_name}: a frame name must not be empty")
            setattr(self, field_name, frame)


def amcl_pose_message(transform: StampedTransform, frame_id: str) -> PoseWithCovarianceStamped:
    """The pose as Nav2's localiser publishes it: stamped with the transform's time (zero covariance)."""
    return PoseWithCovarianceStamped(
        header=Header.at(transform.stamp_s, frame_id),
        pose=PoseWithCovariance(pose=Pose.from_pose2d(transform.transform.to_pose2d())),
    )


def pose2d_message(transform: StampedTransform) -> Float64MultiArray:
    """``[x, y, yaw]`` of a transform, with the pose2d layout."""
    pose = transform.transform.to_pose2d()
    return Float64MultiArray(
        layout=MultiArrayLayout(dim=[MultiArrayDimension(label="pose2d", size=3, stride=3)], data_offset=0),
        data=np.array([pose.x, pose.y, pose.yaw], dtype=np.float64),
    )


class PoseService:
    """The tf listener and 2-D pose publisher on a node; see the module docstring."""

    def __init__(self, node: Node, params: Params) -> None:
        self._node = node
        self._params = params
        self._log = node.log
        self._say = RateLimitedLogger(node.log, interval_s=LOG_INTERVAL_S)
        self._buffer = TfBuffer(cache_time_s=params.cache_time_s, time_jump_reset_s=CLOCK_RESET_S)
        self._available = False
        self._last_tick_s: float | None = None
        self._publisher = node.create_publisher(Float64MultiArray, topics.POSE2D, RELIABLE)
        self._amcl_publisher = node.create_publisher(PoseWithCovarianceStamped, topics.AMCL_POSE, RELIABLE)
        #: The pose and clock time of the last amcl_pose (None before the first).
        self._amcl_last: tuple[float, Pose2D] | None = None
        self._tf_sub = node.create_subscription(TFMessage, topics.TF, self._on_tf, TF_QOS)
        self._tf_static_sub = node.create_subscription(
            TFMessage, topics.TF_STATIC, self._on_tf_static, TF_STATIC_QOS
        )
        self._timer = node.create_timer(1.0 / params.publish_rate_hz, self._on_timer)
        self._clock_wait_timer = (
            node.create_timer(5.0, self._on_clock_wait, wall=True) if node.use_sim_time else None
        )
        self._log.info(
            "publishing %s -> %s as %s at %g Hz on %s time",
            params.reference_frame,
            params.target_frame,
            self._publisher.key,
            params.publish_rate_hz,
            "sim" if node.use_sim_time else "wall",
        )

    def _on_tf(self, msg: TFMessage) -> None:
        self._insert(msg, static=False)

    def _on_tf_static(self, msg: TFMessage) -> None:
        self._insert(msg, static=True)

    def _insert(self, msg: TFMessage, static: bool) -> None:
        intake = self._buffer.add_message(msg, static=static)
        for link, why in intake.refused:
            self._say.warning(f"bad:{link}", "ignored a transform: %s", why)
        for link, stamp_s in intake.went_back:
            self._log.warning(
                "transform %s went back in time to %.3f s (a reset?): cleared the tf history", link, stamp_s
            )

    def _on_timer(self) -> None:
        now_s = self._node.now()
        if clock_went_back(now_s, self._last_tick_s):
            self._log.warning("clock jumped back to %.3f s (a reset?): cleared the tf history", now_s)
            self._buffer.clear_dynamic()
        self._last_tick_s = now_s
        reference, target = self._params.reference_frame, self._params.target_frame
        try:
            transform = self._buffer.lookup(reference, target)
        except TransformError as exc:
            self._unavailable(f"no transform {reference} -> {target} yet: {exc}")
            return
        static_only = transform.stamp_s == 0.0
        age_s = now_s - transform.stamp_s
        limit_s = self._params.max_transform_age_s
        if limit_s > 0.0 and not static_only and age_s > limit_s:
            self._unavailable(
                f"transform {reference} -> {target} is {age_s:.3f} s old (stamp {transform.stamp_s:.3f} s, clock "
                f"{now_s:.3f} s), more than max_transform_age_s={limit_s:g}"
                + ("" if self._node.use_sim_time else "; is use_sim_time needed?")
            )
            return
        if not self._available:
            self._available = True
            self._log.info("transform %s -> %s available: publishing", reference, target)
        self._publisher.publish(pose2d_message(transform))
        self._maybe_amcl_pose(now_s, transform)

    def _maybe_amcl_pose(self, now_s: float, transform: StampedTransform) -> None:
        pose, last, p = transform.transform.to_pose2d(), self._amcl_last, self._params
        if last is not None:
            last_s, last_pose = last
            due = (
                now_s - last_s >= p.amcl_pose_period_s
                or now_s < last_s  # the clock was reset
                or pose.distance_to(last_pose) >= p.amcl_update_min_d_m
                or abs(wrap_angle(pose.yaw - last_pose.yaw)) >= p.amcl_update_min_a_rad
            )
            if not due:
                return
        self._amcl_last = (now_s, pose)
        self._amcl_publisher.publish(amcl_pose_message(transform, p.reference_frame))

    def _unavailable(self, reason: str) -> None:
        if self._available:
            self._available = False
            self._log.warning("%s; publishing nothing until it is back", reason)
            return
        self._say.info("unavailable", "%s; publishing nothing", reason)

    def _on_clock_wait(self) -> None:
        if self._node.clock_started:
            assert self._clock_wait_timer is not None
            self._clock_wait_timer.cancel()
            return
        self._log.warning("use_sim_time is set but no clock message has arrived yet: nothing is published")

    def close(self) -> None:
        self._timer.cancel()
        if self._clock_wait_timer is not None:
            self._clock_wait_timer.cancel()


SERVICE = ServiceSpec(
    "pose",
    Params,
    PoseService,
    description="Keeps a tf buffer and publishes the map -> target_frame pose as [x, y, yaw].",
)


def main(argv: list[str] | None = None) -> int:
    return SERVICE.run(argv)
