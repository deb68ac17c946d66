"""``zendock bench messages``: what crosses the bus per simulated second, per key and per subscriber.

A trials campaign runs (the real stack, docking from random starts); when the stack is healthy and again
after the last trial, every node is asked for its counters (``@zendock/stats/<ns>/<node>``: samples put per
key, samples received per key). The differences, over the simulated seconds between the two, give for
each key the samples published and the samples delivered (one per receiving node), and for each node what
it received. Counting at the nodes, not with a wildcard subscriber, leaves the on-demand streams (camera
images, infrared) as the stack alone would run them.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

from shared.interfaces.simulator import SIM_STATE, SimStateRequest
from shared.names import GRAPH_PREFIX
from shared.node import ServiceError, call_service

STATS_QUERY = f"{GRAPH_PREFIX}/stats/**"


def node_counters(session: Any, timeout_s: float = 3.0) -> dict[str, dict[str, Any]]:
    """Every node's counters, by ``<namespace>/<node>`` (or ``<node>`` outside a namespace)."""
    found: dict[str, dict[str, Any]] = {}
    import zenoh  # noqa: PLC0415

    replies = session.get(
        STATS_QUERY,
        timeout=timeout_s,
        target=zenoh.QueryTarget.ALL,
        consolidation=zenoh.ConsolidationMode.NONE,
    )
    for reply in replies:
        if reply.ok is None:
            continue
        try:
            body = json.loads(reply.ok.payload.to_bytes())
            label = f"{body['namespace']}/{body['node']}" if body["namespace"] else str(body["node"])
        except (ValueError, KeyError, TypeError):
            continue
        found[label] = body
    return found


def _sim_now(session: Any, robot: str) -> float:
    try:
        return call_service(
            session, "simulator/state", SIM_STATE, SimStateRequest(robot=robot)
        ).stamp.to_sec()
    except ServiceError:
        return math.nan


def robot_relative(key: str, robots: list[str]) -> str:
    """``r0/odom`` -> ``odom``: one robot's keys under one name, whichever robot."""
    for robot in robots:
        if key.startswith(f"{robot}/"):
            return key[len(robot) + 1 :]
    return key


def _delta(after: dict[str, int], before: dict[str, int]) -> dict[str, int]:
    return {k: v - before.get(k, 0) for k, v in after.items() if v - before.get(k, 0) > 0}


def _thread_kind(pid: int, tid: int) -> str:
    """``python`` for the interpreter's threads (they keep the process's name), ``zenoh`` for the Rust
    runtime's (Zenoh names its threads: rx-0, tx-0, net-0, ...)."""
    try:
        with open(f"/proc/{pid}/task/{tid}/comm") as f:
            name = f.read().strip()
    except OSError:
        return "gone"
    return "python" if name.startswith(("python", "zendock")) else "zenoh"


def cpu_by_thread_kind(processes: list[tuple[str, int | None]]) -> dict[str, dict[str, float]]:
    """CPU seconds used so far by each service's process, split into its Python and its Zenoh threads."""
    import psutil  # noqa: PLC0415

    out: dict[str, dict[str, float]] = {}
    for name, pid in processes:
        if not pid:
            continue
        try:
            threads = psutil.Process(pid).threads()
        except psutil.Error:
            continue
        split: dict[str, float] = {}
        for thread in threads:
            kind = _thread_kind(pid, thread.id)
            split[kind] = split.get(kind, 0.0) + thread.user_time + thread.system_time
        out[name] = split
    return out


@dataclass
class MessageCount:
    """What the tap saw between its two snapshots."""

    robots: list[str] = field(default_factory=list)
    sim_s: float = math.nan
    wall_s: float = math.nan
    before: dict[str, dict[str, Any]] = field(default_factory=dict)
    after: dict[str, dict[str, Any]] = field(default_factory=dict)

    cpu_before: dict[str, dict[str, float]] = field(default_factory=dict)
    cpu_after: dict[str, dict[str, float]] = field(default_factory=dict)

    @contextmanager
    def tap(
        self, session: Any, robots: list[str], processes: Any = None, endpoint: str = ""
    ) -> Iterator[None]:
        """Entered with the stack healthy, left after the last trial (``run_trials``' ``tap``); ``processes()``
        gives the stack's ``(service, pid)`` pairs for the CPU split (the router's ``endpoint`` is not needed)."""
        self.robots = list(robots)
        self.cpu_before = cpu_by_thread_kind(processes() if processes else [])
        start = _sim_now(session, robots[0])
        wall_start = time.monotonic()
        self.before = node_counters(session)
        try:
            yield
        finally:
            self.after = node_counters(session)
            self.cpu_after = cpu_by_thread_kind(processes() if processes else [])
            self.sim_s = _sim_now(session, robots[0]) - start
            self.wall_s = time.monotonic() - wall_start

    def report(self) -> dict[str, Any]:
        """Per key and per node, per simulated second and per robot."""
        if not (self.sim_s > 0) or not self.after:
            raise RuntimeError("no counters or no simulated time between the snapshots")
        per = self.sim_s * max(1, len(self.robots))
        keys: dict[str, dict[str, Any]] = {}
        nodes: dict[str, float] = {}

        def row_of(key: str) -> dict[str, Any]:
            return keys.setdefault(
                robot_relative(key, self.robots), {"published": 0.0, "delivered": 0.0, "by": set()}
            )

        for label, body in self.after.items():
            old = self.before.get(label, {})
            node = robot_relative(label, self.robots)
            for key, n in _delta(body.get("published", {}), old.get("published", {})).items():
                row_of(key)["published"] += n / per
            received = _delta(body.get("received", {}), old.get("received", {}))
            for key, n in received.items():
                row = row_of(key)
                row["delivered"] += n / per
                row["by"].add(node)
            nodes[node] = nodes.get(node, 0.0) + sum(received.values()) / per
        rows = {
            key: {
                "published_per_sim_s": round(row["published"], 1),
                "delivered_per_sim_s": round(row["delivered"], 1),
                "subscribers": sorted(row["by"]),
            }
            for key, row in sorted(keys.items(), key=lambda kv: -kv[1]["delivered"])
        }
        pacing = {}
        for label, body in self.after.items():
            old_extra = self.before.get(label, {}).get("extra", {})
            for key, value in (body.get("extra") or {}).items():
                if key.startswith("pacing_held_s"):
                    pacing[key.replace("pacing_held_s", "held_wall_s")] = round(
                        value - old_extra.get(key, 0.0), 2
                    )
                elif key == "pacing_holds":
                    pacing["holds"] = int(value - old_extra.get(key, 0.0))
        held = sum(v for k, v in pacing.items() if k.startswith("held_wall_s_"))
        cpu: dict[str, dict[str, float]] = {}
        for name, split in self.cpu_after.items():
            old_split = self.cpu_before.get(name, {})
            row = {
                kind: round(1000 * (v - old_split.get(kind, 0.0)) / self.sim_s, 2)
                for kind, v in split.items()
                if kind != "gone"
            }
            row["all"] = round(sum(row.values()), 2)
            for robot in self.robots:  # trials name a robot's services <service>_<robot>
                name = name.removesuffix(f"_{robot}")
            cpu[name] = row
        return {
            "sim_s": round(self.sim_s, 1),
            "wall_s": round(self.wall_s, 1),
            "rtf": round(self.sim_s / self.wall_s, 2),
            #: The simulator waiting for a moving robot's late command or pose (wall seconds, by what was late).
            "pacing": {**pacing, "held_fraction_of_wall": round(held / self.wall_s, 3)},
            "robots": len(self.robots),
            "published_per_sim_s_per_robot": round(sum(r["published"] for r in keys.values()), 1),
            "delivered_per_sim_s_per_robot": round(sum(r["delivered"] for r in keys.values()), 1),
            "received_per_sim_s_by_node": {
                n: round(v, 1) for n, v in sorted(nodes.items(), key=lambda kv: -kv[1])
            },
            "keys": rows,
            #: CPU milliseconds per simulated second by service, in its Python and its Zenoh threads.
            "cpu_ms_per_sim_s": cpu,
        }
