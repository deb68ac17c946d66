"""The conformance kit in the suite: every zendock service passes its own contract's checks, and a broken
replacement fails with the checks it breaks named (``zendock conform``, :mod:`deploy.contracts.conform`)."""

from __future__ import annotations

from pathlib import Path

import pytest

from deploy.contracts.conform import ConformOptions, run_conform
from deploy.paths import REPO_ROOT
from shared.contracts import CONTRACTS

BROKEN_BATTERY = Path(__file__).resolve().parents[1] / "support" / "broken_battery.py"


def _account(report) -> str:  # type: ignore[no-untyped-def]
    lines = [f"{'pass' if c.passed else 'FAIL'} {c.name}: {c.evidence}" for c in report.checks]
    log = Path(report.log)
    tail = log.read_text(errors="replace").splitlines()[-15:] if log.is_file() else []
    return "\n".join([*lines, "--- its output:", *tail])


ROS2_READY = (REPO_ROOT / ".venv-ros2" / ".ros2-ready").exists()


@pytest.mark.parametrize(
    "service",
    [
        pytest.param(
            name,
            marks=pytest.mark.skipif(
                name == "ros2_dds" and not ROS2_READY, reason=".venv-ros2 is missing: `make ros2` builds it"
            ),
        )
        for name in CONTRACTS
    ],
)
def test_every_zendock_service_passes_its_own_kit(service: str, tmp_path: Path) -> None:
    report = run_conform(service, None, ConformOptions(runs_dir=tmp_path))
    assert report.passed, _account(report)
    assert len(report.checks) >= 6, _account(report)


def test_a_broken_replacement_fails_with_the_checks_it_breaks_named(tmp_path: Path) -> None:
    report = run_conform("battery", ["python", str(BROKEN_BATTERY)], ConformOptions(runs_dir=tmp_path))
    assert not report.passed
    assert set(report.failed()) == {
        "endpoints: announces every required one",  # no endpoint tokens
        "publishes battery_status",  # 2 Hz of wall time, not 10 Hz of sim time
        "answers set_state",
        "drains while the robot drives",
        "charges while mated",  # no set_state, a fixed charge
        "bad requests get an error reply",  # nothing answers
        "SIGTERM: exit 0 within 2 s",  # ignores it
    }, _account(report)
    passed = {c.name for c in report.checks if c.passed}
    assert {"starts: announces its node token", "restarted, it comes back"} <= passed, _account(report)
