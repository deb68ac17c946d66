"""A real rclpy user (ROS 2 Jazzy on Fast DDS, in .venv-ros2) lists, echoes, drives, navigates and docks a
zendock robot through services.ros2_dds, and sees a stopped zendock service leave the ROS 2 graph."""

from __future__ import annotations

import json
import math
import os
import random
import re
import subprocess
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from deploy.launcher import Launcher, free_endpoint, load_stack
from deploy.testing.config import DEFAULT_STACK, StackConfig
from tests.support.processes import REPO_ROOT

ROS2_VENV = REPO_ROOT / ".venv-ros2"
ROS2_PYTHON = ROS2_VENV / "bin" / "python"
USER_SCRIPT = REPO_ROOT / "tests" / "support" / "ros2_user.py"
ROS2_READY = ROS2_PYTHON.exists() and any(
    (ROS2_VENV / "lib").glob("python3.*/site-packages/nav2_msgs/srv/_get_costmap.py")
)

pytestmark = pytest.mark.skipif(
    not ROS2_READY,
    reason=f"{ROS2_VENV} with rclpy and nav2_msgs is missing: `make ros2` builds it (about 5 min)",
)


@pytest.fixture
def dds_stack(tmp_path: Path) -> Iterator[tuple[Launcher, int]]:
    """The default stack (synthetic detector, rtf 4) plus ros2_dds on a random ROS 2 domain in 100-200."""
    domain = random.randint(100, 200)
    endpoint = free_endpoint()
    environment = {
        **StackConfig(detector="synthetic", rtf="4").environment(endpoint, tmp_path),
        "ROS_DOMAIN_ID": str(domain),
    }
    stack = load_stack(DEFAULT_STACK, env=environment, project_dir=REPO_ROOT)
    launcher = Launcher(
        stack, profiles=["ros2-dds"], project_dir=tmp_path, working_dir=REPO_ROOT, project_name="zendock-test"
    )
    assert "ros2_dds" in launcher.services
    try:
        launcher.up()
        launcher.wait_healthy(timeout_s=90.0)
        yield launcher, domain
    finally:
        launcher.down()


def _run_user(launcher: Launcher, domain: int, timeout_s: float) -> tuple[dict[str, dict[str, Any]], str]:
    """Run the rclpy user to the end; its steps by name and its stderr. Stops the planner when asked."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(("VIRTUAL_ENV", "PYTHON"))}
    env.update(ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    env.pop("ROS_LOCALHOST_ONLY", None)
    user = subprocess.Popen(
        [str(ROS2_PYTHON), str(USER_SCRIPT)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=REPO_ROOT,
        env=env,
    )
    timer = threading.Timer(timeout_s, user.kill)
    timer.start()
    steps: dict[str, dict[str, Any]] = {}
    try:
        assert user.stdout is not None
        for line in user.stdout:
            if not line.startswith("{"):
                continue
            step = json.loads(line)
            steps[step["step"]] = step
            print(line.rstrip())  # with -s: what the user saw, step by step
            if step["step"] == "stop_planner":
                launcher.stop("planner")
        stderr = user.stderr.read() if user.stderr is not None else ""
        user.wait(timeout=10)
    finally:
        timer.cancel()
        if user.poll() is None:
            user.kill()
            user.wait()
    return steps, stderr


def test_a_rclpy_user_sees_drives_and_docks_the_robot(dds_stack: tuple[Launcher, int]) -> None:
    launcher, domain = dds_stack
    started = time.monotonic()
    steps, stderr = _run_user(launcher, domain, timeout_s=150.0)
    face_log = "\n".join(launcher.logs("ros2_dds", 40))

    def check(name: str) -> dict[str, Any]:
        step = steps.get(name)
        assert step is not None, (
            f"the rclpy user never reported {name!r} (reported: {list(steps)});\n"
            f"its stderr:\n{stderr[-3000:]}\nros2_dds:\n{face_log}"
        )
        assert step["ok"], f"{name}: {json.dumps(step)}\nros2_dds:\n{face_log}"
        return step

    active = check("nav2_active")
    assert active["frame"] == "map" and active["amcl_pose"] is not None, active
    print(f"\nwaitUntilNav2Active's protocol: {active['seconds']} s from the user's start")
    simulator_log = "\n".join(launcher.logs("simulator"))
    assert "initial pose (0.00, 0.00, 0.00) refused" in simulator_log, simulator_log[-2000:]
    costmaps = check("costmaps")
    world, local = costmaps["global"], costmaps["local"]
    assert world["frame"] == "map" and world["lethal"] > 0, costmaps  # the room's walls
    assert local["size"][0] <= 62 and local["size"][1] <= 62 and local["cells"] < world["cells"], costmaps
    params = check("parameters")
    assert "read at start-up" in params["refused"][1], params
    docking_log = "\n".join(launcher.logs("docking"))
    assert "auto_dock off" in docking_log, docking_log[-2000:]  # ros2 param set reached zendock's docking
    graph = check("graph")
    assert graph["topics"]["/cmd_vel"] == ["geometry_msgs/msg/Twist"], graph
    check("battery_status")
    late_map = check("late_map")
    assert late_map["cells"] == late_map["width"] * late_map["height"] > 0, late_map
    clock = check("clock")
    assert clock["sim_seconds_per_wall_second"] and clock["sim_seconds_per_wall_second"] > 1.5, clock
    check("cmd_vel_odom")
    check("cmd_vel_stamped_odom")
    check("cmd_vel_mixed_odom")
    # both types at once: one of them on a second participant's node (which, depends on how soon the face
    # saw the last step's TwistStamped publisher go)
    face_lines = "\n".join(launcher.logs("ros2_dds"))
    assert "taking that on a second participant's node /simulator_twist" in face_lines, face_log
    # and that node goes once the user's publishers have (the steps after take long enough for a poll)
    assert re.search(r"the second participant's node /simulator_twist\w* is gone", face_lines), face_log
    paths = check("paths")
    assert paths["staging"]["frame"] == "map" and paths["staging"]["ends"][1] == [0.0, 2.0], paths
    assert (
        paths["through"]["ends"][1] == [0.3, 4.0] and paths["through"]["poses"] > paths["staging"]["poses"]
    ), paths
    assert "goal (-2.00, 3.80)" in paths["in_box"]["error_msg"], paths
    assert paths["smoothed"]["ends"][1] == [0.0, 2.0], paths
    check("navigate_to_pose")
    behaviors = check("behaviors")
    turned_to = behaviors["poses"][1][2]
    assert abs(turned_to - math.pi / 2) < 0.1, behaviors  # spin turned the robot to face +y
    front_y = behaviors["poses"][2][1] + 0.2  # the footprint's front edge, facing +y
    assert 4.5 < front_y < 5.0, behaviors  # stopped short of the top wall (y = 5), not on it
    assert "obstacle" in behaviors["drive_on_heading"]["error_msg"], behaviors
    sequences = check("sequences")
    assert math.dist(sequences["through"]["pose_after"][:2], (0.3, 4.0)) < 0.3, sequences
    assert math.dist(sequences["waypoints"]["pose_after"][:2], (0.3, 4.0)) < 0.3, sequences
    assert sequences["waypoints"]["missed"][0][1] == 9001, sequences  # INVALID_GOAL: the box
    assert sequences["gps"]["seconds"] < 5.0, sequences  # refused within seconds
    followed = check("follow_path")
    assert math.dist(followed["FollowPath"]["pose_after"][:2], (1.0, 4.2)) < 0.3, followed
    assert "MPPI" in followed["MPPI"]["error_msg"], followed
    lifecycle = check("lifecycle")
    assert lifecycle["startup_s"] < 10.0, lifecycle  # lifecycleStartup() returns, it does not wait
    check("goal_pose")
    check("cancel")
    check("dock_robot")
    check("undock_robot")
    check("bad_input")
    check("initial_pose")
    refusals = "\n".join(launcher.logs("ros2_dds"))
    for refused in (
        "refused a message on /cmd_vel",
        "refused a goal in frame 'odom'",
        "refused a navigate_to_pose goal",
    ):
        assert refused in refusals, f"ros2_dds did not log {refused!r}:\n{face_log}"
    left = check("planner_left")
    assert "planner" not in left["nodes"] and "battery" in left["nodes"], left
    assert time.monotonic() - started < 150.0


def _in_ros2_python(*args: str, timeout_s: float = 60.0) -> subprocess.CompletedProcess[str]:
    """``.venv-ros2``'s interpreter run with ``args`` in the repository; the caller judges how it ended."""
    return subprocess.run(
        [str(ROS2_PYTHON), *args],
        capture_output=True,
        text=True,
        cwd=REPO_ROOT,
        timeout=timeout_s,
        check=False,
    )


def test_every_message_the_face_carries_converts_both_ways() -> None:
    """zendock -> rclpy -> zendock gives the same message for every route and action part; what does not fit
    (a NaN, a uint16 out of range) is a ConversionError, never anything else."""
    done = _in_ros2_python(str(REPO_ROOT / "tests" / "support" / "ros2_convert_check.py"), timeout_s=120.0)
    assert done.returncode == 0, done.stderr[-3000:]
    cases = [json.loads(line) for line in done.stdout.splitlines() if line.startswith("{")]
    assert len(cases) >= 40, done.stdout
    failed = [case for case in cases if not case["ok"]]
    assert not failed, failed


def test_the_face_keeps_rosidls_code_generator_out_and_its_messages_still_work() -> None:
    """Every generated message imports ``rosidl_generator_py``, whose ``__init__`` also loads the build-time
    code generator (lark, empy: 45 modules, 3 MB of the face's RSS). The face keeps it out; messages still
    import, get their type support and serialise; and once rosidl is in, the face says it came too late."""
    code = (
        "import sys\n"
        "from services.ros2_dds.node import keep_rosidl_generator_out\n"
        "assert keep_rosidl_generator_out()\n"
        "from rclpy.serialization import deserialize_message, serialize_message\n"
        "from nav_msgs.msg import Odometry\n"
        "msg = Odometry()\n"
        "msg.pose.pose.position.x = 1.5\n"
        "back = deserialize_message(serialize_message(msg), Odometry)\n"
        "print(back.pose.pose.position.x, 'lark' in sys.modules, 'em' in sys.modules)\n"
    )
    done = _in_ros2_python("-c", code)
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.split() == ["1.5", "False", "False"], done.stdout
    late = _in_ros2_python(
        "-c",
        "import rosidl_generator_py\n"
        "from services.ros2_dds.node import keep_rosidl_generator_out\n"
        "print(keep_rosidl_generator_out())",
    )
    assert late.returncode == 0, late.stderr[-3000:]
    assert late.stdout.strip() == "False"


def test_the_face_loads_each_interface_and_yaml_on_first_use_and_they_still_work() -> None:
    """A generated ``<pkg>/msg/__init__`` imports every message of its package, and rclpy.parameter imports
    yaml for parameter strings: the face imports each class when it is first read, and yaml when a
    parameter string is parsed. The classes are rclpy's own: they get their type support and serialise."""
    code = (
        "import sys\n"
        "from services.ros2_dds.lazy_interfaces import load_interfaces_on_use, load_on_first_use\n"
        "assert load_interfaces_on_use() and load_on_first_use('yaml')\n"
        "import rclpy.parameter\n"
        "from rclpy.serialization import deserialize_message, serialize_message\n"
        "from nav2_msgs.action import NavigateToPose\n"
        "from geometry_msgs.msg import PoseWithCovarianceStamped\n"
        "msg = PoseWithCovarianceStamped()\n"
        "msg.pose.covariance[35] = 0.25\n"
        "back = deserialize_message(serialize_message(msg), PoseWithCovarianceStamped)\n"
        "goal = NavigateToPose.Goal()\n"
        "goal.pose.pose.position.x = 2.0\n"
        "again = deserialize_message(serialize_message(goal), NavigateToPose.Goal)\n"
        "nav2 = sorted(m for m in sys.modules if m.startswith('nav2_msgs.action._'))\n"
        "before = 'yaml.parser' in sys.modules\n"
        "value = rclpy.parameter.get_parameter_value('0.5').double_value\n"
        "print(back.pose.covariance[35], again.pose.pose.position.x, nav2, before, value)\n"
    )
    done = _in_ros2_python("-c", code)
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.split() == ["0.25", "2.0", "['nav2_msgs.action._navigate_to_pose']", "False", "0.5"], (
        done.stdout
    )
