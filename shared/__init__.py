"""zendock's common kit: what every service, tool and test may use.

The public surface is what this module exports; the submodules are the implementation.
"""

from shared.config_errors import ConfigError
from shared.geometry import (
    Pose2D,
    euler_from_quaternion,
    quaternion_from_yaw,
    wrap_angle,
    yaw_from_quaternion,
)
from shared.names import node_token_key, parse_token_key, topic_key
from shared.node import (
    BLOCKING,
    RELIABLE,
    SENSOR_DATA,
    Node,
    Publisher,
    QoS,
    ServiceError,
    ServiceType,
    Subscription,
    Timer,
    call_service,
)
from shared.ratelimit import RateLimitedLogger
from shared.runtime import ServiceOptions, ServiceParams, run_service, serve
from shared.schema import Message, MessageError, message
from shared.session import DEFAULT_ROUTER_ENDPOINT, SessionSpec, open_session
from shared.world import World, load_world

__all__ = [
    "BLOCKING",
    "DEFAULT_ROUTER_ENDPOINT",
    "RELIABLE",
    "SENSOR_DATA",
    "ConfigError",
    "Message",
    "MessageError",
    "Node",
    "Pose2D",
    "Publisher",
    "QoS",
    "RateLimitedLogger",
    "ServiceError",
    "ServiceOptions",
    "ServiceParams",
    "ServiceType",
    "SessionSpec",
    "Subscription",
    "Timer",
    "World",
    "call_service",
    "euler_from_quaternion",
    "load_world",
    "message",
    "node_token_key",
    "open_session",
    "parse_token_key",
    "quaternion_from_yaw",
    "run_service",
    "serve",
    "topic_key",
    "wrap_angle",
    "yaw_from_quaternion",
]
