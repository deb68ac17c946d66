"""Contract versions move with the contracts: a change under the same version is refused, and every version
has its changelog entry."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from msgspec.structs import replace

from deploy.contracts import versions
from deploy.contracts.document import CONTRACTS_DIR, contract_json
from shared.config_errors import ConfigError
from shared.contracts import CONTRACTS


def _records(directory: Path, **overrides: dict[str, str]) -> None:
    records = versions.recorded(CONTRACTS_DIR) | overrides
    (directory / versions.VERSIONS_FILE).write_text(json.dumps(records), encoding="utf-8")


def test_the_committed_records_match_the_contracts_and_every_version_is_in_the_changelog() -> None:
    assert versions.unversioned_changes() == []
    assert versions.missing_from_changelog() == []
    assert set(versions.recorded()) == set(CONTRACTS)


def test_a_contract_changed_under_its_recorded_version_is_refused_with_the_fix(tmp_path: Path) -> None:
    _records(tmp_path, battery={"version": CONTRACTS["battery"].version, "fingerprint": "0" * 16})
    (problem,) = versions.unversioned_changes(tmp_path)
    assert problem.startswith("battery: the contract changed under version")
    assert "shared/contracts/services/battery.py" in problem and "changelog.md" in problem
    with pytest.raises(ConfigError, match="battery: the contract changed"):
        versions.versions_json(tmp_path)


def test_a_new_version_takes_the_change_and_needs_its_changelog_entry(tmp_path: Path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    current = CONTRACTS["battery"].version
    major, minor = current.split(".")
    new = f"{major}.{int(minor) + 1}"
    bumped = replace(CONTRACTS["battery"], version=new, summary="A battery that says more.")
    monkeypatch.setitem(CONTRACTS, "battery", bumped)
    _records(tmp_path)  # recorded at the current version, with the old fingerprint
    assert versions.unversioned_changes(tmp_path) == []
    assert json.loads(versions.versions_json(tmp_path))["battery"] == {
        "version": new,
        "fingerprint": versions.fingerprint(bumped),
    }
    (tmp_path / versions.CHANGELOG_FILE).write_text(f"## battery {current}\n", encoding="utf-8")
    assert f"battery {new}" in versions.missing_from_changelog(tmp_path)


def test_the_version_is_in_the_contract_document_but_not_in_its_fingerprint() -> None:
    contract = CONTRACTS["pose"]
    assert contract_json(contract)["version"] == contract.version
    assert versions.fingerprint(replace(contract, version="9.9")) == versions.fingerprint(contract)
    assert versions.fingerprint(replace(contract, summary="other words")) != versions.fingerprint(contract)
