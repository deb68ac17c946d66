"""Launch planning: argv words, every service's environment, namespaces and health probes."""

from __future__ import annotations

import sys
import textwrap
from pathlib import Path

import pytest

from deploy.launcher.plan import ZENDOCK_ROOT, health_test_argv, plan_launch, resolve_argv
from deploy.launcher.stack_file import load_stack
from shared.names import node_token_key

REPO_ROOT = ZENDOCK_ROOT


def test_python_and_zendock_mean_this_interpreter_and_this_zendock() -> None:
    assert resolve_argv(["python", "-m", "services.pose"]) == [sys.executable, "-m", "services.pose"]
    assert resolve_argv(["zendock", "router"]) == [sys.executable, "-m", "deploy.cli", "router"]
    assert resolve_argv(["/bin/echo", "python"]) == ["/bin/echo", "python"]


def test_health_test_forms() -> None:
    assert health_test_argv("test -f ready") == ["/bin/sh", "-c", "test -f ready"]
    assert health_test_argv(["CMD-SHELL", "test -f ready"]) == ["/bin/sh", "-c", "test -f ready"]
    assert health_test_argv(["CMD", "python", "-c", "pass"]) == [sys.executable, "-c", "pass"]
    assert health_test_argv(["true"]) == ["true"]


def _stack(tmp_path: Path):  # type: ignore[no-untyped-def]
    path = tmp_path / "stack.yaml"
    path.write_text(
        textwrap.dedent(
            """\
            namespace: fleet
            zenoh: {connect: [tcp/127.0.0.1:7600]}
            services:
              sim:
                command: [python, -m, services.simulator]
                healthcheck: {liveliness: true}
                environment: {LEVEL: debug, PASSED: null, MISSING: null}
              robot1_pose:
                command: [python, -m, services.pose]
                namespace: robot1
                working_dir: sub
                healthcheck: {liveliness: pose, timeout: 2s, test: [CMD, python, -c, pass]}
              absolute:
                command: [python, -m, services.battery]
                namespace: /elsewhere
            """
        ),
        encoding="utf-8",
    )
    return load_stack(path, env={"PASSED": "yes"}, project_dir=tmp_path)


def test_every_service_gets_namespace_connect_and_its_environment(tmp_path: Path) -> None:
    plan = plan_launch(
        _stack(tmp_path), working_dir=tmp_path, base_environment={"HOME": "/root", "LEVEL": "info"}
    )
    sim, pose, absolute = plan.services["sim"], plan.services["robot1_pose"], plan.services["absolute"]
    assert sim.env["ZENDOCK_NAMESPACE"] == "fleet"
    assert pose.env["ZENDOCK_NAMESPACE"] == "fleet/robot1"
    assert absolute.env["ZENDOCK_NAMESPACE"] == "elsewhere"
    assert sim.env["ZENDOCK_CONNECT"] == "tcp/127.0.0.1:7600"
    assert sim.env["LEVEL"] == "debug" and pose.env["LEVEL"] == "info"
    assert sim.env["PASSED"] == "yes" and "MISSING" not in sim.env
    assert sim.env["HOME"] == "/root" and sim.env["PYTHONUNBUFFERED"] == "1"
    assert sim.env["PYTHONPATH"].split(":")[0] == str(ZENDOCK_ROOT)
    assert sim.cwd == tmp_path.resolve() and pose.cwd == (tmp_path / "sub").resolve()


def test_overrides_move_the_whole_stack(tmp_path: Path) -> None:
    plan = plan_launch(
        _stack(tmp_path),
        working_dir=tmp_path,
        namespace="t123",
        connect=["tcp/127.0.0.1:7700"],
        environment={"EXTRA": "1", "LEVEL": "warn"},
        base_environment={},
    )
    assert plan.namespace == "t123" and plan.connect == ("tcp/127.0.0.1:7700",)
    assert plan.services["robot1_pose"].env["ZENDOCK_NAMESPACE"] == "t123/robot1"
    assert plan.services["absolute"].env["ZENDOCK_NAMESPACE"] == "elsewhere"
    assert plan.services["sim"].env["ZENDOCK_CONNECT"] == "tcp/127.0.0.1:7700"
    assert plan.services["sim"].env["EXTRA"] == "1"
    assert plan.services["sim"].env["LEVEL"] == "debug"  # the service's own setting is the most specific
    assert plan.services["robot1_pose"].env["LEVEL"] == "warn"


def test_health_plans_watch_the_right_token(tmp_path: Path) -> None:
    plan = plan_launch(_stack(tmp_path), working_dir=tmp_path, namespace="t9", base_environment={})
    sim, pose = plan.services["sim"].health, plan.services["robot1_pose"].health
    assert sim is not None and pose is not None
    assert sim.liveliness_key == node_token_key("t9", "sim") and sim.test_argv is None
    assert pose.liveliness_key == node_token_key("t9/robot1", "pose")
    assert pose.liveliness_timeout_s == 2.0 and pose.test_argv == (sys.executable, "-c", "pass")
    assert plan.services["absolute"].health is None
    assert plan.liveliness_needed


def test_the_launchers_zenoh_config_is_resolved_against_the_working_dir(tmp_path: Path) -> None:
    path = tmp_path / "secure.yaml"
    path.write_text(
        "zenoh: {connect: [tcp/127.0.0.1:7600], config: creds/viewer.json5}\nservices: {a: {command: [x]}}\n"
    )
    stack = load_stack(path, env={}, project_dir=tmp_path)
    assert stack.zenoh_config == "creds/viewer.json5"
    assert stack.to_dict()["zenoh"] == {"connect": ["tcp/127.0.0.1:7600"], "config": "creds/viewer.json5"}
    assert plan_launch(stack, working_dir=tmp_path / "run").zenoh_config == str(
        tmp_path / "run/creds/viewer.json5"
    )
    assert plan_launch(_stack(tmp_path), working_dir=tmp_path).zenoh_config is None


def test_the_detached_supervisor_gets_the_plan_up_made_unchanged(tmp_path: Path) -> None:
    from deploy.launcher.plan import plan_from_json, plan_to_json

    stack = load_stack(
        REPO_ROOT / "deploy" / "stack.yaml",
        env={},
        project_dir=tmp_path,
        compose={"robot": ["battery", "pose"]},
    )
    plan = plan_launch(stack, working_dir=tmp_path, namespace="r7", connect=["tcp/127.0.0.1:7001"])
    assert plan_from_json(plan_to_json(plan)) == plan
    with_standby = plan_launch(stack, working_dir=tmp_path, standby=True)
    assert with_standby.standby and plan_from_json(plan_to_json(with_standby)) == with_standby
    with pytest.raises(ValueError, match="not a launch plan"):
        plan_from_json('{"project": "x"}')


def test_a_standby_is_planned_only_for_zendocks_services_on_this_interpreter(tmp_path: Path) -> None:
    path = tmp_path / "stack.yaml"
    path.write_text(
        textwrap.dedent(
            """\
            services:
              battery: {command: [python, -u, -m, services.battery, --log-level, debug]}
              dds: {command: [.venv-ros2/bin/python, -m, services.ros2_dds]}
              robot: {command: [zendock, container, battery, +, pose]}
              own: {command: [python, my_battery.py]}
            """
        )
    )
    plan = plan_launch(load_stack(path, env={}, project_dir=tmp_path), working_dir=tmp_path)
    assert plan.services["battery"].standby_argv == (
        sys.executable, "-u", "-m", "deploy.standby", "services.battery", "--log-level", "debug",
    )  # fmt: skip
    assert [name for name, s in plan.services.items() if s.standby_argv is None] == ["dds", "robot", "own"]
