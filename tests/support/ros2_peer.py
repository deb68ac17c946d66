"""A ROS 2 peer zendock did not write: zenoh-ros2-sdk (an rmw_zenoh client from PyPI) in its own process.

    python -m tests.support.ros2_peer --router tcp/127.0.0.1:PORT topics
    python -m tests.support.ros2_peer --router ... echo /battery_status sensor_msgs/msg/BatteryState --count 3
    python -m tests.support.ros2_peer --router ... pub /cmd_vel geometry_msgs/msg/Twist '{"linear": {"x": 0.2}}'

Output is one JSON document per line. The SDK is given Jazzy's definitions and type hashes from rosbags,
so it needs no network; everything else (keys, tokens, attachments, CDR reading) is the SDK's own.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from typing import Any

import numpy as np
from rosbags.typesys import Stores, get_typestore


def _sdk_session(router: str) -> Any:
    from zenoh_ros2_sdk import ZenohSession

    host, _, port = router.removeprefix("tcp/").rpartition(":")
    session = ZenohSession.get_instance(host.strip("[]"), int(port))
    jazzy = get_typestore(Stores.ROS2_JAZZY)
    session.store.register(jazzy.fielddefs)
    for name in jazzy.fielddefs:  # known to the SDK already: no definition lookup on the network
        session._registered_types[name] = name
    return session, jazzy


def _plain(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return [None if isinstance(v, float) and not np.isfinite(v) else v for v in value.tolist()]
    if hasattr(value, "__dataclass_fields__"):
        return {
            name: _plain(getattr(value, name))
            for name in value.__dataclass_fields__
            if name != "__msgtype__" and not name.isupper()
        }
    if isinstance(value, list):
        return [_plain(v) for v in value]
    if isinstance(value, float) and not np.isfinite(value):
        return None
    return value


def _qos(name: str) -> Any:
    from zenoh_ros2_sdk.qos import QosDurability, QosProfile, QosReliability

    return {
        "reliable": QosProfile(),
        "best_effort": QosProfile(reliability=QosReliability.BEST_EFFORT, history_depth=5),
        "latched": QosProfile(durability=QosDurability.TRANSIENT_LOCAL, history_depth=1),
    }[name]


def _fill(cls: Any, data: dict[str, Any], store: Any) -> Any:
    """A rosbags message of ``cls`` from a partial dict (missing fields zero)."""
    _, fields = store.fielddefs[cls.__msgtype__]
    values = {}
    for name, (kind, detail) in fields:
        given = data.get(name)
        if kind == 2:
            values[name] = _fill(store.types[detail], given or {}, store)
        elif kind == 1:
            default: Any = "" if detail[0] == "string" else False if detail[0] == "bool" else 0
            values[name] = given if given is not None else default
        elif kind == 3 and given is None:  # a fixed array (a covariance): zeros of its length
            values[name] = np.zeros(detail[1], dtype=np.float64)
        else:  # a sequence, or a fixed array given: of messages, of strings, or of numbers
            (sub_kind, sub_detail), _length = detail
            if sub_kind == 2:
                values[name] = [_fill(store.types[sub_detail], item, store) for item in given or []]
            elif sub_kind == 1 and sub_detail[0] == "string":
                values[name] = list(given or [])
            else:
                values[name] = np.asarray(given or [], dtype=np.float64)
    return cls(**values)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="ros2_peer")
    parser.add_argument("--router", required=True)
    parser.add_argument("--domain", type=int, default=0)
    sub = parser.add_subparsers(dest="command", required=True)
    topics = sub.add_parser("topics")
    topics.add_argument("--wait-for", default="", help="keep listing until this topic shows up")
    topics.add_argument("--timeout", type=float, default=20.0)
    nodes = sub.add_parser("nodes", help="the graph's nodes, from their liveliness tokens (ros2 node list)")
    nodes.add_argument("--wait-for", default="", help="keep listing until this node shows up")
    nodes.add_argument("--timeout", type=float, default=20.0)
    info = sub.add_parser("info")
    info.add_argument("topic")
    echo = sub.add_parser("echo")
    echo.add_argument("topic")
    echo.add_argument("type")
    echo.add_argument("--count", type=int, default=1)
    echo.add_argument("--qos", default="reliable", choices=["reliable", "best_effort", "latched"])
    echo.add_argument("--timeout", type=float, default=30.0)
    pub = sub.add_parser("pub")
    pub.add_argument("topic")
    pub.add_argument("type")
    pub.add_argument("message", help="the message as JSON (missing fields are zero)")
    pub.add_argument("--rate", type=float, default=10.0)
    pub.add_argument("--seconds", type=float, default=3.0)
    pub.add_argument(
        "--type-hash", default="", help="announce and publish under this hash instead of Jazzy's"
    )
    act = sub.add_parser(
        "action", help="send a goal, print the acceptance, the feedback count and the result"
    )
    act.add_argument("name")
    act.add_argument("type")
    act.add_argument("goal", help="the goal as JSON (missing fields are zero)")
    act.add_argument("--timeout", type=float, default=120.0)
    call = sub.add_parser("call", help="call a service once (ros2 service call), print the response")
    call.add_argument("name")
    call.add_argument("type")
    call.add_argument("request", nargs="?", default="{}", help="the request as JSON (missing fields zero)")
    call.add_argument("--timeout", type=float, default=10.0)
    args = parser.parse_args(argv)

    session, jazzy = _sdk_session(args.router)
    try:
        if args.command == "topics":
            from zenoh_ros2_sdk import get_topic_names_and_types

            deadline = time.monotonic() + args.timeout
            while True:
                found = get_topic_names_and_types(
                    domain_id=args.domain, router_ip=session.router_ip, router_port=session.router_port
                )
                if (
                    not args.wait_for
                    or any(t == args.wait_for for t, _ in found)
                    or time.monotonic() > deadline
                ):
                    break
                time.sleep(0.2)
            print(json.dumps({topic: types for topic, types in found}), flush=True)
        elif args.command == "nodes":
            deadline = time.monotonic() + args.timeout
            while True:
                names = sorted(
                    {
                        str(r.ok.key_expr).split("/")[8]
                        for r in session.liveliness.get(f"@ros2_lv/{args.domain}/*/*/*/NN/**", timeout=0.5)
                        if r.ok is not None
                    }
                )
                if not args.wait_for or args.wait_for in names or time.monotonic() > deadline:
                    break
                time.sleep(0.2)
            print(json.dumps(names), flush=True)
        elif args.command == "info":
            from zenoh_ros2_sdk import get_topic_info

            topic_info = get_topic_info(
                args.topic,
                domain_id=args.domain,
                router_ip=session.router_ip,
                router_port=session.router_port,
                verbose=True,
            )
            print(
                json.dumps(
                    None
                    if topic_info is None
                    else {
                        "types": topic_info.topic_types,
                        "publishers": [
                            {"node": p.node_name, "namespace": p.node_namespace, "qos": p.qos}
                            for p in topic_info.publishers
                        ],
                    }
                ),
                flush=True,
            )
        elif args.command == "echo":
            from zenoh_ros2_sdk import ROS2Subscriber

            received: list[Any] = []
            subscriber = ROS2Subscriber(
                args.topic,
                args.type,
                received.append,
                msg_definition="",
                domain_id=args.domain,
                router_ip=session.router_ip,
                router_port=session.router_port,
                type_hash=jazzy.hash_rihs01(args.type),
                qos=_qos(args.qos),
                node_name="zendock_test_echo",
            )
            deadline = time.monotonic() + args.timeout
            printed = 0
            while printed < args.count and time.monotonic() < deadline:
                while printed < len(received) and printed < args.count:
                    print(json.dumps(_plain(received[printed])), flush=True)
                    printed += 1
                time.sleep(0.02)
            subscriber.close()
            if printed < args.count:
                print(
                    f"ros2_peer: {printed} of {args.count} messages on {args.topic} in {args.timeout} s",
                    file=sys.stderr,
                )
                return 1
        elif args.command == "pub":
            from zenoh_ros2_sdk import ROS2Publisher

            type_hash = args.type_hash or jazzy.hash_rihs01(args.type)
            publisher = ROS2Publisher(
                args.topic,
                args.type,
                msg_definition="",
                domain_id=args.domain,
                router_ip=session.router_ip,
                router_port=session.router_port,
                type_hash=type_hash,
                node_name="zendock_test_pub",
            )
            message = _fill(jazzy.types[args.type], json.loads(args.message), jazzy)
            end = time.monotonic() + args.seconds
            while time.monotonic() < end:
                publisher.publish(
                    **{
                        name: getattr(message, name)
                        for name in message.__dataclass_fields__
                        if name != "__msgtype__" and not name.isupper()
                    }
                )
                time.sleep(1.0 / args.rate)
            publisher.close()
        elif args.command == "action":
            return _action(session, args)
        elif args.command == "call":
            return _call(session, args)
        return 0
    finally:
        session.close()


def _action(session: Any, args: argparse.Namespace) -> int:
    """A ROS 2 action client from the SDK's parts: two service clients and a feedback subscription.

    The action's types are not in Jazzy's common set and the SDK derives request names for ``srv``
    packages only, so the types (and their hashes) come from zendock's definitions of Nav2's actions,
    registered under the names the SDK looks up; keys, tokens, attachments and CDR stay the SDK's.
    """
    import uuid as uuidlib

    from zenoh_ros2_sdk import ROS2ServiceClient, ROS2Subscriber

    from shared.ros2 import types as zendock_types

    ours = zendock_types.typestore()
    package, _, name = args.type.partition("/action/")
    aliases = {}
    for part in ("SendGoal", "GetResult"):
        for side in ("Request", "Response"):
            aliases[f"{package}/srv/{name}_{part}_{side}"] = ours.fielddefs[f"{args.type}_{part}_{side}"]
    needed = {n: d for n, d in ours.fielddefs.items() if n.startswith(args.type)}
    session.store.register({**needed, **aliases})
    for alias in (*aliases, *needed):
        session._registered_types[alias] = alias
    common = {"domain_id": args.domain, "router_ip": session.router_ip, "router_port": session.router_port}
    feedback: list[Any] = []
    feedback_sub = ROS2Subscriber(
        f"{args.name}/_action/feedback",
        f"{args.type}_FeedbackMessage",
        feedback.append,
        msg_definition="",
        type_hash=zendock_types.type_hash(f"{args.type}_FeedbackMessage"),
        node_name="zendock_test_action",
        **common,
    )
    services = {"SendGoal": "send_goal", "GetResult": "get_result"}
    clients = {
        part: ROS2ServiceClient(
            f"{args.name}/_action/{services[part]}",
            f"{args.type}_{part}",
            request_definition="x",
            response_definition="x",
            type_hash=zendock_types.type_hash(f"{args.type}_{part}"),
            node_name="zendock_test_action",
            timeout=args.timeout,
            **common,
        )
        for part in ("SendGoal", "GetResult")
    }
    goal_id = ours.types["unique_identifier_msgs/msg/UUID"](
        uuid=np.frombuffer(uuidlib.uuid4().bytes, dtype=np.uint8)
    )
    goal = _fill(ours.types[f"{args.type}_Goal"], json.loads(args.goal), ours)
    accepted = clients["SendGoal"].call(goal_id=goal_id, goal=goal)
    print(json.dumps({"accepted": None if accepted is None else bool(accepted.accepted)}), flush=True)
    if accepted is None or not accepted.accepted:
        return 1
    result = clients["GetResult"].call(goal_id=goal_id)
    print(
        json.dumps(
            {
                "status": None if result is None else int(result.status),
                "result": None if result is None else _plain(result.result),
                "feedback": len(feedback),
            }
        ),
        flush=True,
    )
    feedback_sub.close()
    for client in clients.values():
        client.close()
    return 0 if result is not None else 1


def _call(session: Any, args: argparse.Namespace) -> int:
    """``ros2 service call NAME TYPE REQUEST`` with the SDK's service client; the types (not all in the
    SDK's common set) and their hashes come from zendock's store, as for actions."""
    from zenoh_ros2_sdk import ROS2ServiceClient

    from shared.ros2 import types as zendock_types

    ours = zendock_types.typestore()
    package = args.type.split("/")[0]
    needed = {
        n: d
        for n, d in ours.fielddefs.items()
        if n.startswith(args.type) or (n.startswith(f"{package}/msg/") and n not in session.store.fielddefs)
    }
    session.store.register(needed)
    for name in needed:
        session._registered_types[name] = name
    client = ROS2ServiceClient(
        args.name,
        args.type,
        request_definition="x",
        response_definition="x",
        type_hash=zendock_types.type_hash(args.type),
        node_name="zendock_test_call",
        timeout=args.timeout,
        domain_id=args.domain,
        router_ip=session.router_ip,
        router_port=session.router_port,
    )
    request = _fill(ours.types[f"{args.type}_Request"], json.loads(args.request), ours)
    fields = {name: getattr(request, name) for name in request.__dataclass_fields__ if name != "__msgtype__"}
    response = client.call(**fields)
    print(json.dumps({"response": None if response is None else _plain(response)}), flush=True)
    client.close()
    return 0 if response is not None else 1


if __name__ == "__main__":
    sys.exit(main())
