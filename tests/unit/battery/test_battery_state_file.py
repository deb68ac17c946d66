"""The battery's charge on disk: round trip, and a bad file meaning 'start from the parameters'."""

from __future__ import annotations

from pathlib import Path

from services.battery.state_file import StoredCharge, load_charge, save_charge


def test_the_charge_comes_back_as_it_was_written(tmp_path: Path) -> None:
    path = tmp_path / "r0" / "battery.json"
    save_charge(path, StoredCharge(0.2437, 20.0, 1.0, False))
    assert load_charge(path) == StoredCharge(0.2437, 20.0, 1.0, False)
    assert not list(path.parent.glob(".*.tmp"))


def test_missing_damaged_or_impossible_files_are_ignored(tmp_path: Path) -> None:
    assert load_charge(tmp_path / "none.json") is None
    damaged = tmp_path / "damaged.json"
    damaged.write_text("{not json", encoding="utf-8")
    assert load_charge(damaged) is None
    impossible = tmp_path / "impossible.json"
    impossible.write_text(
        '{"percentage": 1.7, "drain_scale": 1, "charge_scale": 1, "frozen": false}', encoding="utf-8"
    )
    assert load_charge(impossible) is None
    partial = tmp_path / "partial.json"
    partial.write_text('{"percentage": 0.5}', encoding="utf-8")
    assert load_charge(partial) is None
