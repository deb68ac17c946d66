"""``--service NAME=COMMAND``: what a replacement runs with, in every robot's copy, and the one-line errors."""

from __future__ import annotations

from pathlib import Path

import pytest

from deploy.launcher.stack_file import Stack
from deploy.paths import REPO_ROOT
from deploy.replacements import apply_replacements, parse_replacement, replacements_report
from deploy.trials.records import TrialOptions
from deploy.trials.stack import trials_stack
from shared.config_errors import ConfigError

WORLD = REPO_ROOT / "deploy" / "worlds" / "seed_room.yaml"


def _trials_stack(tmp_path: Path, **options) -> Stack:  # type: ignore[no-untyped-def]
    return trials_stack(
        TrialOptions(world=WORLD, detector="synthetic", **options), "tcp/127.0.0.1:1", ["r0", "r1"]
    )


def test_every_robots_copy_runs_the_command_with_zendocks_flags_and_its_own_namespace(tmp_path: Path) -> None:
    replacement = parse_replacement("docking=python my_docking.py --robot {robot}")
    stack = apply_replacements(_trials_stack(tmp_path), [replacement])
    for robot in ("r0", "r1"):
        spec = stack.services[f"docking_{robot}"]
        assert spec.command[:4] == ["python", "my_docking.py", "--robot", robot]
        assert spec.command[4:] == [
            "-p",
            "use_sim_time=true",
            "-p",
            f"dock_database={WORLD}",
            "-p",
            "controller=graceful",
        ]
        assert spec.healthcheck is not None and spec.healthcheck.liveliness == "docking"
    assert stack.services["battery_r0"].command[:3] == ["python", "-m", "services.battery"]


def test_a_replaced_service_leaves_the_composed_group_and_runs_as_its_own_process(tmp_path: Path) -> None:
    replacement = parse_replacement("battery=./my_battery")
    stack = _trials_stack(tmp_path, compose="light", replacements=(replacement,))
    group = stack.services["robot_r0"].command
    assert group[:3] == ["zendock", "container", "pose"] and "battery" not in group
    assert stack.services["battery_r0"].command[0] == "./my_battery"


def test_replacing_inside_a_container_or_a_missing_service_is_one_clear_error(tmp_path: Path) -> None:
    composed = _trials_stack(tmp_path, compose="all")
    with pytest.raises(ConfigError, match="runs it inside a composed zendock container"):
        apply_replacements(composed, [parse_replacement("planner=x")])
    with pytest.raises(ConfigError, match="runs no services.viz"):
        apply_replacements(_trials_stack(tmp_path), [parse_replacement("viz=x")])


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        ("docking", "expected NAME=COMMAND"),
        ("=python x.py", "expected NAME=COMMAND"),
        ("router=x", "no replaceable service 'router'"),
        ("docking=", "the command is empty"),
        ("docking=python 'x.py", "does not parse as shell words"),
    ],
)
def test_a_malformed_option_names_what_is_wrong(text: str, problem: str) -> None:
    with pytest.raises(ValueError, match=problem):
        parse_replacement(text)


def test_reports_name_each_replacement_and_its_command() -> None:
    assert replacements_report([parse_replacement("docking=python my docking.py")]) == {
        "docking": "python my docking.py"
    }
    assert replacements_report([]) == {}


def test_a_file_named_relative_to_where_the_user_is_becomes_absolute(tmp_path: Path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """zendock runs services in another directory: ``python my_docking.py`` must still find the file."""
    (tmp_path / "my_docking.py").write_text("")
    monkeypatch.chdir(tmp_path)
    replacement = parse_replacement("docking=python my_docking.py --gain 2")
    assert replacement.words == ("python", str(tmp_path / "my_docking.py"), "--gain", "2")


def test_the_same_service_twice_is_one_clear_error(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="--service docking is given twice"):
        apply_replacements(
            _trials_stack(tmp_path), [parse_replacement("docking=a"), parse_replacement("docking=b")]
        )
