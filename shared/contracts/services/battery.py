"""The battery service's contract."""

from __future__ import annotations

from shared import topics
from shared.contracts.model import Contract, Flag, Request, Topic
from shared.contracts.services.common import USE_SIM_TIME
from shared.endpoints import RELIABLE, SENSOR_DATA, QoS
from shared.interfaces.battery import SET_BATTERY_STATE
from shared.messages import (
    BatteryState,
    DockContact,
    Odometry,
)

CONTRACT = Contract(
    service="battery",
    summary="A simulated battery: drains with motion, charges while the robot is mated with a dock.",
    version="1.1",
    publishes=(
        Topic(
            topics.BATTERY_STATUS,
            BatteryState,
            RELIABLE,
            rate_hz=10.0,
            frame_id=topics.BASE_FRAME,
            about="the charge; power_supply_status CHARGING (1) while mated, DISCHARGING (2) otherwise, FULL (4)",
        ),
    ),
    subscribes=(
        Topic(topics.ODOM, Odometry, SENSOR_DATA, rate_hz=20.0, about="the twist sets the motion load"),
        Topic(topics.DOCK_CONTACT, DockContact, QoS(depth=5), rate_hz=20.0, about="charging while `mated`"),
    ),
    serves=(
        Request(
            topics.BATTERY_SET_STATE,
            SET_BATTERY_STATE,
            about="set the charge and the drain/charge scales (NaN: leave as is); answers with the new state",
        ),
    ),
    flags=(
        USE_SIM_TIME,
        Flag("state_file", "keep the charge in this file across restarts"),
        Flag("drain_scale", "the charge drains this many times faster"),
        Flag("charge_scale", "the charge fills this many times faster"),
        Flag("publish_rate_hz", "battery_status this often (10 Hz), and at once on a change of status"),
    ),
    behaviour=(
        "answers set_state: battery_status shows the charge it set",
        "drains while the robot drives",
        "charges while mated: CHARGING and a rising charge with the robot on the dock",
    ),
    needs=("simulator",),
)
