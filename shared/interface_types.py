"""Interface types: what a service or an action carries, named as ROS 2 names them (pure: no bus).

:class:`ServiceType` pairs a request and a response message; :class:`ActionType` a goal, a result and a
feedback, with the wrappers the action protocol sends (``<Action>_SendGoal_Request`` and the rest) and the
``action_msgs`` messages. The endpoints and the action protocol (:mod:`shared.endpoints`,
:mod:`shared.action`) use these; interface definitions (:mod:`shared.interfaces`) declare them without
loading Zenoh, so the logic built on them stays bus-free.
"""

from __future__ import annotations

import enum
import uuid
from dataclasses import field
from typing import Annotated, Any, Generic, TypeVar

import msgspec
import numpy as np

from shared.messages import Time
from shared.schema import Message, Range, UInt8Array, message

Req = TypeVar("Req", bound=Message)
Res = TypeVar("Res", bound=Message)
G = TypeVar("G", bound=Message)
R = TypeVar("R", bound=Message)
F = TypeVar("F", bound=Message)


class ServiceType(msgspec.Struct, Generic[Req, Res], frozen=True):
    """A request/response interface, e.g. ``zendock_msgs/srv/Teleport``."""

    type_name: str
    request: type[Req]
    response: type[Res]


class GoalStatusCode(enum.IntEnum):
    """``action_msgs/msg/GoalStatus`` values."""

    UNKNOWN = 0
    ACCEPTED = 1
    EXECUTING = 2
    CANCELING = 3
    SUCCEEDED = 4
    CANCELED = 5
    ABORTED = 6

    @property
    def terminal(self) -> bool:
        return self in (GoalStatusCode.SUCCEEDED, GoalStatusCode.CANCELED, GoalStatusCode.ABORTED)


def _uuid16() -> np.ndarray:
    return np.zeros(16, dtype=np.uint8)


@message("unique_identifier_msgs/msg/UUID")
class UUID(Message):
    uuid: UInt8Array = field(default_factory=_uuid16)

    @classmethod
    def random(cls) -> UUID:
        return cls(np.frombuffer(uuid.uuid4().bytes, dtype=np.uint8).copy())

    def hex(self) -> str:
        return bytes(self.uuid.astype(np.uint8)).hex()

    def is_zero(self) -> bool:
        return not self.uuid.any()


@message("action_msgs/msg/GoalInfo")
class GoalInfo(Message):
    goal_id: UUID = field(default_factory=UUID)
    stamp: Time = field(default_factory=Time)


@message("action_msgs/msg/GoalStatus")
class GoalStatus(Message):
    goal_info: GoalInfo = field(default_factory=GoalInfo)
    status: Annotated[int, Range(0, 6)] = 0


@message("action_msgs/msg/GoalStatusArray")
class GoalStatusArray(Message):
    status_list: list[GoalStatus] = field(default_factory=list)


@message("action_msgs/srv/CancelGoal_Request")
class CancelGoalRequest(Message):
    goal_info: GoalInfo = field(default_factory=GoalInfo)


@message("action_msgs/srv/CancelGoal_Response")
class CancelGoalResponse(Message):
    ERROR_NONE = 0
    ERROR_REJECTED = 1
    ERROR_UNKNOWN_GOAL_ID = 2
    ERROR_GOAL_TERMINATED = 3
    return_code: Annotated[int, Range(0, 3)] = 0
    goals_canceling: list[GoalInfo] = field(default_factory=list)


@message("zendock_msgs/msg/Empty")
class Empty(Message):
    pass


CANCEL_GOAL = ServiceType("action_msgs/srv/CancelGoal", CancelGoalRequest, CancelGoalResponse)


def _wrapper(type_name: str, fields: dict[str, Any]) -> Any:
    namespace: dict[str, Any] = {"__annotations__": dict(fields)}
    for name, annotation in fields.items():
        default: Any
        if annotation is bool:
            default = False
        elif annotation is int or getattr(annotation, "__origin__", None) is int:
            default = 0
        else:
            default = field(default_factory=annotation)
        namespace[name] = default
    cls = type(type_name.rsplit("/", 1)[-1], (Message,), namespace)
    return message(type_name)(cls)


class ActionType(Generic[G, R, F]):
    """An action interface: goal, result and feedback messages plus the generated wrappers."""

    def __init__(self, type_name: str, goal: type[G], result: type[R], feedback: type[F]) -> None:
        self.type_name = type_name
        self.goal = goal
        self.result = result
        self.feedback = feedback
        self.send_goal_request = _wrapper(f"{type_name}_SendGoal_Request", {"goal_id": UUID, "goal": goal})
        self.send_goal_response = _wrapper(
            f"{type_name}_SendGoal_Response", {"accepted": bool, "stamp": Time}
        )
        self.get_result_request = _wrapper(f"{type_name}_GetResult_Request", {"goal_id": UUID})
        self.get_result_response = _wrapper(
            f"{type_name}_GetResult_Response", {"status": Annotated[int, Range(0, 6)], "result": result}
        )
        self.feedback_message = _wrapper(
            f"{type_name}_FeedbackMessage", {"goal_id": UUID, "feedback": feedback}
        )
        self.send_goal = ServiceType(f"{type_name}_SendGoal", self.send_goal_request, self.send_goal_response)
        self.get_result = ServiceType(
            f"{type_name}_GetResult", self.get_result_request, self.get_result_response
        )
