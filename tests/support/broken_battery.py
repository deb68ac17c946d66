"""A deliberately broken battery for the conformance kit's own test: ``zendock conform battery`` must fail it,
naming the checks it breaks. It announces itself but none of its endpoints, publishes at 2 Hz of wall time
instead of 10 Hz of sim time and with no frame in its header, never changes its charge, serves no set_state,
and ignores SIGTERM."""

import json
import os
import signal
import time

import zenoh

from shared.messages import BatteryState

signal.signal(signal.SIGTERM, signal.SIG_IGN)
ns = os.environ.get("ZENDOCK_NAMESPACE", "")
conf = zenoh.Config()
conf.insert_json5("mode", '"client"')
conf.insert_json5("connect/endpoints", json.dumps([os.environ["ZENDOCK_CONNECT"].split(",")[0]]))
conf.insert_json5("scouting/multicast/enabled", "false")
s = zenoh.open(conf)
token = s.liveliness().declare_token(f"@zendock/node/{ns or '%'}/battery")
pub = s.declare_publisher(
    f"{ns}/battery_status" if ns else "battery_status",
    encoding=zenoh.Encoding("application/msgpack;sensor_msgs/msg/BatteryState"),
)
while True:
    pub.put(BatteryState(percentage=0.9).encode())
    time.sleep(0.5)
