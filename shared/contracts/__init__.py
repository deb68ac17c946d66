"""Every service's contract, defined once in code: see :mod:`shared.contracts.model` and ``.services``."""

from typing import Any

from shared.contracts.model import Action, Contract, ContractViolation, Flag, Request, Topic
from shared.contracts.services import contract_for


def __getattr__(name: str) -> Any:
    if (
        name == "CONTRACTS"
    ):  # loads every service's contract: only the CLI, the docs and the kit want them all
        from shared.contracts import services  # noqa: PLC0415

        return services.CONTRACTS
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["CONTRACTS", "Action", "Contract", "ContractViolation", "Flag", "Request", "Topic", "contract_for"]
