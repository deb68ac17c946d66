"""``zendock health``: the container health check, on a real service's liveliness token."""

from __future__ import annotations

import subprocess
import sys

from tests.support.processes import wait_until


def _health(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "deploy.cli", "health", *args], capture_output=True, text=True, timeout=60
    )


def test_health_follows_the_services_token(spawn, router_endpoint: str, namespace: str) -> None:  # type: ignore[no-untyped-def]
    bus = ("--connect", router_endpoint, "--namespace", namespace)
    battery = spawn("battery")
    wait_until(lambda: _health("-q", "battery", *bus).returncode == 0, 30.0, lambda: "battery never healthy")
    missing = _health("battery", "planner", *bus)
    assert missing.returncode == 1 and "no liveliness token from planner" in missing.stderr
    battery.stop()
    gone = _health("battery", *bus)
    assert gone.returncode == 1 and "battery" in gone.stderr


def test_health_without_a_router_is_one_line_and_exit_1() -> None:
    done = _health("battery", "--connect", "tcp/127.0.0.1:9", "--connect-timeout", "0.5")
    assert (
        done.returncode == 1 and done.stderr.count("\n") == 1 and "cannot reach a Zenoh router" in done.stderr
    )


def test_health_refuses_a_missing_zenoh_config_by_name() -> None:
    done = _health("battery", "--zenoh-config", "/nonexistent.json5")
    assert done.returncode == 2 and "--zenoh-config" in done.stderr and "/nonexistent.json5" in done.stderr
