"""Each zendock service's contract: the one place its endpoints, inputs and promised reactions are written.

The services declare what they declare; their nodes are held to these tables while they run
(:meth:`shared.contracts.model.Contract.check_endpoint`), ``zendock contract NAME`` prints them and
``zendock conform NAME -- COMMAND`` checks a program against them. Rates are of sim time at the defaults.

One module a service (``shared.contracts.services.battery``, ...), each with its ``CONTRACT``: a running
service loads only its own, and with it only the interfaces it names, not every service's (measurement
82). :data:`CONTRACTS` loads them all, for the CLI, the docs and the kit.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from shared.contracts.services.common import DOCKING_STATE

if TYPE_CHECKING:
    from shared.contracts.model import Contract

#: Every service with a contract, by node name (and module name).
SERVICES = (
    "battery",
    "docking",
    "fleet",
    "perception",
    "planner",
    "pose",
    "ros2_bridge",
    "ros2_dds",
    "simulator",
    "viz",
)


def contract_for(service: str) -> Contract | None:
    """The contract of zendock's service ``service`` (its node name), or ``None``."""
    if service not in SERVICES:
        return None
    contract: Contract = importlib.import_module(f"{__name__}.{service}").CONTRACT
    return contract


def __getattr__(name: str) -> Any:
    if name == "CONTRACTS":  # every contract, loaded on first use
        contracts: dict[str, Contract] = {}
        for service in SERVICES:
            contract = contract_for(service)
            assert contract is not None
            contracts[service] = contract
        globals()["CONTRACTS"] = contracts
        return contracts
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["CONTRACTS", "DOCKING_STATE", "SERVICES", "contract_for"]
