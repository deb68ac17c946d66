"""Restart policies, backoff, and dependency order: the pure rules the supervisor follows."""

from __future__ import annotations

import pytest

from deploy.launcher.graph import dependency_order, find_cycle, with_dependencies
from deploy.launcher.restart import Backoff, RestartPolicy, parse_restart_policy


@pytest.mark.parametrize(
    ("policy", "exit_code", "streak", "restart"),
    [
        ("no", 1, 0, False),
        ("no", -9, 0, False),
        ("always", 0, 0, True),
        ("always", 1, 50, True),
        ("unless-stopped", 0, 0, True),
        ("on-failure", 0, 0, False),
        ("on-failure", 1, 0, True),
        ("on-failure", -9, 100, True),
        ("on-failure:2", 1, 0, True),
        ("on-failure:2", 1, 1, True),
        ("on-failure:2", 1, 2, False),
        ("on-failure:2", 0, 0, False),
        ("on-failure:0", 1, 0, False),
        # exit 2 is a configuration error (shared.config_errors.CONFIG_ERROR_EXIT): no policy restarts it
        ("on-failure", 2, 0, False),
        ("always", 2, 0, False),
        ("unless-stopped", 2, 0, False),
    ],
)
def test_restart_policies(policy: str, exit_code: int, streak: int, restart: bool) -> None:
    assert parse_restart_policy(policy).should_restart(exit_code, streak) is restart


def test_restart_policy_text_round_trips() -> None:
    for text in ("no", "always", "on-failure", "on-failure:5", "unless-stopped"):
        assert str(parse_restart_policy(text)) == text
    assert parse_restart_policy(False) == RestartPolicy("no")
    for bad in ("yes", "on-failure:", "on-failure:-1", "always:2", 3, None):
        with pytest.raises(ValueError):
            parse_restart_policy(bad)


def test_backoff_doubles_up_to_its_cap() -> None:
    backoff = Backoff(initial_s=0.5, max_s=10.0)
    assert [backoff.delay_s(n) for n in range(7)] == [0.5, 1.0, 2.0, 4.0, 8.0, 10.0, 10.0]
    assert backoff.delay_s(10_000) == 10.0


def test_a_healthy_run_restarts_at_once_unless_it_restarted_lately() -> None:
    backoff = Backoff(initial_s=0.1, max_s=10.0, reset_after_s=10.0)
    assert backoff.restart_delay_s(0, run_was_healthy=True, since_last_restart_s=None) == 0.0
    assert backoff.restart_delay_s(0, run_was_healthy=True, since_last_restart_s=12.0) == 0.0
    assert backoff.restart_delay_s(0, run_was_healthy=True, since_last_restart_s=3.0) == 0.1
    assert backoff.restart_delay_s(2, run_was_healthy=False, since_last_restart_s=None) == 0.4


def test_dependency_order_puts_dependencies_first_and_keeps_file_order() -> None:
    deps = {"viz": ["router"], "planner": ["map", "router"], "map": [], "router": [], "docking": ["planner"]}
    order = dependency_order(deps)
    assert order == ["map", "router", "viz", "planner", "docking"]
    for name, needs in deps.items():
        assert all(order.index(need) < order.index(name) for need in needs)


def test_cycles_are_found_and_refused() -> None:
    deps = {"a": ["b"], "b": ["c"], "c": ["a"], "d": []}
    assert find_cycle(deps) == ["a", "b", "c", "a"]
    assert find_cycle({"a": ["b"], "b": []}) is None
    with pytest.raises(ValueError, match="dependency cycle: a -> b -> c -> a"):
        dependency_order(deps)


def test_selection_pulls_in_dependencies_transitively() -> None:
    deps = {"docking": ["planner"], "planner": ["map", "router"], "map": [], "router": [], "viz": ["router"]}
    assert with_dependencies(["docking"], deps) == {"docking", "planner", "map", "router"}
    assert with_dependencies([], deps) == set()
