"""A tf buffer: the frame tree over time, with lookups between any two frames (pure: no bus).

Every service that reads ``tf`` or ``tf_static`` keeps one: the pose service (static and moving links, to
publish the robot's 2-D pose) and perception (the camera's 3-D mount on base_link), each feeding it whole
messages through :meth:`TfBuffer.add_message`, so a transform is read and refused the same way everywhere.

Semantics follow tf2's ``BufferCore`` (the ROS 2 ``tf2`` package): each frame has one parent; a
dynamic link keeps a time-ordered history (``cache_time_s`` deep) and is interpolated between
stamps, translation linearly and rotation by slerp; a static link holds at all times. A lookup
walks from both frames up to their common ancestor. ``time_s=None`` asks for the latest common time
of the links on that path (tf2's ``Time(0)``). Errors are :class:`LookupError` subclasses that name the
missing frame, the unconnected trees, or the link and times that would need extrapolation.

A stamp more than ``time_jump_reset_s`` older than a link's newest means the clock went back (a
simulator reset): every dynamic link is forgotten, static ones are kept.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass, field

from shared.frames import frame_name
from shared.geometry import Pose2D, quaternion_from_yaw, quaternion_multiply, wrap_angle, yaw_from_quaternion
from shared.messages import TFMessage
from shared.rigid3 import Rigid3

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]

#: Stamps closer than this count as the same time.
TIME_EPSILON_S = 1e-9


class TransformError(LookupError):
    """A lookup cannot be answered (tf2's TransformException)."""


class FrameNotFoundError(TransformError):
    """A frame no transform mentions."""


class ConnectivityError(TransformError):
    """Both frames are known but no chain of links joins them."""


class ExtrapolationError(TransformError):
    """The requested time is outside the history of a link on the path."""


def _normalised(q: Quat) -> Quat:
    norm = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    if not (math.isfinite(norm) and norm > 1e-9):
        raise ValueError(f"rotation quaternion {q} has no direction (length {norm})")
    return (q[0] / norm, q[1] / norm, q[2] / norm, q[3] / norm)


def _rotate(q: Quat, v: Vec3) -> Vec3:
    """``q v q*`` for a unit quaternion, as ``v + w t + u x t`` with ``t = 2 u x v``."""
    ux, uy, uz, w = q
    tx = 2.0 * (uy * v[2] - uz * v[1])
    ty = 2.0 * (uz * v[0] - ux * v[2])
    tz = 2.0 * (ux * v[1] - uy * v[0])
    return (
        v[0] + w * tx + (uy * tz - uz * ty),
        v[1] + w * ty + (uz * tx - ux * tz),
        v[2] + w * tz + (ux * ty - uy * tx),
    )


def slerp(q0: Quat, q1: Quat, fraction: float) -> Quat:
    """Spherical linear interpolation along the shorter arc (Shoemake 1985)."""
    dot = sum(a * b for a, b in zip(q0, q1, strict=True))
    if dot < 0.0:
        q1 = (-q1[0], -q1[1], -q1[2], -q1[3])
        dot = -dot
    if dot > 0.9995:  # nearly the same rotation: a normalised lerp is exact enough and well-conditioned
        return _normalised(tuple(a + fraction * (b - a) for a, b in zip(q0, q1, strict=True)))  # type: ignore[arg-type]
    theta = math.acos(min(1.0, dot))
    sin_theta = math.sin(theta)
    w0 = math.sin((1.0 - fraction) * theta) / sin_theta
    w1 = math.sin(fraction * theta) / sin_theta
    return _normalised(tuple(w0 * a + w1 * b for a, b in zip(q0, q1, strict=True)))  # type: ignore[arg-type]


@dataclass(frozen=True, slots=True)
class RigidTransform:
    """A pose in 3-D: where a child frame's origin and axes are, in its parent frame."""

    translation: Vec3 = (0.0, 0.0, 0.0)
    rotation: Quat = (0.0, 0.0, 0.0, 1.0)

    @classmethod
    def from_pose2d(cls, pose: Pose2D) -> RigidTransform:
        return cls((pose.x, pose.y, 0.0), quaternion_from_yaw(pose.yaw))

    def normalised(self) -> RigidTransform:
        return RigidTransform(self.translation, _normalised(self.rotation))

    def compose(self, other: RigidTransform) -> RigidTransform:
        """``self * other``: ``other`` (given in self's child frame) expressed in self's parent frame."""
        moved = _rotate(self.rotation, other.translation)
        return RigidTransform(
            (self.translation[0] + moved[0], self.translation[1] + moved[1], self.translation[2] + moved[2]),
            _normalised(quaternion_multiply(self.rotation, other.rotation)),
        )

    def inverse(self) -> RigidTransform:
        x, y, z, w = self.rotation
        conjugate = (-x, -y, -z, w)
        back = _rotate(conjugate, self.translation)
        return RigidTransform((-back[0], -back[1], -back[2]), conjugate)

    def transform_point(self, point: Vec3) -> Vec3:
        moved = _rotate(self.rotation, point)
        return (
            self.translation[0] + moved[0],
            self.translation[1] + moved[1],
            self.translation[2] + moved[2],
        )

    def interpolate(self, other: RigidTransform, fraction: float) -> RigidTransform:
        """Linear in translation, slerp in rotation; ``fraction`` 0 gives self, 1 gives other."""
        return RigidTransform(
            tuple(a + fraction * (b - a) for a, b in zip(self.translation, other.translation, strict=True)),  # type: ignore[arg-type]
            slerp(self.rotation, other.rotation, fraction),
        )

    def yaw_rad(self) -> float:
        """Heading about z, wrapped to [-pi, pi)."""
        return wrap_angle(yaw_from_quaternion(*self.rotation))

    def to_pose2d(self) -> Pose2D:
        """The projection onto the plane: ``(x, y, yaw)``."""
        return Pose2D(self.translation[0], self.translation[1], self.yaw_rad())


@dataclass
class TfIntake:
    """What :meth:`TfBuffer.add_message` did not take as it came: ``refused`` (link, why) and
    ``went_back`` (link, stamp) where the clock went back and the moving links were forgotten."""

    refused: list[tuple[str, str]] = field(default_factory=list)
    went_back: list[tuple[str, float]] = field(default_factory=list)


@dataclass(frozen=True, slots=True)
class StampedTransform:
    """``transform`` maps points in ``child_frame`` to ``parent_frame`` at ``stamp_s`` (0: any time)."""

    parent_frame: str
    child_frame: str
    stamp_s: float
    transform: RigidTransform


@dataclass
class _Link:
    """The link from one child frame up to its parent: static, or a time-ordered history."""

    parent: str
    static: RigidTransform | None = None
    stamps: list[float] = field(default_factory=list)
    transforms: list[RigidTransform] = field(default_factory=list)

    @property
    def is_static(self) -> bool:
        return self.static is not None

    def describe(self, child: str) -> str:
        return f"{self.parent} -> {child}"

    def insert(self, stamp_s: float, transform: RigidTransform, cache_time_s: float) -> None:
        index = bisect.bisect_left(self.stamps, stamp_s)
        if index < len(self.stamps) and abs(self.stamps[index] - stamp_s) <= TIME_EPSILON_S:
            self.transforms[index] = transform  # a repeat of the same instant: the newer message wins
        else:
            self.stamps.insert(index, stamp_s)
            self.transforms.insert(index, transform)
        oldest_kept = bisect.bisect_left(self.stamps, self.stamps[-1] - cache_time_s)
        if oldest_kept:
            del self.stamps[:oldest_kept]
            del self.transforms[:oldest_kept]

    def at(self, time_s: float, child: str) -> RigidTransform:
        if self.static is not None:
            return self.static
        oldest, newest = self.stamps[0], self.stamps[-1]
        if time_s > newest + TIME_EPSILON_S:
            raise ExtrapolationError(
                f"lookup would require extrapolation into the future: requested time {time_s:.6f} s but the "
                f"latest data for {self.describe(child)} is at {newest:.6f} s"
            )
        if time_s < oldest - TIME_EPSILON_S:
            raise ExtrapolationError(
                f"lookup would require extrapolation into the past: requested time {time_s:.6f} s but the "
                f"earliest data for {self.describe(child)} is at {oldest:.6f} s"
            )
        index = bisect.bisect_left(self.stamps, time_s)
        if index < len(self.stamps) and abs(self.stamps[index] - time_s) <= TIME_EPSILON_S:
            return self.transforms[index]
        if index > 0 and abs(self.stamps[index - 1] - time_s) <= TIME_EPSILON_S:
            return self.transforms[index - 1]
        before, after = index - 1, index
        fraction = (time_s - self.stamps[before]) / (self.stamps[after] - self.stamps[before])
        return self.transforms[before].interpolate(self.transforms[after], fraction)


def _frame_name(name: str, role: str) -> str:
    """tf2 ignores a leading slash; an empty name is an error."""
    stripped = frame_name(name)
    if not stripped:
        raise ValueError(f"{role} frame name is empty")
    return stripped


class TfBuffer:
    """Transforms between frames over time; fed by :meth:`set_transform`, read by :meth:`lookup`."""

    def __init__(self, cache_time_s: float = 10.0, time_jump_reset_s: float = 1.0) -> None:
        if not (math.isfinite(cache_time_s) and cache_time_s > 0.0):
            raise ValueError(f"cache_time_s must be a positive number, got {cache_time_s!r}")
        if not (math.isfinite(time_jump_reset_s) and time_jump_reset_s > 0.0):
            raise ValueError(f"time_jump_reset_s must be a positive number, got {time_jump_reset_s!r}")
        self.cache_time_s = cache_time_s
        self.time_jump_reset_s = time_jump_reset_s
        self._links: dict[str, _Link] = {}  # keyed by child frame

    # --- feeding ---------------------------------------------------------------------------------

    def set_transform(
        self,
        parent_frame: str,
        child_frame: str,
        stamp_s: float,
        transform: RigidTransform,
        *,
        static: bool = False,
    ) -> bool:
        """Add one transform (``parent -> child`` at ``stamp_s``). Returns True if it reset the dynamic history.

        Raises ``ValueError`` for an empty or self-referencing frame name, a non-finite value or a
        rotation of zero length. A child given a new parent forgets its old link (the newest wins).
        """
        parent = _frame_name(parent_frame, "parent")
        child = _frame_name(child_frame, "child")
        if parent == child:
            raise ValueError(f"transform from {parent} to itself")
        values = (stamp_s, *transform.translation, *transform.rotation)
        if not all(math.isfinite(v) for v in values):
            raise ValueError(f"transform {parent} -> {child} has a non-finite stamp or value")
        transform = transform.normalised()
        link = self._links.get(child)
        if static:
            self._links[child] = _Link(parent, static=transform)
            return False
        reset = False
        if link is not None and not link.is_static and link.parent == parent and link.stamps:
            if stamp_s < link.stamps[-1] - self.time_jump_reset_s:
                self.clear_dynamic()
                reset = True
            elif stamp_s < link.stamps[-1] - self.cache_time_s:
                return False  # older than anything kept: nothing to interpolate with
        link = self._links.get(child)
        if link is None or link.is_static or link.parent != parent:
            link = self._links[child] = _Link(parent)
        link.insert(stamp_s, transform, self.cache_time_s)
        return reset

    def add_message(self, msg: TFMessage, *, static: bool) -> TfIntake:
        """Every transform of a ``tf`` (or, ``static``, ``tf_static``) message; what was refused and why, and
        the links whose stamps went back in time (the dynamic history was cleared)."""
        intake = TfIntake()
        for item in msg.transforms:
            link = f"{item.header.frame_id} -> {item.child_frame_id}"
            t, q = item.transform.translation, item.transform.rotation
            stamp_s = item.header.stamp.to_sec()
            try:
                reset = self.set_transform(
                    item.header.frame_id,
                    item.child_frame_id,
                    stamp_s,
                    RigidTransform((t.x, t.y, t.z), (q.x, q.y, q.z, q.w)),
                    static=static,
                )
            except ValueError as exc:
                intake.refused.append((link, str(exc)))
                continue
            if reset:
                intake.went_back.append((link, stamp_s))
        return intake

    def clear_dynamic(self) -> None:
        """Forget every dynamic link (static links stay)."""
        self._links = {child: link for child, link in self._links.items() if link.is_static}

    def clear(self) -> None:
        self._links.clear()

    # --- reading ---------------------------------------------------------------------------------

    def frames(self) -> set[str]:
        """Every frame some transform names, as parent or child."""
        return set(self._links) | {link.parent for link in self._links.values()}

    def parent_of(self, frame: str) -> str | None:
        link = self._links.get(frame)
        return link.parent if link is not None else None

    def can_transform(self, target_frame: str, source_frame: str, time_s: float | None = None) -> bool:
        try:
            self.lookup(target_frame, source_frame, time_s)
        except TransformError:
            return False
        return True

    def latest_common_time(self, target_frame: str, source_frame: str) -> float:
        """The newest time every dynamic link between the two frames has data for (0 if all are static)."""
        up_from_source, up_from_target = self._path(target_frame, source_frame)
        return self._latest_common_time(up_from_source + up_from_target)

    def lookup(self, target_frame: str, source_frame: str, time_s: float | None = None) -> StampedTransform:
        """The transform taking points in ``source_frame`` to ``target_frame``: ``source``'s pose in ``target``.

        ``time_s=None`` uses the latest common time. Raises :class:`FrameNotFoundError`,
        :class:`ConnectivityError` or :class:`ExtrapolationError`.
        """
        target = _frame_name(target_frame, "target")
        source = _frame_name(source_frame, "source")
        up_from_source, up_from_target = self._path(target, source)
        if time_s is None:
            time_s = self._latest_common_time(up_from_source + up_from_target)
        ancestor_from_source = self._compose_up(up_from_source, time_s)
        ancestor_from_target = self._compose_up(up_from_target, time_s)
        return StampedTransform(
            target, source, time_s, ancestor_from_target.inverse().compose(ancestor_from_source)
        )

    # --- internals -------------------------------------------------------------------------------

    def _chain(self, frame: str) -> list[str]:
        """``frame`` and its ancestors, up to the root of its tree."""
        chain = [frame]
        seen = {frame}
        link = self._links.get(frame)
        while link is not None:
            if link.parent in seen:
                raise ConnectivityError(
                    f"the frame tree has a loop through {link.parent}: {' -> '.join(chain)}"
                )
            chain.append(link.parent)
            seen.add(link.parent)
            link = self._links.get(link.parent)
        return chain

    def _path(self, target: str, source: str) -> tuple[list[str], list[str]]:
        """The child frames whose links lead from ``source`` and from ``target`` up to their common ancestor."""
        if target == source:  # identity, known frame or not (as tf2)
            return [], []
        known = self.frames()
        for frame in (target, source):
            if frame not in known:
                listed = ", ".join(sorted(known)) or "none yet"
                raise FrameNotFoundError(f"frame '{frame}' does not exist (known frames: {listed})")
        source_chain = self._chain(source)
        target_chain = self._chain(target)
        in_target_chain = {frame: index for index, frame in enumerate(target_chain)}
        for index, frame in enumerate(source_chain):
            if frame in in_target_chain:
                return source_chain[:index], target_chain[: in_target_chain[frame]]
        raise ConnectivityError(
            f"'{target}' and '{source}' are not connected: {source}'s tree ends at '{source_chain[-1]}' and "
            f"{target}'s at '{target_chain[-1]}' (no transform gives either root a parent)"
        )

    def _latest_common_time(self, children: list[str]) -> float:
        newest = [self._links[child].stamps[-1] for child in children if not self._links[child].is_static]
        return min(newest) if newest else 0.0

    def _compose_up(self, children: list[str], time_s: float) -> RigidTransform:
        """``ancestor <- ... <- children[0]`` at ``time_s``: children listed from the bottom up."""
        result = RigidTransform()
        for child in children:
            result = self._links[child].at(time_s, child).compose(result)
        return result


def rigid3_between(frames: TfBuffer, target_frame: str, source_frame: str) -> Rigid3 | None:
    """``target <- source`` at the latest common time as a :class:`~shared.rigid3.Rigid3` (numpy, for
    projections: a camera's mount on base_link), or None while the buffer cannot tell it."""
    try:
        found = frames.lookup(target_frame, source_frame).transform
    except (TransformError, ValueError):
        return None
    return Rigid3.from_parts(found.translation, found.rotation)
