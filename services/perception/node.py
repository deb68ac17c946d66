"""The perception service: camera images in, dock poses out.

Subscribes to ``camera/image_raw``, ``camera/camera_info`` and ``tf_static`` (where the camera's optical
frame sits on base_link); finds ArUco markers and turns each known one into its dock's pose in base_link
(:mod:`services.perception.markers`). The robot's pose (``map_to_base_link_pose2d``), while it comes, puts
the dock database's heading in base_link, which settles a marker's mirror ambiguity: a small, far marker
seen from the side fits both headings about equally well, and sometimes the wrong one better. The
nearest dock seen goes out on ``detected_dock_pose`` (geometry_msgs/PoseStamped in base_link, stamped
with the image's time: what the docking service consumes), and every dock seen on ``dock_detections``
with its id and fit. ``aruco/debug_image`` (the
frame with the markers and their axes drawn) is drawn only while someone subscribes.

Frames the detector cannot use (bad encoding or size, no calibration yet, no camera mount yet), markers
not in the dock database and markers no upright pose explains are counted and logged at most once per
interval per kind; nothing that arrives stops the service. Images queue one deep: when detection is
slower than the camera, the newest frame is the one processed.
"""

from __future__ import annotations

import math
import time
from collections import Counter
from typing import Annotated

import cv2
import numpy as np
from msgspec import Meta

from services.perception.images import ImageError, grey_pixels
from services.perception.markers import DockSighting, MarkerFinder, MarkerSighting, locate_dock
from services.perception.search_regions import SearchRegions
from shared import topics
from shared.controllers import DETECTORS, DetectorName
from shared.geometry import Pose2D
from shared.messages import (
    CameraInfo,
    DockDetection,
    Float64MultiArray,
    Header,
    Image,
    Pose,
    PoseStamped,
    TFMessage,
)
from shared.node import RELIABLE, SENSOR_DATA, Node, QoS, Subscription
from shared.parameters import ServiceParams
from shared.ratelimit import RateLimitedLogger
from shared.rigid3 import Rigid3
from shared.runtime import ServiceSpec
from shared.tf_buffer import TfBuffer, rigid3_between
from shared.world import ROBOT_FRONT_M, DockMarker, dock_markers, load_world

#: Images: the newest only (a late frame is worth less than the next one).
IMAGE_QOS = QoS(reliable=False, block=False, depth=1)
STATS_PERIOD_S = 30.0
#: A marker's last pose helps choose between ambiguous fits for this long (image stamps, s).
CONTINUITY_S = 0.5
#: The robot's pose settles ambiguous fits with the dock database's heading while it is this fresh (wall, s).
ROBOT_POSE_FRESH_S = 1.0
#: The marker's pose in the dock pose's frame: on the dock's face, facing the docked robot.
_MARKER_ON_DOCK = Pose2D(ROBOT_FRONT_M, 0.0, math.pi)


class Params(ServiceParams):
    """Parameters of ``python -m services.perception``."""

    dock_database: Annotated[
        str, Meta(description="dock database or world file: docks with their marker ids and sizes")
    ]
    max_range_m: Annotated[float, Meta(gt=0, description="markers farther than this are not reported")] = 3.5
    max_reprojection_error_px: Annotated[
        float, Meta(gt=0, description="fits worse than this are refused")
    ] = 2.0
    dock_detector: Annotated[
        DetectorName,
        Meta(description="synthetic: the simulator reports docks itself and this service stays idle"),
    ] = "aruco"
    opencv_threads: Annotated[
        int,
        Meta(
            ge=0,
            description="threads OpenCV may use (0: one per core); one is cheaper where the cores are "
            "busy (measurement 62)",
        ),
    ] = 1


class PerceptionService:
    def __init__(self, node: Node, params: Params) -> None:
        self.node = node
        self.params = params
        self._say = RateLimitedLogger(node.log, interval_s=5.0)
        world = load_world(params.dock_database)
        self.markers: dict[int, DockMarker] = {m.marker_id: m for m in dock_markers(world)}
        cv2.setNumThreads(params.opencv_threads or -1)  # -1: OpenCV's default
        self.finder = MarkerFinder(world.aruco_dictionary)
        self.search = SearchRegions()
        #: The camera's mount: the static links ``tf_static`` gives (the same buffer the pose service keeps).
        self.frames = TfBuffer()
        self._camera_matrix: np.ndarray | None = None
        self._distortion = np.zeros(5)
        self.counts: Counter[str] = Counter()
        #: Each marker's last dock pose in base_link and its image stamp: what an ambiguous fit continues.
        self._previous: dict[int, tuple[float, Pose2D]] = {}
        #: The docks' database poses (map) by id, and the robot's latest map pose with when it came (monotonic).
        self._dock_poses = {dock.id: dock.pose2d for dock in world.docks}
        self._robot: tuple[float, Pose2D] | None = None
        self._stats_at = time.monotonic()
        self.detected_pub = node.create_publisher(PoseStamped, topics.DETECTED_DOCK_POSE, SENSOR_DATA)
        self.detections_pub = node.create_publisher(DockDetection, topics.DOCK_DETECTIONS, RELIABLE)
        self.debug_pub = node.create_publisher(Image, topics.ARUCO_DEBUG_IMAGE, IMAGE_QOS)
        node.create_subscription(
            CameraInfo, topics.CAMERA_INFO, self._on_camera_info, QoS(reliable=False, depth=1)
        )
        node.create_subscription(TFMessage, topics.TF_STATIC, self._on_tf_static, QoS(depth=20))
        node.create_subscription(Float64MultiArray, topics.POSE2D, self._on_robot_pose, QoS(depth=1))
        #: Images are read only while someone wants what comes of them (Zenoh's matching status on this
        #: service's outputs), so the simulator renders no frame that nobody uses. The demand is followed
        #: as Zenoh reports each change: a poll, however often, let frames through after the docking
        #: service had let go of its detections (measurement 66).
        self._image_sub: Subscription[Image] | None = None
        if DETECTORS[params.dock_detector].camera:
            for pub in (self.detected_pub, self.detections_pub, self.debug_pub):
                pub.on_matching_change(lambda _matching: node.post(self._follow_demand))
            self._follow_demand()
        else:
            node.log.info(
                "dock_detector is %s: the simulator reports docks, this service stays idle",
                params.dock_detector,
            )
        node.log.info(
            "%d dock marker(s) (%s) from %s", len(self.markers), world.aruco_dictionary, params.dock_database
        )

    def _follow_demand(self) -> None:
        wanted = any(
            pub.has_subscribers() for pub in (self.detected_pub, self.detections_pub, self.debug_pub)
        )
        if wanted and self._image_sub is None:
            self._image_sub = self.node.create_subscription(
                Image, topics.CAMERA_IMAGE, self._on_image, IMAGE_QOS
            )
            self.node.log.info("someone wants dock detections: reading %s", topics.CAMERA_IMAGE)
        elif not wanted and self._image_sub is not None:
            self._image_sub.undeclare()
            self._image_sub = None
            self.node.log.info(
                "no one wants dock detections: no longer reading images; frames so far %s",
                dict(sorted(self.counts.items())),
            )

    # --- inputs --------------------------------------------------------------------------------------

    def _on_camera_info(self, msg: CameraInfo) -> None:
        K = np.asarray(msg.k, dtype=np.float64).reshape(3, 3) if msg.k.size == 9 else None
        if K is None or not np.all(np.isfinite(K)) or K[0, 0] <= 0 or K[1, 1] <= 0 or K[2, 2] != 1.0:
            self._refuse("camera-info", "ignored camera_info with an unusable K %s", list(msg.k))
            return
        if msg.distortion_model not in ("", "plumb_bob", "rational_polynomial") or not np.all(
            np.isfinite(msg.d)
        ):
            self._refuse("camera-info", "ignored camera_info with distortion model %r", msg.distortion_model)
            return
        self._camera_matrix = K
        self._distortion = np.asarray(msg.d, dtype=np.float64) if msg.d.size else np.zeros(5)

    def _on_robot_pose(self, msg: Float64MultiArray) -> None:
        data = msg.data
        if len(data) < 3 or not all(math.isfinite(float(v)) for v in data[:3]):
            self._refuse(
                "robot-pose", "ignored a map_to_base_link_pose2d that is not [x, y, yaw]: %s", list(data)
            )
            return
        self._robot = (time.monotonic(), Pose2D(float(data[0]), float(data[1]), float(data[2])))

    def _expected(self, dock_id: str) -> Pose2D | None:
        """The dock database's pose of ``dock_id`` in base_link, from a fresh robot pose, else None."""
        dock = self._dock_poses.get(dock_id)
        if self._robot is None or dock is None or time.monotonic() - self._robot[0] > ROBOT_POSE_FRESH_S:
            return None
        return dock.relative_to(self._robot[1])

    def _on_tf_static(self, msg: TFMessage) -> None:
        for link, why in self.frames.add_message(msg, static=True).refused:
            self._refuse("tf", "ignored a tf_static entry %s: %s", link, why)

    def _on_image(self, msg: Image) -> None:
        self.counts["frames"] += 1
        try:
            grey = grey_pixels(msg)
        except ImageError as exc:
            self._refuse(f"image-{exc.reason}", "ignored an image: %s", exc)
            return
        if self._camera_matrix is None:
            self._refuse("no-camera-info", "no camera_info yet: images wait for the calibration")
            return
        base_from_camera = rigid3_between(self.frames, topics.BASE_FRAME, msg.header.frame_id)
        if base_from_camera is None:
            self._refuse(
                "no-mount", "no tf_static chain from %s to %s yet", msg.header.frame_id, topics.BASE_FRAME
            )
            return
        stamp_s = msg.header.stamp.to_sec()
        sightings = self._find(grey, stamp_s)
        found = self._locate(sightings, base_from_camera, stamp_s)
        self._publish(msg.header, found)
        if self.debug_pub.has_subscribers():
            self._publish_debug(msg.header, grey, sightings, found, base_from_camera)
        self._report_stats()

    # --- work ----------------------------------------------------------------------------------------

    def _find(self, grey: np.ndarray, stamp_s: float) -> list[MarkerSighting]:
        """Markers near where they were in the last frame, else (or when one is missing) in the whole frame."""
        boxes = self.search.boxes(stamp_s, grey.shape[1], grey.shape[0])
        if boxes is not None:
            sightings = self.finder.find(grey, boxes)
            if self.search.complete(sightings):
                self.counts["searched-boxes"] += 1
                self.search.update(sightings, stamp_s, whole_frame=False)
                return sightings
            self.counts["box-missed"] += 1
        sightings = self.finder.find(grey)
        self.search.update(sightings, stamp_s, whole_frame=True)
        return sightings

    def _locate(
        self, sightings: list[MarkerSighting], base_from_camera: Rigid3, stamp_s: float
    ) -> list[DockSighting]:
        assert self._camera_matrix is not None
        found = []
        for sighting in sightings:
            marker = self.markers.get(sighting.marker_id)
            if marker is None:
                self._refuse(
                    "unknown-marker",
                    "marker %d is not in the dock database (known: %s)",
                    sighting.marker_id,
                    sorted(self.markers),
                )
                continue
            last = self._previous.get(sighting.marker_id)
            previous = last[1] if last is not None and 0.0 <= stamp_s - last[0] <= CONTINUITY_S else None
            dock = locate_dock(
                sighting,
                marker,
                self._camera_matrix,
                self._distortion,
                base_from_camera,
                previous,
                self._expected(marker.dock_id),
            )
            if dock is None:
                self._refuse("not-upright", "marker %d: no upright pose fits its corners", sighting.marker_id)
                continue
            if dock.reprojection_error_px > self.params.max_reprojection_error_px:
                self._refuse(
                    "poor-fit", "marker %d: fit error %.2f px", sighting.marker_id, dock.reprojection_error_px
                )
                continue
            if dock.marker_range_m > self.params.max_range_m:
                self.counts["too-far"] += 1
                continue
            self._previous[sighting.marker_id] = (stamp_s, dock.dock_in_base)
            found.append(dock)
        found.sort(key=lambda d: d.marker_range_m)
        return found

    def _publish(self, header: Header, found: list[DockSighting]) -> None:
        if not found:
            self.counts["no-marker"] += 1
            return
        self.counts["detected"] += 1
        out_header = Header(header.stamp, topics.BASE_FRAME)
        self.detected_pub.publish(PoseStamped(out_header, Pose.from_pose2d(found[0].dock_in_base)))
        for dock in found:
            self.detections_pub.publish(
                DockDetection(
                    out_header,
                    dock.dock_id,
                    dock.marker_id,
                    Pose.from_pose2d(dock.dock_in_base),
                    dock.reprojection_error_px,
                    dock.marker_range_m,
                )
            )

    def _publish_debug(
        self,
        header: Header,
        grey: np.ndarray,
        sightings: list[MarkerSighting],
        found: list[DockSighting],
        base_from_camera: Rigid3,
    ) -> None:
        assert self._camera_matrix is not None
        canvas = cv2.cvtColor(grey, cv2.COLOR_GRAY2RGB)
        if sightings:
            corners = [s.corners.reshape(1, 4, 2).astype(np.float32) for s in sightings]
            ids = np.array([[s.marker_id] for s in sightings], dtype=np.int32)
            cv2.aruco.drawDetectedMarkers(canvas, corners, ids, borderColor=(0, 255, 0))
        for dock in found:
            marker = self.markers[dock.marker_id]
            # The marker's frame from the dock pose, drawn back into the image: what perception believes.
            pose = dock.dock_in_base.compose(_MARKER_ON_DOCK)
            camera_from_base = _invert(base_from_camera)
            rotation = np.array(
                [
                    [-np.sin(pose.yaw), 0.0, np.cos(pose.yaw)],
                    [np.cos(pose.yaw), 0.0, np.sin(pose.yaw)],
                    [0.0, 1.0, 0.0],
                ]
            )
            marker_in_camera = camera_from_base.compose(
                Rigid3(rotation, np.array([pose.x, pose.y, marker.centre_height_m]))
            )
            rvec, _ = cv2.Rodrigues(marker_in_camera.rotation)
            cv2.drawFrameAxes(
                canvas,
                self._camera_matrix,
                self._distortion,
                rvec,
                marker_in_camera.translation,
                marker.size_m * 0.75,
                2,
            )
        height, width = grey.shape
        self.debug_pub.publish(Image(header, height, width, "rgb8", 0, width * 3, canvas.reshape(-1)))

    def _refuse(self, kind: str, fmt: str, *args: object) -> None:
        self.counts[kind] += 1
        self._say.warning(kind, fmt, *args)

    def _report_stats(self) -> None:
        now = time.monotonic()
        if now - self._stats_at < STATS_PERIOD_S:
            return
        self._stats_at = now
        self.node.log.info("frames %s", dict(sorted(self.counts.items())))

    def close(self) -> None:
        self.node.log.info("frames %s", dict(sorted(self.counts.items())))


def _invert(t: Rigid3) -> Rigid3:
    return Rigid3(t.rotation.T, -t.rotation.T @ t.translation)


SERVICE = ServiceSpec(
    "perception",
    Params,
    PerceptionService,
    description="zendock perception: ArUco markers in camera images -> dock poses",
)


def main(argv: list[str] | None = None) -> int:
    return SERVICE.run(argv)
