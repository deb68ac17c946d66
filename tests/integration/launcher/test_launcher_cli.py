"""The ``zendock`` launcher commands as users run them: ``up -d``, ``ps``, ``logs``, ``stop``/``start``,
``down``, and a foreground ``up`` stopped with Ctrl-C. The stack runs its own embedded router."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from datetime import datetime
from pathlib import Path

import pytest

from tests.integration.launcher.conftest import fake, marked_processes, wait_for

REPO_ROOT = Path(__file__).resolve().parents[3]


def stack_text(endpoint: str) -> str:
    return f"""\
        name: clitest
        zenoh: {{connect: ["{endpoint}"]}}
        services:
          router:
            command: [zendock, router, --listen, "{endpoint}"]
          talker:
            command: {fake("--name", "talker", "--token", "talker")}
            depends_on: {{router: {{condition: service_started}}}}
            healthcheck: {{liveliness: true, timeout: 15s}}
            restart: on-failure
          helper:
            command: {fake("--name", "helper", "--grandchild", "group")}
            depends_on: {{talker: {{condition: service_healthy}}}}
        """


def zendock(cwd: Path, mark: str, *args: str, timeout_s: float = 60.0) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "ZENDOCK_TEST_MARK": mark, "PYTHONPATH": str(REPO_ROOT), "NO_COLOR": "1"}
    return subprocess.run(
        [sys.executable, "-m", "deploy.cli", *args],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=timeout_s,
    )


@pytest.fixture
def project(tmp_path: Path, write_stack, endpoint: str, mark: str):  # type: ignore[no-untyped-def]
    write_stack(stack_text(endpoint))
    yield tmp_path
    zendock(tmp_path, mark, "down")


def test_detached_stack_is_driven_from_the_same_directory(project: Path, mark: str) -> None:
    up = zendock(project, mark, "up", "-d", "--wait", "--wait-timeout", "30")
    assert up.returncode == 0, up.stderr + up.stdout
    assert "talker: healthy" in up.stdout and "helper: running" in up.stdout

    ps = zendock(project, mark, "ps", "--json")
    assert ps.returncode == 0, ps.stderr
    rows = json.loads(ps.stdout)
    assert [row["name"] for row in rows] == ["router", "talker", "helper"]
    assert all(
        set(row)
        == {"name", "state", "pid", "restarts", "health", "exit_code", "started_at", "members", "namespace"}
        for row in rows
    )
    assert all(row["exit_code"] is None and datetime.fromisoformat(row["started_at"]).tzinfo for row in rows)
    by_name = {row["name"]: row for row in rows}
    assert by_name["talker"]["health"] == "healthy" and by_name["router"]["health"] == "none"
    assert all(row["state"] == "running" and isinstance(row["pid"], int) for row in rows)

    kill = zendock(project, mark, "kill", "talker")
    assert kill.returncode == 0, kill.stderr
    assert (
        kill.stdout
        == f"talker: killed (SIGKILL to pid {by_name['talker']['pid']}; its restart policy applies)\n"
    )

    def talker_back() -> bool:
        talker = {row["name"]: row for row in json.loads(zendock(project, mark, "ps", "--json").stdout)}[
            "talker"
        ]
        return talker["restarts"] == 1 and talker["state"] == "running" and talker["health"] == "healthy"

    wait_for(talker_back, 20, "talker restarted and healthy")

    logs = zendock(project, mark, "logs", "--tail", "50", "talker")
    assert "talker | talker ready" in logs.stdout
    assert "talker | [zendock] killed by signal 9" in logs.stdout

    for command in ("restart", "logs"):
        unknown = zendock(project, mark, command, "nosuch")
        assert unknown.returncode == 2, (command, unknown.stderr)
        assert (
            unknown.stderr
            == f"zendock {command}: no such service: nosuch (services: router, talker, helper)\n"
        )

    stop = zendock(project, mark, "stop", "helper")
    assert stop.returncode == 0 and "helper: stopped" in stop.stdout
    start = zendock(project, mark, "start", "helper")
    assert start.returncode == 0 and "helper: running" in start.stdout, start.stdout + start.stderr

    table = zendock(project, mark, "ps")
    assert table.stdout.splitlines()[0].split() == ["NAME", "STATE", "PID", "RESTARTS", "HEALTH", "DETAIL"]

    down = zendock(project, mark, "down")
    assert down.returncode == 0, down.stderr
    assert down.stdout.splitlines() == [
        "helper: stopped",
        "talker: stopped",
        "router: stopped",
    ]  # the router last
    assert not marked_processes(mark)
    state_dir = project / ".zendock" / "clitest"
    assert not (state_dir / "state.json").exists() and not (state_dir / "supervisor.json").exists()
    assert (state_dir / "logs" / "talker.log").exists()
    assert json.loads(zendock(project, mark, "ps", "--json").stdout) == []
    assert "nothing is up" in zendock(project, mark, "down").stdout


def test_foreground_up_prints_prefixed_output_and_stops_on_ctrl_c(project: Path, mark: str) -> None:
    env = {**os.environ, "ZENDOCK_TEST_MARK": mark, "PYTHONPATH": str(REPO_ROOT), "NO_COLOR": "1"}
    proc = subprocess.Popen(
        [sys.executable, "-m", "deploy.cli", "up"],
        cwd=project,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    seen: list[str] = []
    try:
        assert proc.stdout is not None
        # the services' lines interleave as the machine schedules them: read until both have been seen
        for line in proc.stdout:
            seen.append(line.rstrip("\n"))
            if any(s.startswith("helper") and "helper up" in s for s in seen) and any(
                s.startswith("router | zendock router: listening on") for s in seen
            ):
                break
        assert any(line.startswith("router | zendock router: listening on") for line in seen), seen
        assert "talker | talker ready" in seen
        proc.send_signal(signal.SIGINT)
        rest, _ = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 0, rest
    lines = rest.splitlines()
    assert "helper | [zendock] stopped" in lines and "router | [zendock] stopped" in lines
    assert (
        "router | [zendock] exited with code 0" in lines and "talker | [zendock] exited with code 0" in lines
    )
    assert lines.index("helper | [zendock] stopped") < lines.index("router | [zendock] stopped")
    assert not marked_processes(mark)


def test_up_refuses_an_invalid_stack_with_the_key_path(tmp_path: Path, mark: str) -> None:
    (tmp_path / "stack.yaml").write_text(
        "services:\n  a: {command: [x], restart: sometimes}\n", encoding="utf-8"
    )
    result = zendock(tmp_path, mark, "up", "-d")
    assert result.returncode == 2
    assert "stack.yaml: services.a.restart: expected one of no, always" in result.stderr


def test_up_wait_names_a_configuration_error_and_does_not_restart_it(
    write_stack, endpoint: str, mark: str
) -> None:
    """A service exiting 2 (a configuration error) stays down, whatever its policy, and ``up --wait`` says why."""
    project = write_stack(f"""\
        name: badworld
        zenoh: {{connect: ["{endpoint}"]}}
        services:
          router:
            command: [zendock, router, --listen, "{endpoint}"]
          map:
            command: [zendock, map, save, --world, nope.yaml, -o, maps]
            restart: on-failure
            depends_on: {{router: {{condition: service_started}}}}
            healthcheck: {{liveliness: true, timeout: 20s}}
        """).parent
    try:
        up = zendock(project, mark, "up", "-d", "--wait", "--wait-timeout", "30")
        assert up.returncode == 1, up.stderr + up.stdout
        assert "map: failed: exited with code 2 (a configuration error: not restarted)" in up.stdout
        reason = up.stderr.splitlines()[-1]
        assert reason.startswith(
            "zendock up: map failed: zendock map save: nope.yaml: cannot read world file"
        ), reason
        assert reason.endswith("the stack is down (`zendock logs` keeps what it printed)"), reason
        wait_for(lambda: not marked_processes(mark), 10, "nothing of the failed stack left running")
        logs = zendock(project, mark, "logs", "map")
        assert "cannot read world file" in logs.stdout, logs.stdout + logs.stderr
    finally:
        zendock(project, mark, "down")


def test_down_cleans_up_after_a_supervisor_that_died(project: Path, mark: str) -> None:
    up = zendock(project, mark, "up", "-d", "--wait", "--wait-timeout", "30")
    assert up.returncode == 0, up.stderr + up.stdout
    state_dir = project / ".zendock" / "clitest"
    marked = lambda: {p.pid for p in marked_processes(mark)}  # noqa: E731

    def recorded_pids() -> set[int]:
        try:
            rows = json.loads((state_dir / "state.json").read_text())["services"]
        except (OSError, ValueError, KeyError):
            return set()
        return {row["pid"] for row in rows if row.get("pid")}

    # the state the cleanup relies on must name every service's running process before the supervisor dies
    wait_for(
        lambda: len(recorded_pids()) == 3 and recorded_pids() <= marked(),
        15,
        "state.json to record the three running services",
    )
    supervisor_pid = json.loads((state_dir / "supervisor.json").read_text())["pid"]
    os.kill(supervisor_pid, signal.SIGKILL)
    wait_for(
        lambda: not any(p.pid == supervisor_pid for p in marked_processes(mark)), 10, "the supervisor to die"
    )
    ps = zendock(project, mark, "ps", "--json")
    assert "supervisor is not running" in ps.stderr
    assert {row["name"] for row in json.loads(ps.stdout)} == {"router", "talker", "helper"}
    down = zendock(project, mark, "down")
    assert down.returncode == 0, down.stderr
    assert not marked_processes(mark)
    assert not (state_dir / "state.json").exists()


@pytest.mark.parametrize("stop_signal", [signal.SIGINT, signal.SIGTERM])
def test_router_serves_with_the_shipped_config_and_exits_0(endpoint: str, stop_signal: int) -> None:
    config = REPO_ROOT / "deploy" / "zenoh" / "router.json5"
    proc = subprocess.Popen(
        [sys.executable, "-m", "deploy.cli", "router", "--config", str(config), "--listen", endpoint],
        cwd=REPO_ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        start_new_session=True,
    )
    try:
        assert proc.stdout is not None
        ready = proc.stdout.readline()
        assert ready.startswith(f"zendock router: listening on {endpoint}"), ready
        from shared.session import SessionSpec, open_session

        with open_session(SessionSpec(mode="client", connect=(endpoint,))) as session:
            assert session.info.routers_zid(), "the client sees no router"
        proc.send_signal(stop_signal)
        assert proc.wait(timeout=30) == 0  # generous: closing the session is slow on a loaded machine
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
