"""The planner as a real process with the simulator and the pose service: navigate_to_pose end to end.

The robot must reach a goal behind a wall, and one beyond a glass partition the map does not show,
without a single collision; cancel and preempt must stop or redirect it; malformed goals are refused
with a reason; ``zendock nav`` drives it from the command line.
"""

from __future__ import annotations

import json
import math
import pathlib
import subprocess
import sys
from collections.abc import Iterator

import msgpack
import numpy as np
import pytest
import zenoh

from services.planner.occupancy_map import save_map
from services.planner.params import Params as PlannerParams
from services.planner.rasterize import map_from_world
from shared import topics
from shared.action import ActionClient, spin_in_background
from shared.geometry import Pose2D, wrap_angle
from shared.interface_types import UUID, GoalStatusCode
from shared.interfaces.lifecycle import (
    CHANGE_STATE,
    GET_STATE,
    MANAGE_LIFECYCLE_NODES,
    ChangeStateRequest,
    GetStateRequest,
    ManageLifecycleNodesRequest,
)
from shared.interfaces.lifecycle import Transition as LifecycleTransition
from shared.interfaces.map_server import COSTMAP_TOPIC, GET_MAP, GET_MAP_SERVICE, GetMapRequest
from shared.interfaces.navigation import (
    FOLLOW_WAYPOINTS,
    NAVIGATE_TO_POSE,
    FollowWaypointsGoal,
    LoadMapResponse,
    NavigateErrorCode,
    NavigateToPoseGoal,
)
from shared.interfaces.simulator import (
    SIM_STATE,
    TELEPORT,
    SimStateRequest,
    SimStateResponse,
    TeleportRequest,
)
from shared.lifecycle import Command, Transition
from shared.messages import (
    Clock,
    CollisionEvent,
    Header,
    OccupancyGrid,
    Odometry,
    Path,
    Pose,
    PoseStamped,
    Twist,
)
from shared.names import stats_key
from shared.navigation import NavigationClient, TaskResult
from shared.node import Node, call_service
from shared.topics import SIM_TELEPORT
from shared.world import load_world
from tests.support.bus import KeyRecorder
from tests.support.processes import REPO_ROOT, wait_until

SEED_ROOM = str(REPO_ROOT / "deploy/worlds/seed_room.yaml")
GLASS_ROOM = str(REPO_ROOT / "deploy/worlds/glass_room.yaml")
RTF = "4"
#: Wall-clock allowance for one goal on a busy machine (a few seconds of it at rtf 4 when idle).
GOAL_TIMEOUT_S = 90.0
#: Ground truth may end a little outside the goal tolerances (0.05 m, 0.05 rad): the robot is still
#: coasting to a stop when the goal is declared reached, and on a loaded machine the pose it judged
#: by is a little late.
XY_SLACK_M = 0.08
YAW_SLACK_RAD = 0.15


@pytest.fixture
def nav_node(bus: zenoh.Session, namespace: str) -> Iterator[Node]:
    node = Node("test_navigator", bus, namespace)
    spin_in_background(node)
    yield node
    node.shutdown()
    node.close()


def _state(bus: zenoh.Session, ns: str) -> SimStateResponse:
    return call_service(bus, f"{ns}/simulator/state", SIM_STATE, SimStateRequest(), timeout_s=5.0)


def _start_stack(spawn, world: str, *planner_args: str):  # type: ignore[no-untyped-def]
    spawn("simulator", "--world", world, "-p", f"rtf={RTF}")
    spawn("pose", "-p", "use_sim_time=true")
    return spawn("planner", "-p", "use_sim_time=true", *planner_args)


def _wait_done(nav: NavigationClient, timeout_s: float = GOAL_TIMEOUT_S) -> TaskResult:
    wait_until(
        nav.is_task_complete, timeout_s, lambda: f"goal still running; last feedback {nav.get_feedback()}"
    )
    return nav.get_result()


def _assert_at(bus: zenoh.Session, ns: str, goal: Pose2D) -> None:
    truth = _state(bus, ns).pose.to_pose2d()
    assert truth.distance_to(goal) < XY_SLACK_M, f"robot at {truth}, goal {goal}"
    assert abs(wrap_angle(truth.yaw - goal.yaw)) < YAW_SLACK_RAD, f"robot at {truth}, goal {goal}"


def _assert_no_errors(planner) -> None:  # type: ignore[no-untyped-def]
    out = planner.output()
    assert "Traceback" not in out and "callback failed" not in out, out[-3000:]


def _moving(odom: KeyRecorder[Odometry], min_speed_mps: float = 0.2) -> bool:
    latest = odom.latest()
    return latest is not None and abs(latest.twist.twist.linear.x) > min_speed_mps


def _raw_goal_with_nan(nan_field: str) -> bytes:
    """A send_goal request whose goal pose has a NaN: no zendock sender would encode it."""
    request = NAVIGATE_TO_POSE.send_goal_request(
        goal_id=UUID.random(), goal=NavigateToPoseGoal(pose=PoseStamped(Header(frame_id="map"), Pose()))
    )
    doc = msgpack.unpackb(request.encode())
    doc["goal"]["pose"]["pose"]["position"][nan_field] = math.nan
    return msgpack.packb(doc)


def test_goal_behind_a_wall_is_reached_and_bad_goals_are_refused(  # type: ignore[no-untyped-def]
    spawn, bus: zenoh.Session, namespace: str, nav_node: Node, router_endpoint: str, tmp_path: pathlib.Path
) -> None:
    world = load_world(SEED_ROOM)
    map_yaml, _ = save_map(map_from_world(world), tmp_path / "maps" / "seed_room.yaml")
    collisions = KeyRecorder(bus, f"{namespace}/collisions", CollisionEvent)
    cmd_vel = KeyRecorder(bus, f"{namespace}/cmd_vel", Twist)
    plans = KeyRecorder(bus, f"{namespace}/plan", Path)
    maps = KeyRecorder(bus, f"{namespace}/map", OccupancyGrid)
    clock = KeyRecorder(bus, f"{namespace}/clock", Clock)
    planner = _start_stack(spawn, SEED_ROOM, "-p", f"map_yaml={map_yaml}")
    nav = NavigationClient(nav_node)
    assert nav.wait_until_active(30.0), "navigate_to_pose server never came up"

    # The map is published, and served on request to late joiners.
    published = maps.wait_for(timeout_s=20.0)
    served = call_service(bus, f"{namespace}/{GET_MAP_SERVICE}", GET_MAP, GetMapRequest()).map
    assert (
        (served.info.width, served.info.height) == (published.info.width, published.info.height) == (140, 112)
    )
    np.testing.assert_array_equal(served.data, map_from_world(world).data.ravel())

    # Malformed goals are refused, each with its reason, and nothing moves.
    refusals = {
        "outside the map": Pose2D(20.0, 20.0, 0.0),
        "lethal": Pose2D(-2.0, 3.8, 0.0),  # inside the box
        "frame_id": PoseStamped(Header(frame_id="odom"), Pose.from_pose2d(Pose2D(0.0, 2.0, 0.0))),
    }
    for reason, goal in refusals.items():
        nav.go_to_pose(goal)
        assert _wait_done(nav, 10.0) is TaskResult.FAILED
        assert reason in nav.failure_reason(), nav.failure_reason()
    for axis in ("x", "y"):
        replies = list(
            bus.get(
                f"{namespace}/navigate_to_pose/_action/send_goal",
                payload=_raw_goal_with_nan(axis),
                timeout=5.0,
            )
        )
        assert replies and replies[0].err is not None, "a NaN goal was not refused"
        assert "finite" in replies[0].err.payload.to_string()
    assert cmd_vel.count == 0, "a refused goal moved the robot"

    # The real goal: behind the interior wall, so the robot must go round its west end.
    goal = Pose2D(2.2, 2.5, 0.0)
    nav.go_to_pose(goal)
    assert _wait_done(nav) is TaskResult.SUCCEEDED, nav.failure_reason()
    _assert_at(bus, namespace, goal)
    assert collisions.count == 0 and _state(bus, namespace).collisions == 0
    path = plans.wait_for(timeout_s=5.0)
    assert path.header.frame_id == "map" and len(path.poses) > 10
    assert min(p.pose.position.x for p in path.poses) < 1.2, "the plan did not go round the wall's end"

    # One zero command when it stops, then silence on cmd_vel.
    stopped_count = cmd_vel.count
    last = cmd_vel.latest()
    assert last is not None and last.linear.x == 0.0 and last.angular.z == 0.0
    now = clock.wait_for(timeout_s=5.0, after=clock.count).clock.to_sec()
    clock.wait_for(lambda m: m.clock.to_sec() > now + 1.0, timeout_s=20.0, after=clock.count)
    assert cmd_vel.count == stopped_count, "cmd_vel kept coming after the goal ended"

    # The command line drives it to the tutorial's staging pose.
    staging = Pose2D(0.0, 2.0, -math.pi / 2)
    cli = subprocess.run(
        [
            sys.executable,
            "-m",
            "deploy.cli",
            "nav",
            str(staging.x),
            str(staging.y),
            str(staging.yaw),
            "--namespace",
            namespace,
            "--connect",
            router_endpoint,
            "--timeout",
            str(GOAL_TIMEOUT_S),
        ],
        cwd=REPO_ROOT,
        capture_output=True,
        text=True,
        timeout=GOAL_TIMEOUT_S + 30,
    )
    assert cli.returncode == 0, cli.stdout + cli.stderr
    assert "distance remaining" in cli.stdout and "goal reached" in cli.stdout, cli.stdout
    _assert_at(bus, namespace, staging)
    assert collisions.count == 0

    # The map can be swapped at run time (and a missing file is reported), the costmaps cleared.
    glass_map = map_from_world(load_world(GLASS_ROOM))
    glass_yaml, _ = save_map(glass_map, tmp_path / "maps" / "glass_room.yaml")
    seen = maps.count
    assert nav.change_map(str(glass_yaml)).result == LoadMapResponse.RESULT_SUCCESS
    maps.wait_for(lambda m: np.array_equal(m.data, glass_map.data.ravel()), timeout_s=10.0, after=seen)
    missing = nav.change_map(str(tmp_path / "maps" / "missing.yaml"))
    assert missing.result == LoadMapResponse.RESULT_MAP_DOES_NOT_EXIST
    served = call_service(bus, f"{namespace}/{GET_MAP_SERVICE}", GET_MAP, GetMapRequest()).map
    np.testing.assert_array_equal(served.data, glass_map.data.ravel())
    nav.clear_all_costmaps()
    _assert_no_errors(planner)


def test_cancel_stops_the_robot_and_a_new_goal_preempts(  # type: ignore[no-untyped-def]
    spawn, bus: zenoh.Session, namespace: str, nav_node: Node
) -> None:
    odom = KeyRecorder(bus, f"{namespace}/odom", Odometry)
    cmd_vel = KeyRecorder(bus, f"{namespace}/cmd_vel", Twist)
    collisions = KeyRecorder(bus, f"{namespace}/collisions", CollisionEvent)
    planner = _start_stack(spawn, SEED_ROOM, "-p", f"world={SEED_ROOM}")
    nav = NavigationClient(nav_node)
    assert nav.wait_until_active(30.0)

    # Cancel mid-way: CANCELED, one zero command, the robot stands still.
    far = Pose2D(-1.5, 1.6, 0.0)
    nav.go_to_pose(far)
    wait_until(lambda: _moving(odom), GOAL_TIMEOUT_S, lambda: f"robot never got going: {nav.get_feedback()}")
    nav.cancel_task()
    assert _wait_done(nav, 20.0) is TaskResult.CANCELED
    detail = nav.get_result_detail()
    assert detail is not None and detail.error_code == NavigateErrorCode.CANCELED
    canceled_at = _state(bus, namespace).stamp.to_sec()
    last = cmd_vel.latest()
    assert last is not None and (last.linear.x, last.angular.z) == (0.0, 0.0)
    stopped_count = cmd_vel.count
    odom.wait_for(lambda m: m.header.stamp.to_sec() > canceled_at + 0.5, timeout_s=20.0, after=odom.count)
    assert abs(odom.latest().twist.twist.linear.x) < 0.01  # type: ignore[union-attr]
    assert cmd_vel.count == stopped_count, "cmd_vel kept coming after the cancel"

    # Preempt: a second goal from another client replaces the first, which ends CANCELED (preempted).
    other = NavigationClient(nav_node)
    nav.go_to_pose(far)
    wait_until(lambda: _moving(odom), GOAL_TIMEOUT_S, lambda: f"robot never got going: {nav.get_feedback()}")
    near = Pose2D(0.5, 4.0, math.pi)
    other.go_to_pose(near)
    assert _wait_done(nav, 20.0) is TaskResult.CANCELED
    detail = nav.get_result_detail()
    assert detail is not None and detail.error_code == NavigateErrorCode.PREEMPTED
    assert _wait_done(other) is TaskResult.SUCCEEDED, other.failure_reason()
    _assert_at(bus, namespace, near)
    assert collisions.count == 0
    _assert_no_errors(planner)


def test_glass_absent_from_the_map_is_found_and_avoided(  # type: ignore[no-untyped-def]
    spawn, bus: zenoh.Session, namespace: str, nav_node: Node
) -> None:
    world = load_world(GLASS_ROOM)
    (gx1, gy), (gx2, _) = world.glass[0]
    collisions = KeyRecorder(bus, f"{namespace}/collisions", CollisionEvent)
    costmaps = KeyRecorder(bus, f"{namespace}/{COSTMAP_TOPIC}", OccupancyGrid, keep=3)
    # A slow-down radius of 1.5 m, not the default 0.8: the robot plans clear of the pane it suspects, and
    # often never has heard glass ahead within 0.8 m, so it would have no cause to slow.
    params = {"world": GLASS_ROOM, "costmap_publish_period_s": 0.5, "glass_slowdown_radius_m": 1.5}
    planner = _start_stack(spawn, GLASS_ROOM, *(w for k, v in params.items() for w in ("-p", f"{k}={v}")))
    nav = NavigationClient(nav_node)
    assert nav.wait_until_active(30.0)

    goal = Pose2D(0.5, 1.5, 0.0)  # beyond the partition; the straight route crosses the glass
    nav.go_to_pose(goal)
    assert _wait_done(nav) is TaskResult.SUCCEEDED, nav.failure_reason()
    _assert_at(bus, namespace, goal)
    assert collisions.count == 0 and _state(bus, namespace).collisions == 0, collisions.messages

    # The glass is in the costmap (through the sonar) though the map shows open floor there.
    occupancy = map_from_world(world)
    costmap = costmaps.wait_for(timeout_s=10.0, after=costmaps.count)
    costs = np.asarray(costmap.data).reshape(costmap.info.height, costmap.info.width)
    along = np.stack([np.linspace(gx1 + 0.2, gx2 - 0.2, 40), np.full(40, gy)], axis=1)
    cells = occupancy.frame.world_to_cells(along)
    assert (occupancy.data[cells[:, 1], cells[:, 0]] == 0).all(), "the map should not show the glass"
    assert (costs[cells[:, 1], cells[:, 0]] >= 99).any(), "no glass cell was marked in the costmap"
    # it slowed for the pane it heard, and counts how long (where a campaign's time goes)
    (reply,) = list(bus.get(stats_key(namespace, "planner"), timeout=5.0))
    extra = json.loads(reply.ok.payload.to_bytes())["extra"]
    assert extra[topics.GLASS_SLOWED_STAT] > 0.0, extra
    # and how far it drove meanwhile: more than nothing, less than those seconds at full speed
    slowed_m, slowed_s = extra[topics.GLASS_SLOWED_M_STAT], extra[topics.GLASS_SLOWED_STAT]
    assert 0.0 < slowed_m < slowed_s * PlannerParams().max_linear_vel_mps, extra
    _assert_no_errors(planner)


def test_a_robot_put_down_facing_a_wall_finds_no_glass_there(  # type: ignore[no-untyped-def]
    spawn, bus: zenoh.Session, namespace: str
) -> None:
    """Trials put the robot down anywhere between dockings. A sonar reading from before must not be
    placed where the robot now stands, and an echo from the new place must be compared with a scan from
    there: either way the wall it heard became glass, and the floor round it, suspected glass, boxed
    the robot in."""
    costmaps = KeyRecorder(bus, f"{namespace}/{COSTMAP_TOPIC}", OccupancyGrid, keep=3)
    clock = KeyRecorder(bus, f"{namespace}/clock", Clock, keep=1)
    # Idle costmap updates 2 s apart: sonar readings from the new place wait that long to be folded in.
    planner = _start_stack(
        spawn,
        GLASS_ROOM,
        "-p",
        f"world={GLASS_ROOM}",
        "-p",
        "costmap_publish_period_s=0.5",
        "-p",
        "idle_costmap_update_rate_hz=0.5",
    )
    costmaps.wait_for(timeout_s=30.0)
    occupancy = map_from_world(load_world(GLASS_ROOM))
    frame = occupancy.frame
    ys, xs = np.mgrid[0 : frame.height, 0 : frame.width]
    centres = frame.cells_to_world(np.stack([xs.ravel(), ys.ravel()], axis=1))
    occupied = centres[occupancy.data.ravel() > 50]
    # 0.47 m from two walls, facing the corner between them: three corners of the room.
    for put_down in (Pose2D(-2.53, 4.52, -2.57), Pose2D(2.53, 4.52, -0.57), Pose2D(2.53, 0.9, 0.57)):
        reply = call_service(
            bus,
            f"{namespace}/{SIM_TELEPORT}",
            TELEPORT,
            TeleportRequest(x=put_down.x, y=put_down.y, yaw=put_down.yaw),
            timeout_s=5.0,
        )
        assert reply.success, reply.message
        teleported_s = clock.wait_for(timeout_s=5.0, after=clock.count).clock.to_sec()
        clock.wait_for(
            lambda m, t=teleported_s: m.clock.to_sec() > t + 5.0, timeout_s=30.0, after=clock.count
        )
        costmap = costmaps.wait_for(timeout_s=10.0, after=costmaps.count)
        costs = np.asarray(costmap.data).reshape(costmap.info.height, costmap.info.width)
        near = centres[np.hypot(centres[:, 0] - put_down.x, centres[:, 1] - put_down.y) < 0.7]
        floor = near[[np.hypot(*(occupied - c).T).min() >= 0.22 for c in near]]  # beyond walls' inflation
        cells = frame.world_to_cells(floor)
        blocked = floor[costs[cells[:, 1], cells[:, 0]] >= 99]
        assert len(blocked) == 0, (
            f"put down at {put_down}: open floor counted as an obstacle at {np.round(blocked, 2).tolist()}"
        )
    _assert_no_errors(planner)


def test_a_goal_behind_a_wall_of_glass_fails_after_recoveries_without_touching_it(  # type: ignore[no-untyped-def]
    spawn, bus: zenoh.Session, namespace: str, nav_node: Node, tmp_path: pathlib.Path
) -> None:
    world_file = tmp_path / "glass_wall.yaml"
    world_file.write_text(
        "name: glass_wall\nbounds: [0.0, 0.0, 4.0, 3.0]\nglass:\n  - [[2.0, 0.0], [2.0, 3.0]]\n"
        "robot: {start: [1.0, 1.5, 0.0]}\n"
    )
    collisions = KeyRecorder(bus, f"{namespace}/collisions", CollisionEvent)
    planner = _start_stack(spawn, str(world_file), "-p", f"world={world_file}", "-p", "max_recoveries=1")
    nav = NavigationClient(nav_node)
    assert nav.wait_until_active(30.0)

    nav.go_to_pose(Pose2D(3.0, 1.5, 0.0))  # the map shows open floor all the way
    assert _wait_done(nav) is TaskResult.FAILED
    detail = nav.get_result_detail()
    assert detail is not None, nav.failure_reason()
    assert detail.error_code in (NavigateErrorCode.NO_VALID_PATH, NavigateErrorCode.STUCK), detail
    assert "gave up after 1 recoveries" in detail.error_msg, detail.error_msg
    assert collisions.count == 0 and _state(bus, namespace).collisions == 0
    assert _state(bus, namespace).pose.position.x < 2.0 - 0.2  # never reached the pane
    _assert_no_errors(planner)


def test_without_the_range_layer_the_robot_drives_into_the_glass(  # type: ignore[no-untyped-def]
    spawn, bus: zenoh.Session, namespace: str, nav_node: Node
) -> None:
    """The control experiment: the lidar-built map has no glass, so only the sonar keeps the robot off it."""
    collisions = KeyRecorder(bus, f"{namespace}/collisions", CollisionEvent)
    _start_stack(spawn, GLASS_ROOM, "-p", f"world={GLASS_ROOM}", "-p", "use_range_layer=false")
    nav = NavigationClient(nav_node)
    assert nav.wait_until_active(30.0)
    nav.go_to_pose(Pose2D(0.5, 1.5, 0.0))
    hit = collisions.wait_for(lambda m: m.kind == "glass", timeout_s=GOAL_TIMEOUT_S)
    assert hit.count >= 1
    nav.cancel_task()


def test_a_navigation_goal_from_elsewhere_ends_a_waypoint_sequence(  # type: ignore[no-untyped-def]
    spawn, bus: zenoh.Session, namespace: str, nav_node: Node
) -> None:
    """follow_waypoints drives the planner's own navigate_to_pose; when another goal takes the robot (zendock's
    docking, say), the sequence ends with a reason instead of taking the robot back with its next leg."""
    odom = KeyRecorder(bus, f"{namespace}/odom", Odometry)
    planner = _start_stack(spawn, SEED_ROOM, "-p", f"world={SEED_ROOM}")
    waypoints = ActionClient(nav_node, FOLLOW_WAYPOINTS, "follow_waypoints")
    assert waypoints.server_ready(30.0)
    poses = [
        PoseStamped(Header(frame_id="map"), Pose.from_pose2d(Pose2D(x, y, 0.0)))
        for x, y in ((-1.5, 1.6), (0.5, 4.0))
    ]
    sequence = waypoints.send_goal(FollowWaypointsGoal(poses=poses))
    wait_until(lambda: _moving(odom), GOAL_TIMEOUT_S, "the robot never got going on the first waypoint")
    other = NavigationClient(nav_node)
    near = Pose2D(0.5, 4.0, math.pi)
    other.go_to_pose(near)
    wait_until(lambda: sequence.done, 20.0, lambda: f"the sequence went on: {sequence}")
    assert sequence.status is GoalStatusCode.ABORTED, sequence
    assert sequence.result is not None and "taken by another goal" in sequence.result.error_msg, sequence
    assert _wait_done(other) is TaskResult.SUCCEEDED, other.failure_reason()  # not taken back
    _assert_at(bus, namespace, near)
    _assert_no_errors(planner)


def _lifecycle_state(bus: zenoh.Session, ns: str, nav2_node: str) -> str:
    response = call_service(bus, f"{ns}/{nav2_node}/get_state", GET_STATE, GetStateRequest(), timeout_s=5.0)
    return response.current_state.label


def _change(bus: zenoh.Session, ns: str, nav2_node: str, transition: Transition) -> bool:
    request = ChangeStateRequest(LifecycleTransition(id=int(transition), label=transition.label))
    return call_service(bus, f"{ns}/{nav2_node}/change_state", CHANGE_STATE, request, timeout_s=5.0).success


def _manage(bus: zenoh.Session, ns: str, manager: str, command: Command) -> bool:
    request = ManageLifecycleNodesRequest(command=int(command))
    key = f"{ns}/{manager}/manage_nodes"
    return call_service(bus, key, MANAGE_LIFECYCLE_NODES, request, timeout_s=20.0).success


def test_a_navigator_taken_out_of_active_stops_the_robot_and_refuses_goals_until_activated(  # type: ignore[no-untyped-def]
    spawn, bus: zenoh.Session, namespace: str, nav_node: Node
) -> None:
    """Nav2's lifecycle on the stand-ins: deactivating bt_navigator cancels its running goal and refuses
    the next with a reason; a lifecycle manager moves the nodes it manages, across services, and a
    STARTUP of nodes already active fails as Nav2's does."""
    odom = KeyRecorder(bus, f"{namespace}/odom", Odometry)
    planner = _start_stack(spawn, SEED_ROOM, "-p", f"world={SEED_ROOM}")
    nav = NavigationClient(nav_node)
    assert nav.wait_until_active(30.0)
    nav.go_to_pose(Pose2D(-1.5, 1.6, 0.0))
    wait_until(lambda: _moving(odom), GOAL_TIMEOUT_S, lambda: f"robot never got going: {nav.get_feedback()}")

    assert _change(bus, namespace, "bt_navigator", Transition.DEACTIVATE)
    assert _wait_done(nav, 20.0) is TaskResult.CANCELED
    assert _lifecycle_state(bus, namespace, "bt_navigator") == "inactive"
    assert _lifecycle_state(bus, namespace, "planner_server") == "active"  # one node, not the service
    odom.wait_for(lambda m: abs(m.twist.twist.linear.x) < 0.01, timeout_s=20.0, after=odom.count)
    nav.go_to_pose(Pose2D(0.5, 4.0, math.pi))
    wait_until(nav.is_task_complete, 10.0, "a goal to an inactive bt_navigator was neither refused nor done")
    assert "bt_navigator is inactive" in nav.failure_reason(), nav.failure_reason()
    assert not _change(bus, namespace, "bt_navigator", Transition.DEACTIVATE)  # already inactive

    # the localisation manager (served by the pose service) moves the planner's map_server and its own amcl
    assert _manage(bus, namespace, "lifecycle_manager_localization", Command.PAUSE)
    assert {_lifecycle_state(bus, namespace, n) for n in ("map_server", "amcl")} == {"inactive"}
    assert _manage(bus, namespace, "lifecycle_manager_localization", Command.RESUME)
    assert {_lifecycle_state(bus, namespace, n) for n in ("map_server", "amcl")} == {"active"}

    assert _change(bus, namespace, "bt_navigator", Transition.ACTIVATE)
    nav.go_to_pose(Pose2D(0.5, 4.0, math.pi))
    wait_until(
        lambda: _moving(odom), GOAL_TIMEOUT_S, lambda: f"robot never got going: {nav.failure_reason()}"
    )
    nav.cancel_task()
    assert _wait_done(nav, 20.0) is TaskResult.CANCELED
    # STARTUP configures first: nodes already active refuse it, and the command fails, as Nav2's would
    assert not _manage(bus, namespace, "lifecycle_manager_navigation", Command.STARTUP)
    assert _lifecycle_state(bus, namespace, "controller_server") == "active"
    _assert_no_errors(planner)
