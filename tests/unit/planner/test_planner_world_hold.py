"""The planner's hold on the simulated world while it works with its robot standing."""

from __future__ import annotations

import pytest

from services.planner.world_hold import HOLDER, WorldHold
from shared.messages import PacingHold


def _hold() -> tuple[WorldHold, list[PacingHold]]:
    sent: list[PacingHold] = []
    return WorldHold(sent.append, enabled=True), sent


def test_one_hold_for_all_reasons_let_go_when_the_last_ends() -> None:
    hold, sent = _hold()
    hold.begin("plan", 3.0)
    hold.begin("clearing", 3.05)
    assert [(m.hold, m.header.stamp.to_sec()) for m in sent] == [(True, pytest.approx(3.0))]
    assert sent[0].holder == HOLDER and not sent[0].until_driven  # the planner drives next itself
    hold.end("plan", 3.1)
    assert len(sent) == 1  # the clearing still holds
    hold.end("clearing", 3.2)
    assert [m.hold for m in sent] == [True, False]
    assert hold.reasons == frozenset()


def test_ending_what_never_began_says_nothing() -> None:
    hold, sent = _hold()
    hold.end("plan", 1.0)
    hold.end_all(1.0)
    assert sent == []


def test_during_lets_go_even_when_the_work_fails() -> None:
    hold, sent = _hold()
    with pytest.raises(RuntimeError), hold.during("way through suspicion", 2.0):
        raise RuntimeError("the search failed")
    assert [m.hold for m in sent] == [True, False]


def test_the_end_of_a_goal_lets_go_of_everything() -> None:
    hold, sent = _hold()
    hold.begin("plan", 5.0)
    hold.begin("glass put back", 5.0)
    hold.end_all(5.5)
    assert [m.hold for m in sent] == [True, False]
    assert hold.reasons == frozenset()


def test_off_sim_time_nothing_is_held() -> None:
    sent: list[PacingHold] = []
    hold = WorldHold(sent.append, enabled=False)
    with hold.during("plan", 1.0):
        pass
    hold.begin("plan", 1.0)
    hold.end_all(1.0)
    assert sent == [] and hold.reasons == frozenset()
