"""Robots sharing a dock, as processes: the docking services ask the fleet service before they dock.

Two robots in one simulated room with one dock. Each has its own battery, pose and docking services
(``fleet=true``); the planner is played by teleports (:class:`TeleportNavigator`). The dock is granted to
the first robot that needs it; the second waits at the room's holding pose, in the fleet's queue, until
the first has charged and undocked; then it docks. With no fleet service at all, a robot still docks at
a dock it sees free. Every outcome is read on the simulator's ground truth.
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import zenoh

from services.docking.node import DOCKING_STATE
from shared import topics
from shared.geometry import Pose2D
from shared.interfaces.battery import SET_BATTERY_STATE, SetBatteryStateRequest
from shared.interfaces.fleet import FleetDocks, FleetQueue
from shared.interfaces.simulator import SIM_STATE, SimStateRequest
from shared.messages import BatteryState, String
from shared.names import topic_key
from shared.node import ServiceUnavailable, call_service
from tests.integration.test_docking_service import CHARGING, TeleportNavigator
from tests.support.bus import KeyRecorder
from tests.support.processes import wait_until

HOLDING = Pose2D(6.5, 1.0, 0.0)
PATROLS = {"r1": "[[3.0, 2.0, 3.14159], [3.0, 4.5, 3.14159]]", "r2": "[[5.5, 4.5, 0.0], [5.5, 1.5, 0.0]]"}


def _world(tmp_path: Path) -> str:
    path = tmp_path / "one_dock.yaml"
    path.write_text(
        "name: one_dock\nbounds: [0.0, 0.0, 8.0, 6.0]\n"
        "docks:\n  - {id: west, pose: [0.6, 3.0, 3.14159265]}\n"
        f"holding:\n  - [{HOLDING.x}, {HOLDING.y}, {HOLDING.yaw}]\n"
        "robots:\n  - {name: r1, start: [3.0, 2.0, 3.14159265]}\n  - {name: r2, start: [5.0, 4.0, 3.14159265]}\n"
    )
    return str(path)


class _Robot:
    """One robot's services and what the test watches of it."""

    def __init__(
        self, spawn, bus: zenoh.Session, namespace: str, name: str, world: str, *docking: str
    ) -> None:  # type: ignore[no-untyped-def]
        self.bus, self.name, self.ns = bus, name, f"{namespace}/{name}"
        self.sim_ns = namespace
        self.battery = KeyRecorder(bus, topic_key(self.ns, topics.BATTERY_STATUS), BatteryState, keep=5000)
        self.state = KeyRecorder(bus, topic_key(self.ns, DOCKING_STATE), String, keep=5000)
        spawn("battery", "-p", "use_sim_time=true", namespace_override=self.ns)
        spawn("pose", "-p", "use_sim_time=true", namespace_override=self.ns)
        args = ["-p", "use_sim_time=true", "-p", f"dock_database={world}", "-p", "fleet=true"]
        for param in docking:
            args += ["-p", param]
        self.docking = spawn("docking", *args, namespace_override=self.ns)
        self.navigator = TeleportNavigator(bus, self.ns, dwell_s=1.0, robot=name)

    def set_battery(self, percentage: float) -> None:
        """Asked again while nothing answers: the battery's queryable may not have reached the router yet when
        the docking service (what the test waits on) is already idle."""
        key = topic_key(self.ns, topics.BATTERY_SET_STATE)
        deadline = time.monotonic() + 10.0
        while True:
            try:
                call_service(
                    self.bus,
                    key,
                    SET_BATTERY_STATE,
                    SetBatteryStateRequest(percentage=percentage),
                    timeout_s=5.0,
                )
                return
            except ServiceUnavailable:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.2)

    def wait_state(self, name: str, timeout_s: float, after: int = 0) -> int:
        self.state.wait_for(lambda m: m.data == name, timeout_s=timeout_s, after=after)
        return self.state.count

    def wait_charging(self, timeout_s: float, after: int = 0) -> None:
        self.battery.wait_for(lambda m: m.power_supply_status in CHARGING, timeout_s=timeout_s, after=after)

    def truth(self):  # type: ignore[no-untyped-def]
        return call_service(
            self.bus,
            topic_key(self.sim_ns, topics.SIM_STATE),
            SIM_STATE,
            SimStateRequest(robot=self.name),
            timeout_s=5.0,
        )

    def close(self) -> None:
        self.navigator.close()
        self.battery.close()
        self.state.close()


def test_two_robots_take_turns_at_one_dock(spawn, bus: zenoh.Session, namespace: str, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    world = _world(tmp_path)
    docks = KeyRecorder(bus, f"{namespace}/fleet/docks", FleetDocks, keep=5000)
    queue = KeyRecorder(bus, f"{namespace}/fleet/queue", FleetQueue, keep=5000)
    spawn("simulator", "--world", world, "-p", "rtf=5")
    spawn("fleet", "-p", f"world={world}", "-p", "publish_period_s=0.5")
    robots = {
        name: _Robot(spawn, bus, namespace, name, world, f"patrol={PATROLS[name]}") for name in ("r1", "r2")
    }
    r1, r2 = robots["r1"], robots["r2"]
    try:
        for robot in robots.values():
            robot.wait_state("PATROLLING", timeout_s=30.0)
        r1.set_battery(0.2)
        r1.wait_charging(timeout_s=60.0)
        held = docks.wait_for(lambda m: m.docks[0].robot == r1.ns, timeout_s=10.0)
        assert held.docks[0].dock_id == "west"

        r2.set_battery(0.2)
        r2.wait_state("WAITING_FOR_DOCK", timeout_s=20.0)
        queue.wait_for(lambda m: [q.robot for q in m.robots] == [r2.ns], timeout_s=10.0)
        # The waiting robot goes to the room's holding pose, out of the dock's way.
        wait_until(
            lambda: any(g.distance_to(HOLDING) < 1e-6 for g in r2.navigator.goals_sent()),
            10.0,
            lambda: f"r2's planner goals: {r2.navigator.goals_sent()}",
        )
        assert not any(m.power_supply_status in CHARGING for m in r2.battery.messages)

        # r1 charged: it undocks to patrol again and releases the dock, which goes to r2.
        mark = r2.battery.count
        r1.set_battery(0.97)
        r1.wait_state("UNDOCKING", timeout_s=20.0)
        r2.wait_charging(timeout_s=90.0, after=mark)
        truth = r2.truth()
        assert truth.contact.mated and truth.contact.dock_id == "west", truth.contact
        assert truth.collisions == 0 and r1.truth().collisions == 0
        docks.wait_for(lambda m: m.docks[0].robot == r2.ns, timeout_s=10.0)
        # Never two robots in the dock: r1 had left it (ground truth) before r2 was granted it.
        r1_pose = r1.truth().pose.position
        assert math.dist((r1_pose.x, r1_pose.y), (0.6, 3.0)) > 0.4
        assert "released dock west" in r1.docking.output()
        assert "the fleet granted dock west" in r2.docking.output()
    finally:
        for robot in robots.values():
            robot.close()
        docks.close()
        queue.close()


def test_with_the_fleet_down_a_robot_docks_at_a_dock_it_sees_free(
    spawn,
    bus: zenoh.Session,
    namespace: str,  # type: ignore[no-untyped-def]
    tmp_path: Path,
) -> None:
    world = _world(tmp_path)
    spawn("simulator", "--world", world, "-p", "rtf=5")
    robot = _Robot(spawn, bus, namespace, "r1", world, "fleet_patience_s=2")
    try:
        robot.wait_state("IDLE", timeout_s=30.0)
        robot.set_battery(0.2)
        robot.wait_state("WAITING_FOR_DOCK", timeout_s=20.0)
        robot.wait_charging(timeout_s=60.0)
        assert robot.truth().contact.mated
        log = robot.docking.output()
        assert "the fleet did not answer" in log and "docking at west, seen free" in log, log[-3000:]
    finally:
        robot.close()


def test_a_robot_whose_docking_service_is_killed_keeps_its_dock_and_docks_after_restart(  # type: ignore[no-untyped-def]
    spawn, bus: zenoh.Session, namespace: str, tmp_path: Path
) -> None:
    world = _world(tmp_path)
    docks = KeyRecorder(bus, f"{namespace}/fleet/docks", FleetDocks, keep=5000)
    spawn("simulator", "--world", world, "-p", "rtf=5")
    spawn("fleet", "-p", f"world={world}", "-p", "publish_period_s=0.5", "-p", "lease_s=10")
    robots = {name: _Robot(spawn, bus, namespace, name, world) for name in ("r1", "r2")}
    r1, r2 = robots["r1"], robots["r2"]
    try:
        for robot in robots.values():
            robot.wait_state("IDLE", timeout_s=30.0)
        r1.set_battery(0.2)
        r1.wait_state("NAV_TO_STAGING_POSE", timeout_s=20.0)
        docks.wait_for(lambda m: m.docks[0].robot == r1.ns, timeout_s=10.0)
        r2.set_battery(0.2)
        r2.wait_state("WAITING_FOR_DOCK", timeout_s=20.0)

        r1.docking.kill9()
        killed_at, killed_wall = docks.count, time.monotonic()
        r1.docking.start()
        r1.wait_charging(timeout_s=60.0)
        print(
            f"\nkill -9 of r1's docking service while it held the dock: charging {time.monotonic() - killed_wall:.1f} s "
            "(wall) after the kill, the dock r1's throughout"
        )
        assert r1.truth().contact.mated
        after_kill = docks.messages[len(docks.messages) - (docks.count - killed_at) :]
        assert after_kill and all(m.docks[0].robot == r1.ns for m in after_kill), (
            "the dock stayed r1's while its docking service was down and restarting"
        )
        # Nothing else stalled: r2 still waits for the dock, its service alive and saying so.
        mark = r2.state.count
        r2.state.wait_for(lambda m: m.data == "WAITING_FOR_DOCK", timeout_s=10.0, after=mark)
        assert "already yours" not in r2.docking.output()
    finally:
        for robot in robots.values():
            robot.close()
        docks.close()
