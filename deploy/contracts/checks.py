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
from deploy.contracts.probe import MALFORMED_PAYLOADS, Probe, Samples
from deploy.paths import REPO_ROOT
from deploy.percentiles import median
from shared.action import ActionClient, spin_in_background
from shared.contracts import Contract, Topic
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
from shared.world import DOCK_GEOMETRY, World

#: How long a started service has to announce itself.
START_LIMIT_S = 20.0
#: A measured rate within this fraction of the contract's passes.
RATE_TOLERANCE = 0.3
#: An event topic may burst this much over its ``max_rate_hz`` (plus one message) within a second.
RATE_TOLERANCE_ABOVE = 1.3
#: Sim seconds over which a rate is measured.
RATE_SPAN_S = 3.0


@dataclass
class Check:
    """One row of the report: pass, FAIL, or not run (``ran`` false, the evidence saying why)."""

    name: str
    passed: bool
    evidence: str
    seconds: float = 0.0
    ran: bool = True

    @property
    def result(self) -> str:
        return "pass" if self.passed else "FAIL" if self.ran else "not run"

    def as_dict(self) -> dict[str, Any]:
        return {
            "check": self.name,
            "result": self.result,
            "passed": self.passed,
            "evidence": self.evidence,
            "seconds": round(self.seconds, 2),
        }


@dataclass(frozen=True)
class PlannedCheck:
    """A check named before any runs, so that every one gets its row even when it cannot run."""

    name: str
    body: Callable[[], tuple[bool, str]]
    #: Asked just before it would run: why it cannot (``""``: it can).
    blocked: Callable[[], str] | None = None
    #: When it fails, the checks after it do not run, for this reason.
    stops_the_rest: str = ""

    def run(self) -> Check:
        start = time.monotonic()
        try:
            passed, evidence = self.body()
        except Exception as exc:  # a check that cannot finish has failed: say why, go on to the next
            passed, evidence = False, f"{type(exc).__name__}: {exc}"
        return Check(self.name, passed, evidence, time.monotonic() - start)

    def not_run(self, why: str) -> Check:
        return Check(self.name, False, f"not run: {why}", ran=False)


def run_in_turn(planned: list[PlannedCheck], on_row: Callable[[Check], None]) -> list[Check]:
    """Every planned check's row, in order: run, or not run with the reason (an earlier gate failed, or its
    own precondition does not hold)."""
    rows: list[Check] = []
    stopped = ""
    for check in planned:
        why = stopped or (check.blocked() if check.blocked else "")
        row = check.not_run(why) if why else check.run()
        rows.append(row)
        on_row(row)
        if row.ran and not row.passed and check.stops_the_rest:
            stopped = check.stops_the_rest
    return rows


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


# --- the checks every service gets ---------------------------------------------------------------------------


def check_starts(ctx: Context) -> PlannedCheck:
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

    return PlannedCheck("starts: announces its node token", body, stops_the_rest="it did not start")


def _full_required(ctx: Context) -> set[tuple[str, str, str]]:
    return {
        (kind, ctx.key(name), type_name)
        for kind, name, type_name in ctx.contract.required_endpoints()
        if not (kind == "sub" and ctx.contract.subscribes_on_demand)
    }


def check_endpoints(ctx: Context) -> list[PlannedCheck]:
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
        PlannedCheck("endpoints: announces every required one", required),
        PlannedCheck("endpoints: declares only what the contract names", only_named),
    ]


def check_publishes(ctx: Context) -> list[PlannedCheck]:
    checks: list[PlannedCheck] = []
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

        checks.append(PlannedCheck(f"publishes {topic.name}", body))
    return checks


class RunWatch:
    """What a service publishes over the whole run, from before it starts: the frames its messages carry,
    and how fast its event topics come. Event topics are judged on what the behaviour checks drew out."""

    def __init__(self, ctx: Context) -> None:
        # not what is published only while someone listens: watching would change what the service does
        self.topics = [
            t
            for t in ctx.contract.publishes
            if not t.fleet_wide and not t.on_demand and (t.frame_id or t.max_rate_hz)
        ]
        self._tallies: dict[str, Samples] = {}
        self._subscribers: list[Any] = []
        for topic in self.topics:
            tally, sub = ctx.probe.watch(
                ctx.key(topic.name), topic.type, ctx.sim, keep_times=topic.max_rate_hz is not None
            )
            self._tallies[topic.name] = tally
            self._subscribers.append(sub)

    def tally(self, topic: Topic) -> Samples:
        return self._tallies[topic.name]

    def close(self) -> None:
        for sub in self._subscribers:
            sub.undeclare()
        self._subscribers = []


def _frame_words(frame: str, child: str, with_child: bool) -> str:
    return f"{frame!r}" + (f", child {child!r}" if with_child else "")


def check_frames(ctx: Context, watch: RunWatch) -> PlannedCheck | None:
    """Every message seen on a key whose contract names its frame carries that frame (``None``: the contract
    names no frame)."""
    framed = [t for t in watch.topics if t.frame_id]
    if not framed:
        return None

    def body() -> tuple[bool, str]:
        watch.close()
        wrong, seen, heard = [], 0, []
        for topic in framed:
            frames = watch.tally(topic).frames
            if frames:
                heard.append(topic.name)
            with_child = bool(topic.child_frame_id)
            for (frame, child), count in frames.items():
                seen += count
                if frame != topic.frame_id or (with_child and child != topic.child_frame_id):
                    wrong.append(
                        f"{topic.name}: {count} in {_frame_words(frame, child, with_child)}, the contract says "
                        f"{_frame_words(topic.frame_id, topic.child_frame_id, with_child)}"
                    )
        if wrong:
            return False, "; ".join(wrong)
        if not seen:
            return False, f"no message on {', '.join(t.name for t in framed)} to check"
        return True, f"{seen} messages on {', '.join(heard)}, each in the contract's frame"

    return PlannedCheck("frames: every header names the contract's frame", body)


def check_event_rates(ctx: Context, watch: RunWatch) -> PlannedCheck | None:
    """No event topic comes faster than its contract's ``max_rate_hz`` in any second of the run (``None``:
    the contract bounds none)."""
    bounded = [t for t in watch.topics if t.max_rate_hz is not None]
    if not bounded:
        return None
    clock = "sim" if ctx.sim else "wall"

    def body() -> tuple[bool, str]:
        watch.close()
        over, peaks = [], []
        for topic in bounded:
            assert topic.max_rate_hz is not None
            peak = watch.tally(topic).peak_per_s()
            peaks.append(f"{topic.name} {peak}")
            if peak > RATE_TOLERANCE_ABOVE * topic.max_rate_hz + 1:
                over.append(
                    f"{topic.name}: {peak} in one second of {clock} time, the contract allows "
                    f"{topic.max_rate_hz:g}/s"
                )
        if over:
            return False, "; ".join(over)
        return True, f"most in any second of {clock} time: {', '.join(peaks)}"

    return PlannedCheck("events: none faster than the contract allows", body)


def check_bad_requests(ctx: Context) -> PlannedCheck:
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

    return PlannedCheck("bad requests get an error reply", body)


def check_malformed_burst(ctx: Context, still_serving: Callable[[], tuple[bool, str]]) -> PlannedCheck:
    def body() -> tuple[bool, str]:
        # every key the contract names it subscribes or serves, required or not (a service that left its
        # tokens out is flooded all the same), and whatever it subscribes right now (on-demand subscriptions
        # too), the shared clock aside
        keys = [ctx.key(t.name) for t in ctx.contract.subscribes if not t.fleet_wide]
        declared = ctx.probe.node_endpoints(ctx.namespace, ctx.contract.service)
        keys += sorted(
            {key for kind, key, _type in declared if kind == "sub" and not key.endswith("clock")} - set(keys)
        )
        keys += [ctx.key(r.name) for r in ctx.contract.serves]
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

    return PlannedCheck("survives malformed payloads on every key", body)


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


def check_sigterm(ctx: Context) -> PlannedCheck:
    def body() -> tuple[bool, str]:
        code, took = ctx.candidate.terminate(SIGTERM_LIMIT_S)
        if code is None:
            return False, f"still running {SIGTERM_LIMIT_S:g} s after SIGTERM"
        return code == 0, f"exit code {code} after {took:.2f} s"

    def exited() -> str:
        return "" if ctx.candidate.running else f"it had already exited (code {ctx.candidate.exit_code})"

    return PlannedCheck(f"SIGTERM: exit 0 within {SIGTERM_LIMIT_S:g} s", body, blocked=exited)


def check_restart(ctx: Context) -> PlannedCheck:
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

    return PlannedCheck("restarted, it comes back", body)


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


def _pose_reads(ctx: Context, target: Pose2D, timeout_s: float) -> Float64MultiArray | None:
    """The first ``map_to_base_link_pose2d`` within 5 cm and 0.05 rad of ``target``, else None."""

    def close(m: Float64MultiArray) -> bool:
        x, y, yaw = (float(v) for v in m.data[:3]) if len(m.data) >= 3 else (math.inf, math.inf, math.inf)
        return math.hypot(x - target.x, y - target.y) < 0.05 and abs(wrap_angle(yaw - target.yaw)) < 0.05

    return ctx.probe.wait_for(ctx.key("map_to_base_link_pose2d"), Float64MultiArray, close, timeout_s)


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
    ctx.probe.pass_time(seconds, True, wall_limit_s)


def battery_behaviour(ctx: Context) -> list[PlannedCheck]:
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
        PlannedCheck("answers set_state", answers),
        PlannedCheck("drains while the robot drives", drains),
        PlannedCheck("charges while mated", charges),
    ]


def pose_behaviour(ctx: Context) -> list[PlannedCheck]:
    def follows() -> tuple[bool, str]:
        target = in_front_of_dock(ctx.world, 1.0)
        _teleport(ctx, target)
        msg = _pose_reads(ctx, target, 5.0)
        return (
            msg is not None,
            f"[{', '.join(f'{v:.3f}' for v in msg.data)}] for truth {target}"
            if msg
            else f"map_to_base_link_pose2d never came within 5 cm / 0.05 rad of {target}",
        )

    return [PlannedCheck("follows the robot", follows)]


def simulator_behaviour(ctx: Context) -> list[PlannedCheck]:
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

    return [
        PlannedCheck("keeps the clock", clock),
        PlannedCheck("answers teleport", teleport),
        PlannedCheck("drives", drives),
    ]


def _cancel(client: ActionClient[Any, Any, Any], handle: Any) -> None:
    """Cancel a goal that outlived its check, and wait (briefly) for the answer before the node closes."""
    answered = threading.Event()
    client.cancel_goal(handle, on_done=lambda _reply, _error: answered.set())
    answered.wait(5.0)


def _node_client(ctx: Context) -> Node:
    node = Node("conform_client", ctx.probe.session, ctx.robot_namespace, use_sim_time=True)
    spin_in_background(node)
    return node


def planner_behaviour(ctx: Context) -> list[PlannedCheck]:
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

    return [PlannedCheck("navigates", navigates)]


def _supply_status(msg: BatteryState | None) -> str:
    if msg is None:
        return "not charging"
    return "FULL" if msg.power_supply_status == BatteryState.POWER_SUPPLY_STATUS_FULL else "CHARGING"


def docking_behaviour(ctx: Context) -> list[PlannedCheck]:
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

    return [PlannedCheck("docks", docks)]


#: How far a detected dock may lie from the truth and still count as seen, in metres and radians.
SEEN_WITHIN_M = 0.05
SEEN_WITHIN_RAD = 0.1
#: How long (wall) a detection that close may take to come: over 400 camera frames at the kit's 4x.
SEEN_WAIT_S = 8.0


def units_hint(got_m: float, truth_m: float) -> str:
    """A guess at the unit a distance came in, when it is off by a factor a unit explains."""
    if truth_m < 0.1:
        return ""
    ratio = got_m / truth_m
    for factor, unit in ((1000.0, "millimetres"), (100.0, "centimetres")):
        if 0.8 * factor < ratio < 1.2 * factor:
            return f": {unit}?"
    return ""


def perception_behaviour(ctx: Context) -> list[PlannedCheck]:
    def sees() -> tuple[bool, str]:
        robot = in_front_of_dock(ctx.world, 1.0)
        _teleport(ctx, robot)
        truth = ctx.world.docks[0].pose2d.relative_to(robot)
        arrived: list[Pose2D] = []

        def close(m: PoseStamped) -> bool:
            seen = m.pose.to_pose2d()
            arrived.append(seen)
            off_m, off_rad = _pose_error(seen, truth)
            return off_m < SEEN_WITHIN_M and off_rad < SEEN_WITHIN_RAD

        msg = ctx.probe.wait_for(ctx.key("detected_dock_pose"), PoseStamped, close, SEEN_WAIT_S)
        wanted = f"({truth.x:.3f}, {truth.y:.3f}, yaw {truth.yaw:.3f})"
        if msg is not None:
            seen = msg.pose.to_pose2d()
            return (
                True,
                f"dock at ({seen.x:.3f}, {seen.y:.3f}, yaw {seen.yaw:.3f}) in base_link, truth {wanted}",
            )
        within = (
            f"within {SEEN_WITHIN_M * 100:g} cm and {SEEN_WITHIN_RAD:g} rad of {wanted} in {SEEN_WAIT_S:g} s"
        )
        if not arrived:
            return False, f"no detection {within}: none arrived"
        last = arrived[-1]
        hint = units_hint(math.hypot(last.x, last.y), math.hypot(truth.x, truth.y))
        turned = _pose_error(last, truth)[1]
        if not hint and turned > SEEN_WITHIN_RAD:
            hint = f": yaw off by {turned:.2f} rad" + (", turned by pi?" if turned > 3.0 else "")
        return False, (
            f"no detection {within}: {len(arrived)} arrived, the last at x = {last.x:.3f}, y = {last.y:.3f}, "
            f"yaw {last.yaw:.3f}{hint}"
        )

    def sees_round() -> tuple[bool, str]:
        marker = DOCK_GEOMETRY.marker_pose(ctx.world.docks[0])
        dock = ctx.world.docks[0].pose2d
        worst_m, worst_rad, problems, looked = 0.0, 0.0, [], 0
        for range_m, angle_deg in VIEWPOINTS:
            robot = viewpoint(marker, range_m, math.radians(angle_deg))
            where = f"{range_m:g} m, {angle_deg:+g} deg"
            why = ctx.world.placement_problem(robot.x, robot.y)
            if why is None:
                try:
                    _teleport(ctx, robot)
                except ValueError as exc:
                    why = str(exc)
            if why is not None:
                problems.append(f"{where}: no room for the robot in this world ({why})")
                continue
            # The move counts from when the robot's pose says so: perception settles a side view's mirror
            # ambiguity by the pose, and a frame taken after the teleport but judged by the pose from
            # before it is the teleport's doing, not the service's (no robot jumps metres).
            _pose_reads(ctx, robot, POSE_WAIT_S)
            moved_s = ctx.probe.sim_now() if ctx.sim else None
            _wait_sim(ctx, 0.5)  # most detections of frames from before the move are out of the way
            looked += 1
            truth = dock.relative_to(robot)
            # A loaded machine may deliver detections of frames taken before the move later still: on sim
            # time a detection's stamp (its frame's) says which viewpoint it belongs to, and the check
            # listens a little longer for detections of frames taken after it.
            stale, errors, listened_s = 0, [], 0.0
            for _ in range(ROUND_WINDOWS):
                samples = ctx.probe.collect(
                    ctx.key("detected_dock_pose"),
                    PoseStamped,
                    1.5,
                    ctx.sim,
                    wall_limit_s=10.0,
                    keep_messages=True,
                )
                listened_s += 1.5
                for m in samples.messages or []:
                    if moved_s is not None and m.header.stamp.to_sec() < moved_s + STALE_MARGIN_S:
                        stale += 1
                    else:
                        errors.append(_pose_error(m.pose.to_pose2d(), truth))
                if errors or not stale:
                    break
            if not errors:
                problems.append(
                    f"{where}: no detection in {listened_s:g} s"
                    + (
                        f" of a frame taken after the move ({stale} of frames from before it)"
                        if stale
                        else ""
                    )
                )
                continue
            position_m, yaw_rad = median(e[0] for e in errors), median(e[1] for e in errors)
            flipped = sum(1 for e in errors if e[1] > FLIPPED_RAD)
            worst_m, worst_rad = max(worst_m, position_m), max(worst_rad, yaw_rad)
            limit_m = ROUND_WITHIN_M + ROUND_WITHIN_PER_M * range_m
            if position_m > limit_m or yaw_rad > ROUND_WITHIN_RAD or flipped:
                problems.append(
                    f"{where}: median {1000 * position_m:.0f} mm and {yaw_rad:.3f} rad off over {len(errors)} "
                    f"detections (limits {1000 * limit_m:.0f} mm, {ROUND_WITHIN_RAD:g} rad)"
                    + (
                        f", {flipped} turned more than {FLIPPED_RAD:g} rad (a flipped solution?)"
                        if flipped
                        else ""
                    )
                )
        failed = [p for p in problems if "no room" not in p]
        evidence = f"{looked} viewpoints, worst median {1000 * worst_m:.0f} mm and {worst_rad:.3f} rad" + (
            "; " + "; ".join(problems) if problems else ""
        )
        return not failed and looked > 0, evidence

    return [
        PlannedCheck("sees the dock", sees),
        PlannedCheck("sees the dock from 0.4 to 3 m and 40 degrees aside", sees_round),
    ]


#: ``(range_m, angle_deg)``: base_link to the marker's centre, and off the marker's axis (either side). A
#: viewpoint the world has no room for (seed_room's west wall at 3 m and -40 degrees) is named and skipped.
VIEWPOINTS = (
    (0.4, 0.0),
    (0.4, -40.0),
    (0.4, 40.0),
    (1.0, -40.0),
    (1.0, 40.0),
    (2.0, 0.0),
    (2.0, -40.0),
    (2.0, 40.0),
    (3.0, 0.0),
    (3.0, -30.0),
    (3.0, 30.0),
    (3.0, -40.0),
    (3.0, 40.0),
)
#: A viewpoint's median detection is within this much plus ``ROUND_WITHIN_PER_M`` a metre of range ...
ROUND_WITHIN_M = 0.02
ROUND_WITHIN_PER_M = 0.02
#: ... and this much of the dock's heading; no single detection is turned further than ``FLIPPED_RAD``.
ROUND_WITHIN_RAD = 0.1
FLIPPED_RAD = 0.3


#: A detection stamped less than this after the teleport's sim time may be of a frame from before it (the
#: probe hears the sim clock a message late).
STALE_MARGIN_S = 0.1
#: How long a viewpoint waits for the robot's pose to read the teleport (wall); past it the check goes on.
POSE_WAIT_S = 5.0
#: How many 1.5 s windows the check listens through while only detections of earlier frames arrive.
ROUND_WINDOWS = 3


def viewpoint(marker: Pose2D, range_m: float, angle_rad: float) -> Pose2D:
    """Where the robot stands ``range_m`` from the marker's centre, ``angle_rad`` off its axis, facing it."""
    x = marker.x + range_m * math.cos(marker.yaw + angle_rad)
    y = marker.y + range_m * math.sin(marker.yaw + angle_rad)
    return Pose2D(x, y, math.atan2(marker.y - y, marker.x - x))


def _pose_error(seen: Pose2D, truth: Pose2D) -> tuple[float, float]:
    return math.hypot(seen.x - truth.x, seen.y - truth.y), abs(wrap_angle(seen.yaw - truth.yaw))


def fleet_behaviour(ctx: Context) -> list[PlannedCheck]:
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

    return [PlannedCheck("reserves and releases", reserves)]


def ros2_bridge_behaviour(ctx: Context) -> list[PlannedCheck]:
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

    return [PlannedCheck("shows zendock to ROS 2", shows)]


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


def ros2_dds_behaviour(ctx: Context) -> list[PlannedCheck]:
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

    return [PlannedCheck("shows zendock to ROS 2 on DDS (real rclpy)", shows)]


BEHAVIOURS: dict[str, Callable[[Context], list[PlannedCheck]]] = {
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
