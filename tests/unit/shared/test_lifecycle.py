"""Nav2's lifecycle as the stand-ins keep it: the transitions a node takes or refuses, and the order in
which a manager's commands move its nodes."""

from __future__ import annotations

import pytest

from shared.lifecycle import Command, NodeLifecycle, State, Transition, managed_state, plan

NODES = ["controller_server", "planner_server", "bt_navigator"]


def test_a_stand_in_starts_active_and_pauses_and_resumes() -> None:
    node = NodeLifecycle("bt_navigator")
    assert node.active
    assert node.change(Transition.DEACTIVATE) is None and node.state == State.INACTIVE
    assert node.change(Transition.ACTIVATE) is None and node.active


def test_a_transition_from_the_wrong_state_is_refused_with_the_states_named() -> None:
    node = NodeLifecycle("amcl")
    refused = node.change(Transition.CONFIGURE)
    assert refused == "amcl: cannot configure from active (it starts from unconfigured)"
    assert node.active  # nothing changed
    assert "no transition 99" in (node.change(99) or "")


def test_a_finalized_node_takes_no_transition() -> None:
    node = NodeLifecycle("amcl")
    assert node.change(Transition.ACTIVE_SHUTDOWN) is None and node.state == State.FINALIZED
    assert all(node.change(t) is not None for t in Transition)


def test_startup_configures_then_activates_in_order_and_pause_goes_in_reverse() -> None:
    assert plan(Command.STARTUP, NODES) == [
        *((n, Transition.CONFIGURE, True) for n in NODES),
        *((n, Transition.ACTIVATE, True) for n in NODES),
    ]
    assert [n for n, _t, _s in plan(Command.PAUSE, NODES)] == list(reversed(NODES))


def test_shutdown_carries_on_past_refusals_to_finalized() -> None:
    steps = plan(Command.SHUTDOWN, NODES)
    assert [t for _n, t, _s in steps] == [Transition.DEACTIVATE] * 3 + [Transition.CLEANUP] * 3 + [
        Transition.UNCONFIGURED_SHUTDOWN
    ] * 3
    assert not any(stop for _n, _t, stop in steps)
    nodes = {n: NodeLifecycle(n) for n in NODES}
    nodes["planner_server"].change(Transition.DEACTIVATE)  # already paused: its deactivate is refused
    for name, transition, _stop in steps:
        nodes[name].change(transition)
    assert {n.state for n in nodes.values()} == {State.FINALIZED}


def test_each_command_leaves_the_managers_view_as_nav2s() -> None:
    assert managed_state(Command.PAUSE, True) == State.INACTIVE
    assert managed_state(Command.RESUME, True) == State.ACTIVE
    assert managed_state(Command.RESET, True) == State.UNCONFIGURED
    assert managed_state(Command.STARTUP, False) == State.UNKNOWN
    assert managed_state(Command.SHUTDOWN, False) == State.FINALIZED


def test_an_unknown_command_names_the_known_ones() -> None:
    with pytest.raises(ValueError, match="no lifecycle command 9 .*STARTUP 0.*CLEANUP 6"):
        plan(9, NODES)
