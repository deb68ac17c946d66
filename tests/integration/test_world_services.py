"""The world services together: pose follows the simulator through tf, and a killed service comes back.

Killing one service must not disturb the others: they keep publishing, and the restarted one rebuilds
its state from the next messages.
"""

from __future__ import annotations

import numpy as np
import zenoh

from shared.interfaces.simulator import SIM_STATE, SimStateRequest
from shared.messages import BatteryState, Clock, Float64MultiArray
from shared.node import call_service
from tests.support.bus import KeyRecorder
from tests.support.processes import REPO_ROOT

SEED_ROOM = str(REPO_ROOT / "deploy/worlds/seed_room.yaml")


def test_pose_matches_ground_truth_and_services_survive_a_restart(
    spawn, bus: zenoh.Session, namespace: str
) -> None:  # type: ignore[no-untyped-def]
    clock = KeyRecorder(bus, f"{namespace}/clock", Clock)
    pose = KeyRecorder(bus, f"{namespace}/map_to_base_link_pose2d", Float64MultiArray)
    battery = KeyRecorder(bus, f"{namespace}/battery_status", BatteryState)
    sim = spawn("simulator", "--world", SEED_ROOM, "-p", "rtf=2")
    spawn("pose", "-p", "use_sim_time=true")
    battery_proc = spawn("battery", "-p", "use_sim_time=true")

    first = pose.wait_for(timeout_s=30.0)
    truth = call_service(bus, f"{namespace}/simulator/state", SIM_STATE, SimStateRequest()).pose.to_pose2d()
    np.testing.assert_allclose(first.data[:2], [truth.x, truth.y], atol=1e-3)
    battery.wait_for(timeout_s=20.0)

    # kill -9 the battery: pose and simulator keep going
    battery_proc.kill9()
    n_pose = pose.count
    pose.wait_for(after=n_pose + 5, timeout_s=20.0)
    assert sim.alive()
    # restart it: it publishes again, stamped on the simulator's clock
    battery_proc.start()
    now = clock.latest().clock.to_sec()  # type: ignore[union-attr]
    battery.wait_for(lambda m: m.header.stamp.to_sec() > now, timeout_s=30.0)

    # kill -9 the simulator and start it again: pose resumes after the clock restarts from zero
    sim.kill9()
    sim.start()
    n_pose = pose.count
    pose.wait_for(after=n_pose, timeout_s=30.0)
    clock.wait_for(lambda m: m.clock.to_sec() < 5.0, after=clock.count, timeout_s=30.0)
    pose.wait_for(after=pose.count + 3, timeout_s=30.0)
    assert battery_proc.alive()
