"""Several hosts: services on two "machines" meet through their routers, survive a cut link, and dock.

Each host is a network namespace the test creates (see tests/support/netns.py), joined to the other by
a veth pair with link-local addresses. Host A runs router A, the simulator, the battery and pose; host B
runs router B (connected to router A over the veth), the planner and the docking service. Nothing of
the robot's motion control is on host A, so when the link goes down the simulator stops hearing
``cmd_vel`` and its watchdog must brake the robot; when the link comes back, the routers meet again and
the docking run carries on to the charger.

The test process cannot reach either namespace's network, so a probe inside host A
(tests/support/multihost_probe.py) watches the robot and triggers the run, reporting over a pipe.
"""

from __future__ import annotations

import json
import math
import os
import queue
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from shared.messages import BatteryState
from tests.support.netns import HOST_A_ADDRESS, HostPair, NetnsProcess, NetnsUnavailable
from tests.support.processes import REPO_ROOT

pytestmark = [pytest.mark.multihost, pytest.mark.timeout(150)]

WORLD = REPO_ROOT / "deploy" / "worlds" / "seed_room.yaml"
ROBOT = "robot"
RTF = "3"
ROUTER_PORT = 7447
ROUTER_A = f"tcp/{HOST_A_ADDRESS}:{ROUTER_PORT}"
ROUTER_B_LOCAL = f"tcp/127.0.0.1:{ROUTER_PORT}"
HOST_A_NODES = {f"{ROBOT}/simulator", f"{ROBOT}/battery", f"{ROBOT}/pose"}
HOST_B_NODES = {f"{ROBOT}/planner", f"{ROBOT}/docking"}
#: The simulator's cmd_vel watchdog (0.3 s) plus braking from full speed (0.5 m/s at 2.5 m/s^2), with margin.
STOP_WITHIN_SIM_S = 1.0
STAY_STOPPED_SIM_S = 3.0
#: At most 0.5 m/s for the watchdog's 0.3 s and the delivery of the last command, then 0.05 m of braking.
MAX_COAST_M = 0.35
MIN_SAMPLES = 10
STOPPED_LINEAR_MPS = 0.01
STOPPED_ANGULAR_RPS = 0.05


class Probe:
    """The probe process in a namespace; a reader thread turns its JSON lines into a queue."""

    def __init__(self, netns: str, connect: str, log_path: Path, trace_path: Path) -> None:
        self.log_path = log_path
        self.trace_path = trace_path
        self._stderr = open(log_path, "ab")  # noqa: SIM115 - closed in stop()
        self.proc = subprocess.Popen(
            [
                "ip",
                "netns",
                "exec",
                netns,
                sys.executable,
                "-m",
                "tests.support.multihost_probe",
                "--connect",
                connect,
                "--namespace",
                ROBOT,
            ],
            cwd=REPO_ROOT,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=self._stderr,
            env={**os.environ, "PYTHONUNBUFFERED": "1"},
            start_new_session=True,
            text=True,
            bufsize=1,
        )
        self._lines: queue.Queue[dict[str, Any]] = queue.Queue()
        self.latest: dict[str, Any] = {}
        self.events: list[dict[str, Any]] = []
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        """Queue every line, and keep them all in ``trace_path`` for a post-mortem."""
        assert self.proc.stdout is not None
        with open(self.trace_path, "w") as trace:
            for line in self.proc.stdout:
                trace.write(line)
                try:
                    self._lines.put(json.loads(line))
                except json.JSONDecodeError:
                    self._lines.put({"kind": "garbage", "line": line[:200]})

    def command(self, text: str) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(text + "\n")
        self.proc.stdin.flush()

    def next_record(self, deadline: float) -> dict[str, Any] | None:
        """The next line before ``deadline`` (monotonic), or None; statuses also update :attr:`latest`."""
        remaining = deadline - time.monotonic()
        if remaining <= 0:
            return None
        try:
            record = self._lines.get(timeout=remaining)
        except queue.Empty:
            return None
        if record.get("kind") == "status":
            self.latest = record
        else:
            self.events.append(record)
        return record

    def catch_up(self) -> dict[str, Any]:
        """Take in every line already printed; returns the latest status."""
        while self.next_record(time.monotonic() + 0.001) is not None:
            pass
        return self.latest

    def wait(
        self,
        kind: str,
        predicate: Callable[[dict[str, Any]], bool],
        timeout_s: float,
        what: str,
        on_status: Callable[[dict[str, Any]], None] | None = None,
    ) -> dict[str, Any]:
        """The first record of ``kind`` matching ``predicate``; ``on_status`` sees every status meanwhile."""
        deadline = time.monotonic() + timeout_s
        while True:
            record = self.next_record(deadline)
            if record is None:
                alive = "running" if self.proc.poll() is None else f"exited {self.proc.returncode}"
                raise AssertionError(
                    f"timed out after {timeout_s:g} s waiting for {what}; probe {alive}; "
                    f"last status {self.latest}; events {self.events[-5:]}"
                )
            if record.get("kind") == "status" and on_status is not None:
                on_status(record)
            if record.get("kind") == kind and predicate(record):
                return record

    def output(self) -> str:
        try:
            return self.log_path.read_text(errors="replace")
        except OSError:
            return ""

    def stop(self) -> None:
        if self.proc.poll() is None:
            try:
                self.command("quit")
                self.proc.wait(5)
            except (OSError, subprocess.TimeoutExpired):
                pass
        if self.proc.poll() is None:
            try:
                os.killpg(self.proc.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            self.proc.wait(5)
        self._stderr.close()


class Hosts:
    """The two namespaces and everything started in them, for one test."""

    def __init__(self, pair: HostPair, log_dir: Path) -> None:
        self.pair = pair
        self.log_dir = log_dir
        self.services: list[NetnsProcess] = []
        self.probes: list[Probe] = []

    def run(self, netns: str, module: str, *args: str, label: str) -> NetnsProcess:
        proc = NetnsProcess(netns, module, list(args), self.log_dir / f"{label}.log")
        self.services.append(proc)
        return proc

    def service(self, netns: str, name: str, connect: str, *params: str) -> NetnsProcess:
        return self.run(
            netns, f"services.{name}", "--connect", connect, "--namespace", ROBOT, *params, label=name
        )

    def router(self, netns: str, listen: str, connect: str | None, label: str) -> NetnsProcess:
        args = ["router", "--listen", listen]
        if connect is not None:
            config = self.log_dir / f"{label}.json5"
            config.write_text(
                json.dumps(
                    {
                        "mode": "router",
                        "connect": {
                            "endpoints": [connect],
                            "timeout_ms": -1,
                            "exit_on_failure": False,
                            "retry": {
                                "period_init_ms": 250,
                                "period_max_ms": 1000,
                                "period_increase_factor": 2,
                            },
                        },
                        "scouting": {"multicast": {"enabled": False}},
                        "transport": {"shared_memory": {"enabled": False}},
                    },
                    indent=2,
                )
            )
            args += ["--config", str(config)]
        return self.run(netns, "deploy.cli", *args, label=label)

    def probe(self, netns: str, connect: str) -> Probe:
        probe = Probe(netns, connect, self.log_dir / "probe.log", self.log_dir / "probe_trace.jsonl")
        self.probes.append(probe)
        return probe

    def logs(self) -> str:
        parts = [f"----- {p.log_path.stem} ({p.netns}) -----\n{p.output()[-3000:]}" for p in self.services]
        parts += [f"----- probe stderr -----\n{p.output()[-3000:]}" for p in self.probes]
        return "\n".join(parts)

    def close(self) -> None:
        for probe in self.probes:
            probe.stop()
        for proc in reversed(self.services):
            proc.stop(grace_s=3.0)


@pytest.fixture
def hosts(tmp_path: Path, request: pytest.FixtureRequest) -> Iterator[Hosts]:
    """Hosts A and B, torn down (processes killed, namespaces deleted) whatever the test does."""
    if os.geteuid() != 0:
        pytest.skip("creating network namespaces needs root")
    try:
        pair = HostPair.create(f"zd{os.getpid()}")
    except NetnsUnavailable as exc:
        pytest.skip(str(exc))
    harness = Hosts(pair, tmp_path)
    try:
        yield harness
    finally:
        try:
            harness.close()
            failed = getattr(request.node, "rep_call", None) is not None and request.node.rep_call.failed
            if failed:
                print(f"\n{harness.logs()}")
        finally:
            leftovers = pair.leftover_pids()
            pair.delete()
    assert not leftovers, f"processes still inside the namespaces after stopping them: {leftovers}"
    assert not pair.exists(), f"namespaces {pair.a}/{pair.b} were not deleted"


def _speed_stopped(status: dict[str, Any]) -> bool:
    linear, angular = status.get("linear_mps"), status.get("angular_radps")
    return (
        linear is not None and abs(linear) < STOPPED_LINEAR_MPS and abs(angular or 0.0) < STOPPED_ANGULAR_RPS
    )


def _healthy(status: dict[str, Any]) -> bool:
    nodes = set(status["nodes"])
    return (
        (HOST_A_NODES | HOST_B_NODES) <= nodes
        and status["sim_time_s"] is not None
        and status["odom_count"] > 0
        and status["battery_percentage"] is not None
        and status["pose2d_count"] > 0
    )


def test_robot_brakes_when_the_hosts_are_cut_apart_and_docks_once_they_meet_again(hosts: Hosts) -> None:
    a, b = hosts.pair.a, hosts.pair.b
    hosts.router(a, ROUTER_A, None, "router_a")
    hosts.router(b, ROUTER_B_LOCAL, ROUTER_A, "router_b")
    hosts.service(a, "simulator", ROUTER_A, "--world", str(WORLD), "-p", f"rtf={RTF}", "-p", "seed=0")
    hosts.service(a, "battery", ROUTER_A, "-p", "use_sim_time=true")
    hosts.service(a, "pose", ROUTER_A, "-p", "use_sim_time=true")
    hosts.service(b, "planner", ROUTER_B_LOCAL, "-p", "use_sim_time=true", "-p", f"world={WORLD}")
    hosts.service(b, "docking", ROUTER_B_LOCAL, "-p", "use_sim_time=true", "-p", f"dock_database={WORLD}")
    probe = hosts.probe(a, ROUTER_A)

    probe.wait("ready", lambda _r: True, 30, "the probe's session in host A")
    probe.wait(
        "status",
        _healthy,
        60,
        f"nodes {sorted(HOST_A_NODES | HOST_B_NODES)} seen from host A, "
        "with clock, odom, battery_status and map_to_base_link_pose2d",
    )

    probe.command("trigger 0.26 20")
    triggered = probe.wait("trigger", lambda _r: True, 15, "the battery/set_state reply")
    assert triggered["ok"], triggered

    probe.wait("status", lambda s: abs(s["linear_mps"]) > 0.1, 45, "the robot driving (odom speed > 0.1 m/s)")
    at_cut = probe.catch_up()
    cut_s = at_cut["sim_time_s"]
    hosts.pair.set_link(up=False)

    # Judge only fresh odometry: while the link is down, router A may deliver host A's own traffic late
    # (its queues toward host B are full), so a status can repeat an old reading.
    fresh: list[dict[str, Any]] = []

    def keep_fresh(status: dict[str, Any]) -> None:
        newest = fresh[-1]["odom_time_s"] if fresh else at_cut["odom_time_s"]
        if status["odom_time_s"] is not None and status["odom_time_s"] > newest:
            fresh.append(status)

    def settled(samples: list[dict[str, Any]]) -> list[dict[str, Any]]:
        return [s for s in samples if s["odom_time_s"] >= cut_s + STOP_WITHIN_SIM_S]

    held = probe.wait(
        "status",
        lambda s: (
            s["odom_time_s"] >= cut_s + STOP_WITHIN_SIM_S + STAY_STOPPED_SIM_S
            and len(settled(fresh)) >= MIN_SAMPLES
        ),
        40,
        f"{MIN_SAMPLES} odometry samples over {STAY_STOPPED_SIM_S} s of sim time with the link down",
        on_status=keep_fresh,
    )
    first_stop = next((s for s in fresh if _speed_stopped(s)), None)
    summary = (
        f"cut at sim {cut_s:.2f} s driving {at_cut['linear_mps']:.2f} m/s; first stopped odometry at "
        f"{first_stop['odom_time_s'] if first_stop else None}; {len(fresh)} fresh samples while cut"
    )
    moving = [s for s in settled(fresh) if not _speed_stopped(s)]
    assert not moving, f"still moving {STOP_WITHIN_SIM_S} s after the cut: {moving[:3]} ({summary})"
    coast_m = max(math.dist((at_cut["x_m"], at_cut["y_m"]), (s["x_m"], s["y_m"])) for s in fresh)
    assert coast_m <= MAX_COAST_M, f"the robot coasted {coast_m:.2f} m after the cut ({summary})"
    assert held["collisions"] == 0, f"collisions while the link was down: {probe.events}"

    hosts.pair.set_link(up=True)
    docked = probe.wait(
        "status",
        lambda s: (
            s["power_supply_status"] == BatteryState.POWER_SUPPLY_STATUS_CHARGING and s["mated"] is True
        ),
        90,
        "CHARGING with the contacts mated after the link came back",
    )
    assert docked["collisions"] == 0, f"collisions during the run: {probe.events}"
