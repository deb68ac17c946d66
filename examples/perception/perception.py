"""A dock detector for a zendock stack, written from zendock's contracts alone (see ``../wire.py`` and
docs/contracts/perception.md).

It takes the place of ``python -m services.perception``:

- subscribes ``<ns>/camera/camera_info`` (the pinhole's K), ``<ns>/tf_static`` (base_link -> camera_link ->
  camera_optical_frame) and ``<ns>/camera/image_raw`` (mono8);
- finds the docks' ArUco markers in each image (OpenCV's ``ArucoDetector``, the world's dictionary),
  solves each marker's pose with IPPE (``solvePnPGeneric``, which gives both poses a flat square admits:
  mirror images about the line of sight) and keeps one that stands upright, as a marker on a dock's
  vertical face does; of two upright ones, the one whose heading is nearer the dock database's heading
  seen from the robot (``map_to_base_link_pose2d``, while it comes), else the better fit;
- turns the marker's pose into the dock pose (the docked base_link pose: 0.20 m behind the marker's face,
  facing it) and publishes, stamped with the image, the nearest dock on ``detected_dock_pose`` and every
  dock seen on ``dock_detections``, both in base_link.

Run:  python examples/perception/perception.py -p dock_database=<world.yaml> [--connect ENDPOINT]
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import cv2
import numpy as np
import yaml

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # the examples' wire.py

from wire import BadMessage, Msg, Node, get, header, parse_options, pose_msg, seconds_of

#: The marker's face is this far ahead of the dock pose (the robot's front, half its 0.40 m length).
MARKER_AHEAD_M = 0.20
#: A solution whose face leans further than this from vertical is not a marker on a dock's face.
MAX_LEAN_RAD = math.radians(25.0)
#: The robot's pose settles the mirror ambiguity for a frame taken at most this long after it came (s). Judged
#: against the frame's stamp, not the clock: every callback holds the node's lock, so on a loaded machine a
#: pose waits behind the images before it, and by the clock it looked stale while it was the frame's own.
POSE_FRESH_S = 1.0


def wrap(angle: float) -> float:
    return math.atan2(math.sin(angle), math.cos(angle))


def rotation_of(q: Msg) -> np.ndarray:
    """The 3x3 rotation of a geometry_msgs/Quaternion map."""
    x, y, z, w = (get(q, c, float) for c in "xyzw")
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def matrix_of(transform: Msg) -> np.ndarray:
    """The 4x4 matrix of a geometry_msgs/Transform map."""
    m = np.eye(4)
    m[:3, :3] = rotation_of(get(transform, "rotation", dict))
    m[:3, 3] = [get(transform, f"translation.{c}", float) for c in "xyz"]
    return m


class Docks:
    """The world file's docks by marker id (id, marker size), their map poses by id, the marker dictionary."""

    def __init__(self, path: str) -> None:
        world = yaml.safe_load(Path(path).read_text(encoding="utf-8"))
        self.dictionary = world.get("aruco_dictionary", "DICT_4X4_50")
        self.by_marker: dict[int, tuple[str, float]] = {}
        self.poses: dict[str, tuple[float, float, float]] = {}
        for index, dock in enumerate(world.get("docks", [])):
            x, y, yaw = (float(v) for v in dock["pose"])
            self.poses[str(dock["id"])] = (x, y, yaw)
            marker_id = dock.get("marker_id")
            self.by_marker[index if marker_id is None else int(marker_id)] = (
                str(dock["id"]),
                float(dock.get("marker_size_m", 0.12)),
            )


class Perception:
    def __init__(self, node: Node) -> None:
        self.node = node
        path = node.params.get("dock_database")
        if not path:
            raise SystemExit("perception: -p dock_database=<world.yaml> is required")
        self.docks = Docks(str(path))
        dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, self.docks.dictionary))
        parameters = cv2.aruco.DetectorParameters()
        # corners from the fitted contour: sub-pixel refinement pulls a small, far marker's corners
        # inwards (3 m away it reads 5 % too far); the contour's lines do not
        parameters.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_CONTOUR
        self.detector = cv2.aruco.ArucoDetector(dictionary, parameters)
        self.camera_matrix: np.ndarray | None = None
        self.mounts: dict[str, tuple[str, np.ndarray]] = {}  # child -> (parent, parent_from_child)
        self.robot: tuple[float, float, float, float] | None = None  # x, y, yaw in the map; when (node clock)
        self.detected = node.publisher("detected_dock_pose", "geometry_msgs/msg/PoseStamped", reliable=False)
        self.detections = node.publisher("dock_detections", "zendock_msgs/msg/DockDetection")
        node.subscribe("camera/camera_info", "sensor_msgs/msg/CameraInfo", self.on_camera_info)
        node.subscribe("tf_static", "tf2_msgs/msg/TFMessage", self.on_tf_static)
        node.subscribe("camera/image_raw", "sensor_msgs/msg/Image", self.on_image)
        node.subscribe("map_to_base_link_pose2d", "std_msgs/msg/Float64MultiArray", self.on_robot_pose)

    # --- inputs ---------------------------------------------------------------------------------------

    def on_camera_info(self, msg: Msg) -> None:
        k = get(msg, "k", list)
        if len(k) != 9:
            raise BadMessage(f"camera_info k has {len(k)} numbers, expected 9")
        self.camera_matrix = np.array(k, dtype=np.float64).reshape(3, 3)

    def on_robot_pose(self, msg: Msg) -> None:
        data = get(msg, "data", list)
        if len(data) < 3 or not all(isinstance(v, (int, float)) and math.isfinite(v) for v in data[:3]):
            raise BadMessage("map_to_base_link_pose2d: data is not [x, y, yaw]")
        self.robot = (float(data[0]), float(data[1]), float(data[2]), self.node.now())

    def expected_heading(self, dock_id: str, frame_s: float) -> float | None:
        """The database's heading of the dock in base_link, from a robot pose fresh for a frame taken at
        ``frame_s``, or None."""
        now = frame_s if self.node.use_sim_time else self.node.now()  # stamps are on the simulator's clock
        if self.robot is None or now - self.robot[3] > POSE_FRESH_S:
            return None
        return wrap(self.docks.poses[dock_id][2] - self.robot[2])

    def on_tf_static(self, msg: Msg) -> None:
        for item in get(msg, "transforms", list):
            parent = get(item, "header.frame_id", str).lstrip("/")
            child = get(item, "child_frame_id", str).lstrip("/")
            self.mounts[child] = (parent, matrix_of(get(item, "transform", dict)))

    def base_from(self, frame: str) -> np.ndarray | None:
        """base_link <- ``frame`` through the static mounts, or None while they are not all known."""
        m = np.eye(4)
        for _ in range(8):
            if frame == "base_link":
                return m
            if frame not in self.mounts:
                return None
            frame, parent_from_child = self.mounts[frame]
            m = parent_from_child @ m
        return None

    def on_image(self, msg: Msg) -> None:
        if self.camera_matrix is None or get(msg, "encoding", str) != "mono8":
            return
        frame = get(msg, "header.frame_id", str).lstrip("/")
        base_from_camera = self.base_from(frame)
        if base_from_camera is None:
            return
        height, width = get(msg, "height", int), get(msg, "width", int)
        data = msg["data"]
        pixels = np.frombuffer(bytes(data) if isinstance(data, list) else data, dtype=np.uint8)
        if pixels.size != height * width:
            raise BadMessage(f"image of {pixels.size} bytes, expected {height}x{width}")
        corners, ids, _rejected = self.detector.detectMarkers(pixels.reshape(height, width))
        if ids is None:
            return
        frame_s = seconds_of(get(msg, "header.stamp", dict))
        found = []
        for marker_corners, marker_id in zip(corners, ids.ravel(), strict=True):
            dock = self.docks.by_marker.get(int(marker_id))
            if dock is None:
                continue
            seen = self.dock_pose(
                marker_corners.reshape(4, 2), dock[1], base_from_camera, self.expected_heading(dock[0], frame_s)
            )
            if seen is not None:
                found.append((dock[0], int(marker_id), *seen))
        if not found:
            return
        stamp = header(frame_s, "base_link")
        found.sort(key=lambda f: f[4])  # nearest first
        dock_id, _marker, (x, y, yaw), _error, _range = found[0]
        self.detected.publish({"header": stamp, "pose": pose_msg(x, y, yaw)})
        for dock_id, marker_id, (x, y, yaw), error_px, range_m in found:
            self.detections.publish(
                {
                    "header": stamp,
                    "dock_id": dock_id,
                    "marker_id": marker_id,
                    "pose": pose_msg(x, y, yaw),
                    "reprojection_error_px": error_px,
                    "marker_range_m": range_m,
                }
            )

    # --- from corners to the dock --------------------------------------------------------------------------

    def dock_pose(
        self, corners: np.ndarray, size_m: float, base_from_camera: np.ndarray, expected: float | None
    ) -> tuple[tuple[float, float, float], float, float] | None:
        """``((x, y, yaw) of the dock in base_link, reprojection error px, camera-to-marker m)`` from the
        marker's corners, or None when no solution stands upright. ``expected``: the dock's heading in
        base_link the database gives (None: unknown)."""
        half = size_m / 2.0
        square = np.array([[-half, half, 0.0], [half, half, 0.0], [half, -half, 0.0], [-half, -half, 0.0]])
        count, rvecs, tvecs, errors = cv2.solvePnPGeneric(
            square, corners.astype(np.float64), self.camera_matrix, None, flags=cv2.SOLVEPNP_IPPE_SQUARE
        )
        upright = []
        for i in range(count):
            camera_from_marker = np.eye(4)
            camera_from_marker[:3, :3] = cv2.Rodrigues(rvecs[i])[0]
            camera_from_marker[:3, 3] = tvecs[i].ravel()
            base_from_marker = base_from_camera @ camera_from_marker
            normal, up = base_from_marker[:3, 2], base_from_marker[:3, 1]
            lean = math.asin(min(1.0, abs(normal[2])))
            if lean > MAX_LEAN_RAD or up[2] < math.cos(MAX_LEAN_RAD):
                continue  # lying down or upside down: not a marker on a dock's face
            facing = math.atan2(normal[1], normal[0])  # out of the dock's face, towards the robot
            dock_yaw = wrap(facing + math.pi)
            x = base_from_marker[0, 3] - MARKER_AHEAD_M * math.cos(dock_yaw)
            y = base_from_marker[1, 3] - MARKER_AHEAD_M * math.sin(dock_yaw)
            error_px = float(np.ravel(errors)[i]) if errors is not None else 0.0
            upright.append(((x, y, dock_yaw), error_px, float(np.linalg.norm(tvecs[i]))))
        if not upright:
            return None
        if expected is not None:  # the mirror ambiguity: the database's heading settles it
            return min(upright, key=lambda u: abs(wrap(u[0][2] - expected)))
        return min(upright, key=lambda u: u[1])  # the better fit


def main() -> int:
    options = parse_options("perception", __doc__ or "")
    node = Node(options)
    Perception(node)
    node.declare_ready()
    return node.run(0.5, lambda: None)


if __name__ == "__main__":
    sys.exit(main())
