"""A ROS 2 user of a zendock robot on DDS: real rclpy (Jazzy, Fast DDS) and ROS 2 message packages only.

Run it with ``.venv-ros2/bin/python tests/support/ros2_user.py`` on a ``ROS_DOMAIN_ID`` where
``services.ros2_dds`` shows zendock (discovery on loopback: ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``).
It goes through what a ROS 2 user does, one JSON line per step on stdout (``{"step": ..., "ok": ...}``):
first what a Nav2 script's ``waitUntilNav2Active()`` does (``amcl/get_state`` until ``active``, a zero
``/initialpose`` until ``/amcl_pose`` comes, ``bt_navigator/get_state``; the protocol, written here), then
lists nodes and topics, echoes ``/battery_status``, joins ``/map`` late (TRANSIENT_LOCAL), follows ``/clock``
with ``use_sim_time``, drives with ``/cmd_vel`` (Twist, then TwistStamped) and watches ``/odom``, sends NavigateToPose and DockRobot
goals (feedback, result, CHARGING), asks Nav2's lifecycle managers to start up, pause and resume, sends a ``/goal_pose`` and sees the robot arrive, cancels a goal, sends what zendock refuses, sets the localiser's belief with ``/initialpose``, and, after printing ``{"step": "stop_planner"}``, waits
for ``/planner`` to leave the graph. It imports nothing of zendock's.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections.abc import Callable
from typing import Any

import rclpy
from action_msgs.msg import GoalStatus
from builtin_interfaces.msg import Duration
from geographic_msgs.msg import GeoPose
from geometry_msgs.msg import PoseStamped, PoseWithCovarianceStamped, Twist, TwistStamped
from lifecycle_msgs.srv import GetState
from nav2_msgs.action import (
    AssistedTeleop,
    BackUp,
    ComputePathThroughPoses,
    ComputePathToPose,
    DockRobot,
    DriveOnHeading,
    FollowGPSWaypoints,
    FollowPath,
    FollowWaypoints,
    NavigateThroughPoses,
    NavigateToPose,
    SmoothPath,
    Spin,
    UndockRobot,
    Wait,
)
from nav2_msgs.srv import (
    ClearCostmapAroundPose,
    ClearCostmapAroundRobot,
    ClearCostmapExceptRegion,
    ClearEntireCostmap,
    GetCostmap,
    ManageLifecycleNodes,
)
from nav_msgs.msg import OccupancyGrid, Odometry
from rcl_interfaces.msg import Parameter as ParameterMsg
from rcl_interfaces.msg import ParameterType, ParameterValue
from rcl_interfaces.srv import DescribeParameters, GetParameters, ListParameters, SetParameters
from rclpy.action import ActionClient
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import BatteryState
from std_msgs.msg import Float64MultiArray

ZENDOCK_NODES = ("simulator", "battery", "pose", "planner", "perception", "docking", "ros2_dds")
EXPECTED_TYPES = {
    "/battery_status": "sensor_msgs/msg/BatteryState",
    "/odom": "nav_msgs/msg/Odometry",
    "/scan": "sensor_msgs/msg/LaserScan",
    "/map": "nav_msgs/msg/OccupancyGrid",
    "/tf": "tf2_msgs/msg/TFMessage",
    "/tf_static": "tf2_msgs/msg/TFMessage",
    "/clock": "rosgraph_msgs/msg/Clock",
    "/map_to_base_link_pose2d": "std_msgs/msg/Float64MultiArray",
    "/plan": "nav_msgs/msg/Path",
    "/cmd_vel": "geometry_msgs/msg/Twist",
    "/goal_pose": "geometry_msgs/msg/PoseStamped",
    "/initialpose": "geometry_msgs/msg/PoseWithCovarianceStamped",
}
CHARGING = BatteryState.POWER_SUPPLY_STATUS_CHARGING
LATCHED = QoSProfile(
    depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE
)


def report(step: str, ok: bool, **details: Any) -> None:
    print(json.dumps({"step": step, "ok": ok, **details}), flush=True)


def _map_pose(x: float, y: float) -> PoseStamped:
    """A pose in ``map`` at (x, y), facing +x."""
    pose = PoseStamped()
    pose.header.frame_id = "map"
    pose.pose.position.x, pose.pose.position.y = x, y
    pose.pose.orientation.w = 1.0
    return pose


class User:
    def __init__(self, node: Node) -> None:
        self.node = node

    def spin_until(self, done: Callable[[], bool], timeout_s: float) -> bool:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if done():
                return True
            rclpy.spin_once(self.node, timeout_sec=0.05)
        return done()

    def collect(self, msg_type: Any, topic: str, count: int, timeout_s: float, qos: Any = 10) -> list[Any]:
        got: list[Any] = []
        sub = self.node.create_subscription(msg_type, topic, got.append, qos)
        self.spin_until(lambda: len(got) >= count, timeout_s)
        self.node.destroy_subscription(sub)
        return got

    # --- steps ----------------------------------------------------------------------------------

    def _lifecycle_state(self, nav2_node: str, timeout_s: float) -> str:
        """Ask ``<nav2_node>/get_state`` until it answers (as a Nav2 script does): its label."""
        reply = self._call(GetState, f"{nav2_node}/get_state", timeout_s=timeout_s)
        return reply.current_state.label if reply is not None else "no answer"

    def _call(
        self,
        srv_type: Any,
        name: str,
        fill: Callable[[Any], None] = lambda _request: None,
        timeout_s: float = 10.0,
    ) -> Any:
        """One call as a Nav2 script or ``ros2`` makes it (wait for the service, call, wait for the reply);
        ``fill`` sets the request's fields. None without a service or a reply."""
        client = self.node.create_client(srv_type, name)
        try:
            if not client.wait_for_service(timeout_sec=timeout_s):
                return None
            request = srv_type.Request()
            fill(request)
            future = client.call_async(request)
            self.spin_until(future.done, timeout_s)
            return future.result() if future.done() else None
        finally:
            self.node.destroy_client(client)

    def costmaps(self) -> None:
        """``clearAllCostmaps()`` (local, then global), the local costmap's region clears, ``getGlobalCostmap()``
        and ``getLocalCostmap()``."""
        cleared = [
            self._call(ClearEntireCostmap, name) is not None
            for name in (
                "local_costmap/clear_entirely_local_costmap",
                "global_costmap/clear_entirely_global_costmap",
            )
        ]

        def distance(value: float) -> Callable[[Any], None]:
            def fill(request: Any) -> None:
                request.reset_distance = value

            return fill

        def around_pose(request: Any) -> None:
            request.pose = _map_pose(1.0, 4.2)
            request.reset_distance = 1.0

        # clearCostmapExceptRegion(), clearCostmapAroundRobot(), clearCostmapAroundPose(): the local costmap's
        region = [
            self._call(ClearCostmapExceptRegion, "local_costmap/clear_costmap_except_region", distance(3.0))
            is not None,
            self._call(ClearCostmapAroundRobot, "local_costmap/clear_costmap_around_robot", distance(1.0))
            is not None,
            self._call(ClearCostmapAroundPose, "local_costmap/clear_costmap_around_pose", around_pose)
            is not None,
        ]
        got = {}
        for which in ("global", "local"):
            reply = self._call(GetCostmap, f"{which}_costmap/get_costmap")
            if reply is None:
                got[which] = None
                continue
            meta = reply.map.metadata
            data = list(reply.map.data)
            got[which] = {
                "size": [meta.size_x, meta.size_y],
                "cells": len(data),
                "resolution": round(meta.resolution, 3),
                "lethal": sum(1 for c in data if c == 254),
                "frame": reply.map.header.frame_id,
            }
        report(
            "costmaps",
            all(cleared)
            and all(region)
            and all(g is not None and g["cells"] == g["size"][0] * g["size"][1] > 0 for g in got.values()),
            cleared=cleared,
            region=region,
            **got,
        )

    def _param_call(self, srv_type: Any, node: str, fill: Callable[[Any], None]) -> Any:
        """One of ``ros2 param``'s requests to ``/<node>/<service>``."""
        name = {
            ListParameters: "list_parameters",
            GetParameters: "get_parameters",
            SetParameters: "set_parameters",
            DescribeParameters: "describe_parameters",
        }[srv_type]
        return self._call(srv_type, f"/{node}/{name}", fill)

    def parameters(self) -> None:
        """``ros2 param list /docking``, ``get /docking use_sim_time`` (and the simulator's), ``get|set /docking
        auto_dock``, a refused set of a read-only parameter, ``describe``; auto_dock is put back as it was."""

        def names(r: Any) -> None:
            r.names = ["auto_dock", "dock_database"]

        def set_to(name: str, value: ParameterValue) -> Callable[[Any], None]:
            return lambda r: setattr(r, "parameters", [ParameterMsg(name=name, value=value)])

        listed = self._param_call(ListParameters, "docking", lambda r: None)
        sim_time = self._param_call(GetParameters, "docking", lambda r: setattr(r, "names", ["use_sim_time"]))
        # the simulator makes the clock rather than following it: its use_sim_time is false
        clock_maker = self._param_call(
            GetParameters, "simulator", lambda r: setattr(r, "names", ["use_sim_time"])
        )
        before = self._param_call(GetParameters, "docking", names)
        described = self._param_call(DescribeParameters, "docking", names)
        off = self._param_call(
            SetParameters, "docking", set_to("auto_dock", ParameterValue(type=ParameterType.PARAMETER_BOOL))
        )
        after = self._param_call(GetParameters, "docking", names)
        refused = self._param_call(
            SetParameters,
            "docking",
            set_to(
                "dock_database", ParameterValue(type=ParameterType.PARAMETER_STRING, string_value="x.yaml")
            ),
        )
        back = self._param_call(
            SetParameters,
            "docking",
            set_to("auto_dock", ParameterValue(type=ParameterType.PARAMETER_BOOL, bool_value=True)),
        )
        details = {
            "listed": sorted(listed.result.names) if listed else None,
            "use_sim_time": sim_time.values[0].bool_value if sim_time else None,
            "simulator_use_sim_time": clock_maker.values[0].bool_value if clock_maker else None,
            "auto_dock_before": before.values[0].bool_value if before else None,
            "read_only": [d.read_only for d in described.descriptors] if described else None,
            "set_off": off.results[0].successful if off else None,
            "auto_dock_after": after.values[0].bool_value if after else None,
            "refused": [refused.results[0].successful, refused.results[0].reason] if refused else None,
            "set_back": back.results[0].successful if back else None,
        }
        ok = (
            details["listed"] is not None
            and "auto_dock" in details["listed"]
            and details["use_sim_time"] is True
            and details["simulator_use_sim_time"] is False
            and details["auto_dock_before"] is True
            and details["read_only"] == [False, True]
            and details["set_off"] is True
            and details["auto_dock_after"] is False
            and details["refused"] is not None
            and details["refused"][0] is False
            and details["set_back"] is True
        )
        report("parameters", ok, **details)

    def nav2_active(self) -> None:
        """What ``waitUntilNav2Active()`` asks, in its order: the localiser active, an initial pose (all
        zeros in ``map``, as a script that did not set one sends) answered by ``/amcl_pose``, the navigator
        active. The robot does not start at the map's origin: the localiser must not believe it does."""
        started = time.monotonic()
        amcl = self._lifecycle_state("amcl", 30.0)
        amcl_poses: list[Any] = []
        sub = self.node.create_subscription(
            PoseWithCovarianceStamped, "amcl_pose", amcl_poses.append, LATCHED
        )
        pub = self.node.create_publisher(PoseWithCovarianceStamped, "initialpose", 10)
        zero = PoseWithCovarianceStamped()
        zero.header.frame_id = "map"
        # A script publishes at once; here the test also checks the estimate is refused, so it must arrive.
        self.spin_until(lambda: pub.get_subscription_count() > 0, 10.0)
        # At least once: the latched /amcl_pose may have come while the publisher was being matched.
        deadline = time.monotonic() + 30.0
        while True:
            pub.publish(zero)
            self.spin_until(lambda: bool(amcl_poses), 1.0)
            if amcl_poses or time.monotonic() >= deadline:
                break
        navigator = self._lifecycle_state("bt_navigator", 30.0)
        active_s = time.monotonic() - started
        # The zero estimate is refused (the scans contradict it): the belief stays where the robot is.
        pose = self.robot_pose()
        self.node.destroy_subscription(sub)
        self.node.destroy_publisher(pub)
        first = amcl_poses[0].pose.pose.position if amcl_poses else None
        report(
            "nav2_active",
            amcl == "active"
            and navigator == "active"
            and bool(amcl_poses)
            and pose is not None
            and math.hypot(pose[0], pose[1]) > 0.5,
            amcl=amcl,
            bt_navigator=navigator,
            amcl_pose=[round(first.x, 3), round(first.y, 3)] if first is not None else None,
            frame=amcl_poses[0].header.frame_id if amcl_poses else None,
            belief=[round(v, 3) for v in pose] if pose is not None else None,
            seconds=round(active_s, 2),
        )

    def graph(self) -> None:
        def complete() -> bool:
            topics = dict(self.node.get_topic_names_and_types())
            return set(ZENDOCK_NODES) <= set(self.node.get_node_names()) and all(
                t in topics for t in EXPECTED_TYPES
            )

        self.spin_until(complete, 30.0)
        nodes = sorted(set(self.node.get_node_names()) - {self.node.get_name()})
        topics = {name: types for name, types in self.node.get_topic_names_and_types()}
        wrong = {
            t: topics.get(t) for t, ros_type in EXPECTED_TYPES.items() if ros_type not in topics.get(t, [])
        }
        # The face's nodes carry only what zendock serves: not rclpy's /rosout writer, not its type description
        # service (each a DDS endpoint, memory the face keeps under its limit).
        rclpy_extras = sorted(
            f"/{node} {name}"
            for node in ZENDOCK_NODES
            if node in nodes
            for name, _ in [
                *self.node.get_publisher_names_and_types_by_node(node, "/"),
                *self.node.get_service_names_and_types_by_node(node, "/"),
            ]
            if name == "/rosout" or name.endswith("/get_type_description")
        )
        report(
            "graph",
            set(ZENDOCK_NODES) <= set(nodes) and not wrong and not rclpy_extras,
            nodes=nodes,
            topics={
                t: topics[t] for t in sorted(topics) if not t.startswith(("/rosout", "/parameter_events"))
            },
            missing_nodes=sorted(set(ZENDOCK_NODES) - set(nodes)),
            wrong_topics=wrong,
            rclpy_extras=rclpy_extras,
        )

    def battery(self) -> None:
        got = self.collect(BatteryState, "/battery_status", 3, 15.0)
        report(
            "battery_status",
            len(got) >= 3,
            count=len(got),
            percentage=got[-1].percentage if got else None,
            power_supply_status=got[-1].power_supply_status if got else None,
            frame_id=got[-1].header.frame_id if got else None,
        )

    def late_map(self) -> None:
        infos = self.node.get_publishers_info_by_topic("/map")
        durability = [str(i.qos_profile.durability.name) for i in infos]
        started = time.monotonic()
        got = self.collect(OccupancyGrid, "/map", 1, 10.0, LATCHED)
        after = time.monotonic() - started
        grid = got[0] if got else None
        report(
            "late_map",
            bool(got) and durability == ["TRANSIENT_LOCAL"],
            publisher_durability=durability,
            after_s=round(after, 3),
            width=grid.info.width if grid else None,
            height=grid.info.height if grid else None,
            resolution=round(grid.info.resolution, 4) if grid else None,
            cells=len(grid.data) if grid else None,
        )

    def clock(self) -> None:
        sim = Node(
            "sim_time_user", parameter_overrides=[Parameter("use_sim_time", Parameter.Type.BOOL, True)]
        )
        got: list[Any] = []
        sub = sim.create_subscription(Clock, "/clock", got.append, 10)
        wall0 = time.monotonic()
        deadline = wall0 + 10.0
        while time.monotonic() < deadline and len(got) < 20:
            rclpy.spin_once(sim, timeout_sec=0.05)
        wall = time.monotonic() - wall0
        stamps = [m.clock.sec + m.clock.nanosec * 1e-9 for m in got]
        now = sim.get_clock().now().nanoseconds * 1e-9
        increasing = all(b >= a for a, b in zip(stamps, stamps[1:]))
        ratio = (stamps[-1] - stamps[0]) / wall if len(stamps) > 1 and wall > 0 else None
        sim.destroy_subscription(sub)
        sim.destroy_node()
        report(
            "clock",
            len(got) >= 20 and increasing and bool(stamps) and abs(now - stamps[-1]) < 1.0,
            count=len(got),
            increasing=increasing,
            sim_seconds_per_wall_second=ratio and round(ratio, 2),
            node_time=round(now, 3),
            last_clock=round(stamps[-1], 3) if stamps else None,
        )

    def _drive(
        self,
        msg_type: Any,
        forward: Any,
        step: str,
        seconds: float,
        ready: Callable[[], bool] = lambda: True,
    ) -> None:
        """Drive with ``forward`` once /odom arrives, the publisher is matched and ``ready()`` holds."""
        odom: list[Odometry] = []
        sub = self.node.create_subscription(Odometry, "/odom", odom.append, 10)
        pub = self.node.create_publisher(msg_type, "/cmd_vel", 10)
        matched = self.spin_until(lambda: bool(odom) and pub.get_subscription_count() > 0 and ready(), 10.0)
        start = odom[-1].pose.pose.position if odom else None

        def moved_m() -> float:
            end = odom[-1].pose.pose.position if odom else None
            return math.hypot(end.x - start.x, end.y - start.y) if start and end else 0.0

        # ``seconds`` of driving, and on a busy machine up to three times that until the robot has moved
        # (the face may take a moment to start forwarding from a publisher it has just discovered)
        began = time.monotonic()
        while time.monotonic() < began + seconds or (
            moved_m() <= 0.1 and time.monotonic() < began + 3 * seconds
        ):
            pub.publish(forward)
            self.spin_until(lambda: False, 0.05)
        pub.publish(msg_type())
        self.spin_until(lambda: False, 0.3)
        moved = moved_m()
        self.node.destroy_publisher(pub)
        self.node.destroy_subscription(sub)
        report(step, moved > 0.1, matched=matched, moved_m=round(moved, 3), odom_messages=len(odom))

    def drive(self) -> None:
        forward = Twist()
        forward.linear.x = 0.2
        self._drive(Twist, forward, "cmd_vel_odom", 1.0)

    def drive_stamped(self) -> None:
        """TwistStamped, as Jazzy's controllers publish /cmd_vel (the face takes it once it sees such a publisher)."""
        forward = TwistStamped()
        forward.header.frame_id = "base_link"
        forward.twist.linear.x = -0.2
        self._drive(TwistStamped, forward, "cmd_vel_stamped_odom", 1.0)

    def drive_mixed(self) -> None:
        """TwistStamped while another publisher holds /cmd_vel as Twist: both types at once (the face takes
        the second on a second DDS participant). The Twist publisher is another participant's too: one
        participant cannot have a topic under two types, the user's no more than the face's."""
        other = rclpy.Context()
        rclpy.init(context=other)
        holder = rclpy.create_node("twist_holder", context=other)
        try:
            holder.create_publisher(Twist, "/cmd_vel", 10)
            forward = TwistStamped()
            forward.header.frame_id = "base_link"
            forward.twist.linear.x = 0.2

            def both_types_taken() -> bool:
                # the face takes each type on a node of its own once it has seen both publishers: drive
                # then, not while it may still hold the topic under the last step's type alone
                types = {i.topic_type for i in self.node.get_subscriptions_info_by_topic("/cmd_vel")}
                return {"geometry_msgs/msg/Twist", "geometry_msgs/msg/TwistStamped"} <= types

            self._drive(TwistStamped, forward, "cmd_vel_mixed_odom", 1.0, ready=both_types_taken)
        finally:
            holder.destroy_node()
            rclpy.shutdown(context=other)

    def robot_pose(self) -> tuple[float, float, float] | None:
        got = self.collect(Float64MultiArray, "/map_to_base_link_pose2d", 1, 10.0)
        return tuple(got[-1].data[:3]) if got else None  # type: ignore[return-value]

    def run_goal(
        self, client: ActionClient, goal: Any, timeout_s: float, cancel_after_feedback: bool = False
    ) -> dict[str, Any]:
        if not client.wait_for_server(timeout_sec=15.0):
            return {"error": "action server not found"}
        feedback: list[Any] = []
        sent = client.send_goal_async(goal, feedback_callback=lambda fb: feedback.append(fb.feedback))
        if not self.spin_until(sent.done, 15.0) or sent.result() is None:
            return {"error": "no answer to the goal"}
        handle = sent.result()
        if not handle.accepted:
            return {"accepted": False}
        out: dict[str, Any] = {"accepted": True}
        if cancel_after_feedback:
            self.spin_until(lambda: bool(feedback), 15.0)
            cancelling = handle.cancel_goal_async()
            self.spin_until(cancelling.done, 10.0)
            reply = cancelling.result()
            out["cancel_return_code"] = reply.return_code if reply is not None else None
        result = handle.get_result_async()
        self.spin_until(result.done, timeout_s)
        done = result.result()
        out.update(
            status=done.status if done is not None else None,
            feedbacks=len(feedback),
            result=done.result if done is not None else None,
            last_feedback=feedback[-1] if feedback else None,
        )
        return out

    def paths(self) -> None:
        """BasicNavigator's getPath, smoothPath and getPathThroughPoses: a path from the robot to the staging
        goal, smoothed, one through two poses, and the reasons for a goal inside the box and for a planner
        zendock lacks."""

        def ask(action: Any, name: str, fill: Callable[[Any], None]) -> dict[str, Any]:
            client = ActionClient(self.node, action, f"/{name}")
            goal = action.Goal()
            fill(goal)
            out = self.run_goal(client, goal, 30.0)
            client.destroy()
            result = out.pop("result", None)
            out.pop("last_feedback", None)
            results[name] = result
            if result is not None:
                poses = result.path.poses
                out.update(
                    error_code=result.error_code,
                    error_msg=result.error_msg,
                    poses=len(poses),
                    frame=result.path.header.frame_id,
                    ends=[
                        [round(p.pose.position.x, 2), round(p.pose.position.y, 2)]
                        for p in poses[:1] + poses[-1:]
                    ],
                )
            return out

        def to(x: float, y: float, planner_id: str = "") -> Callable[[Any], None]:
            def fill(goal: Any) -> None:
                goal.goal, goal.planner_id = _map_pose(x, y), planner_id

            return fill

        def through(goal: Any) -> None:
            goal.goals = [_map_pose(-1.0, 2.0), _map_pose(0.3, 4.0)]

        results: dict[str, Any] = {}
        succeeded, aborted = GoalStatus.STATUS_SUCCEEDED, GoalStatus.STATUS_ABORTED
        staging = ask(ComputePathToPose, "compute_path_to_pose", to(0.0, 2.0))
        planned = results["compute_path_to_pose"]

        def smooth(goal: Any) -> None:
            goal.path, goal.check_for_collisions = planned.path, True

        smoothed = ask(SmoothPath, "smooth_path", smooth) if planned is not None else {}
        via = ask(ComputePathThroughPoses, "compute_path_through_poses", through)
        in_box = ask(ComputePathToPose, "compute_path_to_pose", to(-2.0, 3.8))
        other_planner = ask(ComputePathToPose, "compute_path_to_pose", to(0.0, 2.0, "SmacPlanner"))
        report(
            "paths",
            staging.get("status") == succeeded
            and staging.get("poses", 0) > 2
            and smoothed.get("status") == succeeded
            and smoothed.get("poses", 0) > 2
            and via.get("status") == succeeded
            and in_box.get("status") == aborted
            and in_box.get("error_code") == ComputePathToPose.Result.GOAL_OCCUPIED
            and other_planner.get("error_code") == ComputePathToPose.Result.INVALID_PLANNER,
            staging=staging,
            smoothed=smoothed,
            through=via,
            in_box=in_box,
            other_planner=other_planner,
        )

    def navigate(self) -> None:
        client = ActionClient(self.node, NavigateToPose, "/navigate_to_pose")
        goal = NavigateToPose.Goal()
        goal.pose.header.frame_id = "map"
        goal.pose.pose.position.x, goal.pose.pose.position.y = 0.3, 4.0
        goal.pose.pose.orientation.z, goal.pose.pose.orientation.w = 1.0, 0.0  # facing -x
        out = self.run_goal(client, goal, 60.0)
        pose = self.robot_pose()
        last = out.pop("last_feedback", None)
        result = out.pop("result", None)
        report(
            "navigate_to_pose",
            out.get("status") == GoalStatus.STATUS_SUCCEEDED and out.get("feedbacks", 0) > 0,
            **out,
            error_code=result.error_code if result is not None else None,
            distance_remaining=round(last.distance_remaining, 3) if last is not None else None,
            pose_after=[round(v, 3) for v in pose] if pose else None,
        )
        client.destroy()

    def behaviors(self) -> None:
        """BasicNavigator's spin, driveOnHeading, backup, the wait behaviour and assistedTeleop, from where
        navigate left the robot ((0.3, 4.0) facing -x, the room's top wall at y = 5): turn to face the wall,
        drive at it (zendock stops short of it and says why), back up, wait; assisted teleop is refused
        with a reason."""
        outcomes: dict[str, Any] = {}

        def run(name: str, action: Any, fill: Callable[[Any], None], timeout_s: float) -> dict[str, Any]:
            client = ActionClient(self.node, action, f"/{name}")
            goal = action.Goal()
            fill(goal)
            out = self.run_goal(client, goal, timeout_s)
            client.destroy()
            result = out.pop("result", None)
            out.pop("last_feedback", None)
            if result is not None:
                out.update(error_code=result.error_code, error_msg=result.error_msg)
                out["elapsed_s"] = round(
                    result.total_elapsed_time.sec + result.total_elapsed_time.nanosec * 1e-9, 2
                )
            outcomes[name] = out
            return out

        def spin(goal: Any) -> None:
            goal.target_yaw = -math.pi / 2  # from facing -x to facing +y
            goal.time_allowance = Duration(sec=10)

        def at_the_wall(goal: Any) -> None:
            goal.target.x, goal.speed, goal.time_allowance = 2.0, 0.2, Duration(sec=30)

        def back(goal: Any) -> None:
            goal.target.x, goal.speed, goal.time_allowance = 0.15, 0.1, Duration(sec=10)

        def wait(goal: Any) -> None:
            goal.time = Duration(sec=1)

        before = self.robot_pose()
        turned = run("spin", Spin, spin, 30.0)
        after_spin = self.robot_pose()
        driven = run("drive_on_heading", DriveOnHeading, at_the_wall, 60.0)
        at_wall = self.robot_pose()
        backed = run("backup", BackUp, back, 30.0)
        waited = run("wait", Wait, wait, 20.0)
        teleop = run("assisted_teleop", AssistedTeleop, lambda goal: None, 20.0)
        succeeded = GoalStatus.STATUS_SUCCEEDED
        report(
            "behaviors",
            turned.get("status") == succeeded
            and driven.get("status") == GoalStatus.STATUS_ABORTED
            and driven.get("error_code") == DriveOnHeading.Result.COLLISION_AHEAD
            and backed.get("status") == succeeded
            and waited.get("status") == succeeded
            and waited.get("feedbacks", 0) > 0
            and teleop.get("status") == GoalStatus.STATUS_ABORTED
            and teleop.get("error_code") == AssistedTeleop.Result.UNKNOWN
            and "not served" in teleop.get("error_msg", ""),
            **outcomes,
            poses=[[round(v, 3) for v in p] if p else None for p in (before, after_spin, at_wall)],
        )

    def sequences(self) -> None:
        """BasicNavigator's goThroughPoses, then followWaypoints with a waypoint inside the box: the others
        are reached, that one is in missed_waypoints with the reason's code; followGpsWaypoints is refused
        at once with a reason."""

        def run(action: Any, name: str, poses: list[PoseStamped]) -> dict[str, Any]:
            client = ActionClient(self.node, action, f"/{name}")
            goal = action.Goal()
            goal.poses = poses
            out = self.run_goal(client, goal, 90.0)
            client.destroy()
            result = out.pop("result", None)
            last = out.pop("last_feedback", None)
            if result is not None:
                out.update(error_code=result.error_code, error_msg=result.error_msg)
                missed = getattr(result, "missed_waypoints", [])
                out["missed"] = [[m.index, m.error_code] for m in missed]
            if last is not None and hasattr(last, "number_of_poses_remaining"):
                out["last_poses_remaining"] = last.number_of_poses_remaining
            out["pose_after"] = [round(v, 2) for v in self.robot_pose() or ()]
            return out

        through = run(
            NavigateThroughPoses, "navigate_through_poses", [_map_pose(1.0, 4.2), _map_pose(0.3, 4.0)]
        )
        waypoints = run(
            FollowWaypoints,
            "follow_waypoints",
            [_map_pose(1.0, 4.2), _map_pose(-2.0, 3.8), _map_pose(0.3, 4.0)],
        )
        gps_client = ActionClient(self.node, FollowGPSWaypoints, "/follow_gps_waypoints")
        gps_goal = FollowGPSWaypoints.Goal()
        gps_goal.gps_poses = [GeoPose()]
        asked = time.monotonic()
        gps = self.run_goal(gps_client, gps_goal, 15.0)
        gps_client.destroy()
        gps_result = gps.pop("result", None)
        gps.pop("last_feedback", None)
        gps["seconds"] = round(time.monotonic() - asked, 2)
        if gps_result is not None:
            gps.update(error_code=gps_result.error_code, error_msg=gps_result.error_msg)
        succeeded = GoalStatus.STATUS_SUCCEEDED
        report(
            "sequences",
            through.get("status") == succeeded
            and through.get("feedbacks", 0) > 0
            and waypoints.get("status") == succeeded
            and [m[0] for m in waypoints.get("missed", [])] == [1]
            and gps.get("status") == GoalStatus.STATUS_ABORTED
            and "no GPS" in gps.get("error_msg", ""),
            through=through,
            waypoints=waypoints,
            gps=gps,
        )

    def follow_path(self) -> None:
        """BasicNavigator's followPath: a path from getPath, driven by the controller alone; then one from a
        controller zendock lacks, refused with Nav2's INVALID_CONTROLLER."""
        target = _map_pose(1.0, 4.2)
        planner = ActionClient(self.node, ComputePathToPose, "/compute_path_to_pose")
        ask = ComputePathToPose.Goal()
        ask.goal = target
        planned = self.run_goal(planner, ask, 30.0)
        planner.destroy()
        path = planned["result"].path if planned.get("result") is not None else None
        outcomes: dict[str, Any] = {}
        for controller_id in ("FollowPath", "MPPI"):
            client = ActionClient(self.node, FollowPath, "/follow_path")
            goal = FollowPath.Goal()
            goal.path, goal.controller_id = path, controller_id
            out = self.run_goal(client, goal, 60.0) if path is not None else {}
            client.destroy()
            result = out.pop("result", None)
            out.pop("last_feedback", None)
            if result is not None:
                out.update(error_code=result.error_code, error_msg=result.error_msg)
            out["pose_after"] = [round(v, 2) for v in self.robot_pose() or ()]
            outcomes[controller_id] = out
        followed, refused = outcomes["FollowPath"], outcomes["MPPI"]
        report(
            "follow_path",
            followed.get("status") == GoalStatus.STATUS_SUCCEEDED
            and followed.get("feedbacks", 0) > 0
            and refused.get("error_code") == FollowPath.Result.INVALID_CONTROLLER,
            poses=len(path.poses) if path is not None else 0,
            **outcomes,
        )

    def lifecycle(self) -> None:
        """``lifecycleStartup()``'s protocol: every ``nav2_msgs/srv/ManageLifecycleNodes`` service in the graph
        asked to ``STARTUP`` (a running stack is already active: each answers, ``success: false``). Then a
        ``PAUSE`` of the navigation manager: ``bt_navigator`` says ``inactive`` and refuses a navigate goal,
        until a ``RESUME``."""
        managers = sorted(
            name
            for name, types in self.node.get_service_names_and_types()
            if "nav2_msgs/srv/ManageLifecycleNodes" in types
        )

        def command(value: int) -> Callable[[Any], None]:
            def fill(request: Any) -> None:
                request.command = value

            return fill

        started = time.monotonic()
        startup = {}
        for name in managers:
            reply = self._call(
                ManageLifecycleNodes, name, command(ManageLifecycleNodes.Request.STARTUP), 30.0
            )
            startup[name] = None if reply is None else reply.success
        startup_s = round(time.monotonic() - started, 2)
        navigation = "/lifecycle_manager_navigation/manage_nodes"
        paused = self._call(
            ManageLifecycleNodes, navigation, command(ManageLifecycleNodes.Request.PAUSE), 30.0
        )
        state_paused = self._lifecycle_state("bt_navigator", 10.0)
        goal = NavigateToPose.Goal()
        goal.pose = _map_pose(1.0, 4.2)
        refused = self.run_goal(ActionClient(self.node, NavigateToPose, "navigate_to_pose"), goal, 10.0)
        resumed = self._call(
            ManageLifecycleNodes, navigation, command(ManageLifecycleNodes.Request.RESUME), 30.0
        )
        state_resumed = self._lifecycle_state("bt_navigator", 10.0)
        report(
            "lifecycle",
            managers == ["/lifecycle_manager_localization/manage_nodes", navigation]
            and set(startup.values()) == {False}
            and paused is not None
            and paused.success
            and state_paused == "inactive"
            and refused.get("accepted") is False
            and resumed is not None
            and resumed.success
            and state_resumed == "active",
            managers=managers,
            startup=startup,
            startup_s=startup_s,
            paused=state_paused,
            goal_while_paused=refused,
            resumed=state_resumed,
        )

    def goal_pose(self) -> None:
        """RViz's 2D Goal Pose: a PoseStamped on /goal_pose, and the robot drives there."""
        target = (0.5, 2.6, -math.pi / 2)
        goal = PoseStamped()
        goal.header.frame_id = "map"
        goal.pose.position.x, goal.pose.position.y = target[0], target[1]
        goal.pose.orientation.z, goal.pose.orientation.w = math.sin(target[2] / 2), math.cos(target[2] / 2)
        pub = self.node.create_publisher(PoseStamped, "/goal_pose", 10)
        self.spin_until(lambda: pub.get_subscription_count() > 0, 10.0)
        pub.publish(goal)
        poses: list[Any] = []
        sub = self.node.create_subscription(
            Float64MultiArray, "/map_to_base_link_pose2d", lambda m: poses.append(tuple(m.data[:3])), 10
        )

        def arrived() -> bool:
            return bool(poses) and math.hypot(poses[-1][0] - target[0], poses[-1][1] - target[1]) < 0.25

        ok = self.spin_until(arrived, 60.0)
        self.node.destroy_subscription(sub)
        self.node.destroy_publisher(pub)
        report(
            "goal_pose",
            ok,
            target=list(target),
            pose_after=[round(v, 3) for v in poses[-1]] if poses else None,
        )

    def cancel(self) -> None:
        client = ActionClient(self.node, NavigateToPose, "/navigate_to_pose")
        goal = NavigateToPose.Goal()
        goal.pose.header.frame_id = "map"
        goal.pose.pose.position.x, goal.pose.pose.position.y = -2.0, 2.0
        goal.pose.pose.orientation.w = 1.0
        out = self.run_goal(client, goal, 30.0, cancel_after_feedback=True)
        out.pop("last_feedback", None)
        out.pop("result", None)
        report(
            "cancel",
            out.get("status") == GoalStatus.STATUS_CANCELED and out.get("cancel_return_code") == 0,
            **out,
        )
        client.destroy()

    def dock(self) -> None:
        client = ActionClient(self.node, DockRobot, "/dock_robot")
        goal = DockRobot.Goal(use_dock_id=True, dock_id="home", navigate_to_staging_pose=True)
        out = self.run_goal(client, goal, 90.0)
        last = out.pop("last_feedback", None)
        result = out.pop("result", None)
        battery = self.collect(BatteryState, "/battery_status", 2, 10.0)
        charging = bool(battery) and battery[-1].power_supply_status == CHARGING
        report(
            "dock_robot",
            out.get("status") == GoalStatus.STATUS_SUCCEEDED
            and bool(result and result.success)
            and out.get("feedbacks", 0) > 0
            and charging,
            **out,
            success=bool(result.success) if result is not None else None,
            error_code=result.error_code if result is not None else None,
            last_feedback_state=last.state if last is not None else None,
            power_supply_status=battery[-1].power_supply_status if battery else None,
            charging=charging,
        )
        client.destroy()

    def undock(self) -> None:
        """BasicNavigator's undockRobot from the dock just reached: SUCCEEDED, and the battery stops charging."""
        client = ActionClient(self.node, UndockRobot, "/undock_robot")
        out = self.run_goal(client, UndockRobot.Goal(dock_type=""), 60.0)
        client.destroy()
        result = out.pop("result", None)
        out.pop("last_feedback", None)
        battery = self.collect(BatteryState, "/battery_status", 2, 10.0)
        report(
            "undock_robot",
            out.get("status") == GoalStatus.STATUS_SUCCEEDED
            and bool(result and result.success)
            and bool(battery)
            and battery[-1].power_supply_status != CHARGING,
            **out,
            success=bool(result.success) if result is not None else None,
            error_code=result.error_code if result is not None else None,
            power_supply_status=battery[-1].power_supply_status if battery else None,
        )

    def bad_input(self) -> None:
        """What zendock cannot take is refused (a NaN velocity, a goal in the odom frame, a NaN goal), and the
        face goes on: still in the graph, still forwarding."""
        nan = float("nan")
        cmd = self.node.create_publisher(Twist, "/cmd_vel", 10)
        goal_pose = self.node.create_publisher(PoseStamped, "/goal_pose", 10)
        self.spin_until(
            lambda: cmd.get_subscription_count() > 0 and goal_pose.get_subscription_count() > 0, 10.0
        )
        broken = Twist()
        broken.linear.x = nan
        elsewhere = PoseStamped()
        elsewhere.header.frame_id = "odom"
        elsewhere.pose.orientation.w = 1.0
        for _ in range(5):
            cmd.publish(broken)
            goal_pose.publish(elsewhere)
            self.spin_until(lambda: False, 0.05)
        client = ActionClient(self.node, NavigateToPose, "/navigate_to_pose")
        goal = NavigateToPose.Goal()
        goal.pose.header.frame_id = "map"
        goal.pose.pose.position.x = nan
        out = self.run_goal(client, goal, 10.0)
        client.destroy()
        self.node.destroy_publisher(cmd)
        self.node.destroy_publisher(goal_pose)
        alive = "ros2_dds" in self.node.get_node_names()
        battery = self.collect(BatteryState, "/battery_status", 1, 10.0)
        report(
            "bad_input",
            out.get("accepted") is False and alive and bool(battery),
            nan_goal=out,
            face_in_graph=alive,
            battery_after=len(battery),
        )

    def initial_pose(self) -> None:
        """RViz's 2D Pose Estimate: the localiser believes the robot is there (the robot does not move)."""
        before = self.robot_pose()
        if before is None:
            report("initial_pose", False, error="no /map_to_base_link_pose2d")
            return
        target = (before[0] + 0.3, before[1] - 0.2, before[2])
        estimate = PoseWithCovarianceStamped()
        estimate.header.frame_id = "map"
        estimate.pose.pose.position.x, estimate.pose.pose.position.y = target[0], target[1]
        estimate.pose.pose.orientation.z = math.sin(target[2] / 2)
        estimate.pose.pose.orientation.w = math.cos(target[2] / 2)
        pub = self.node.create_publisher(PoseWithCovarianceStamped, "/initialpose", 10)
        self.spin_until(lambda: pub.get_subscription_count() > 0, 10.0)
        pub.publish(estimate)
        believed: list[Any] = []
        sub = self.node.create_subscription(
            Float64MultiArray, "/map_to_base_link_pose2d", lambda m: believed.append(tuple(m.data[:3])), 10
        )

        def there() -> bool:
            return (
                bool(believed) and math.hypot(believed[-1][0] - target[0], believed[-1][1] - target[1]) < 0.05
            )

        ok = self.spin_until(there, 10.0)
        self.node.destroy_subscription(sub)
        self.node.destroy_publisher(pub)
        report(
            "initial_pose",
            ok,
            before=[round(v, 3) for v in before],
            estimate=[round(v, 3) for v in target],
            believed=[round(v, 3) for v in believed[-1]] if believed else None,
        )

    def node_leaves(self) -> None:
        report("stop_planner", True)
        started = time.monotonic()
        gone = self.spin_until(lambda: "planner" not in self.node.get_node_names(), 30.0)
        report(
            "planner_left",
            gone,
            after_s=round(time.monotonic() - started, 3),
            nodes=sorted(set(self.node.get_node_names()) - {self.node.get_name()}),
        )


STEPS = (
    "nav2_active",
    "costmaps",
    "parameters",
    "graph",
    "battery",
    "late_map",
    "clock",
    "drive",
    "drive_stamped",
    "drive_mixed",
    "paths",
    "navigate",
    "behaviors",
    "sequences",
    "follow_path",
    "lifecycle",
    "goal_pose",
    "cancel",
    "dock",
    "undock",
    "bad_input",
    "initial_pose",
    "node_leaves",
)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", default=",".join(STEPS), help="comma-separated, in order")
    args = parser.parse_args(argv)
    rclpy.init()
    node = Node("ros2_user")
    user = User(node)
    try:
        for step in args.steps.split(","):
            started = time.monotonic()
            try:
                getattr(user, step)()
            except Exception as exc:  # one step's failure is reported; the next steps still run
                report(step, False, error=f"{type(exc).__name__}: {exc}")
            print(
                json.dumps({"step": f"{step}_time", "ok": True, "s": round(time.monotonic() - started, 2)}),
                file=sys.stderr,
                flush=True,
            )
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
