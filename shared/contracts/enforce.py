"""Holding a running zendock service to its contract.

A node of a service with a contract checks every endpoint it declares against it. Under test
(``ZENDOCK_STRICT_CONTRACTS=1``, which the project's test suite sets for every process it starts) an
endpoint the contract does not name stops the service at once (from a callback too: the process exits 70), so the contract and the wiring cannot
drift apart unnoticed; otherwise it is logged as an error and the service goes on.
"""

from __future__ import annotations

import os

from shared.contracts.model import ContractViolation
from shared.contracts.services import contract_for
from shared.executor import in_callback
from shared.node import Node

STRICT_ENV = "ZENDOCK_STRICT_CONTRACTS"
#: The exit code of a strict service that declared, in a callback, an endpoint its contract does not name.
STRICT_EXIT = 70


def hold_to_contract(node: Node) -> None:
    """Make ``node`` check its endpoints against the contract of the service it is (by node name)."""
    contract = contract_for(node.name)
    if contract is None:
        return
    strict = os.environ.get(STRICT_ENV) == "1"

    def check(kind: str, type_name: str, key: str) -> None:
        try:
            contract.check_endpoint(kind, type_name, key, node.name)
        except ContractViolation as exc:
            node.log.error("%s", exc)
            if strict and in_callback():  # a callback's exception is only logged: end the process instead
                os._exit(STRICT_EXIT)
            if strict:
                raise

    node.endpoint_check = check
