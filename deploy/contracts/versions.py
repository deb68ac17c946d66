"""Contract versions held to the contracts: a change without a new version, or a version without its
changelog entry, is caught before it reaches a user who wrote a replacement from the pages.

``docs/contracts/versions.json`` records, for each contract, its version and a fingerprint of everything its
page and ``zendock contract NAME --json`` say. ``python -m deploy.docs_site`` refreshes a record only when the
version moved with the change; a contract changed under the same version is refused there and by the suite.
"""

from __future__ import annotations

import hashlib
import json
import re
from pathlib import Path

from deploy.contracts.document import CONTRACTS_DIR, contract_json
from shared.config_errors import ConfigError
from shared.contracts import CONTRACTS, Contract

VERSIONS_FILE = "versions.json"
CHANGELOG_FILE = "changelog.md"
_VERSION = re.compile(r"^\d+\.\d+$")


def fingerprint(contract: Contract) -> str:
    """A hash of the contract's whole document (its message schemas too), its version aside."""
    body = contract_json(contract)
    body.pop("version")
    return hashlib.sha256(json.dumps(body, sort_keys=True).encode()).hexdigest()[:16]


def recorded(directory: Path = CONTRACTS_DIR) -> dict[str, dict[str, str]]:
    """The committed records: service -> {version, fingerprint} (empty when there are none yet)."""
    path = directory / VERSIONS_FILE
    if not path.is_file():
        return {}
    return json.loads(path.read_text(encoding="utf-8"))


def unversioned_changes(directory: Path = CONTRACTS_DIR) -> list[str]:
    """One line for each contract that changed since its record while keeping the recorded version."""
    out = []
    for service, record in sorted(recorded(directory).items()):
        contract = CONTRACTS.get(service)
        if contract is None or contract.version != record["version"]:
            continue
        if fingerprint(contract) != record["fingerprint"]:
            out.append(
                f"{service}: the contract changed under version {contract.version}: raise its version in "
                f"shared/contracts/services/{service}.py and say what changed in docs/contracts/{CHANGELOG_FILE}"
            )
    return out


def missing_from_changelog(directory: Path = CONTRACTS_DIR) -> list[str]:
    """``service version`` of each contract whose version has no ``## service version`` heading."""
    path = directory / CHANGELOG_FILE
    text = path.read_text(encoding="utf-8") if path.is_file() else ""
    headings = set(re.findall(r"^## (\S+ \d+\.\d+)\b", text, flags=re.MULTILINE))
    return [
        f"{c.service} {c.version}" for c in CONTRACTS.values() if f"{c.service} {c.version}" not in headings
    ]


def versions_json(directory: Path = CONTRACTS_DIR) -> str:
    """The records as they should be committed; refuses a contract changed under its recorded version."""
    bad = [
        f"{c.service}: version {c.version!r} is not major.minor"
        for c in CONTRACTS.values()
        if not _VERSION.match(c.version)
    ]
    bad += unversioned_changes(directory)
    if bad:
        raise ConfigError("; ".join(bad))
    records = {c.service: {"version": c.version, "fingerprint": fingerprint(c)} for c in CONTRACTS.values()}
    return json.dumps(records, indent=2, sort_keys=True) + "\n"
