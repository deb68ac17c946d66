"""Dock reservations: one robot per dock, the nearest free dock, leases, and a queue served by need."""

from __future__ import annotations

import itertools
import random

import pytest

from services.fleet.dock_book import DockBook


def _book(**kwargs) -> DockBook:  # type: ignore[no-untyped-def]
    return DockBook(("a", "b"), **kwargs)


def test_the_named_dock_if_free_else_the_nearest_free_one() -> None:
    book = _book()
    assert book.request("r1", 0.2, 0.0, wanted="b").dock_id == "b"
    assert book.request("r2", 0.2, 0.0, wanted="b").dock_id == "a", "b is taken: the free one"
    book.release("r1")
    assert book.request("r3", 0.2, 1.0, path_lengths_m={"a": 9.0, "b": 4.0}).dock_id == "b"
    assert book.request("r3", 0.2, 2.0).reason == "already yours"
    assert book.request("r4", 0.2, 0.0, wanted="zz").reason.startswith("no dock 'zz'")


def test_nearest_by_planned_path_and_unreachable_docks_are_never_granted() -> None:
    book = _book()
    assert book.request("r1", 0.2, 0.0, path_lengths_m={"a": 7.5, "b": 3.0}).dock_id == "b"
    book.release("r1")
    assert book.request("r1", 0.2, 0.0, path_lengths_m={"a": 7.5, "b": float("inf")}).dock_id == "a"
    decision = _book().request("r9", 0.2, 0.0, path_lengths_m={})
    assert not decision.granted and decision.queue_position == 1


def test_when_every_dock_is_taken_the_queue_is_served_lowest_battery_first() -> None:
    book = _book()
    book.request("r1", 0.20, 0.0)
    book.request("r2", 0.20, 0.0)
    assert book.request("r3", 0.22, 1.0).queue_position == 1
    assert book.request("r4", 0.15, 2.0).queue_position == 1, "less charge: ahead of r3"
    assert [w.robot for w in book.queue_order()] == ["r4", "r3"]
    assert book.release("r1") == "a"
    assert not book.request("r3", 0.21, 3.0).granted, "r4 needs it more"
    assert book.request("r4", 0.14, 3.1).dock_id == "a"
    assert book.request("r3", 0.21, 3.2).queue_position == 1


def test_a_silent_robot_loses_its_dock_after_the_lease_and_one_heard_from_keeps_it() -> None:
    book = _book(lease_s=10.0)
    book.request("r1", 0.2, 0.0)
    book.request("r2", 0.2, 0.0)
    book.heard_from("r2", 8.0)
    assert book.expire(9.0) == []
    lapsed = book.expire(10.5)
    assert [c.robot for c in lapsed] == ["r1"] and book.holding("r1") is None
    assert book.holding("r2") == "b"
    assert book.expire(17.9) == [] and [c.robot for c in book.expire(18.5)] == ["r2"]


def test_a_critical_robot_asks_a_charged_one_to_leave() -> None:
    book = _book(critical_battery=0.1, charged_enough=0.6)
    book.request("r1", 0.2, 0.0)
    book.request("r2", 0.2, 0.0)
    book.request("r1", 0.9, 5.0)  # r1 charged on its dock
    book.request("r2", 0.4, 5.0)
    assert not book.request("r3", 0.08, 6.0).granted
    assert book.leave_requests == {"r1": "r3"}, "the most charged holder is asked"
    book.release("r1")
    assert book.request("r3", 0.07, 7.0).dock_id == "a"
    assert book.leave_requests == {}


@pytest.mark.parametrize("seed", range(20))
def test_no_dock_ever_has_two_robots_whatever_happens(seed: int) -> None:
    rng = random.Random(seed)
    book = DockBook(("a", "b", "c"), lease_s=3.0)
    robots = [f"r{i}" for i in range(6)]
    for step in itertools.count():
        if step == 400:
            break
        now = step * 0.1
        robot = rng.choice(robots)
        action = rng.random()
        if action < 0.5:
            lengths = {d: rng.uniform(1.0, 10.0) for d in ("a", "b", "c") if rng.random() < 0.8}
            book.request(
                robot, rng.uniform(0.0, 1.0), now, wanted=rng.choice([None, "a", "b"]), path_lengths_m=lengths
            )
        elif action < 0.7:
            book.release(robot)
        elif action < 0.9:
            book.heard_from(robot, now)
        else:
            book.expire(now)
        holders = [c.robot for c in book.claims.values()]
        assert len(holders) == len(set(holders)), "a robot holds two docks"
        assert all(c.dock_id == d for d, c in book.claims.items())
        assert not set(holders) & set(book.queue), "a robot both holds a dock and waits for one"


def test_a_bad_book_is_refused() -> None:
    with pytest.raises(ValueError, match="distinct"):
        DockBook(("a", "a"))
    with pytest.raises(ValueError, match="lease_s"):
        DockBook(("a",), lease_s=0.0)
    with pytest.raises(ValueError, match="critical_battery"):
        DockBook(("a",), critical_battery=0.7, charged_enough=0.6)
    with pytest.raises(ValueError, match="robot's name"):
        DockBook(("a",)).request("", 0.5, 0.0)


def test_queued_robots_each_get_a_holding_spot_of_their_own_while_any_is_free() -> None:
    book = DockBook(("a",), holding_spots=2)
    assert book.request("r1", 0.2, 0.0).granted
    spots = [book.request(r, 0.2, 0.0).holding_spot for r in ("r2", "r3", "r4")]
    assert spots == [0, 1, None], "two spots, the third robot waits where it stands"
    assert book.request("r2", 0.19, 1.0).holding_spot == 0, "asking again keeps the spot"
    book.release("r1")
    assert book.request("r2", 0.19, 2.0).granted
    assert book.request("r4", 0.2, 2.0).holding_spot == 0, "r2's spot is free again"


def test_a_silent_robot_leaves_the_queue_after_the_lease_and_no_longer_holds_up_the_living() -> None:
    book = DockBook(("a",), lease_s=10.0)
    book.request("r1", 0.2, 0.0)
    book.request("dead", 0.05, 0.0)
    book.request("r3", 0.2, 0.0)
    book.heard_from("r3", 9.0)
    book.release("r1")
    assert not book.request("r3", 0.2, 9.5).granted, "dead has less charge and is not yet expired"
    book.expire(10.5)
    assert [w.robot for w in book.queue_order()] == ["r3"]
    assert book.request("r3", 0.2, 10.6).dock_id == "a"
