"""The named checks of ``zendock conform``: the same for every service, then each service's behaviour.

Each check returns a :class:`Check` (name, passed, evidence). The generic checks read the contract; the
behaviour checks are the ones the contract's ``behaviour`` lines name, written here once per service.
They drive the robot through the simulator's requests and judge by the simulator's truth.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from deploy.contracts.candidate import SIGTERM_LIMIT_S, Candidate
from deploy.contracts.probe import MALFORMED_PAYLOADS, Probe
from deploy.paths import REPO_ROOT
from shared.action import ActionClient, spin_in_background
from shared.contracts import Contract
from shared.encoding import ENCODING_PREFIX
from shared.geometry import Pose2D, wrap_angle
from shared.interfaces.battery import SET_BATTERY_STATE, SetBatteryStateRequest
from shared.interfaces.docking import DOCK_ROBOT, DockRobotGoal
from shared.interfaces.fleet import (
    RELEASE_DOCK,
    RESERVE_DOCK,
    FleetDocks,
    ReleaseDockRequest,
    ReserveDockRequest,
)
from shared.interfaces.navigation import NAVIGATE_TO_POSE, NavigateToPoseGoal
from shared.interfaces.simulator import TELEPORT, TeleportRequest
from shared.messages import (
    BatteryState,
    DockContact,
    Float64MultiArray,
    Header,
    Odometry,
    Pose,
    PoseStamped,
    Twist,
    Vector3,
)
from shared.node import Node, call_service
from shared.world import World

#: How long a started service has to announce itself.
START_LIMIT_S = 20.0
#: A measured rate within this fraction of the contract's passes.
RATE_TOLERANCE = 0.3
#: Sim seconds over which a rate is measured.
RATE_SPAN_S = 3.0


@dataclass
class Check:
    name: str
    passed: bool
    evidence: str
    seconds: float = 0.0

    def as_dict(self) -> dict[str, Any]:
        return {
            "check": self.name,
            "passed": self.passed,
            "evidence": self.evidence,
            "seconds": round(self.seconds, 2),
        }


@dataclass
class Context:
    """Everything a check needs: the contract, the program, the bus, the world, where the robot lives."""

    contract: Contract
    candidate: Candidate
    probe: Probe
    world: World
    #: The candidate's namespace (the robot's, or the fleet's for the fleet service).
    namespace: str
    #: The robot's namespace (where the simulator's keys are).
    robot_namespace: str
    #: Whether a simulator's clock runs (rates are then on sim time).
    sim: bool
    domain_id: int = 0

    def key(self, name: str) -> str:
        return self.probe.key(name, self.namespace)

    def robot_key(self, name: str) -> str:
        return self.probe.key(name, self.robot_namespace)


def timed(name: str, body: Callable[[], tuple[bool, str]]) -> Check:
    start = time.monotonic()
    try:
        passed, evidence = body()
    except Exception as exc:  # a check that cannot finish has failed: say why, go on to the next
        passed, evidence = False, f"{type(exc).__name__}: {exc}"
    return Check(name, passed, evidence, time.monotonic() - start)


# --- the checks every service gets ---------------------------------------------------------------------------


def check_starts(ctx: Context) -> Check:
    def body() -> tuple[bool, str]:
        took = ctx.probe.wait_node(
            ctx.namespace, ctx.contract.service, START_LIMIT_S, lambda: ctx.candidate.running
        )
        if took is None:
            why = (
                f"exited with code {ctx.candidate.exit_code}"
                if not ctx.candidate.running
                else f"not within {START_LIMIT_S:g} s"
            )
            last = ctx.candidate.last_lines(1)
            return False, f"no node token @zendock/node/.../{ctx.contract.service}: {why}" + (
                f"; last line: {last[0]}" if last else ""
            )
        return True, f"node token after {took:.1f} s"

    return timed("starts: announces its node token", body)


def _full_required(ctx: Context) -> set[tuple[str, str, str]]:
    return {
        (kind, ctx.key(name), type_name)
        for kind, name, type_name in ctx.contract.required_endpoints()
        if not (kind == "sub" and ctx.contract.subscribes_on_demand)
    }


def check_endpoints(ctx: Context) -> list[Check]:
    declared: set[tuple[str, str, str]] = set()

    def required() -> tuple[bool, str]:
        nonlocal declared
        want = _full_required(ctx)
        deadline = time.monotonic() + 5.0
        while True:  # tokens propagate: look again for a few seconds before judging
            declared = ctx.probe.node_endpoints(ctx.namespace, ctx.contract.service)
            missing = sorted(want - declared)
            if not missing or time.monotonic() > deadline:
                break
            time.sleep(0.5)
        if missing:
            return False, "missing: " + ", ".join(f"{k} {key} ({t})" for k, key, t in missing)
        return True, f"all {len(want)} required endpoints announced"

    def only_named() -> tuple[bool, str]:
        extra = []
        for kind, key, type_name in sorted(declared):
            try:
                ctx.contract.check_endpoint(kind, type_name, key, ctx.contract.service, ctx.namespace)
            except RuntimeError:
                extra.append(f"{kind} {key} ({type_name})")
        return (
            not extra,
            "none beyond the contract" if not extra else "not in the contract: " + ", ".join(extra),
        )

    return [
        timed("endpoints: announces every required one", required),
        timed("endpoints: declares only what the contract names", only_named),
    ]


def check_publishes(ctx: Context) -> list[Check]:
    checks = []
    for topic in ctx.contract.publishes:
        if not topic.required or topic.rate_hz is None:
            continue
        expected = topic.rate_hz

        def body(topic=topic, expected=expected) -> tuple[bool, str]:
            samples = ctx.probe.collect(
                ctx.key(topic.name), topic.type, RATE_SPAN_S, ctx.sim, wall_limit_s=20.0
            )
            if samples.received == 0:
                return False, "nothing arrived"
            if samples.failures:
                return (
                    False,
                    f"{samples.received - samples.decoded} of {samples.received} did not decode: {samples.failures[0]}",
                )
            wanted_encoding = f"{ENCODING_PREFIX};{topic.type.TYPE_NAME}"
            if samples.encodings != {wanted_encoding}:
                return False, f"encoding {sorted(samples.encodings)}, expected {wanted_encoding}"
            rate = samples.rate_hz()
            clock = "sim" if ctx.sim else "wall"
            if rate is None or abs(rate - expected) > RATE_TOLERANCE * expected:
                return (
                    False,
                    f"{samples.decoded} messages, {rate or 0:.1f} Hz of {clock} time; the contract says {expected:g} Hz",
                )
            return (
                True,
                f"{samples.decoded} messages, {rate:.1f} Hz of {clock} time (contract {expected:g} Hz), all decode",
            )

        checks.append(timed(f"publishes {topic.name}", body))
    return checks


def check_bad_requests(ctx: Context) -> Check:
    def body() -> tuple[bool, str]:
        keys = [ctx.key(r.name) for r in ctx.contract.serves if r.required]
        keys += [ctx.key(f"{a.name}/_action/send_goal") for a in ctx.contract.serves_actions if a.required]
        if not keys:
            return True, "serves no request"
        problems, answered = [], []
        for key in keys:
            verdict, text = ctx.probe.query_raw(key, MALFORMED_PAYLOADS[2])
            if verdict != "error":
                problems.append(f"{key}: {'answered as if valid' if verdict == 'ok' else 'no reply'}")
            else:
                answered.append(f'{key}: "{text[:60]}"')
        return (not problems, "; ".join(problems) if problems else "error replies: " + "; ".join(answered))

    return timed("bad requests get an error reply", body)


def check_malformed_burst(ctx: Context, still_serving: Callable[[], tuple[bool, str]]) -> Check:
    def body() -> tuple[bool, str]:
        keys = [ctx.key(t.name) for t in ctx.contract.subscribes if t.required and not t.fleet_wide]
        # and whatever it subscribes right now (on-demand subscriptions too), the shared clock aside
        declared = ctx.probe.node_endpoints(ctx.namespace, ctx.contract.service)
        keys += sorted(
            {key for kind, key, _type in declared if kind == "sub" and not key.endswith("clock")} - set(keys)
        )
        keys += [ctx.key(r.name) for r in ctx.contract.serves if r.required]
        sent = 0
        for key in keys:
            for _ in range(10):
                for payload in MALFORMED_PAYLOADS:
                    ctx.probe.put_raw(key, payload)
                    sent += 1
        time.sleep(1.0)
        if not ctx.candidate.running:
            return (
                False,
                f"exited with code {ctx.candidate.exit_code} after {sent} malformed payloads on {len(keys)} keys",
            )
        ok, evidence = still_serving()
        return ok, f"{sent} malformed payloads on {len(keys)} keys; {evidence}"

    return timed("survives malformed payloads on every key", body)


def still_serving(ctx: Context) -> Callable[[], tuple[bool, str]]:
    """After abuse: its token is there and, if it publishes continuously, a valid message still comes."""

    def body() -> tuple[bool, str]:
        if (
            ctx.probe.wait_node(ctx.namespace, ctx.contract.service, 5.0, lambda: ctx.candidate.running)
            is None
        ):
            return False, "its node token is gone"
        steady = [t for t in ctx.contract.publishes if t.required and t.rate_hz]
        if not steady:
            return True, "still announced"
        topic = steady[0]
        got = ctx.probe.wait_for(ctx.key(topic.name), topic.type, lambda _m: True, 5.0)
        return (
            got is not None,
            f"still publishes {topic.name}" if got is not None else f"{topic.name} stopped",
        )

    return body


def check_sigterm(ctx: Context) -> Check:
    def body() -> tuple[bool, str]:
        code, took = ctx.candidate.terminate(SIGTERM_LIMIT_S)
        if code is None:
            return False, f"still running {SIGTERM_LIMIT_S:g} s after SIGTERM"
        return code == 0, f"exit code {code} after {took:.2f} s"

    return timed(f"SIGTERM: exit 0 within {SIGTERM_LIMIT_S:g} s", body)


def check_restart(ctx: Context) -> Check:
    def body() -> tuple[bool, str]:
        ctx.candidate.close()
        ctx.candidate.start()
        took = ctx.probe.wait_node(
            ctx.namespace, ctx.contract.service, START_LIMIT_S, lambda: ctx.candidate.running
        )
        if took is None:
            return False, f"no node token within {START_LIMIT_S:g} s of the restart"
        ok, evidence = still_serving(ctx)()
        return ok, f"back after {took:.1f} s; {evidence}"

    return timed("restarted, it comes back", body)


# --- behaviour: what each service does with its inputs ---------------------------------------------------------


def _teleport(ctx: Context, pose: Pose2D) -> None:
    reply = call_service(
        ctx.probe.session,
        ctx.robot_key("simulator/teleport"),
        TELEPORT,
        TeleportRequest(x=pose.x, y=pose.y, yaw=pose.yaw),
        timeout_s=5.0,
    )
    if not reply.success:
        raise ValueError(f"teleport to {pose} refused: {reply.message}")


def in_front_of_dock(world: World, distance_m: float) -> Pose2D:
    """Facing the first dock, ``distance_m`` short of its docked pose."""
    dock = world.docks[0].pose2d
    return Pose2D(
        dock.x - distance_m * math.cos(dock.yaw), dock.y - distance_m * math.sin(dock.yaw), dock.yaw
    )


def _truth(ctx: Context) -> Pose2D | None:
    msg = ctx.probe.wait_for(ctx.robot_key("ground_truth_pose"), PoseStamped, lambda _m: True, 3.0)
    return msg.pose.to_pose2d() if msg is not None else None


class _Driver:
    """Publishes a twist on cmd_vel at 10 Hz (wall) until stopped, as a teleoperator would."""

    def __init__(self, ctx: Context, linear: float, angular: float) -> None:
        self._ctx, self._twist = ctx, Twist(Vector3(linear, 0.0, 0.0), Vector3(0.0, 0.0, angular))
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        key = self._ctx.robot_key("cmd_vel")
        while not self._stop.is_set():
            self._ctx.probe.put_raw(key, self._twist.encode())
            self._stop.wait(0.1)
        self._ctx.probe.put_raw(key, Twist().encode())

    def __enter__(self) -> _Driver:
        self._thread.start()
        return self

    def __exit__(self, *_exc: object) -> None:
        self._stop.set()
        self._thread.join(2.0)


def _battery(ctx: Context, timeout_s: float = 3.0) -> BatteryState | None:
    return ctx.probe.wait_for(ctx.robot_key("battery_status"), BatteryState, lambda _m: True, timeout_s)


def _set_battery(ctx: Context, **values: Any) -> None:
    call_service(
        ctx.probe.session,
        ctx.robot_key("battery/set_state"),
        SET_BATTERY_STATE,
        SetBatteryStateRequest(**values),
        timeout_s=5.0,
    )


def _wait_sim(ctx: Context, seconds: float, wall_limit_s: float = 30.0) -> None:
    start_wall = time.monotonic()
    ctx.probe.wait_clock(wall_limit_s)
    start = ctx.probe.now(True)
    while ctx.probe.now(True) - start < seconds and time.monotonic() - start_wall < wall_limit_s:
        time.sleep(0.05)


def battery_behaviour(ctx: Context) -> list[Check]:
    def answers() -> tuple[bool, str]:
        _set_battery(ctx, percentage=0.5, drain_scale=1.0, charge_scale=1.0)
        msg = ctx.probe.wait_for(
            ctx.robot_key("battery_status"), BatteryState, lambda m: abs(m.percentage - 0.5) < 0.01, 5.0
        )
        return (
            msg is not None,
            f"battery_status at {msg.percentage:.3f} after set_state(0.5)"
            if msg
            else "battery_status never showed the charge set_state asked for",
        )

    def drains() -> tuple[bool, str]:
        _teleport(ctx, in_front_of_dock(ctx.world, 1.5))
        _set_battery(ctx, percentage=0.8, drain_scale=50.0)
        before = _battery(ctx)
        with _Driver(ctx, 0.15, 0.0):
            _wait_sim(ctx, 2.0)
            after = _battery(ctx)
        if before is None or after is None:
            return False, "no battery_status"
        ok = (
            after.percentage < before.percentage
            and after.power_supply_status == BatteryState.POWER_SUPPLY_STATUS_DISCHARGING
        )
        return (
            ok,
            f"{before.percentage:.4f} -> {after.percentage:.4f} over 2 s of driving, status {after.power_supply_status}",
        )

    def charges() -> tuple[bool, str]:
        _set_battery(ctx, percentage=0.5, charge_scale=50.0, drain_scale=1.0)
        _teleport(ctx, in_front_of_dock(ctx.world, 0.02))
        mated = ctx.probe.wait_for(ctx.robot_key("dock_contact"), DockContact, lambda m: m.mated, 5.0)
        if mated is None:
            return False, "the simulator never reported the contacts mated (placement)"
        first = ctx.probe.wait_for(
            ctx.robot_key("battery_status"),
            BatteryState,
            lambda m: m.power_supply_status == BatteryState.POWER_SUPPLY_STATUS_CHARGING,
            5.0,
        )
        if first is None:
            return False, "mated, but battery_status never said CHARGING"
        _wait_sim(ctx, 2.0)
        later = _battery(ctx)
        ok = later is not None and later.percentage > first.percentage
        return (
            ok,
            f"CHARGING, {first.percentage:.4f} -> {later.percentage if later else float('nan'):.4f} over 2 s mated",
        )

    return [
        timed("answers set_state", answers),
        timed("drains while the robot drives", drains),
        timed("charges while mated", charges),
    ]


def pose_behaviour(ctx: Context) -> list[Check]:
    def follows() -> tuple[bool, str]:
        target = in_front_of_dock(ctx.world, 1.0)
        _teleport(ctx, target)

        def close(m: Float64MultiArray) -> bool:
            x, y, yaw = (float(v) for v in m.data[:3]) if len(m.data) >= 3 else (math.inf, math.inf, math.inf)
            return math.hypot(x - target.x, y - target.y) < 0.05 and abs(wrap_angle(yaw - target.yaw)) < 0.05

        msg = ctx.probe.wait_for(ctx.key("map_to_base_link_pose2d"), Float64MultiArray, close, 5.0)
        return (
            msg is not None,
            f"[{', '.join(f'{v:.3f}' for v in msg.data)}] for truth {target}"
            if msg
            else f"map_to_base_link_pose2d never came within 5 cm / 0.05 rad of {target}",
        )

    return [timed("follows the robot", follows)]


def simulator_behaviour(ctx: Context) -> list[Check]:
    def clock() -> tuple[bool, str]:
        ctx.probe.wait_clock(5.0)
        first = ctx.probe.sim_now()
        time.sleep(1.5)
        later = ctx.probe.sim_now()
        ok = first is not None and later is not None and later > first
        return ok, f"clock {first} -> {later} over 1.5 s wall"

    def teleport() -> tuple[bool, str]:
        target = in_front_of_dock(ctx.world, 1.2)
        _teleport(ctx, target)
        msg = ctx.probe.wait_for(
            ctx.robot_key("ground_truth_pose"),
            PoseStamped,
            lambda m: m.pose.to_pose2d().distance_to(target) < 0.02,
            5.0,
        )
        return (
            msg is not None,
            f"ground_truth_pose at {msg.pose.to_pose2d()}" if msg else f"never reached {target}",
        )

    def drives() -> tuple[bool, str]:
        with _Driver(ctx, 0.0, 0.5):
            msg = ctx.probe.wait_for(
                ctx.robot_key("odom"), Odometry, lambda m: m.twist.twist.angular.z > 0.2, 5.0
            )
        return (
            msg is not None,
            f"odom turning at {msg.twist.twist.angular.z:.2f} rad/s" if msg else "odom never showed the turn",
        )

    return [timed("keeps the clock", clock), timed("answers teleport", teleport), timed("drives", drives)]


def _cancel(client: ActionClient[Any, Any, Any], handle: Any) -> None:
    """Cancel a goal that outlived its check, and wait (briefly) for the answer before the node closes."""
    answered = threading.Event()
    client.cancel_goal(handle, on_done=lambda _reply, _error: answered.set())
    answered.wait(5.0)


def _node_client(ctx: Context) -> Node:
    node = Node("conform_client", ctx.probe.session, ctx.robot_namespace, use_sim_time=True)
    spin_in_background(node)
    return node


def planner_behaviour(ctx: Context) -> list[Check]:
    def navigates() -> tuple[bool, str]:
        start = in_front_of_dock(ctx.world, 1.8)
        _teleport(ctx, start)
        goals = [
            Pose2D(start.x + math.cos(a), start.y + math.sin(a), a)
            for a in (start.yaw + math.pi, start.yaw + 2.0, start.yaw - 2.0, start.yaw + 1.2)
        ]
        goal = next((g for g in goals if ctx.world.placement_problem(g.x, g.y) is None), None)
        if goal is None:
            return False, "no free goal 1 m from the start in this world"
        node = _node_client(ctx)
        try:
            client = ActionClient(node, NAVIGATE_TO_POSE, "navigate_to_pose")
            feedback: list[Any] = []
            handle = client.send_goal(
                NavigateToPoseGoal(PoseStamped(Header(frame_id="map"), Pose.from_pose2d(goal))),
                on_feedback=feedback.append,
            )
            deadline = time.monotonic() + 90.0
            while not handle.done and time.monotonic() < deadline:
                time.sleep(0.1)
            if not handle.done:  # the robot must not drive on through the checks that follow
                _cancel(client, handle)
            truth = _truth(ctx)
        finally:
            node.close()
        miss = truth.distance_to(goal) if truth else math.inf
        ok = handle.status.name == "SUCCEEDED" and bool(feedback) and miss < 0.25
        return (
            ok,
            f"status {handle.status.name}, {len(feedback)} feedback, {miss:.2f} m from the goal {handle.rejection or handle.error}".rstrip(),
        )

    return [timed("navigates", navigates)]


def _supply_status(msg: BatteryState | None) -> str:
    if msg is None:
        return "not charging"
    return "FULL" if msg.power_supply_status == BatteryState.POWER_SUPPLY_STATUS_FULL else "CHARGING"


def docking_behaviour(ctx: Context) -> list[Check]:
    def docks() -> tuple[bool, str]:
        _teleport(ctx, in_front_of_dock(ctx.world, 1.5))
        node = _node_client(ctx)
        try:
            client = ActionClient(node, DOCK_ROBOT, "dock_robot")
            feedback: list[Any] = []
            handle = client.send_goal(
                DockRobotGoal(use_dock_id=True, dock_id=ctx.world.docks[0].id), on_feedback=feedback.append
            )
            deadline = time.monotonic() + 150.0
            while not handle.done and time.monotonic() < deadline:
                time.sleep(0.1)
            if not handle.done:
                _cancel(client, handle)
        finally:
            node.close()
        # CHARGING, or FULL: a battery that was nearly full when the robot mated is full a moment later (both
        # mean the contacts carry current, as the docking service and the trials count them)
        on_dock = (BatteryState.POWER_SUPPLY_STATUS_CHARGING, BatteryState.POWER_SUPPLY_STATUS_FULL)
        charging = ctx.probe.wait_for(
            ctx.robot_key("battery_status"), BatteryState, lambda m: m.power_supply_status in on_dock, 5.0
        )
        success = bool(handle.result is not None and getattr(handle.result, "success", False))
        ok = handle.status.name == "SUCCEEDED" and success and bool(feedback) and charging is not None
        return ok, (
            f"status {handle.status.name}, success {success}, {len(feedback)} feedback, "
            f"{_supply_status(charging)} {handle.rejection or handle.error}"
        ).rstrip()

    return [timed("docks", docks)]


def perception_behaviour(ctx: Context) -> list[Check]:
    def sees() -> tuple[bool, str]:
        robot = in_front_of_dock(ctx.world, 1.0)
        _teleport(ctx, robot)
        truth = ctx.world.docks[0].pose2d.relative_to(robot)
        msg = ctx.probe.wait_for(
            ctx.key("detected_dock_pose"),
            PoseStamped,
            lambda m: math.hypot(m.pose.position.x - truth.x, m.pose.position.y - truth.y) < 0.05,
            15.0,
        )
        return (
            msg is not None,
            f"dock at ({msg.pose.position.x:.3f}, {msg.pose.position.y:.3f}) in base_link, truth "
            f"({truth.x:.3f}, {truth.y:.3f})"
            if msg
            else f"no detection within 5 cm of ({truth.x:.3f}, {truth.y:.3f}) in 15 s",
        )

    return [timed("sees the dock", sees)]


def fleet_behaviour(ctx: Context) -> list[Check]:
    def reserves() -> tuple[bool, str]:
        session = ctx.probe.session
        granted = call_service(
            session,
            ctx.key("fleet/reserve_dock"),
            RESERVE_DOCK,
            ReserveDockRequest(robot="conform_r1", battery=0.2),
            timeout_s=5.0,
        )
        if not granted.granted:
            return False, f"not granted: {granted.reason}"
        taken = ctx.probe.wait_for(
            ctx.key("fleet/docks"),
            FleetDocks,
            lambda m: any(d.dock_id == granted.dock_id and d.robot == "conform_r1" for d in m.docks),
            5.0,
        )
        call_service(
            session, ctx.key("fleet/release_dock"), RELEASE_DOCK, ReleaseDockRequest(robot="conform_r1"), 5.0
        )
        freed = ctx.probe.wait_for(
            ctx.key("fleet/docks"),
            FleetDocks,
            lambda m: any(d.dock_id == granted.dock_id and not d.robot for d in m.docks),
            5.0,
        )
        ok = taken is not None and freed is not None
        return (
            ok,
            f"{granted.dock_id} granted, {'shown taken' if taken else 'never shown taken'}, "
            f"{'then free' if freed else 'never shown free again'}",
        )

    return [timed("reserves and releases", reserves)]


def ros2_bridge_behaviour(ctx: Context) -> list[Check]:
    def shows() -> tuple[bool, str]:
        deadline = time.monotonic() + 10.0
        names: set[str] = set()
        while time.monotonic() < deadline:
            replies = ctx.probe.session.liveliness().get(f"@ros2_lv/{ctx.domain_id}/**", timeout=1.0)
            names = {
                str(r.ok.key_expr).split("/")[-1]
                for r in replies
                if r.ok is not None and "/NN/" in str(r.ok.key_expr)
            }
            if "simulator" in names:
                return True, f"ROS 2 nodes announced: {', '.join(sorted(names))}"
            time.sleep(0.5)
        return (
            False,
            f"no rmw_zenoh node token for the simulator on domain {ctx.domain_id} (saw {sorted(names)})",
        )

    return [timed("shows zendock to ROS 2", shows)]


#: What a ROS 2 machine sees: real rclpy, on the face's domain, loopback discovery; prints the node names it finds.
_RCLPY_NODE_LIST = """
import json, sys, time
import rclpy
rclpy.init()
node = rclpy.create_node("zendock_conform_probe")
names = []
deadline = time.monotonic() + float(sys.argv[1])
while time.monotonic() < deadline:
    rclpy.spin_once(node, timeout_sec=0.2)
    names = sorted(set(node.get_node_names()) - {"zendock_conform_probe"})
    if "simulator" in names:
        break
print(json.dumps(names))
node.destroy_node()
rclpy.shutdown()
"""


def ros2_dds_behaviour(ctx: Context) -> list[Check]:
    def shows() -> tuple[bool, str]:
        python = REPO_ROOT / ".venv-ros2" / "bin" / "python"
        if not python.exists():
            return False, f"looking from ROS 2 needs {python} with rclpy (make ros2)"
        env = {k: v for k, v in os.environ.items() if not k.startswith(("VIRTUAL_ENV", "PYTHON"))}
        env.update(ROS_DOMAIN_ID=str(ctx.domain_id), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
        done = subprocess.run(
            [str(python), "-c", _RCLPY_NODE_LIST, "15"], env=env, capture_output=True, text=True, timeout=60
        )
        lines = done.stdout.strip().splitlines()
        if done.returncode != 0 or not lines:
            return False, f"the rclpy probe failed ({done.returncode}): {done.stderr.strip()[-200:]}"
        names = json.loads(lines[-1])
        ok = "simulator" in names
        return ok, (
            f"an rclpy node on domain {ctx.domain_id} sees: {', '.join(names)}"
            if ok
            else f"no /simulator node on DDS domain {ctx.domain_id} (saw {names})"
        )

    return [timed("shows zendock to ROS 2 on DDS (real rclpy)", shows)]


BEHAVIOURS: dict[str, Callable[[Context], list[Check]]] = {
    "battery": battery_behaviour,
    "docking": docking_behaviour,
    "fleet": fleet_behaviour,
    "perception": perception_behaviour,
    "planner": planner_behaviour,
    "pose": pose_behaviour,
    "ros2_bridge": ros2_bridge_behaviour,
    "ros2_dds": ros2_dds_behaviour,
    "simulator": simulator_behaviour,
}
