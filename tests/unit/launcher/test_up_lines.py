"""``zendock up -d --wait`` prints one line per service as it settles: name, word, seconds since ``up``."""

from deploy.commands.up import status_line
from deploy.launcher.status import ServiceStatus


def _status(**fields) -> ServiceStatus:  # type: ignore[no-untyped-def]
    base = {
        "name": "router",
        "state": "running",
        "pid": 1,
        "restarts": 0,
        "health": "none",
        "phase": "running",
        "starts": 1,
    }
    return ServiceStatus(**{**base, **fields})


def test_a_healthy_service_is_named_with_the_time_since_up() -> None:
    line = status_line(_status(name="docking", health="healthy"), wait=True, elapsed_s=3.04)
    assert line == "docking: healthy (3.0s)"


def test_a_service_without_healthcheck_shows_its_state_and_a_failure_its_reason() -> None:
    assert status_line(_status(), wait=True, elapsed_s=0.42) == "router: running (0.4s)"
    failed = _status(state="exited", phase="exited", exit_code=1, detail="exited with code 1")
    assert status_line(failed, wait=True) == "router: failed: exited with code 1"


def test_without_wait_a_started_service_says_started() -> None:
    assert status_line(_status(name="map"), wait=False, elapsed_s=1.0) == "map: started (1.0s)"
