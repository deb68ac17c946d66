"""``zendock bench messages``: rates per simulated second from two snapshots of the nodes' counters."""

from __future__ import annotations

import pytest

from deploy.bench.messages import MessageCount


def test_rates_per_key_subscriber_and_robot_come_from_the_counters_differences() -> None:
    count = MessageCount(robots=["r0"], sim_s=10.0, wall_s=2.0)
    count.before = {
        "simulator": {
            "published": {"r0/clock": 100, "r0/odom": 50},
            "received": {},
            "extra": {"pacing_holds": 1, "pacing_held_s_cmd_vel": 0.1},
        },
        "r0/battery": {"published": {}, "received": {"r0/clock": 100}},
    }
    count.after = {
        "simulator": {
            "published": {"r0/clock": 300, "r0/odom": 550},
            "received": {"r0/cmd_vel": 200},
            "extra": {"pacing_holds": 5, "pacing_held_s_cmd_vel": 0.5},
        },
        "r0/battery": {
            "published": {"r0/battery_status": 100},
            "received": {"r0/clock": 300, "r0/odom": 500},
        },
        "r0/docking": {
            "published": {"r0/cmd_vel": 200},
            "received": {"r0/odom": 500, "r0/battery_status": 100},
        },
    }
    count.cpu_before = {"battery_r0": {"python": 1.0, "zenoh": 0.5}}
    count.cpu_after = {"battery_r0": {"python": 1.2, "zenoh": 0.6}}
    report = count.report()
    assert report["keys"]["clock"] == {
        "published_per_sim_s": 20.0,
        "delivered_per_sim_s": 20.0,
        "subscribers": ["battery"],
    }
    assert (
        report["keys"]["odom"]["delivered_per_sim_s"] == 100.0
        and report["keys"]["odom"]["published_per_sim_s"] == 50.0
    )
    assert report["published_per_sim_s_per_robot"] == pytest.approx(20 + 50 + 10 + 20)
    assert report["received_per_sim_s_by_node"]["battery"] == pytest.approx(20 + 50)
    assert report["rtf"] == 5.0 and report["pacing"]["holds"] == 4
    assert report["pacing"]["held_wall_s_cmd_vel"] == pytest.approx(0.4)
    assert report["pacing"]["held_fraction_of_wall"] == pytest.approx(0.2)
    assert report["cpu_ms_per_sim_s"]["battery"] == {"python": 20.0, "zenoh": 10.0, "all": 30.0}


def test_no_simulated_time_is_an_error_not_a_division_by_zero() -> None:
    with pytest.raises(RuntimeError, match="no simulated time"):
        MessageCount(robots=["r0"], sim_s=0.0, wall_s=1.0, after={"x": {}}).report()
