"""A docking service for a zendock stack, written from zendock's contracts alone (see ``../wire.py``).

It takes the place of ``python -m services.docking``: it serves the ``dock_robot`` and ``undock_robot``
actions (opennav_docking_msgs DockRobot / UndockRobot) and, like zendock's, starts docking by itself when
``battery_status`` falls below ``low_battery_threshold`` (that is what ``zendock demo`` waits for).

A docking run: find the dock (``dock_id`` in the dock database, the world file given as
``-p dock_database=...``, or the goal's ``dock_pose``), have the planner drive to a staging pose
``staging_offset_m`` in front of it (a ``navigate_to_pose`` goal), then drive the last stretch itself on
``cmd_vel``, steering onto the dock's axis from ``map_to_base_link_pose2d`` and the dock pose refined by
``detected_dock_pose``, slower as it nears the dock, until ``battery_status`` says CHARGING (or FULL), as
a real robot would know it. ``-p use_dock_contact=true`` also stops on the simulator's ground truth
``dock_contact`` (mated), which zendock's docking contract does not list. A run that stalls against the
dock backs off and tries again.

Run:  python examples/docking/docking.py -p use_sim_time=true -p dock_database=deploy/worlds/seed_room.yaml
"""

from __future__ import annotations

import math
import re
import sys
from collections import deque
from dataclasses import dataclass
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # the examples' wire.py

from wire import (
    ABORTED,
    CANCELED,
    SUCCEEDED,
    ActionClient,
    ActionServer,
    BadMessage,
    GoalHandle,
    Msg,
    Node,
    exact_fields,
    get,
    header,
    parse_options,
    planar_pose,
    pose_msg,
    seconds_of,
    time_msg,
    twist_msg,
)

Pose = tuple[float, float, float]  # x, y, yaw in the map frame
CONTROL_PERIOD_S = 0.05
#: DockRobot result error codes and feedback states (opennav_docking_msgs).
DOCK_NOT_IN_DB, DOCK_NOT_VALID, FAILED_TO_STAGE, FAILED_TO_CONTROL, TIMEOUT = 901, 902, 903, 905, 907
NAV_TO_STAGING_POSE, CONTROLLING, RETRY = 1, 3, 5
CHARGING_STATUSES = (1, 4)  # sensor_msgs/BatteryState CHARGING, FULL
#: The approach: steer at a point this far ahead on the dock's axis (pure pursuit of a line); shorter
#: corrects a sideways offset sooner but swings more. The mated contacts allow 4 cm and 0.1 rad.
LOOKAHEAD_M = 0.25
MAX_SPEED_MPS, MIN_SPEED_MPS, SLOW_DOWN_PER_S = 0.3, 0.04, 0.6
#: The approach takes over from the planner this close to the staging pose, heading roughly at the dock:
#: waiting for the planner to stop and turn on the staging pose costs seconds and gains nothing.
HANDOVER_M, HANDOVER_HEADING_RAD = 0.3, 0.8
TURN_GAIN, MAX_TURN_RADPS = 2.5, 1.0
BACK_OFF_SPEED_MPS = 0.15
#: Older poses hold the robot still; older battery or contact messages say nothing.
MAX_POSE_AGE_S, MAX_STATUS_AGE_S = 0.5, 1.0
#: No centimetre of progress for this long: the robot is stuck against the dock, back off and retry.
STALL_S = 4.0


def fresh(stamp_s: float, now: float, max_age_s: float) -> bool:
    """Heard within ``max_age_s``; a stamp from the future (the clock went back: a simulator reset) is not."""
    return 0.0 <= now - stamp_s <= max_age_s


def wrap(angle: float) -> float:
    return math.atan2(math.sin(angle), math.cos(angle))


def compose(a: Pose, b: Pose) -> Pose:
    """Pose ``b`` (given in the frame of ``a``) in ``a``'s parent frame."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], wrap(a[2] + b[2])


def in_dock_frame(robot: Pose, dock: Pose) -> Pose:
    """The robot in the dock pose's frame: x along the dock's axis (negative while short of it), y sideways."""
    c, s = math.cos(dock[2]), math.sin(dock[2])
    dx, dy = robot[0] - dock[0], robot[1] - dock[1]
    return c * dx + s * dy, -s * dx + c * dy, wrap(robot[2] - dock[2])


# --- the dock database: the ``docks`` list of a world file, read without a YAML library -----------------

_TOKEN = re.compile(r"""\s*([\[\]{},]|"[^"]*"|'[^']*'|[^\[\]{},]+)""")


def _scalar(text: str) -> Any:
    text = text.strip()
    if text[:1] in "\"'":
        return text[1:-1]
    try:
        return float(text)
    except ValueError:
        return text


def _flow(text: str) -> Any:
    """A YAML flow value (``{id: home, pose: [1, 2, 0.5]}``, ``[...]`` or a scalar): the subset dock
    entries use, so the example needs nothing beyond the standard library."""
    tokens = [t.strip() for t in _TOKEN.findall(text) if t.strip()]
    pos = 0

    def value() -> Any:
        nonlocal pos
        token = tokens[pos]
        pos += 1
        if token in "[{":
            items: Any = [] if token == "[" else {}
            while tokens[pos] not in "]}":
                if token == "[":
                    items.append(value())
                else:
                    key, _, rest = tokens[pos].partition(":")
                    pos += 1
                    items[key.strip()] = _scalar(rest) if rest.strip() else value()
                if tokens[pos] == ",":
                    pos += 1
            pos += 1
            return items
        return _scalar(token)

    return value()


def read_docks(path: str) -> dict[str, Pose]:
    """``{id: (x, y, yaw)}`` from the ``docks:`` list of a world file or dock database, in flow
    (``- {id: home, pose: [x, y, yaw]}``) or block style (``- id: home`` then ``pose: [...]``).
    A dock pose is base_link's pose when docked: the dock stands straight ahead of it."""
    lines = [re.sub(r"\s+#.*$", "", line.rstrip()) for line in Path(path).read_text().splitlines()]
    entries: list[Any] = []
    inside = False
    for line in lines:
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        if not line[0].isspace() and not line.startswith("-"):  # a top-level key
            inside = line.startswith("docks:")
            if inside and line[6:].strip():
                entries.extend(_flow(line[6:]))
            continue
        if not inside:
            continue
        text = line.strip()
        if text.startswith("- "):
            text = text[2:].strip()
            entries.append(_flow(text) if text.startswith("{") else {})
        if isinstance(entries[-1], dict) and not text.startswith("{"):
            key, _, rest = text.partition(":")
            entries[-1][key.strip()] = _flow(rest)
    docks: dict[str, Pose] = {}
    for i, entry in enumerate(entries):
        pose = entry.get("pose") if isinstance(entry, dict) else None
        if not (isinstance(pose, list) and len(pose) == 3 and all(isinstance(v, float) for v in pose)):
            raise ValueError(f"{path}: docks.{i}: expected {{id, pose: [x, y, yaw]}}, got {entry!r}")
        dock_id = entry.get("id")
        docks[dock_id if isinstance(dock_id, str) else f"{dock_id:g}"] = (pose[0], pose[1], pose[2])
    if not docks:
        raise ValueError(f"{path}: no docks")
    return docks


# --- a run: one docking or undocking, from its goal to its result --------------------------------------


@dataclass
class Run:
    kind: str  # dock | undock
    dock_id: str
    dock: Pose  # the database pose (or the goal's)
    started_s: float
    handle: GoalHandle | None = None  # None: started by the low battery
    server: ActionServer | None = None
    phase: str = "navigating"  # navigating | approaching | backing_off | undocking
    phase_s: float = 0.0
    max_s: float = 600.0  # the whole run
    max_staging_s: float = 1000.0  # the navigation to the staging pose
    nav_goal: bytes | None = None
    retries: int = 0
    best_distance: float = math.inf
    progress_s: float = 0.0
    feedback_s: float = -math.inf
    estimate: Pose | None = None  # the dock refined by detections
    sightings: int = 0


class Docking:
    """The docking service on a node; everything runs under the node's lock (see ``wire.Node``)."""

    def __init__(self, node: Node) -> None:
        self.node = node
        p = node.params
        self.docks = read_docks(str(p["dock_database"]))
        self.staging_offset = float(p.get("staging_offset_m", 0.7))
        self.low_battery = float(p.get("low_battery_threshold", 0.25))
        self.auto_dock = bool(p.get("auto_dock", True))
        self.trigger_dock = str(p.get("dock_id", ""))
        self.use_detection = bool(p.get("use_detection", True))
        self.use_dock_contact = bool(p.get("use_dock_contact", False))
        self.max_retries = int(p.get("max_retries", 3))
        self.max_docking_s = float(p.get("max_docking_time_s", 600.0))
        self.run: Run | None = None
        self.pose: Pose | None = None
        self.pose_s = -math.inf
        self.history: deque[tuple[float, Pose]] = deque(maxlen=40)  # 4 s of poses, for detections' stamps
        self.command = (0.0, 0.0)
        self.odom, self.odom_s = (0.0, 0.0), -math.inf  # measured linear and angular speed
        self.charging_s = self.mated_s = -math.inf
        self.low_latched = False
        self.state, self.state_s = "", -math.inf
        self.detections: Any = None
        self.cmd_vel = node.publisher("cmd_vel", "geometry_msgs/msg/Twist")
        self.state_pub = node.publisher("docking/state", "std_msgs/msg/String")
        self.nav = ActionClient(node, "navigate_to_pose", "nav2_msgs/action/NavigateToPose")
        node.subscribe("map_to_base_link_pose2d", "std_msgs/msg/Float64MultiArray", self.on_pose)
        node.subscribe("battery_status", "sensor_msgs/msg/BatteryState", self.on_battery)
        node.subscribe("odom", "nav_msgs/msg/Odometry", self.on_odom)
        if self.use_dock_contact:
            node.subscribe("dock_contact", "zendock_msgs/msg/DockContact", self.on_contact)
        self.dock_server = ActionServer(node, "dock_robot", "opennav_docking_msgs/action/DockRobot",
                                        on_goal=self.check_dock_goal, on_accepted=self.on_dock_goal,
                                        on_cancel=self.on_cancel, empty_result=lambda: self.dock_result(False, 0))
        self.undock_server = ActionServer(node, "undock_robot", "opennav_docking_msgs/action/UndockRobot",
                                          on_goal=self.check_undock_goal,
                                          on_accepted=self.on_undock_goal, on_cancel=self.on_cancel,
                                          empty_result=lambda: {"success": False, "error_code": 0})
        node.log.info("%d dock(s) from %s: %s", len(self.docks), p["dock_database"], ", ".join(self.docks))

    # --- inputs ------------------------------------------------------------------------------------

    def on_pose(self, msg: Msg) -> None:
        data = get(msg, "data", list)
        if len(data) != 3 or not all(isinstance(v, (int, float)) and math.isfinite(v) for v in data):
            raise BadMessage(f"field 'data': expected [x, y, yaw], got {data!r}")
        self.pose, self.pose_s = (float(data[0]), float(data[1]), float(data[2])), self.node.now()
        self.history.append((self.pose_s, self.pose))

    def on_battery(self, msg: Msg) -> None:
        percentage, charging = get(msg, "percentage", float), get(msg, "power_supply_status", int) in CHARGING_STATUSES
        if charging:
            self.charging_s = self.node.now()
        if charging or percentage >= self.low_battery + 0.02:
            self.low_latched = False
        elif percentage < self.low_battery and not self.low_latched:
            self.low_latched = True  # once per crossing: a canceled run is not started again at the next message
            if self.auto_dock and self.run is None:
                self.node.log.info("battery at %.1f%%: docking", 100 * percentage)
                self.start_dock(self.trigger_dock, None, None, None, 120.0, True)

    def on_odom(self, msg: Msg) -> None:
        self.odom = get(msg, "twist.twist.linear.x", float), get(msg, "twist.twist.angular.z", float)
        self.odom_s = self.node.now()

    def on_contact(self, msg: Msg) -> None:
        if get(msg, "mated", bool):
            self.mated_s = self.node.now()

    def on_detection(self, msg: Msg) -> None:
        """A dock seen from base_link (zendock's detected_dock_pose frame), at its stamp: put it in the map
        with the robot's pose of that moment, and average it into the run's dock estimate."""
        run = self.run
        frame = get(msg, "header.frame_id", str)
        if frame not in ("", "base_link"):
            raise BadMessage(f"detected_dock_pose in frame {frame!r}, expected base_link")
        seen = planar_pose(get(msg, "pose", dict))
        robot = self.pose_at(seconds_of(get(msg, "header.stamp", dict)))
        if run is None or run.phase != "approaching" or robot is None:
            return
        x, y, yaw = compose(robot, seen)
        if math.hypot(x - run.dock[0], y - run.dock[1]) > 0.5:  # another dock, or a wrong detection
            return
        run.sightings += 1
        if run.estimate is None:
            run.estimate = (x, y, yaw)
        else:
            gain = max(1.0 / run.sightings, 0.1)  # a mean at first, then a slow average
            ex, ey, eyaw = run.estimate
            run.estimate = (ex + gain * (x - ex), ey + gain * (y - ey), wrap(eyaw + gain * wrap(yaw - eyaw)))

    def pose_at(self, stamp_s: float) -> Pose | None:
        """The robot's pose at ``stamp_s``, interpolated between the poses heard around it."""
        before = after = None
        for t, pose in self.history:
            if t <= stamp_s:
                before = (t, pose)
            elif after is None:
                after = (t, pose)
        if before is None or after is None:
            return before[1] if before is not None and stamp_s - before[0] < 0.2 else None
        k = (stamp_s - before[0]) / max(after[0] - before[0], 1e-9)
        (ax, ay, ayaw), (bx, by, byaw) = before[1], after[1]
        return ax + k * (bx - ax), ay + k * (by - ay), wrap(ayaw + k * wrap(byaw - ayaw))

    def docked(self, now: float) -> bool:
        return fresh(self.charging_s, now, MAX_STATUS_AGE_S) or fresh(self.mated_s, now, MAX_STATUS_AGE_S)

    # --- goals -------------------------------------------------------------------------------------

    def check_dock_goal(self, goal: Msg) -> None:
        exact_fields(goal, ("use_dock_id", "dock_id", "dock_pose", "dock_type", "max_staging_time",
                            "navigate_to_staging_pose"), "opennav_docking_msgs/action/DockRobot_Goal")
        if not get(goal, "use_dock_id", bool) and get(goal, "dock_pose.header.frame_id", str) not in ("", "map"):
            raise ValueError(f"dock_pose must be in the map frame, got {goal['dock_pose']['header']['frame_id']!r}")
        if not get(goal, "max_staging_time", float) > 0.0:
            raise ValueError("max_staging_time must be > 0")
        planar_pose(get(goal, "dock_pose.pose", dict))
        get(goal, "dock_id", str), get(goal, "dock_type", str), get(goal, "navigate_to_staging_pose", bool)

    @staticmethod
    def check_undock_goal(goal: Msg) -> None:
        exact_fields(goal, ("dock_type", "max_undocking_time"), "opennav_docking_msgs/action/UndockRobot_Goal")
        get(goal, "dock_type", str)
        if not get(goal, "max_undocking_time", float) > 0.0:
            raise ValueError("max_undocking_time must be > 0")

    def on_dock_goal(self, handle: GoalHandle) -> None:
        goal = handle.goal
        use_id = goal["use_dock_id"]
        self.dock_server.set_status(handle, 2)  # EXECUTING
        self.start_dock(goal["dock_id"] if use_id else "", None if use_id else planar_pose(goal["dock_pose"]["pose"]),
                        handle, self.dock_server, goal["max_staging_time"], goal["navigate_to_staging_pose"])

    def start_dock(self, dock_id: str, pose: Pose | None, handle: GoalHandle | None, server: ActionServer | None,
                   max_staging_s: float, navigate: bool) -> None:
        now = self.node.now()
        self.stop_run("preempted by a new goal")
        here = self.pose
        if pose is None and not dock_id and here is not None:  # the nearest dock
            dock_id = min(self.docks, key=lambda d: math.dist(self.docks[d][:2], here[:2]))
        dock_id = dock_id or next(iter(self.docks))
        run = Run("dock", dock_id if pose is None else "(goal pose)", pose or self.docks.get(dock_id, (0, 0, 0)),
                  now, handle, server, phase_s=now, max_s=self.max_docking_s, max_staging_s=max_staging_s)
        self.run = run
        if pose is None and dock_id not in self.docks:
            return self.finish(run, False, DOCK_NOT_IN_DB, f"dock {dock_id!r} is not in {list(self.docks)}")
        if self.docked(now):
            return self.finish(run, True, 0, "already docked")
        self.node.log.info("docking at %s %s", run.dock_id, _fmt(run.dock))
        if navigate and not self.near(self.staging(run.dock), 0.15):
            goal = {"pose": {"header": header(now, "map"), "pose": pose_msg(*self.staging(run.dock))}, "behavior_tree": ""}
            run.nav_goal = self.nav.send_goal(goal, lambda status, result, error: self.on_nav_done(run, status, result, error))
        else:
            self.begin_approach(run)

    def on_nav_done(self, run: Run, status: int, result: Msg | None, error: str) -> None:
        if run is not self.run or run.phase != "navigating":
            return  # a goal of a run already over
        run.nav_goal = None
        if status == SUCCEEDED:
            self.begin_approach(run)
            return
        why = error or (result or {}).get("error_msg") or f"status {status}"
        self.finish(run, False, FAILED_TO_STAGE, f"navigation to the staging pose failed: {why}")

    def on_undock_goal(self, handle: GoalHandle) -> None:
        now = self.node.now()
        self.stop_run("preempted by an undock goal")
        self.undock_server.set_status(handle, 2)
        here = self.pose or (0.0, 0.0, 0.0)
        dock_id = min(self.docks, key=lambda d: math.dist(self.docks[d][:2], here[:2]))
        self.run = Run("undock", dock_id, self.docks[dock_id], now, handle, self.undock_server, "undocking", now,
                       max_s=handle.goal["max_undocking_time"])

    def on_cancel(self, handle: GoalHandle) -> None:
        run = self.run
        if run is not None and run.handle is handle:
            self.finish(run, False, 0, "canceled", status=CANCELED)

    def stop_run(self, why: str) -> None:
        """End whatever run there is (its goal CANCELED): a new goal takes the robot."""
        if self.run is not None:
            self.finish(self.run, False, 0, why, status=CANCELED)

    def finish(self, run: Run, success: bool, code: int, why: str, status: int | None = None) -> None:
        """The one way a run ends: stop the robot (or the planner), answer the goal, say why."""
        if run.nav_goal is not None:
            self.nav.cancel_goal(run.nav_goal)  # the planner stops the robot
        else:
            self.drive(0.0, 0.0)
        if self.detections is not None:
            self.detections.undeclare()
            self.detections = None
        self.run = None
        self.set_state("docked" if success and run.kind == "dock" else "idle" if success or status == CANCELED
                       else "failed")
        log = self.node.log.info if success else self.node.log.warning
        log("%s %s: %s (code %d, %d retries, %d dock sightings, %.1f s)", run.kind, "succeeded" if success else "ended",
            why, code, run.retries, run.sightings, self.node.now() - run.started_s)
        if run.handle is not None and run.server is not None:
            result = self.dock_result(success, code, run.retries) if run.kind == "dock" else {
                "success": success, "error_code": code}
            run.server.finish(run.handle, status or (SUCCEEDED if success else ABORTED), result)

    @staticmethod
    def dock_result(success: bool, code: int, retries: int = 0) -> Msg:
        return {"success": success, "error_code": code, "num_retries": retries}

    # --- control, every CONTROL_PERIOD_S of the node's clock ------------------------------------------

    def staging(self, dock: Pose) -> Pose:
        return compose(dock, (-self.staging_offset, 0.0, 0.0))

    def near(self, pose: Pose, tolerance_m: float) -> bool:
        return self.pose is not None and math.dist(self.pose[:2], pose[:2]) < tolerance_m

    def begin_approach(self, run: Run) -> None:
        now = self.node.now()
        run.phase, run.phase_s, run.progress_s, run.best_distance = "approaching", now, now, math.inf
        if self.use_detection and self.detections is None:  # only while needed: cameras render on demand
            self.detections = self.node.subscribe("detected_dock_pose", "geometry_msgs/msg/PoseStamped", self.on_detection)

    def drive(self, linear: float, angular: float) -> None:
        self.command = (linear, angular)
        self.cmd_vel.publish(twist_msg(linear, angular))

    def predicted_pose(self, now: float) -> Pose:
        """The pose carried forward over its age by the speed odometry measures (or, without odometry, by
        the last command): the pose comes at 10 Hz, the control runs at 20 Hz, and at 0.3 m/s a 0.1 s
        old pose is 3 cm behind."""
        assert self.pose is not None
        age = min(max(now - self.pose_s, 0.0), 0.3)
        (v, w), (x, y, yaw) = self.odom if fresh(self.odom_s, now, 0.2) else self.command, self.pose
        return x + v * age * math.cos(yaw), y + v * age * math.sin(yaw), wrap(yaw + w * age)

    def set_state(self, state: str) -> None:
        now = self.node.now()
        if state != self.state or now - self.state_s >= 1.0:
            self.state, self.state_s = state, now
            self.state_pub.publish({"data": state})

    def tick(self) -> None:
        now, run = self.node.now(), self.run
        if run is None:
            return self.set_state(self.state or "idle")
        self.set_state(run.phase)
        if now < run.phase_s:  # the clock went back (a simulator reset): time the run from now
            run.started_s = run.phase_s = run.progress_s = now
        if now - run.started_s > run.max_s:
            return self.finish(run, False, TIMEOUT, f"no end after {run.max_s:g} s")
        if run.kind == "dock" and run.phase != "navigating" and self.docked(now):
            return self.finish(run, True, 0, "charging" if fresh(self.charging_s, now, MAX_STATUS_AGE_S) else "mated")
        if run.phase == "navigating":
            if now - run.phase_s > run.max_staging_s:
                self.finish(run, False, FAILED_TO_STAGE, f"not at the staging pose after {run.max_staging_s:g} s")
            elif (self.pose is not None and self.near(self.staging(run.dock), HANDOVER_M)
                  and abs(wrap(self.pose[2] - run.dock[2])) < HANDOVER_HEADING_RAD and run.nav_goal is not None):
                self.nav.cancel_goal(run.nav_goal)
                run.nav_goal = None
                self.begin_approach(run)
            return self.feedback(run, now, NAV_TO_STAGING_POSE)
        if self.pose is None or not fresh(self.pose_s, now, MAX_POSE_AGE_S):
            return self.drive(0.0, 0.0)  # no fresh pose: hold still
        robot = self.predicted_pose(now)
        if run.phase == "approaching":
            self.approach(run, robot, now)
        else:
            self.back_off(run, robot, now)
        self.feedback(run, now, CONTROLLING if run.phase == "approaching" else RETRY)

    def approach(self, run: Run, robot: Pose, now: float) -> None:
        """Steer onto the dock's axis and drive along it, slower as the dock nears.

        The heading aims at a point ``LOOKAHEAD_M`` ahead on the axis, so a sideways offset decays over
        the approach and the robot arrives square to the dock; far from that heading it turns in place
        first. Stuck short of the dock (pressed against its body, off the contacts) it backs off to retry.
        """
        dock = run.estimate if run.estimate is not None and run.sightings >= 3 else run.dock
        along, lateral, heading = in_dock_frame(robot, dock)
        distance = -along
        if math.hypot(along, lateral) < run.best_distance - 0.01:  # a centimetre closer: progress
            run.best_distance, run.progress_s = math.hypot(along, lateral), now
        if distance < -0.03 or now - run.progress_s > STALL_S:
            return self.retry(run, now, f"{'past the dock' if distance < -0.03 else 'stalled'} "
                              f"{distance:.2f} m out, {lateral:+.3f} m aside, {heading:+.2f} rad")
        error = wrap(math.atan2(-lateral, LOOKAHEAD_M) - heading)
        speed = min(MAX_SPEED_MPS, max(MIN_SPEED_MPS, SLOW_DOWN_PER_S * distance)) * max(0.0, 1.0 - abs(error) / 0.6)
        self.drive(speed, max(-MAX_TURN_RADPS, min(MAX_TURN_RADPS, TURN_GAIN * error)))

    def retry(self, run: Run, now: float, why: str) -> None:
        if run.retries >= self.max_retries:
            return self.finish(run, False, FAILED_TO_CONTROL, f"no contact after {run.retries} retries ({why})")
        run.retries += 1
        self.node.log.info("retry %d: %s", run.retries, why)
        run.phase, run.phase_s = "backing_off", now

    def back_off(self, run: Run, robot: Pose, now: float) -> None:
        """Reverse straight out along the dock's axis (undocking, or before another approach)."""
        along, _, heading = in_dock_frame(robot, run.dock)
        if run.kind == "undock" and -along >= self.staging_offset:
            return self.finish(run, True, 0, f"{-along:.2f} m off the dock")
        if run.kind == "dock" and (-along >= self.staging_offset or now - run.phase_s > 10.0):
            return self.begin_approach(run)
        self.drive(-BACK_OFF_SPEED_MPS, max(-0.5, min(0.5, -TURN_GAIN * heading)))

    def feedback(self, run: Run, now: float, state: int) -> None:
        if run.handle is None or run.kind != "dock" or now - run.feedback_s < 0.5:
            return
        run.feedback_s = now
        took = time_msg(max(0.0, now - run.started_s))
        self.dock_server.publish_feedback(run.handle, {"state": state, "docking_time": took, "num_retries": run.retries})

    def close(self) -> None:
        """On SIGTERM: leave the robot stopped and the planner without our goal."""
        if self.run is not None:
            self.finish(self.run, False, 0, "shutting down", status=ABORTED)
        self.dock_server.close()
        self.undock_server.close()


def _fmt(pose: Pose) -> str:
    return f"({pose[0]:.2f}, {pose[1]:.2f}, {pose[2]:.2f})"


def main() -> int:
    options = parse_options("docking", "A docking service for a zendock stack (an example).")
    try:
        if "dock_database" not in options.params:
            raise ValueError("-p dock_database=<world or dock database YAML> is required")
        read_docks(str(options.params["dock_database"]))
    except (OSError, ValueError, IndexError, KeyError, AttributeError) as exc:
        print(f"docking: error: dock_database: {exc}", file=sys.stderr)
        return 2
    node = Node(options)
    docking = Docking(node)
    node.declare_ready()
    return node.run(CONTROL_PERIOD_S, docking.tick, docking.close)


if __name__ == "__main__":
    sys.exit(main())
