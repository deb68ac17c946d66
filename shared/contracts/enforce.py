"""Holding a running zendock service to its contract.

A node of a service with a contract checks every endpoint it declares against it. Under test
(``ZENDOCK_STRICT_CONTRACTS=1``, which the project's test suite sets for every process it starts) an
endpoint the contract does not name stops the service at once, so the contract and the wiring cannot
drift apart unnoticed; otherwise it is logged as an error and the service goes on.
"""

from __future__ import annotations

import os

from shared.contracts.model import ContractViolation
from shared.contracts.services import contract_for
from shared.node import Node

STRICT_ENV = "ZENDOCK_STRICT_CONTRACTS"


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
            if strict:
                raise
            node.log.error("%s", exc)

    node.endpoint_check = check
