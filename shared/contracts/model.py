"""What a contract is made of: the endpoints a service declares, what it is handed, what it must survive.

A contract is data. zendock's own services are held to theirs while they run (a node refuses to declare an
endpoint its contract does not name, :func:`Contract.check_endpoint`); ``docs/contracts/`` is rendered from
the same objects, and ``zendock conform`` checks a running program against them. So the documents a user
writes a replacement from cannot drift from what zendock's own service does.

Keys are relative to the robot's namespace (``battery_status`` is ``robot1/battery_status`` for the robot
``robot1``); a service that serves several robots (the simulator) declares each robot's copy.
"""

from __future__ import annotations

from typing import Any

import msgspec

from shared.endpoints import QoS
from shared.interface_types import ActionType, ServiceType
from shared.schema import Message


class ContractViolation(RuntimeError):
    """A service declared an endpoint its contract does not name (a bug in the service or the contract)."""


class _Conditional:
    """Required (declared whenever the service runs) unless ``when`` says when it is declared."""

    __slots__ = ()
    when: str

    @property
    def required(self) -> bool:
        return not self.when


class Topic(msgspec.Struct, _Conditional, frozen=True):
    """A key a service publishes or subscribes, with its message type and delivery."""

    name: str
    type: type[Message]
    qos: QoS
    #: Messages per second of sim time while the service runs (``None``: on events, or as its inputs come).
    rate_hz: float | None = None
    #: Events: at most this many messages in any second of sim time (``None``: a steady ``rate_hz``).
    max_rate_hz: float | None = None
    #: ``""``: always declared while the service runs; otherwise when it is (``"while docking"``).
    when: str = ""
    about: str = ""
    #: A key outside the robot's namespace, matched by its last parts (the fleet's peers ``*/battery_status``).
    fleet_wide: bool = False
    #: ``header.frame_id`` of every message at the defaults (``""``: the type has no header, or any frame).
    #: Frames are never prefixed with the robot's name on the bus: the key's namespace tells robots apart.
    frame_id: str = ""
    #: ``child_frame_id`` of every message (odometry's moving frame), likewise.
    child_frame_id: str = ""

    @property
    def on_demand(self) -> bool:
        """Published only while someone listens: a listener changes what the service does."""
        return "someone listens" in f"{self.when} {self.about}"


class Request(msgspec.Struct, _Conditional, frozen=True):
    """A request/response service (a Zenoh queryable)."""

    name: str
    type: ServiceType[Any, Any]
    when: str = ""
    about: str = ""


class Action(msgspec.Struct, _Conditional, frozen=True):
    """An action (goal, feedback, result, cancel) over the keys ``<name>/_action/...``."""

    name: str
    type: ActionType[Any, Any, Any]
    when: str = ""
    about: str = ""


class Flag(msgspec.Struct, frozen=True):
    """A ``-p name=value`` the launcher may hand the service; a replacement may ignore it unless ``needed``."""

    name: str
    about: str
    needed: bool = False


class Contract(msgspec.Struct, frozen=True):
    """One service's whole promise. ``behaviour`` names the checks ``zendock conform`` runs on its reactions."""

    service: str
    summary: str
    #: ``major.minor``: the major rises when a replacement written to the old pages would break (a key, a
    #: type or a frame changed, a duty added), the minor for what only adds (an optional key, words).
    #: Each version has its entry in ``docs/contracts/changelog.md``; a test holds both to every change.
    version: str
    publishes: tuple[Topic, ...] = ()
    subscribes: tuple[Topic, ...] = ()
    serves: tuple[Request, ...] = ()
    calls: tuple[Request, ...] = ()
    serves_actions: tuple[Action, ...] = ()
    uses_actions: tuple[Action, ...] = ()
    flags: tuple[Flag, ...] = ()
    #: What ``zendock conform`` checks of its reactions to inputs, in words (each a named check).
    behaviour: tuple[str, ...] = ()
    #: The other services ``zendock conform`` runs beside it (the rest of the stack it needs).
    needs: tuple[str, ...] = ()
    #: Subscribes on demand to keys a client asks for (the ROS 2 bridge forwards what a ROS 2 node wants).
    subscribes_on_demand: bool = False
    notes: tuple[str, ...] = ()

    # --- the endpoints it declares, as the graph shows them -----------------------------------------------

    def endpoints(self) -> list[tuple[str, str, str, bool]]:
        """Every endpoint the graph may show for this service: ``(kind, key, type name, required)``."""
        out: list[tuple[str, str, str, bool]] = []
        out += [("pub", t.name, t.type.TYPE_NAME, t.required) for t in self.publishes]
        out += [("sub", t.name, t.type.TYPE_NAME, t.required) for t in self.subscribes]
        out += [("srv", r.name, r.type.type_name, r.required) for r in self.serves]
        for a in self.serves_actions:
            base = f"{a.name}/_action"
            out += [
                ("act", a.name, a.type.type_name, a.required),
                ("srv", f"{base}/send_goal", a.type.send_goal.type_name, a.required),
                ("srv", f"{base}/cancel_goal", "action_msgs/srv/CancelGoal", a.required),
                ("srv", f"{base}/get_result", a.type.get_result.type_name, False),
                ("pub", f"{base}/feedback", a.type.feedback_message.TYPE_NAME, a.required),
                ("pub", f"{base}/status", "action_msgs/msg/GoalStatusArray", a.required),
            ]
        for a in self.uses_actions:
            base = f"{a.name}/_action"
            out += [
                ("sub", f"{base}/feedback", a.type.feedback_message.TYPE_NAME, False),
                ("sub", f"{base}/status", "action_msgs/msg/GoalStatusArray", False),
            ]
        return out

    def required_endpoints(self) -> list[tuple[str, str, str]]:
        """What every implementation must declare: every endpoint without a ``when``, subscriptions too
        (an input the service cannot do without, such as the simulator's ``cmd_vel``). A subscription a
        replacement may do without says so in its ``when`` ("optional: ..."); a service that subscribes on
        demand (the ROS 2 faces) has no required subscription."""
        return [
            (kind, key, type_name)
            for kind, key, type_name, required in self.endpoints()
            if required and not (kind == "sub" and self.subscribes_on_demand)
        ]

    def check_endpoint(
        self, kind: str, type_name: str, key: str, node_name: str, namespace: str | None = None
    ) -> None:
        """Raise :class:`ContractViolation` unless the contract names this endpoint (``key`` is the full key).

        With ``namespace`` the key must be the name in exactly that namespace (``zendock conform`` knows
        where the program runs); without, in any robot's (a simulator serves several)."""
        if kind == "sub" and self.subscribes_on_demand:
            return
        if is_common_endpoint(kind, type_name, key, node_name):
            return
        fleet_wide = {t.name for t in (*self.publishes, *self.subscribes) if t.fleet_wide}
        for want_kind, name, want_type, _required in self.endpoints():
            if want_kind != kind or want_type != type_name:
                continue
            if namespace is not None and name not in fleet_wide:
                if key == (f"{namespace}/{name}" if namespace else name):
                    return
            elif key_matches(key, name, name in fleet_wide):
                return
        raise ContractViolation(
            f"{self.service}: declares {kind} {key} ({type_name}), which its contract (shared/contracts) does not name"
        )


def key_matches(key: str, name: str, fleet_wide: bool = False) -> bool:
    """Whether the full ``key`` is the contract's relative ``name`` in some robot's namespace."""
    if fleet_wide:
        return key.endswith(name)
    return key == name or key.endswith("/" + name)


#: Every node may declare these: the clock it follows on sim time and its parameter services (``zendock param``).
def is_common_endpoint(kind: str, type_name: str, key: str, node_name: str) -> bool:
    if kind == "sub" and type_name == "rosgraph_msgs/msg/Clock" and key_matches(key, "clock"):
        return True
    return kind == "srv" and type_name.startswith("zendock_msgs/srv/") and f"{node_name}/_param/" in key


# --- what every service gets and must do, whatever it is ---------------------------------------------------

#: The environment the launcher hands every service.
ENVIRONMENT: dict[str, str] = {
    "ZENDOCK_CONNECT": "comma-separated Zenoh endpoints to connect to in client mode (tcp/127.0.0.1:7447)",
    "ZENDOCK_NAMESPACE": "the robot's namespace: every key is `<namespace>/<key>` (empty: the key alone)",
}
#: Flags the launcher may put on any service's command line (after the replacement's own words).
COMMON_FLAGS: tuple[Flag, ...] = (
    Flag("--namespace NS", "the robot's namespace; overrides ZENDOCK_NAMESPACE"),
    Flag("--connect ENDPOINT", "repeatable; overrides ZENDOCK_CONNECT"),
    Flag(
        "-p NAME=VALUE",
        "repeatable; a parameter, the value in YAML; a replacement ignores the names it does not use",
    ),
)
#: What a service announces on the bus, so launchers, ``zendock nodes`` and the ROS 2 bridge see it.
ANNOUNCEMENTS: tuple[str, ...] = (
    "Ready: a Zenoh liveliness token `@zendock/node/<ns>/<service>` once it serves (the launcher's health check); "
    "`<ns>` is the namespace with `/` written `%`, and `%` alone for none.",
    "Each endpoint: a liveliness token `@zendock/<kind>/<ns>/<service>/<type>/<key>` with kind pub, sub, srv or act, "
    "`<type>` the ROS type name with `/` written `%`, and `<key>` the full key.",
    "Required: every endpoint whose `when` reads `always`, subscriptions included, has its token while the "
    "service runs (`zendock conform` fails a missing one); an `optional: ...` subscription a replacement "
    "may leave out; any other `when` says when the endpoint is there.",
)
#: How frames are named on the bus (the ``frame`` column of each contract's publishes).
FRAME_RULES: tuple[str, ...] = (
    "Every stamped message's `header.frame_id` is the frame its contract names at the defaults "
    "(`map`, `odom`, `base_link`, `lidar_link`, `ultrasonic_link`, `camera_optical_frame`); "
    "a leading `/` is ignored, as tf ignores it. `zendock conform` checks every message it sees.",
    "Frames are never prefixed with the robot's name on the bus: in a fleet each robot's messages say "
    "`base_link`, and the key's namespace (`r1/odom`) tells robots apart. Only the live view shows them "
    "side by side as `r1/base_link`.",
    "Positions are in metres and angles in radians, as in ROS; a pose's orientation is a unit quaternion "
    "whose yaw is the heading in its frame.",
)

#: What every service must survive and how it must end.
DUTIES: tuple[str, ...] = (
    "Bad input never ends it: a payload that does not decode as the key's type is refused and counted; "
    "a burst of them on every key it subscribes changes nothing else.",
    "A request that does not decode gets an error reply (a Zenoh `reply_err` with a line of text), not silence.",
    "SIGTERM or SIGINT: it closes its Zenoh session and exits with code 0 within 2 s.",
    "Started again, it comes back: the same token and the same keys.",
)
