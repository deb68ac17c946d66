"""``zendock_msgs/srv/{List,Get,Set}Parameter(s)``: read and change a node's parameters while it runs.

Every service answers these under ``<ns>/<node>/_param/{list,get,set}`` (:func:`shared.names.parameter_service`),
as every ROS 2 node answers ``list_parameters``/``get_parameters``/``set_parameters``. A value travels as
JSON text (``0.5``, ``true``, ``"base_link"``, ``[0.1, 0.0, 0.0]``): parameters have many types and the
message schema has no "any". A refused change is a normal answer (``successful`` false and the reason, as
ROS 2's ``SetParametersResult``); asking for an unknown name is an error reply naming it.
"""

from __future__ import annotations

from dataclasses import field

from shared.interface_types import ServiceType
from shared.schema import Message, message


@message("zendock_msgs/msg/ParameterDescriptor")
class ParameterDescriptor(Message):
    """One parameter: its dotted name, its value as JSON, whether it may change while the node runs and,
    if so, when a change takes effect (``applies``: "at once", "next docking run", ...)."""

    name: str = ""
    value_json: str = "null"
    settable: bool = False
    applies: str = ""
    description: str = ""


@message("zendock_msgs/srv/ListParameters_Request")
class ListParametersRequest(Message):
    """Every parameter of the node, sorted by name."""


@message("zendock_msgs/srv/ListParameters_Response")
class ListParametersResponse(Message):
    parameters: list[ParameterDescriptor] = field(default_factory=list)


@message("zendock_msgs/srv/GetParameter_Request")
class GetParameterRequest(Message):
    name: str = ""


@message("zendock_msgs/srv/GetParameter_Response")
class GetParameterResponse(Message):
    parameter: ParameterDescriptor = field(default_factory=ParameterDescriptor)


@message("zendock_msgs/srv/SetParameter_Request")
class SetParameterRequest(Message):
    """Set ``name`` to the value ``value_json`` (JSON text), validated as at start-up."""

    name: str = ""
    value_json: str = "null"


@message("zendock_msgs/srv/SetParameter_Response")
class SetParameterResponse(Message):
    """``successful`` false: nothing changed, ``reason`` says why. ``parameter`` is the value in force after."""

    successful: bool = False
    reason: str = ""
    parameter: ParameterDescriptor = field(default_factory=ParameterDescriptor)


LIST_PARAMETERS: ServiceType[ListParametersRequest, ListParametersResponse] = ServiceType(
    "zendock_msgs/srv/ListParameters", ListParametersRequest, ListParametersResponse
)
GET_PARAMETER: ServiceType[GetParameterRequest, GetParameterResponse] = ServiceType(
    "zendock_msgs/srv/GetParameter", GetParameterRequest, GetParameterResponse
)
SET_PARAMETER: ServiceType[SetParameterRequest, SetParameterResponse] = ServiceType(
    "zendock_msgs/srv/SetParameter", SetParameterRequest, SetParameterResponse
)
