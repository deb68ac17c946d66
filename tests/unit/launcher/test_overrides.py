"""``--set SERVICE.PARAM=VALUE``: a parameter of one of zendock's services, over the stack's own."""

from __future__ import annotations

from pathlib import Path

import pytest

from deploy.launcher.launch import GroupRun, ModuleRun
from deploy.launcher.overrides import apply_sets, parse_set, with_params
from deploy.launcher.stack_file import load_stack
from deploy.paths import REPO_ROOT
from deploy.replacements import apply_replacements, parse_replacement
from shared.config_errors import ConfigError

STACK = REPO_ROOT / "deploy" / "stack.yaml"


def _flags(run: object) -> tuple[str, ...]:
    assert isinstance(run, ModuleRun)
    return run.flags


def test_a_set_replaces_the_stacks_value_and_adds_a_new_one(tmp_path: Path) -> None:
    stack = load_stack(STACK, env={}, project_dir=tmp_path)
    changed = apply_sets(stack, [parse_set("docking.controller=seed"), parse_set("docking.auto_dock=false")])
    flags = _flags(changed.services["docking"].run)
    assert "controller=seed" in flags and "controller=graceful" not in flags
    assert (
        flags[-2:] == ("-p", "auto_dock=false")
        and flags.count("-p") == _flags(stack.services["docking"].run).count("-p") + 1
    )
    assert changed.services["planner"] == stack.services["planner"]


def test_a_set_reaches_a_member_of_a_group_and_a_replacement_gets_it(tmp_path: Path) -> None:
    composed = load_stack(STACK, env={}, project_dir=tmp_path, compose={"robot": ["battery", "docking"]})
    run = with_params(composed, "docking", {"auto_dock": False}).services["robot"].run
    assert isinstance(run, GroupRun) and "auto_dock=false" in run.members[1].flags
    alone = with_params(load_stack(STACK, env={}, project_dir=tmp_path), "docking", {"auto_dock": False})
    replaced = apply_replacements(alone, [parse_replacement("docking=python mine.py")])
    assert replaced.services["docking"].command[-2:] == ["-p", "auto_dock=false"]


@pytest.mark.parametrize("text", ["docking", "auto_dock=false", ".auto_dock=1", "docking.=1"])
def test_a_malformed_set_names_the_form(text: str) -> None:
    with pytest.raises(ValueError, match=r"expected SERVICE.PARAMETER=VALUE"):
        parse_set(text)


def test_a_set_to_the_value_the_stack_already_gives_changes_nothing(tmp_path: Path) -> None:
    stack = load_stack(STACK, env={}, project_dir=tmp_path)
    assert with_params(stack, "docking", {"controller": "graceful"}) == stack


def test_a_set_for_a_service_the_stack_does_not_run_is_one_clear_error(tmp_path: Path) -> None:
    stack = load_stack(STACK, env={}, project_dir=tmp_path)
    with pytest.raises(ConfigError, match="runs no zendock service 'dockin'"):
        with_params(stack, "dockin", {"auto_dock": False})
