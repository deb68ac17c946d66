"""Every service's contract, defined once in code: see :mod:`shared.contracts.model` and ``.services``."""

from shared.contracts.model import Action, Contract, ContractViolation, Flag, Request, Topic
from shared.contracts.services import CONTRACTS, contract_for

__all__ = ["CONTRACTS", "Action", "Contract", "ContractViolation", "Flag", "Request", "Topic", "contract_for"]
