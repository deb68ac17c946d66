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
    lines = [f"{c.result} {c.name}: {c.evidence}" for c in report.checks]
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
        "frames: every header names the contract's frame",  # an empty frame_id, not base_link
        "bad requests get an error reply",  # nothing answers
        "SIGTERM: exit 0 within 2 s",  # ignores it
    }, _account(report)
    passed = {c.name for c in report.checks if c.passed}
    assert {"starts: announces its node token", "restarted, it comes back"} <= passed, _account(report)


BROKEN_PERCEPTION = Path(__file__).resolve().parents[1] / "support" / "broken_perception.py"


def test_a_perception_with_four_mistakes_fails_with_each_one_named(tmp_path: Path) -> None:
    """A wrong frame, a dock turned by pi, 51 detections a camera frame, subscriptions not announced."""
    report = run_conform("perception", ["python", str(BROKEN_PERCEPTION)], ConformOptions(runs_dir=tmp_path))
    rows = {c.name: c for c in report.checks}
    account = _account(report)
    assert not report.passed and report.contract_version == CONTRACTS["perception"].version
    frames = rows["frames: every header names the contract's frame"]
    assert not frames.passed and "'camera_optical_frame', the contract says 'base_link'" in frames.evidence, (
        account
    )
    sees = rows["sees the dock"]
    assert not sees.passed and "turned by pi?" in sees.evidence, account
    events = rows["events: none faster than the contract allows"]
    assert not events.passed and "detected_dock_pose:" in events.evidence, account
    endpoints = rows["endpoints: announces every required one"]
    assert not endpoints.passed and "sub r1/camera/camera_info" in endpoints.evidence, account
    # the burst floods every key the contract names, announced or not
    burst = rows["survives malformed payloads on every key"]
    named = len(CONTRACTS["perception"].subscribes) + len(CONTRACTS["perception"].serves)
    assert burst.passed and f"on {named} keys" in burst.evidence, account
    # every check has its row, run or not
    assert all(c.result in ("pass", "FAIL", "not run") for c in report.checks)
    assert "SIGTERM: exit 0 within 2 s" in rows and "restarted, it comes back" in rows, account
