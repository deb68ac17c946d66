"""What the examples send, zendock's strict decoders accept, and the docks they read are the worlds' docks.

The examples are written without zendock (see test_examples_import_nothing_of_zendock); this test, which may
use zendock, holds them to its wire: every message they build decodes with zendock's message classes, and
their small YAML reader finds the same docks as zendock's world loader in every shipped world.
"""

from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path
from types import ModuleType

import msgpack
import pytest

from shared.interface_types import GoalStatusArray
from shared.interfaces.battery import SetBatteryStateResponse
from shared.interfaces.docking import DOCK_ROBOT, DockRobotFeedback, DockRobotResult
from shared.interfaces.navigation import NAVIGATE_TO_POSE
from shared.messages import BatteryState, Header, String, Time, Twist
from shared.world import load_world

EXAMPLES = Path(__file__).resolve().parents[3] / "examples"
WORLDS = sorted((EXAMPLES.parent / "deploy" / "worlds").rglob("*.yaml"))


def _load(relative: str) -> ModuleType:
    """An example file as a module (it puts ``examples/`` on the path for ``wire`` itself)."""
    path = EXAMPLES / relative
    spec = importlib.util.spec_from_file_location(f"example_{path.stem}", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up there
    saved = list(sys.path)
    try:
        spec.loader.exec_module(module)
    finally:
        sys.path[:] = saved  # the example's own path entry stays with the example (``wire`` is imported)
    return module


@pytest.fixture(scope="module")
def docking() -> ModuleType:
    return _load("docking/docking.py")


@pytest.fixture(scope="module")
def wire(docking: ModuleType) -> ModuleType:
    return sys.modules["wire"]


def _wire_bytes(msg: dict) -> bytes:
    return msgpack.packb(msg, use_bin_type=True)


@pytest.mark.parametrize("world", WORLDS, ids=lambda p: p.stem)
def test_the_examples_read_the_same_docks_as_zendock(docking: ModuleType, world: Path) -> None:
    expected = {d.id: tuple(map(float, d.pose)) for d in load_world(world).docks}
    assert docking.read_docks(str(world)) == expected  # the same decimal text: the same floats


def test_a_block_style_dock_database(docking: ModuleType, tmp_path: Path) -> None:
    path = tmp_path / "docks.yaml"
    path.write_text(
        "# a dock database\ndocks:\n  - id: a   # the first\n    pose: [1.0, 2, -0.5]\n    type: charger\n"
        "  - {id: 'b', pose: [3.5, 4.0, 0.0]}\nother: 1\n"
    )
    assert docking.read_docks(str(path)) == {"a": (1.0, 2.0, -0.5), "b": (3.5, 4.0, 0.0)}


def test_messages_decode_with_zendocks_classes(wire: ModuleType) -> None:
    assert Time.decode(_wire_bytes(wire.time_msg(1.9999999999))) == Time(2, 0)
    assert Header.decode(_wire_bytes(wire.header(12.5, "map"))).stamp == Time(12, 500_000_000)
    twist = Twist.decode(_wire_bytes(wire.twist_msg(0.2, -0.5)))
    assert (twist.linear.x, twist.angular.z) == (0.2, -0.5)
    nav_goal = {
        "pose": {"header": wire.header(3.0, "map"), "pose": wire.pose_msg(1.0, 2.0, 1.2)},
        "behavior_tree": "",
    }
    decoded = NAVIGATE_TO_POSE.goal.decode(_wire_bytes(nav_goal))
    assert decoded.pose.pose.to_pose2d().yaw == pytest.approx(1.2)
    assert wire.planar_pose(wire.pose_msg(1.0, 2.0, -2.5)) == pytest.approx((1.0, 2.0, -2.5))
    String.decode(_wire_bytes({"data": "approaching"}))


def test_action_messages_decode_with_zendocks_classes(wire: ModuleType, docking: ModuleType) -> None:
    handle = wire.GoalHandle(bytes(range(16)), {}, wire.time_msg(4.0))
    status = {"status_list": [{"goal_info": handle.info(), "status": wire.SUCCEEDED}]}
    assert (
        GoalStatusArray.decode(_wire_bytes(status)).status_list[0].goal_info.goal_id.hex()
        == bytes(range(16)).hex()
    )
    DockRobotResult.decode(_wire_bytes(docking.Docking.dock_result(True, 0, 1)))
    feedback = {"state": docking.CONTROLLING, "docking_time": wire.time_msg(3.5), "num_retries": 0}
    DockRobotFeedback.decode(_wire_bytes(feedback))
    DOCK_ROBOT.feedback_message.decode(
        _wire_bytes({"goal_id": wire.uuid_msg(bytes(16)), "feedback": feedback})
    )
    DOCK_ROBOT.send_goal_response.decode(_wire_bytes({"accepted": True, "stamp": wire.time_msg(1.0)}))


def test_the_battery_state_and_set_state_response_decode(wire: ModuleType) -> None:
    battery = _load("battery/battery.py")

    class FakeNode:
        params = {"initial_percentage": 0.9995}
        log = __import__("logging").getLogger("test")

        def __init__(self) -> None:
            self.published: list[dict] = []

        def now(self) -> float:
            return 10.0

        def publisher(self, *_: object) -> FakeNode:
            return self

        def publish(self, msg: dict) -> None:
            self.published.append(msg)

        def subscribe(self, *_: object) -> None:
            pass

        serve = subscribe

    node = FakeNode()
    model = battery.Battery(node)
    model.tick()
    assert BatteryState.decode(_wire_bytes(node.published[-1])).power_supply_status == battery.DISCHARGING
    model.mated_at = 10.0
    model.tick()
    assert BatteryState.decode(_wire_bytes(node.published[-1])).power_supply_status == battery.FULL
    request = {"percentage": 0.5, "drain_scale": math.nan, "charge_scale": 2.0, "frozen": False}
    response = SetBatteryStateResponse.decode(_wire_bytes(model.on_set_state(request)))
    assert (response.state.percentage, response.state.power_supply_status, response.charge_scale) == (
        0.5,
        1,
        2.0,
    )
    with pytest.raises(wire.BadMessage, match="percentage"):
        model.on_set_state({**request, "percentage": 1.5})
    with pytest.raises(wire.BadMessage, match="unknown field"):
        model.on_set_state({**request, "extra": 1})
