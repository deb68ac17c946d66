"""``zendock param`` and ``zendock nodes`` against a real battery service: list, get, set at runtime.

The battery runs as a process on the test router in a fresh namespace, on wall time (no simulator: it
stands still off the dock, so only the base load drains it). The CLI runs in-process through
deploy.cli.main, as a user would type it.
"""

from __future__ import annotations

import json
import time

import pytest
import zenoh

from deploy import cli
from shared import topics
from shared.messages import BatteryState
from shared.names import topic_key
from tests.support.bus import KeyRecorder

DEMO_DRAIN_SCALE = 300.0  # 0.4 A off a 2 Ah battery: 1.7 % a second at this scale, 0.006 % at 1


@pytest.fixture
def zendock(router_endpoint: str, namespace: str, capsys: pytest.CaptureFixture[str]):  # type: ignore[no-untyped-def]
    """``zendock("param", "get", "battery", "drain_scale")`` -> ``(exit code, stdout, stderr)``."""

    def run(command: str, verb: str, *argv: str) -> tuple[int, str, str]:
        capsys.readouterr()
        code = cli.main([command, verb, "--connect", router_endpoint, "--namespace", namespace, *argv])
        captured = capsys.readouterr()
        return code, captured.out, captured.err

    return run


def _drop_over(status: KeyRecorder[BatteryState], seconds: float) -> float:
    """How much the charge fell over ``seconds`` of battery_status messages."""
    start = status.wait_for(after=status.count, timeout_s=5.0)
    time.sleep(seconds)
    end = status.wait_for(after=status.count, timeout_s=5.0)
    return start.percentage - end.percentage


def test_param_list_get_set_on_a_running_battery(
    spawn,
    bus: zenoh.Session,
    namespace: str,  # type: ignore[no-untyped-def]
    zendock,
) -> None:
    status = KeyRecorder(bus, topic_key(namespace, topics.BATTERY_STATUS), BatteryState)
    spawn("battery", "-p", "initial_percentage=0.9")
    status.wait_for(timeout_s=20.0)
    node = f"/{namespace}/battery"

    # nodes: the battery with its endpoints, parameter services included.
    code, out, _ = zendock("nodes", "list")
    assert code == 0 and out.splitlines() == [node]
    code, out, _ = zendock("nodes", "info", "battery")
    assert code == 0
    lines = out.splitlines()
    assert lines[0] == node
    assert f"    {namespace}/battery_status: sensor_msgs/msg/BatteryState" in lines
    assert f"    {namespace}/odom: nav_msgs/msg/Odometry" in lines
    assert f"    {namespace}/battery/set_state: zendock_msgs/srv/SetBatteryState" in lines
    assert f"    {namespace}/battery/_param/set: zendock_msgs/srv/SetParameter" in lines
    assert lines.index("  Publishers:") < lines.index("  Subscriptions:") < lines.index("  Services:")
    code, out, _ = zendock("nodes", "info", node, "--json")
    assert (
        code == 0
        and {"key": f"{namespace}/dock_contact", "type": "zendock_msgs/msg/DockContact"}
        in (json.loads(out)["subscriptions"])
    )

    # param list: every parameter, with its value and whether it is settable.
    code, out, _ = zendock("param", "list", node)
    assert code == 0
    rows = {line.split()[0]: line for line in out.splitlines()[1:]}
    assert out.splitlines()[0].split() == ["NAME", "VALUE", "SETTABLE"]
    assert rows["drain_scale"].split()[1:] == ["1.0", "yes,", "at", "once"]
    assert rows["capacity_ah"].split()[1:] == ["2.0", "no"]
    code, out, _ = zendock("param", "list", "battery", "--json")
    listed = {p["name"]: p for p in json.loads(out)}
    assert listed["initial_percentage"]["value"] == 0.9 and not listed["initial_percentage"]["settable"]

    # A good value applies at once: the charge falls hundreds of times faster.
    slow = _drop_over(status, 1.0)
    code, out, err = zendock("param", "set", "battery", "drain_scale", str(DEMO_DRAIN_SCALE))
    assert (code, err) == (0, "")
    assert out == f"Set parameter successful: drain_scale = {DEMO_DRAIN_SCALE} (applies at once)\n"
    fast = _drop_over(status, 1.0)
    assert slow < 0.001 < 0.01 < fast, (slow, fast)
    code, out, _ = zendock("param", "get", node, "drain_scale")
    assert (code, out) == (0, f"drain_scale: {DEMO_DRAIN_SCALE}\n")

    # A bad value, a read-only parameter and an unknown name are refused with the reason, exit 2.
    code, out, err = zendock("param", "set", "battery", "drain_scale", "-1")
    assert (code, out) == (2, "")
    assert err == (f"zendock param set: {node}: drain_scale: must be at least 0.0 (got -1)\n")
    code, _, err = zendock("param", "set", "battery", "capacity_ah", "3")
    assert code == 2 and err.startswith(f"zendock param set: {node}: capacity_ah: read at start-up only")
    code, _, err = zendock("param", "set", "battery", "drain", "3")
    assert code == 2 and (
        "drain: no such parameter (did you mean drain_scale?) (settable: charge_scale, drain_scale, frozen)"
        in err
    )
    code, _, err = zendock("param", "get", "battery", "drain")
    assert code == 2 and err.startswith(f"zendock param get: {node}: drain: no such parameter")
    code, out, _ = zendock("param", "get", "battery", "drain_scale", "--json")
    assert json.loads(out)["value"] == DEMO_DRAIN_SCALE  # the refused changes changed nothing

    # A node that is not there: exit 1.
    code, _, err = zendock("param", "list", "no_such_node", "--connect-timeout", "2")
    assert code == 1 and "did not answer" in err


def test_battery_get_and_set_from_the_command_line(
    spawn,
    bus: zenoh.Session,
    namespace: str,  # type: ignore[no-untyped-def]
    router_endpoint: str,
    zendock,
) -> None:
    status = KeyRecorder(bus, topic_key(namespace, topics.BATTERY_STATUS), BatteryState)
    spawn("battery", "-p", "initial_percentage=0.9")
    status.wait_for(timeout_s=20.0)

    code, out, err = zendock("battery", "get", "--json")
    got = json.loads(out)
    assert (code, err) == (0, ""), err
    assert got["percentage"] == pytest.approx(0.9, abs=0.01) and got["status"] == "DISCHARGING", got
    assert (got["drain_scale"], got["charge_scale"], got["frozen"]) == (1.0, 1.0, False), got

    # A percentage, frozen: the charge holds there.
    code, out, err = zendock("battery", "set", "20%", "--freeze")
    assert (code, err) == (0, "") and out.startswith("20.0%  DISCHARGING") and "frozen" in out, (out, err)
    mark = status.count
    held = [status.wait_for(after=mark + i, timeout_s=5.0).percentage for i in range(2)]
    assert held == [pytest.approx(0.2), pytest.approx(0.2)], held
    code, out, _ = zendock("param", "get", "battery", "frozen")
    assert (code, out) == (0, "frozen: true\n")

    # A knob alone keeps the rest (still frozen, still 20%); thawed, the charge falls at the new rate.
    code, out, _ = zendock("battery", "set", "--drain-scale", str(DEMO_DRAIN_SCALE), "--json")
    after = json.loads(out)
    assert code == 0 and after["frozen"] and after["drain_scale"] == DEMO_DRAIN_SCALE, after
    assert after["percentage"] == pytest.approx(0.2), after
    code, _, _ = zendock("battery", "set", "--thaw")
    assert code == 0
    status.wait_for(lambda m: m.percentage < 0.19, timeout_s=10.0, after=status.count)

    # Mistakes name themselves: nothing asked, a level out of range; and no battery in another namespace.
    code, _, err = zendock("battery", "set")
    assert code == 2 and "nothing to set" in err, err
    with pytest.raises(SystemExit) as refused:
        zendock("battery", "set", "120%")
    assert refused.value.code == 2
    code = cli.main(["battery", "get", "--connect", router_endpoint, "--namespace", f"{namespace}_none"])
    assert code == 1
