"""``x-compose``: a stack's group of services becomes one ``zendock container`` service."""

from __future__ import annotations

from pathlib import Path

import pytest

from deploy.launcher import load_stack
from deploy.launcher.composition import CompositionError, compose_groups
from deploy.launcher.launch import GroupRun, ModuleRun, ProgramRun, read_command, run_words
from deploy.launcher.stack_file import validate_stack_file
from shared.config_errors import ConfigError

REPO_ROOT = Path(__file__).resolve().parents[3]


def _services(document: dict) -> dict:  # type: ignore[type-arg]
    """The document's services, validated and read as a stack file's are."""
    return {
        name: spec.launch() for name, spec in validate_stack_file(document, "stack.yaml").services.items()
    }


def _doc() -> dict:  # type: ignore[type-arg]
    return {
        "services": {
            "router": {"command": ["zendock", "router"]},
            "map": {"command": ["zendock", "map", "save"], "restart": "no"},
            "battery": {
                "command": ["python", "-m", "services.battery", "-p", "use_sim_time=true"],
                "depends_on": {"router": {"condition": "service_started"}},
                "restart": "on-failure",
                "environment": {"A": "1"},
            },
            "planner": {
                "command": "python -m services.planner -p map_yaml=m.yaml",
                "stop_grace_period": "8s",
                "depends_on": {"router": {}, "map": {"condition": "service_completed_successfully"}},
                "healthcheck": {"liveliness": True, "timeout": "20s"},
            },
            "viewer": {"command": ["python", "-m", "services.viz"], "depends_on": ["planner", "router"]},
        }
    }


def test_a_group_replaces_its_members_with_one_container() -> None:
    services = _services(_doc())
    out = compose_groups(services, {"robot": ["battery", "planner"]})
    assert set(out) == {"router", "map", "robot", "viewer"} and "robot" not in services
    robot = out["robot"]
    assert robot.run == GroupRun(
        (ModuleRun("battery", ("-p", "use_sim_time=true")), ModuleRun("planner", ("-p", "map_yaml=m.yaml")))
    )
    assert robot.command == [
        "zendock",
        "container",
        "battery",
        "-p",
        "use_sim_time=true",
        "+",
        "planner",
        "-p",
        "map_yaml=m.yaml",
    ]
    assert {name: d.condition for name, d in robot.depends_on.items()} == {
        "router": "service_started",
        "map": "service_completed_successfully",
    }
    assert robot.healthcheck is not None
    assert (robot.healthcheck.liveliness, robot.healthcheck.timeout) == ("planner", 20.0)
    assert str(robot.restart) == "on-failure" and robot.stop_grace_period == 8.0
    assert robot.environment == {"A": "1"}
    assert set(out["viewer"].depends_on) == {"robot", "router"}


@pytest.mark.parametrize(
    ("groups", "message"),
    [
        ({"robot": ["battery", "nowhere"]}, "unknown service 'nowhere'"),
        ({"robot": ["battery", "map"]}, "only zendock's services run in a container"),
        ({"robot": []}, "non-empty list"),
        ({"router": ["battery"]}, "already named 'router'"),
        ({"a": ["battery"], "b": ["battery"]}, "already in group 'a'"),
    ],
)
def test_groups_that_cannot_run_as_one_process_are_named(groups: dict, message: str) -> None:  # type: ignore[type-arg]
    with pytest.raises(CompositionError, match=message):
        compose_groups(_services(_doc()), groups)


def test_the_default_stack_composes_and_a_bad_x_compose_is_one_clear_error(tmp_path: Path) -> None:
    stack = load_stack(
        REPO_ROOT / "deploy/stack.yaml",
        env={},
        project_dir=tmp_path,
        compose={"robot": ["perception", "battery", "pose", "planner", "docking"]},
    )
    assert "robot" in stack.services and "docking" not in stack.services
    assert stack.services["robot"].members == ("perception", "battery", "pose", "planner", "docking")
    assert stack.services["robot"].command[:3] == ["zendock", "container", "perception"]
    bad = tmp_path / "stack.yaml"
    bad.write_text(
        "services:\n  a: {command: [python, -m, services.battery]}\nx-compose: [a]\n", encoding="utf-8"
    )
    with pytest.raises(ConfigError, match="x-compose: expected a mapping"):
        load_stack(bad, env={}, project_dir=tmp_path)
    bad.write_text(
        "services:\n  a: {command: [python, -m, services.battery]}\nx-compose: {g: [a, b]}\n",
        encoding="utf-8",
    )
    with pytest.raises(ConfigError, match="x-compose.g: unknown service 'b'"):
        load_stack(bad, env={}, project_dir=tmp_path)


@pytest.mark.parametrize(
    ("command", "members"),
    [
        (
            ["zendock", "container", "battery", "-p", "a=1", "+", "pose", "+", "planner", "-p", "m=x"],
            ("battery", "pose", "planner"),
        ),
        (
            ["zendock", "container", "--namespace", "r1", "--log-level", "DEBUG", "battery", "+", "docking"],
            ("battery", "docking"),
        ),
        (["/venv/bin/zendock", "container", "pose"], ("pose",)),
    ],
)
def test_a_groups_members_are_read_once_from_its_container_command(
    command: list[str], members: tuple[str, ...]
) -> None:
    run = read_command(command)
    assert isinstance(run, GroupRun) and run.services == members
    assert run_words(run) == command  # the words again, as they were (the zendock named runs them)


@pytest.mark.parametrize(
    ("command", "run"),
    [
        (["python", "-m", "services.battery", "-p", "a=1"], ModuleRun("battery", ("-p", "a=1"))),
        (
            [".venv-ros2/bin/python", "-m", "services.ros2_dds"],
            ModuleRun("ros2_dds", (), ".venv-ros2/bin/python"),
        ),
        (
            ["python", "-u", "-X", "importtime", "-m", "services.pose"],
            ModuleRun("pose", (), "python", ("-u", "-X", "importtime")),
        ),
        (["zendock", "router"], ProgramRun(("zendock", "router"))),
        (["python", "-m", "services"], ProgramRun(("python", "-m", "services"))),
        (
            ["python", "my_docking.py", "-m", "services.docking"],
            ProgramRun(("python", "my_docking.py", "-m", "services.docking")),
        ),
        (["zendock", "container", "+", "pose"], ProgramRun(("zendock", "container", "+", "pose"))),
    ],
)
def test_a_command_is_read_into_its_run(command: list[str], run: object) -> None:
    assert read_command(command) == run
    assert run_words(read_command(command)) == command


def test_the_launch_plan_of_a_composed_stack_names_the_groups_services(tmp_path: Path) -> None:
    from deploy.launcher.plan import plan_launch

    stack = load_stack(
        REPO_ROOT / "deploy/stack.yaml",
        env={},
        project_dir=tmp_path,
        compose={"robot": ["battery", "pose", "planner", "docking"]},
    )
    plan = plan_launch(stack, working_dir=tmp_path)
    assert plan.services["robot"].members == ("battery", "pose", "planner", "docking")
    assert plan.services["simulator"].members == ()
