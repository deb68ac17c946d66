"""How fast the robot met its dock: the observer's arrival speed, from ground truth when the contacts mated."""

from __future__ import annotations

import math

import pytest

from deploy.observer import ARRIVAL_SPEED_LIMIT_MPS, RunObserver, RunRecord
from shared import topics
from shared.geometry import Pose2D
from shared.messages import BatteryState, DockContact, Header, Pose, PoseStamped, Time
from shared.names import topic_key
from shared.session import SessionSpec, open_session
from tests.support.processes import wait_until

NS = "obs_arrival"


def test_the_arrival_speed_is_the_ground_truth_speed_just_before_mating() -> None:
    # 0.4 m/s, then braking to 0.08 m/s from t = 1.0 on (20 Hz samples)
    driven = [(0.05 * i, 0.4 * 0.05 * i, 0.0, 0.0) for i in range(21)]
    x = driven[-1][1]
    for i in range(21, 41):
        x += 0.08 * 0.05
        driven.append((0.05 * i, x, 0.0, 0.0))
    record = RunRecord(driven=driven, mated_s=1.5)
    assert record.arrival_speed_mps == pytest.approx(0.08)
    assert record.speed_at(1.0) == pytest.approx(0.4)
    assert math.isnan(RunRecord(driven=driven).arrival_speed_mps)  # never mated
    assert math.isnan(RunRecord(mated_s=1.0).arrival_speed_mps)  # no track


def _charged(arrival_mps: float) -> RunRecord:
    """A record that charged on a mated contact, the robot at ``arrival_mps`` for the last second."""
    driven = [(0.05 * i, arrival_mps * 0.05 * i, 0.0, 0.0) for i in range(21)]
    contact = DockContact(Header(Time.from_sec(1.0), topics.MAP_FRAME), "home", True, True, 0.0, 0.0, 0.0)
    return RunRecord(trigger_s=0.0, charging_s=1.0, contact_at_charging=contact, driven=driven, mated_s=1.0)


def test_meeting_the_plate_faster_than_its_contact_speed_limit_is_no_docking() -> None:
    gentle, hard = _charged(0.08).outcome(), _charged(0.3).outcome()
    assert gentle.docked and not gentle.too_fast
    assert hard.charging and hard.too_fast and not hard.docked
    assert not _charged(ARRIVAL_SPEED_LIMIT_MPS * 1.5).outcome().docked
    no_track = RunRecord(trigger_s=0.0, charging_s=1.0, contact_at_charging=_charged(0.3).contact_at_charging)
    assert no_track.outcome().docked  # no ground truth then: nothing says it was too fast


def test_the_observer_takes_the_first_reading_of_the_mating_that_started_charging() -> None:
    # A lone peer with no endpoints: its subscribers get its own puts, and nothing leaves the process.
    with open_session(SessionSpec(mode="peer", connect=())) as session:
        observer = RunObserver(session, NS)
        try:
            observer.arm()

            def put(key: str, msg) -> None:  # type: ignore[no-untyped-def]
                session.put(topic_key(NS, key), msg.encode())

            def header(t: float) -> Header:
                return Header(Time.from_sec(t), topics.MAP_FRAME)

            put(topics.BATTERY_STATUS, BatteryState(header=header(0.0), percentage=0.2))
            for i in range(12):  # 0.1 m/s along x
                t = 0.05 * i
                put(
                    topics.GROUND_TRUTH_POSE,
                    PoseStamped(header(t), Pose.from_pose2d(Pose2D(0.1 * t, 0.0, 0.0))),
                )
            # mated for a moment, parted, then mated for good from t = 0.4
            for t, mated in (
                (0.2, True),
                (0.25, False),
                (0.3, False),
                (0.4, True),
                (0.45, True),
                (0.5, True),
            ):
                put(topics.DOCK_CONTACT, DockContact(header=header(t), dock_id="home", mated=mated))
            wait_until(lambda: len(observer.snapshot().driven) == 12, 5.0, lambda: observer.snapshot().driven)
            charging = BatteryState(
                header=header(0.5),
                percentage=0.2,
                power_supply_status=BatteryState.POWER_SUPPLY_STATUS_CHARGING,
            )
            put(topics.BATTERY_STATUS, charging)
            # each key has its own callback thread: the contacts may still be on their way after the battery
            wait_until(
                lambda: observer.snapshot().mated_s == pytest.approx(0.4),
                5.0,
                lambda: f"mating began at {observer.snapshot().mated_s}",
            )
            record = observer.snapshot()
            assert record.arrival_speed_mps == pytest.approx(0.1)
        finally:
            observer.close()
