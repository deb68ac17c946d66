"""ROS 2 peers zendock did not write (zenoh-ros2-sdk, rmw_zenoh's wire) list, echo and drive a zendock robot."""

from __future__ import annotations

import json
import math
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import zenoh
import zenoh.ext

from services.planner.occupancy_map import save_map
from services.planner.rasterize import map_from_world
from shared.geometry import Pose2D
from shared.messages import BatteryState, Float64MultiArray, PoseStamped, TFMessage
from shared.ros2 import types as ros_types
from shared.ros2.wire import ADMIN_SPACE, Attachment, data_key, entity_gid
from shared.world import load_world
from tests.support.bus import KeyRecorder
from tests.support.processes import REPO_ROOT, wait_until

SEED_ROOM = str(REPO_ROOT / "deploy/worlds/seed_room.yaml")


def _peer(router: str, *args: str, timeout_s: float = 60.0) -> list[Any]:
    """Run the peer to the end; its JSON lines (failing with its output when it fails)."""
    done = subprocess.run(
        [sys.executable, "-m", "tests.support.ros2_peer", "--router", router, *args],
        capture_output=True,
        text=True,
        timeout=timeout_s,
        cwd=REPO_ROOT,
        check=False,
    )
    assert done.returncode == 0, f"ros2_peer {' '.join(args)} failed:\n{done.stdout}\n{done.stderr[-3000:]}"
    return [json.loads(line) for line in done.stdout.splitlines() if line.strip()]


def _publisher_token(bus: zenoh.Session, topic: str) -> str:
    """The liveliness key of the (one) ROS 2 publisher of ``topic`` in domain 0."""
    mangled = topic.replace("/", "%")
    keys = [str(r.ok.key_expr) for r in bus.liveliness().get(f"{ADMIN_SPACE}/0/**", timeout=5.0) if r.ok]
    found = [k for k in keys if k.split("/")[5] == "MP" and k.split("/")[9] == mangled]
    assert len(found) == 1, keys
    return found[0]


@contextmanager
def _publishing(router: str, *args: str) -> Iterator[subprocess.Popen[str]]:
    proc = subprocess.Popen(
        [sys.executable, "-m", "tests.support.ros2_peer", "--router", router, "pub", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=REPO_ROOT,
    )
    try:
        yield proc
    finally:
        proc.kill()
        proc.communicate(timeout=10)


def test_a_ros2_peer_lists_zendock_topics_and_echoes_the_battery(
    spawn, bus: zenoh.Session, namespace: str, router_endpoint: str
) -> None:  # type: ignore[no-untyped-def]
    ours = KeyRecorder(bus, f"{namespace}/battery_status", BatteryState)
    battery = spawn("battery")
    bridge = spawn("ros2_bridge")
    ours.wait_for(timeout_s=30.0)
    listed = _peer(router_endpoint, "topics", "--wait-for", "/battery_status")[0]
    assert listed["/battery_status"] == ["sensor_msgs/msg/BatteryState"]
    # Only the services that are up are ROS 2 nodes: no simulator, no planner, so no /scan and no /map.
    assert "/scan" not in listed and "/map" not in listed and "/cmd_vel" not in listed, listed
    assert _peer(router_endpoint, "nodes")[0] == ["battery", "ros2_bridge"]
    info = _peer(router_endpoint, "info", "/battery_status")[0]
    assert info["publishers"] == [{"node": "battery", "namespace": "/", "qos": "::,10:,:,:,,"}]

    # What rides with each sample, seen by a plain Zenoh subscriber on the data key while the peer echoes.
    attachments: list[Attachment] = []
    key = data_key(
        0,
        "/battery_status",
        "sensor_msgs/msg/BatteryState",
        ros_types.type_hash("sensor_msgs/msg/BatteryState"),
    )
    raw = bus.declare_subscriber(
        key, lambda s: attachments.append(Attachment.decode(s.attachment.to_bytes()))
    )
    echoed = _peer(router_endpoint, "echo", "/battery_status", "sensor_msgs/msg/BatteryState", "--count", "3")
    assert len(echoed) == 3
    raw.undeclare()
    # rmw_zenoh numbers a publisher's samples from 1 (rmw_publisher_data.cpp: PublisherData's
    # sequence_number_(1), sequence_number_++ per put), and its gid is the XXH3-128 hash of its liveliness
    # key (liveliness_utils.cpp, Entity::Entity: simplified_XXH3_128bits), the gid rmw_zenoh's graph has.
    assert [a.sequence_number for a in attachments] == list(range(1, len(attachments) + 1)), attachments
    assert {a.gid for a in attachments} == {entity_gid(_publisher_token(bus, "/battery_status"))}
    for msg in echoed:
        stamp = (msg["header"]["stamp"]["sec"], msg["header"]["stamp"]["nanosec"])
        same = [m for m in ours.messages if (m.header.stamp.sec, m.header.stamp.nanosec) == stamp]
        assert same, f"no zendock battery message stamped {stamp}"
        assert math.isclose(msg["percentage"], same[0].percentage, rel_tol=1e-6)
        assert msg["power_supply_status"] == same[0].power_supply_status
    wait_until(
        lambda: "no ROS 2 subscription to /battery_status left" in bridge.output(),
        10.0,
        lambda: bridge.output()[-2000:],
    )
    battery.stop()
    wait_until(lambda: "zendock's battery is gone" in bridge.output(), 10.0, lambda: bridge.output()[-2000:])
    assert _peer(router_endpoint, "nodes")[0] == ["ros2_bridge"]


def test_a_ros2_peer_drives_the_robot_and_bad_input_is_refused(
    spawn, bus: zenoh.Session, namespace: str, router_endpoint: str
) -> None:  # type: ignore[no-untyped-def]
    truth = KeyRecorder(bus, f"{namespace}/ground_truth_pose", PoseStamped)
    tf_static = KeyRecorder(bus, f"{namespace}/tf_static", TFMessage)
    # tf_static every 10 s: a late subscriber's first one comes from the bridge's cache, not a fresh one.
    spawn("simulator", "--world", SEED_ROOM, "-p", "rtf=1", "-p", "tf.static_rate_hz=0.1")
    bridge = spawn("ros2_bridge")
    key = data_key(0, "/tf_static", "tf2_msgs/msg/TFMessage", ros_types.type_hash("tf2_msgs/msg/TFMessage"))
    put_at: dict[int, float] = {}  # sequence number -> when the bridge's put reached the bus
    raw = bus.declare_subscriber(
        key,
        lambda s: put_at.setdefault(
            Attachment.decode(s.attachment.to_bytes()).sequence_number, time.monotonic()
        ),
    )
    start = truth.wait_for(timeout_s=30.0).pose.to_pose2d()
    wait_until(lambda: "zendock's simulator is up" in bridge.output(), 30.0, lambda: bridge.output()[-2000:])
    listed = _peer(router_endpoint, "topics", "--wait-for", "/scan")[0]
    assert listed["/scan"] == ["sensor_msgs/msg/LaserScan"]
    assert set(listed["/cmd_vel"]) == {"geometry_msgs/msg/Twist", "geometry_msgs/msg/TwistStamped"}

    # RViz's pose estimate: the localiser believes the robot is there, the robot does not move.
    believed = KeyRecorder(bus, f"{namespace}/map_to_base_link_pose2d", Float64MultiArray)
    spawn("pose", "-p", "use_sim_time=true")
    believed.wait_for(timeout_s=30.0)
    estimate = Pose2D(start.x + 0.3, start.y - 0.2, start.yaw + 0.4)
    half = estimate.yaw / 2
    _peer(
        router_endpoint,
        "pub",
        "/initialpose",
        "geometry_msgs/msg/PoseWithCovarianceStamped",
        json.dumps(
            {
                "header": {"frame_id": "map"},
                "pose": {
                    "pose": {
                        "position": {"x": estimate.x, "y": estimate.y},
                        "orientation": {"z": math.sin(half), "w": math.cos(half)},
                    }
                },
            }
        ),
        "--rate",
        "2",
        "--seconds",
        "1",
    )
    believed.wait_for(
        lambda m: (
            math.hypot(m.data[0] - estimate.x, m.data[1] - estimate.y) < 0.01
            and abs(math.remainder(m.data[2] - estimate.yaw, math.tau)) < 0.01
        ),
        timeout_s=20.0,
    )
    assert truth.latest().pose.to_pose2d().distance_to(start) < 0.01  # type: ignore[union-attr]

    def moved(msg: PoseStamped) -> bool:
        pose = msg.pose.to_pose2d()
        return math.hypot(pose.x - start.x, pose.y - start.y) > 0.05

    with _publishing(
        router_endpoint, "/cmd_vel", "geometry_msgs/msg/Twist", '{"linear": {"x": 0.2}}', "--seconds", "20"
    ):
        truth.wait_for(moved, timeout_s=30.0, after=truth.count)

    # TwistStamped, as Jazzy's controllers send it: turn on the spot.
    heading = truth.wait_for(timeout_s=10.0, after=truth.count).pose.to_pose2d().yaw
    with _publishing(
        router_endpoint,
        "/cmd_vel",
        "geometry_msgs/msg/TwistStamped",
        '{"twist": {"angular": {"z": 0.8}}}',
        "--seconds",
        "20",
    ):
        truth.wait_for(
            lambda m: abs(math.remainder(m.pose.to_pose2d().yaw - heading, math.tau)) > 0.2,
            timeout_s=30.0,
            after=truth.count,
        )

    # A type hash that is not Jazzy's, and bytes that are not CDR: refused by name, the bridge lives on.
    with _publishing(
        router_endpoint,
        "/cmd_vel",
        "geometry_msgs/msg/Twist",
        '{"linear": {"x": 0.2}}',
        "--type-hash",
        "RIHS01_" + "00" * 32,
        "--seconds",
        "20",
    ):
        wait_until(lambda: "is not Jazzy's" in bridge.output(), 30.0, lambda: bridge.output()[-2000:])
    twist_hash = ros_types.type_hash("geometry_msgs/msg/Twist")
    bus.put(data_key(0, "/cmd_vel", "geometry_msgs/msg/Twist", twist_hash), b"\x00\x01\x00\x00\x01")
    bus.put(
        data_key(
            0,
            "/goal_pose",
            "geometry_msgs/msg/PoseStamped",
            ros_types.type_hash("geometry_msgs/msg/PoseStamped"),
        ),
        b"\x93garbage",
    )
    bus.put(f"0/cmd_vel/geometry_msgs::msg::dds_::Vector3_/{twist_hash}", b"\x00\x01\x00\x00" + bytes(24))
    wait_until(
        lambda: (
            "refused a message on /cmd_vel" in bridge.output()
            and "refused a message on /goal_pose" in bridge.output()
            and "refused /cmd_vel as geometry_msgs::msg::dds_::Vector3_" in bridge.output()
        ),
        30.0,
        lambda: bridge.output()[-2000:],
    )
    assert bridge.alive(), "the bridge died on bad input"

    # /tf_static is transient local: a subscriber joining late gets the cached message from the bridge's
    # AdvancedPublisher, under the topic's own key, with no ROS 2 subscription token to prompt a re-send.
    wait_until(lambda: bool(put_at), 10.0, "the bridge never published /tf_static")
    raw.undeclare()
    # The publisher announces itself where late-publisher detection looks (zenoh-ext's @adv/pub token).
    assert [r for r in bus.liveliness().get(f"{key}/@adv/pub/**", timeout=5.0) if r.ok]
    late: list[zenoh.Sample] = []
    # Configured as rmw_zenoh configures a TRANSIENT_LOCAL + RELIABLE subscription (rmw_subscription_data.cpp,
    # SubscriptionData::init): history of `depth` samples with detect_late_publishers, subscriber detection,
    # recovery on the publisher's heartbeats.
    subscriber = zenoh.ext.declare_advanced_subscriber(
        bus,
        key,
        late.append,
        history=zenoh.ext.HistoryConfig(detect_late_publishers=True, max_samples=1),
        recovery=zenoh.ext.RecoveryConfig(periodic_queries=None, heartbeat=True),
        subscriber_detection=True,
    )
    joined_at = time.monotonic()
    try:
        wait_until(lambda: bool(late), 5.0, "no cached /tf_static for a late subscriber")
    finally:
        subscriber.undeclare()
    cached = Attachment.decode(late[0].attachment.to_bytes())
    assert put_at.get(cached.sequence_number, math.inf) < joined_at, (
        "a fresh sample came first, not the cached one"
    )
    assert str(late[0].key_expr) == key
    assert cached.gid == entity_gid(_publisher_token(bus, "/tf_static"))
    frames = {
        t.child_frame_id
        for t in ros_types.from_cdr(late[0].payload.to_bytes(), "tf2_msgs/msg/TFMessage").transforms
    }
    assert {t.child_frame_id for t in tf_static.messages[-1].transforms} == frames
    assert "camera_optical_frame" in frames


def test_a_ros2_peer_asks_what_a_nav2_script_asks_of_nav2s_servers(
    spawn, router_endpoint: str, tmp_path: Path
) -> None:  # type: ignore[no-untyped-def]
    """``waitUntilNav2Active()`` polls ``amcl/get_state`` (lifecycle_msgs/srv/GetState) until ``active``: on
    rmw_zenoh's wire the bridge relays it to the pose service, which stands in for amcl. The costmap
    services come from the planner; without a robot pose the local costmap is an empty square in the
    grid's frame."""
    pose = spawn("pose")
    planner = spawn("planner", "-p", f"world={SEED_ROOM}")
    bridge = spawn("ros2_bridge")
    for service in (bridge, pose, planner):
        wait_until(lambda s=service: "ready" in s.output(), 30.0, lambda s=service: s.output()[-2000:])
    answer = _peer(router_endpoint, "call", "/amcl/get_state", "lifecycle_msgs/srv/GetState")[0]
    assert answer["response"]["current_state"] == {"id": 3, "label": "active"}, answer
    state = _peer(router_endpoint, "call", "/bt_navigator/get_state", "lifecycle_msgs/srv/GetState")[0]
    assert state["response"]["current_state"]["label"] == "active", state
    whole = _peer(router_endpoint, "call", "/global_costmap/get_costmap", "nav2_msgs/srv/GetCostmap")[0]
    meta = whole["response"]["map"]["metadata"]
    assert meta["size_x"] * meta["size_y"] == len(whole["response"]["map"]["data"]) > 0, meta
    assert 254 in whole["response"]["map"]["data"]  # the room's walls, lethal
    local = _peer(router_endpoint, "call", "/local_costmap/get_costmap", "nav2_msgs/srv/GetCostmap")[0]
    assert local["response"]["map"]["data"] == [], local  # no robot pose yet: an empty square
    assert local["response"]["map"]["metadata"]["resolution"] > 0.0, local  # in the grid's frame
    cleared = _peer(
        router_endpoint,
        "call",
        "/global_costmap/clear_entirely_global_costmap",
        "nav2_msgs/srv/ClearEntireCostmap",
    )[0]
    assert cleared["response"] is not None
    wait_until(lambda: "costmap cleared" in planner.output(), 10.0, lambda: planner.output()[-2000:])
    # changeMap(): a map file that is not there, then one that is (Nav2's result codes).
    load = ("call", "/map_server/load_map", "nav2_msgs/srv/LoadMap")
    missing = _peer(router_endpoint, *load, json.dumps({"map_url": str(tmp_path / "none.yaml")}))[0]
    assert missing["response"]["result"] == 1, missing  # RESULT_MAP_DOES_NOT_EXIST
    saved, _ = save_map(map_from_world(load_world(SEED_ROOM)), tmp_path / "room.yaml")
    loaded = _peer(router_endpoint, *load, json.dumps({"map_url": f"file://{saved}"}))[0]
    assert loaded["response"]["result"] == 0, loaded
    assert loaded["response"]["map"]["info"]["width"] > 0, loaded["response"]["map"]["info"]
    # The behaviours (BasicNavigator's spin, and wait): without a robot pose a spin cannot know how far it
    # turned, so it ends at once with Nav2's TF_ERROR and says why; a wait needs no pose.
    spin = _peer(router_endpoint, "action", "/spin", "nav2_msgs/action/Spin", '{"target_yaw": 1.0}')
    assert spin[0]["accepted"] is True, spin
    assert spin[1]["status"] == 6 and spin[1]["result"]["error_code"] == 702, spin  # ABORTED, TF_ERROR
    assert "no robot pose" in spin[1]["result"]["error_msg"], spin
    wait = _peer(router_endpoint, "action", "/wait", "nav2_msgs/action/Wait", '{"time": {"sec": 1}}')
    assert wait[1]["status"] == 4 and wait[1]["feedback"] > 0, wait  # SUCCEEDED, with time_left on the way
    assert wait[1]["result"]["total_elapsed_time"]["sec"] >= 1, wait
    # ros2 param: the planner's parameters as its ROS 2 node's, a read-only one refused with zendock's reason
    params = ("/planner/list_parameters", "rcl_interfaces/srv/ListParameters")
    names = _peer(router_endpoint, "call", *params)[0]["response"]["result"]["names"]
    assert "use_sim_time" in names and "waypoint_stop_on_failure" in names, names
    describe = ("call", "/planner/describe_parameters", "rcl_interfaces/srv/DescribeParameters")
    described = _peer(
        router_endpoint, *describe, json.dumps({"names": ["use_sim_time", "waypoint_stop_on_failure"]})
    )
    sim_time, stop = described[0]["response"]["descriptors"]
    assert sim_time["read_only"] and sim_time["type"] == 1 and not stop["read_only"], described
    get = ("call", "/planner/get_parameters", "rcl_interfaces/srv/GetParameters")
    value = _peer(router_endpoint, *get, json.dumps({"names": ["waypoint_stop_on_failure"]}))[0]
    current = value["response"]["values"][0]
    assert current["type"] == 1, value  # BOOL
    flip = {"type": 1, "bool_value": not current["bool_value"]}
    set_ = ("call", "/planner/set_parameters", "rcl_interfaces/srv/SetParameters")
    both = [{"name": "waypoint_stop_on_failure", "value": flip}, {"name": "use_sim_time", "value": flip}]
    results = _peer(router_endpoint, *set_, json.dumps({"parameters": both}))[0]["response"]["results"]
    assert results[0]["successful"], results
    assert not results[1]["successful"] and "read at start-up" in results[1]["reason"], results
    again = _peer(router_endpoint, *get, json.dumps({"names": ["waypoint_stop_on_failure"]}))[0]
    assert again["response"]["values"][0]["bool_value"] == flip["bool_value"], again
    # getPath(): from a given start (there is no robot pose here), then without one (Nav2's TF_ERROR).
    staging = {
        "header": {"frame_id": "map"},
        "pose": {"position": {"x": 0.0, "y": 2.0}, "orientation": {"w": 1.0}},
    }
    start = {
        "header": {"frame_id": "map"},
        "pose": {"position": {"x": 1.8, "y": 4.2}, "orientation": {"w": 1.0}},
    }
    compute = ("action", "/compute_path_to_pose", "nav2_msgs/action/ComputePathToPose")
    path = _peer(router_endpoint, *compute, json.dumps({"goal": staging, "start": start, "use_start": True}))
    assert path[1]["status"] == 4, path
    poses = path[1]["result"]["path"]["poses"]
    assert len(poses) > 2 and path[1]["result"]["path"]["header"]["frame_id"] == "map", path
    assert poses[-1]["pose"]["position"]["x"] == 0.0 and poses[-1]["pose"]["position"]["y"] == 2.0, poses[-1]
    no_start = _peer(router_endpoint, *compute, json.dumps({"goal": staging}))
    assert no_start[1]["status"] == 6 and no_start[1]["result"]["error_code"] == 202, no_start
    assert "no robot pose" in no_start[1]["result"]["error_msg"], no_start
