"""The launcher's supervision through its Python API: order, health, restarts, stops, and no leftovers."""

from __future__ import annotations

import asyncio
import os
import re
import signal
import threading
import time
from pathlib import Path

import psutil
import pytest

from deploy.commands.ps import format_table
from deploy.launcher import Backoff, Launcher, StackNotReady
from tests.integration.launcher.conftest import fake, marked_processes, read_records, wait_for


def test_services_start_in_dependency_order(launch, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    record = tmp_path / "events.txt"
    stack = launch(
        f"""\
        services:
          late:
            command: {fake("--name", "late", "--record", str(record))}
            depends_on: {{healthy: {{condition: service_healthy}}, step: {{condition: service_completed_successfully}}}}
          started:
            command: {fake("--name", "started", "--record", str(record))}
            depends_on: [healthy]
          healthy:
            command: {fake("--name", "healthy", "--token", "healthy", "--ready-after", "0.4", "--record", str(record))}
            healthcheck: {{liveliness: true, timeout: 10s}}
          step:
            command: {fake("--name", "step", "--exit-after", "0.3", "--record", str(record))}
        """
    )
    statuses = stack.wait_healthy(timeout_s=20)
    assert statuses["healthy"].health == "healthy"
    assert statuses["step"].state == "exited" and statuses["step"].exit_code == 0
    assert statuses["started"].started_at > statuses["healthy"].started_at  # service_started: launched after
    wait_for(
        lambda: {"late", "started"} <= {row[0] for row in read_records(record)}, 10, "late and started to run"
    )
    events = {(name, event): when for name, event, when, _ in read_records(record)}
    assert events[("late", "start")] > events[("healthy", "ready")]
    assert events[("late", "start")] > events[("step", "exit")]
    assert [s.name for s in stack.ps()] == ["healthy", "step", "late", "started"]


def test_health_comes_from_liveliness_tokens_and_exec_checks(launch, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    ready_file = tmp_path / "ready"
    stack = launch(
        f"""\
        services:
          slow:
            command: {fake("--token", "slow", "--ready-after", "0.6")}
            healthcheck: {{liveliness: true, timeout: 10s}}
          silent:
            command: {fake("--name", "silent")}
            healthcheck: {{liveliness: true, timeout: 500ms}}
          renamed:
            command: {fake("--token", "other_node")}
            healthcheck: {{liveliness: other_node}}
          probed:
            command: {fake("--name", "probed")}
            healthcheck: {{test: "test -f {ready_file}", interval: 100ms, retries: 2}}
          plain:
            command: {fake("--name", "plain")}
          robot1_talker:
            command: {fake("--token", "talker")}
            namespace: robot1
            healthcheck: {{liveliness: talker, timeout: 10s}}
          robot2_talker:
            command: {fake("--token", "talker", "--ready-after", "30")}
            namespace: robot2
            healthcheck: {{liveliness: talker, timeout: 10s}}
        """
    )
    assert stack.status("slow").health == "starting"
    stack.wait_until(lambda st: st["slow"].health == "healthy", 15, "slow healthy")
    stack.wait_until(lambda st: st["silent"].health == "unhealthy", 15, "silent unhealthy")
    stack.wait_until(lambda st: st["renamed"].health == "healthy", 15, "renamed healthy")
    stack.wait_until(lambda st: st["probed"].health == "unhealthy", 15, "probe failing")
    ready_file.touch()
    stack.wait_until(lambda st: st["probed"].health == "healthy", 15, "probe passing")
    assert stack.status("plain").health == "none"
    # one file, two robots: the same node name in two namespaces is told apart
    stack.wait_until(lambda st: st["robot1_talker"].health == "healthy", 15, "robot1's talker healthy")
    assert stack.status("robot2_talker").health == "starting"
    assert stack.status("silent").state == "running"


def test_a_stop_ends_exec_checks_even_when_a_check_loses_its_cancellation(  # type: ignore[no-untyped-def]
    launch, monkeypatch
) -> None:
    """On Python 3.11 ``asyncio.wait_for`` returns the result instead of raising when a cancellation lands
    just as the awaited process exits; the health loop then ran on and ``down`` waited for it for ever."""
    from deploy.launcher import supervisor

    checking = threading.Event()

    async def check_that_swallows_cancellation(*_args: object, **_kwargs: object) -> bool:
        checking.set()
        try:
            await asyncio.sleep(3600)
        except asyncio.CancelledError:
            return True  # what wait_for did: a result, no CancelledError
        return False

    monkeypatch.setattr(supervisor, "run_check", check_that_swallows_cancellation)
    stack = launch(
        f"""\
        services:
          probed:
            command: {fake("--name", "probed")}
            healthcheck: {{test: "true", interval: 10s}}
        """
    )
    wait_for(checking.is_set, 10, "the first health check to start")
    assert stack.status("probed").state == "running"
    stack.down(timeout_s=15)  # raises TimeoutError, naming probed, if the health loop outlives the stop


def test_restart_policies(launch) -> None:  # type: ignore[no-untyped-def]
    quick = ("--exit-after", "0.05")
    stack = launch(
        f"""\
        services:
          no_policy: {{command: {fake(*quick, "--exit-code", "1")}, restart: "no"}}
          on_failure_ok: {{command: {fake(*quick, "--exit-code", "0")}, restart: on-failure}}
          on_failure_max: {{command: {fake(*quick, "--exit-code", "3")}, restart: "on-failure:2"}}
          on_failure: {{command: {fake(*quick, "--exit-code", "1")}, restart: on-failure}}
          always: {{command: {fake(*quick, "--exit-code", "0")}, restart: always}}
          unless_stopped: {{command: {fake(*quick, "--exit-code", "1")}, restart: unless-stopped}}
          misconfigured: {{command: {fake(*quick, "--exit-code", "2")}, restart: always}}
        """
    )
    statuses = stack.wait_until(
        lambda st: (
            all(st[n].restarts >= 3 for n in ("on_failure", "always", "unless_stopped"))
            and all(
                st[n].state == "exited"
                for n in ("no_policy", "on_failure_ok", "on_failure_max", "misconfigured")
            )
        ),
        30,
        "the policies to play out",
    )
    assert (statuses["no_policy"].restarts, statuses["no_policy"].exit_code) == (0, 1)
    assert (statuses["on_failure_ok"].restarts, statuses["on_failure_ok"].exit_code) == (0, 0)
    assert (statuses["on_failure_max"].restarts, statuses["on_failure_max"].exit_code) == (2, 3)
    assert stack.logs("on_failure_max").count("[zendock] exited with code 3") == 3
    # a configuration error (exit 2) would only repeat: not restarted, whatever the policy, and ps says why
    assert (statuses["misconfigured"].restarts, statuses["misconfigured"].exit_code) == (0, 2)
    assert "configuration error" in statuses["misconfigured"].detail
    stack.stop("always", "on_failure")
    stopped = stack.ps()
    restarts_when_stopped = {s.name: s.restarts for s in stopped}
    assert {s.name: s.state for s in stopped}["always"] == "stopped"
    stack.wait_until(
        lambda st: st["unless_stopped"].restarts >= restarts_when_stopped["unless_stopped"] + 2,
        10,
        "more restarts",
    )
    assert stack.status("always").restarts == restarts_when_stopped["always"]
    assert stack.status("on_failure").state == "stopped"


def test_a_run_that_passed_its_healthcheck_restarts_without_growing_backoff(launch) -> None:  # type: ignore[no-untyped-def]
    """The backoff guards against start-up crash loops: a service that became healthy and then died (a
    kill, a fault later on) restarts after the first delay every time; one that never passed a
    healthcheck waits twice as long at each restart of its streak."""
    dies = ("--exit-after", "1.0", "--exit-code", "1")
    stack = launch(
        f"""\
        services:
          healthy_then_dies:
            command: {fake("--token", "healthy_then_dies", *dies)}
            restart: on-failure
            healthcheck: {{liveliness: true, timeout: 10s}}
          never_healthy:
            command: {fake(*dies)}
            restart: on-failure
        """,
        backoff=Backoff(initial_s=0.2, max_s=5.0, reset_after_s=60.0),
    )
    stack.wait_until(lambda st: all(s.restarts >= 4 for s in st.values()), 30, "four restarts of each")
    delays = {
        name: re.findall(r"restarting in ([0-9.]+)s", "\n".join(stack.logs(name)))
        for name in ("healthy_then_dies", "never_healthy")
    }
    # a healthy run's first death restarts at once; the next ones, within reset_after_s, wait
    assert delays["healthy_then_dies"][:4] == ["0.0", "0.2", "0.2", "0.2"], delays
    assert delays["never_healthy"][:4] == ["0.2", "0.4", "0.8", "1.6"], delays


def test_kill_9_of_a_service_leads_to_a_restart(launch) -> None:  # type: ignore[no-untyped-def]
    stack = launch(
        f"""\
        services:
          worker:
            command: {fake("--token", "worker")}
            restart: on-failure
            healthcheck: {{liveliness: true, timeout: 10s}}
          bystander:
            command: {fake("--token", "bystander")}
            healthcheck: {{liveliness: true, timeout: 10s}}
        """
    )
    before = stack.wait_healthy(timeout_s=15)
    os.kill(before["worker"].pid, signal.SIGKILL)
    after = stack.wait_until(
        lambda st: (
            st["worker"].restarts == 1
            and st["worker"].state == "running"
            and st["worker"].health == "healthy"
        ),
        15,
        "the killed worker to be back and healthy",
    )
    assert after["worker"].pid != before["worker"].pid
    assert after["bystander"].pid == before["bystander"].pid and after["bystander"].restarts == 0
    assert "[zendock] killed by signal 9" in stack.logs("worker")


def test_stop_escalates_and_down_leaves_no_process(launch, mark: str) -> None:  # type: ignore[no-untyped-def]
    stack = launch(
        f"""\
        services:
          polite: {{command: {fake("--grandchild", "group")}}}
          escaped: {{command: {fake("--grandchild", "session")}}}
          deaf_to_int: {{command: {fake("--ignore", "SIGINT")}, stop_grace_period: 1s}}
          deaf: {{command: {fake("--ignore", "SIGINT", "--ignore", "SIGTERM")}, stop_grace_period: 600ms}}
        """
    )

    def grandchildren_up() -> bool:
        return all(
            any(line.startswith("grandchild ") for line in stack.logs(name)) for name in ("polite", "escaped")
        )

    wait_for(grandchildren_up, 15, "the grandchildren")
    wait_for(
        lambda: all(any(" up (pid" in line for line in stack.logs(n)) for n in ("deaf_to_int", "deaf")),
        15,
        "handlers",
    )
    processes = marked_processes(mark)
    assert len(processes) >= 6
    started = time.monotonic()
    stack.stop("deaf")
    assert time.monotonic() - started >= 0.6
    assert stack.status("deaf").exit_code == -signal.SIGKILL
    stack.stop("deaf_to_int")
    assert stack.status("deaf_to_int").exit_code == 0  # SIGTERM at half the grace period: a clean exit
    stack.down()
    assert not marked_processes(mark)
    assert all(not p.is_running() or p.status() == psutil.STATUS_ZOMBIE for p in processes)


def test_stop_start_restart_recheck_dependencies(launch) -> None:  # type: ignore[no-untyped-def]
    stack = launch(
        f"""\
        services:
          base:
            command: {fake("--token", "base")}
            healthcheck: {{liveliness: true, timeout: 10s}}
          user:
            command: {fake("--name", "user")}
            depends_on: {{base: {{condition: service_healthy}}}}
        """
    )
    stack.wait_healthy(timeout_s=15)
    stack.stop("base")
    assert stack.status("base").state == "stopped" and stack.status("user").state == "running"
    stack.restart("user", timeout_s=0.5)
    waiting = stack.status("user")
    assert waiting.state == "restarting" and waiting.pid is None
    assert "waiting for base (service_healthy)" in waiting.detail
    stack.start("base")
    stack.wait_until(lambda st: st["user"].state == "running", 15, "user to start once base is healthy")
    assert stack.status("base").health == "healthy"


def test_a_failed_dependency_stops_its_dependents(launch) -> None:  # type: ignore[no-untyped-def]
    stack = launch(
        f"""\
        services:
          step: {{command: {fake("--exit-after", "0", "--exit-code", "4")}}}
          needs_step:
            command: {fake("--name", "never")}
            depends_on: {{step: {{condition: service_completed_successfully}}}}
        """
    )
    status = stack.wait_state("needs_step", "exited", 15)
    assert status.pid is None and status.restarts == 0
    assert "dependency step exited with code 4" in status.detail
    assert not any("never up" in line for line in stack.logs("needs_step"))


def test_a_missing_program_counts_as_a_failure_and_is_not_restarted(launch) -> None:  # type: ignore[no-untyped-def]
    stack = launch(
        """\
        services:
          ghost: {command: [/nonexistent/zendock-ghost], restart: "on-failure:3"}
        """
    )
    status = stack.wait_until(lambda st: st["ghost"].state == "exited", 10, "ghost to give up")["ghost"]
    assert status.exit_code == 127 and status.restarts == 0, "a command not found would only fail again"
    assert "a command not found: not restarted" in status.detail
    assert any("cannot start /nonexistent/zendock-ghost" in line for line in stack.logs("ghost"))


def test_the_launcher_downs_even_when_the_body_raises(
    tmp_path: Path, mark: str, router_endpoint: str
) -> None:
    stack_file = tmp_path / "stack.yaml"
    stack_file.write_text(
        f"services:\n  sleeper: {{command: {fake('--name', 'sleeper')}}}\n", encoding="utf-8"
    )
    launcher = Launcher(
        stack_file, project_dir=tmp_path, connect=[router_endpoint], environment={"ZENDOCK_TEST_MARK": mark}
    )
    try:
        with launcher:
            wait_for(lambda: marked_processes(mark), 10, "the sleeper")
            raise RuntimeError("a failing test body")
    except RuntimeError:
        pass
    assert not marked_processes(mark)
    assert not (tmp_path / ".zendock" / tmp_path.name.lower() / "state.json").exists()


def test_a_stack_that_never_gets_healthy_names_the_service_and_its_last_line(launch) -> None:  # type: ignore[no-untyped-def]
    """What ``demo``, ``trials`` and ``fleet`` print when a replacement never declares its node token."""
    stack = launch(
        f"""\
        services:
          ready:
            command: {fake("--token", "ready")}
            healthcheck: {{liveliness: true, timeout: 10s}}
          replacement:
            command: {fake("--name", "my_docking")}
            healthcheck: {{liveliness: docking, timeout: 500ms}}
        """
    )
    with pytest.raises(StackNotReady) as failure:
        stack.wait_healthy(timeout_s=2.0)
    summary = failure.value.summary
    assert summary.startswith("replacement not healthy after 2s"), summary
    assert "ready" not in summary.split("(")[0].replace("replacement", ""), summary
    assert "its last line: my_docking" in summary, summary  # the fake prints "my_docking up (pid ...)"


def test_a_crash_loop_backs_off_and_ps_says_why_it_last_stopped(launch, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    """A service that fails at start-up is retried after 0.1, 0.2, 0.4 s ... (not a tight loop), and ``ps``
    names the cause while it restarts and after it comes back: the exit and the line that said why."""
    needed = tmp_path / "calibration.yaml"
    stack = launch(
        f"""\
        services:
          looping: {{command: {fake("--fail-unless-exists", str(needed))}, restart: always}}
        """,
        backoff=Backoff(initial_s=0.1, max_s=1.0, reset_after_s=10.0),
    )
    why = f"exited with code 3: fake: {needed} missing"
    looping = stack.wait_until(lambda st: st["looping"].restarts >= 3, 30, "three restarts")["looping"]
    assert why in looping.last_exit, looping
    delays = [float(d) for d in re.findall(r"restarting in ([0-9.]+)s", "\n".join(stack.logs("looping")))]
    assert delays[:3] == [0.1, 0.2, 0.4], delays
    needed.write_text("ok\n")
    running = stack.wait_until(lambda st: st["looping"].state == "running", 30, "running again")
    assert running["looping"].last_exit == why
    assert f"(last: {why})" in format_table(list(running.values()))
