"""The fleet service as a process: dock reservations, the queue, leases tied to liveliness, bad requests."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import zenoh

from shared.interfaces.fleet import (
    RELEASE_DOCK,
    RESERVE_DOCK,
    FleetDocks,
    FleetQueue,
    ReleaseDockRequest,
    ReserveDockRequest,
)
from shared.names import node_token_key
from shared.node import ServiceError, call_service
from tests.support.bus import KeyRecorder
from tests.support.processes import wait_until


def _world(tmp_path: Path) -> str:
    path = tmp_path / "two_docks.yaml"
    path.write_text(
        "name: two_docks\nbounds: [0.0, 0.0, 8.0, 6.0]\n"
        "docks:\n  - {id: west, pose: [0.6, 3.0, 3.14159265]}\n  - {id: east, pose: [7.4, 3.0, 0.0]}\n"
        "robots:\n  - {name: r1, start: [3.0, 3.0, 0.0]}\n  - {name: r2, start: [5.0, 3.0, 0.0]}\n"
    )
    return str(path)


def _reserve(bus: zenoh.Session, ns: str, robot: str, battery: float, **lengths: float):  # type: ignore[no-untyped-def]
    request = ReserveDockRequest(
        robot=f"{ns}/{robot}",
        battery=battery,
        dock_ids=list(lengths),
        path_lengths=np.array(list(lengths.values()), dtype=float),
    )
    return call_service(bus, f"{ns}/fleet/reserve_dock", RESERVE_DOCK, request, timeout_s=5.0)


def test_reservations_queue_and_leases(spawn, bus: zenoh.Session, namespace: str, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    docks = KeyRecorder(bus, f"{namespace}/fleet/docks", FleetDocks)
    queue = KeyRecorder(bus, f"{namespace}/fleet/queue", FleetQueue)
    spawn("fleet", "-p", f"world={_world(tmp_path)}", "-p", "lease_s=1.5", "-p", "publish_period_s=0.2")
    docks.wait_for(timeout_s=20.0)
    # r2 is alive (its docking node's token); r1 never shows one, so its lease runs out.
    alive = bus.liveliness().declare_token(node_token_key(f"{namespace}/r2", "docking"))
    try:
        first = _reserve(bus, namespace, "r1", 0.20, west=6.0, east=2.5)
        assert (first.granted, first.dock_id) == (True, "east"), first
        second = _reserve(bus, namespace, "r2", 0.22, east=1.0, west=8.0)
        assert (second.granted, second.dock_id) == (True, "west"), "east is r1's: the free one"
        third = _reserve(bus, namespace, "r3", 0.15)
        assert not third.granted and third.queue_position == 1 and "taken" in third.reason
        queued = queue.wait_for(lambda m: [r.robot for r in m.robots] == [f"{namespace}/r3"], timeout_s=5.0)
        assert queued.robots[0].battery == np.float64(0.15)
        held = docks.wait_for(
            lambda m: {d.dock_id: d.robot for d in m.docks}.get("west") == f"{namespace}/r2", timeout_s=5.0
        )
        assert {d.dock_id: d.robot for d in held.docks} == {
            "east": f"{namespace}/r1",
            "west": f"{namespace}/r2",
        }
        # r1 is not seen alive: after the lease its dock is free, and r2 (alive) keeps its own.
        freed = docks.wait_for(
            lambda m: {d.dock_id: d.robot for d in m.docks}.get("east") == "",
            timeout_s=10.0,
            after=docks.count,
        )
        assert {d.dock_id: d.robot for d in freed.docks}["west"] == f"{namespace}/r2"
        granted = _reserve(bus, namespace, "r3", 0.14)
        assert (granted.granted, granted.dock_id) == (True, "east")
        released = call_service(
            bus,
            f"{namespace}/fleet/release_dock",
            RELEASE_DOCK,
            ReleaseDockRequest(robot=f"{namespace}/r2"),
            timeout_s=5.0,
        )
        assert released.dock_id == "west"
    finally:
        alive.undeclare()


def test_bad_requests_get_a_reason_and_the_service_lives_on(
    spawn,
    bus: zenoh.Session,
    namespace: str,  # type: ignore[no-untyped-def]
    tmp_path: Path,
) -> None:
    docks = KeyRecorder(bus, f"{namespace}/fleet/docks", FleetDocks)
    spawn("fleet", "-p", f"world={_world(tmp_path)}")
    docks.wait_for(timeout_s=20.0)
    mismatched = ReserveDockRequest(
        robot="r1", battery=0.2, dock_ids=["west", "east"], path_lengths=np.array([1.0])
    )
    reply = call_service(bus, f"{namespace}/fleet/reserve_dock", RESERVE_DOCK, mismatched, timeout_s=5.0)
    assert not reply.granted and "path lengths" in reply.reason
    assert "fraction" in _reserve(bus, namespace, "r1", 7.0).reason
    assert (
        "no dock 'nope'"
        in call_service(
            bus,
            f"{namespace}/fleet/reserve_dock",
            RESERVE_DOCK,
            ReserveDockRequest(robot="r1", battery=0.2, dock_id="nope"),
            timeout_s=5.0,
        ).reason
    )
    bus.put(f"{namespace}/fleet/reserve_dock", b"\x00garbage")
    try:
        call_service(
            bus,
            f"{namespace}/fleet/release_dock",
            RELEASE_DOCK,
            ReleaseDockRequest(robot="r9"),
            timeout_s=5.0,
        )
    except ServiceError as exc:  # pragma: no cover - the failure's message says what broke
        raise AssertionError(f"the fleet stopped answering after garbage: {exc}") from None
    wait_until(lambda: docks.latest() is not None, 5.0, "no fleet/docks")
