"""Traffic between robots: priority, meeting head-on, the passing place, and giving way."""

from __future__ import annotations

import math

import numpy as np
import pytest

from services.docking.task_io import STOP, Navigate, NavOutcome, NavStatus, Outcome, TickInputs
from services.docking.traffic import (
    CLEAR_OF_WAY_M,
    STILL_GIVING_WAY_S,
    STILL_PRIORITY_S,
    GiveWay,
    Meeting,
    Peer,
    has_priority,
    must_give_way,
    passing_place,
    peer_way,
    way_ahead,
)
from shared.geometry import Pose2D

# A corridor 0.8 m wide from x=2 to x=8 (y 2.6 .. 3.4) between two open rooms of a 10 x 6 m hall.
CORRIDOR = [
    ((2.0, 2.6), (8.0, 2.6)),
    ((2.0, 3.4), (8.0, 3.4)),
    ((2.0, 0.0), (2.0, 2.6)),
    ((2.0, 3.4), (2.0, 6.0)),
    ((8.0, 0.0), (8.0, 2.6)),
    ((8.0, 3.4), (8.0, 6.0)),
]
HALL = [
    ((0.0, 0.0), (10.0, 0.0)),
    ((10.0, 0.0), (10.0, 6.0)),
    ((10.0, 6.0), (0.0, 6.0)),
    ((0.0, 6.0), (0.0, 0.0)),
]


def test_priority_goes_to_less_charge_then_to_the_name_first() -> None:
    assert has_priority("r2", 0.3, "r1", 0.6)
    assert not has_priority("r2", 0.6, "r1", 0.3)
    assert has_priority("r1", 0.5, "r2", 0.5) and not has_priority("r2", 0.5, "r1", 0.5)


WALLS = CORRIDOR + HALL


def test_head_on_in_a_corridor_one_gives_way_and_the_other_waits_for_the_way_to_clear() -> None:
    r1 = Pose2D(3.5, 3.0, 0.0)
    r2 = Pose2D(6.0, 3.0, math.pi)
    met = must_give_way(r1, "r1", 0.8, [Peer("r2", r2, 0.4, True)], WALLS)
    assert met is not None and met[1] is Meeting.HEAD_ON, "r2 has less charge: r1 gives way"
    met = must_give_way(r2, "r2", 0.4, [Peer("r1", r1, 0.8, True)], WALLS)
    assert met is not None and met[1] is Meeting.HEAD_ON_PRIORITY, "r2 waits for r1 to back out"
    assert must_give_way(r1, "r1", 0.8, [Peer("r2", r2, 0.4, False)], WALLS) is None, (
        "a parked robot is not met"
    )
    following = Pose2D(6.0, 3.0, 0.0)  # going the same way, ahead of r1
    assert must_give_way(r1, "r1", 0.8, [Peer("r2", following, 0.4, True)], WALLS) is None
    far = Peer("r2", Pose2D(7.5, 3.0, math.pi), 0.4, True)
    assert must_give_way(r1, "r1", 0.8, [far], WALLS) is None, "too far"


def test_head_on_in_open_space_is_left_to_the_planners() -> None:
    r1 = Pose2D(3.0, 3.0, 0.0)
    r2 = Pose2D(5.0, 3.0, math.pi)
    assert must_give_way(r1, "r1", 0.8, [Peer("r2", r2, 0.4, True)], HALL) is None


def test_the_priority_robot_waits_only_while_the_other_is_on_its_way() -> None:
    me = Pose2D(4.5, 3.0, math.pi)
    at_passing_place = Peer("r1", Pose2D(2.5, 4.0, 0.0), 0.8, False, giving_way=True)
    assert must_give_way(me, "r2", 0.4, [at_passing_place], WALLS) is None, "off its way: no new wait"
    task = GiveWay(Peer("r1", Pose2D(3.3, 3.0, 0.0), 0.8, True), Meeting.HEAD_ON_PRIORITY, None, resume=None)
    assert task.step(_inputs(0.0, me)) == STOP and task.result is None
    assert task.holding == "waiting for r1 to back out of the way"
    task.peer_seen(at_passing_place.pose)
    task.step(_inputs(0.5, me))
    assert task.result is None, "held at least a second, however clear the way looks"
    task.step(_inputs(4.0, me))
    assert task.result is not None and task.result.outcome is Outcome.SUCCEEDED


def test_the_way_ahead_is_the_plan_from_the_robot_on_or_else_the_line_it_heads_along() -> None:
    plan = np.column_stack([np.arange(0.0, 10.01, 0.05), np.zeros(201)])
    way = way_ahead(Pose2D(2.0, 0.1, 0.0), plan)
    np.testing.assert_allclose(way[0], [2.0, 0.1])
    np.testing.assert_allclose(way[1], [2.0, 0.0])
    assert way[-1][0] == pytest.approx(5.5) and np.all(way[1:, 1] == 0.0)  # the next 3.5 m of the plan
    heading_line = way_ahead(Pose2D(2.0, 1.0, math.pi / 2), None)
    np.testing.assert_allclose(heading_line[[0, -1]], [[2.0, 1.0], [2.0, 4.5]], atol=1e-12)
    np.testing.assert_allclose(
        way_ahead(Pose2D(2.0, 1.0, math.pi / 2), plan), heading_line
    )  # not on this plan


def test_the_priority_robot_does_not_wait_for_one_beyond_the_end_of_its_plan() -> None:
    """A robot with priority going to a waypoint met the one that gave way to it again where it waited,
    beside the waypoint: on the line the first heads along, off the way it drives. Each waited for the
    other until one had stood still long enough."""
    me = Pose2D(5.0, 3.0, math.pi)
    beyond_the_end = Peer("r1", Pose2D(3.0, 3.0, 0.0), 0.8, False, giving_way=True)
    plan = np.column_stack([np.arange(5.0, 3.99, -0.05), np.full(21, 3.0)])  # ends at (4.0, 3.0)
    met = must_give_way(me, "r2", 0.4, [beyond_the_end], WALLS)
    assert met is not None and met[1] is Meeting.HEAD_ON_PRIORITY, "on the line it heads along"
    assert must_give_way(me, "r2", 0.4, [beyond_the_end], WALLS, own_plan=plan) is None
    assert must_give_way(me, "r2", 0.4, [beyond_the_end], WALLS, own_plan=lambda: plan) is None
    on_the_way = Peer("r1", Pose2D(4.2, 3.0, 0.0), 0.8, True)
    met = must_give_way(me, "r2", 0.4, [on_the_way], WALLS, own_plan=plan)
    assert met is not None and met[1] is Meeting.HEAD_ON_PRIORITY, "standing on the plan: wait for it"
    # A wait that began on the plan ends once the other is off it, though still on the line ahead.
    task = GiveWay(on_the_way, Meeting.HEAD_ON_PRIORITY, None, resume=None, own_way=way_ahead(me, plan))
    task.step(_inputs(0.0, me))
    task.peer_seen(beyond_the_end.pose)
    task.step(_inputs(1.5, me))
    assert task.result is not None and task.result.outcome is Outcome.SUCCEEDED
    by_the_line = GiveWay(on_the_way, Meeting.HEAD_ON_PRIORITY, None, resume=None)
    by_the_line.step(_inputs(0.0, me))
    by_the_line.peer_seen(beyond_the_end.pose)
    by_the_line.step(_inputs(1.5, me))
    assert by_the_line.result is None, "by the line it heads along the other is still in the way"


def test_a_robot_crossing_in_front_makes_the_one_without_priority_stop() -> None:
    me = Pose2D(5.0, 1.0, 0.0)
    crossing = Peer("r2", Pose2D(5.8, 1.6, -math.pi / 2), 0.4, True)  # in front, left, heading across
    met = must_give_way(me, "r1", 0.8, [crossing], HALL)
    assert met is not None and met[1] is Meeting.CROSSING
    assert must_give_way(me, "r1", 0.3, [crossing], HALL) is None, "with priority it carries on"
    behind = Peer("r2", Pose2D(4.5, 1.3, 0.0), 0.4, True)
    assert must_give_way(me, "r1", 0.8, [behind], HALL) is None


def test_a_robot_too_close_in_front_stops_even_the_one_with_priority_for_a_moment() -> None:
    me = Pose2D(5.0, 1.0, 0.0)
    close = Peer("r2", Pose2D(5.6, 1.2, math.pi / 2), 0.9, True)  # r1 has priority (less charge)
    met = must_give_way(me, "r1", 0.3, [close], HALL)
    assert met is not None and met[1] is Meeting.TOO_CLOSE
    assert must_give_way(me, "r1", 0.3, [close], HALL, calm={"r2"}) is None, "stopped for it lately"
    task = GiveWay(close, Meeting.TOO_CLOSE, None, resume=None)
    task.step(_inputs(0.0, me))
    task.step(_inputs(1.0, me))
    assert task.result is None and task.holding == "r2 is too close in front"
    task.step(_inputs(1.6, me))
    assert task.result is not None and task.result.outcome is Outcome.SUCCEEDED


def test_stopping_for_a_crossing_robot_lasts_until_it_is_out_of_the_way() -> None:
    me = Pose2D(0.0, 0.0, 0.0)
    task = GiveWay(Peer("r2", Pose2D(0.5, 0.4, -math.pi / 2), 0.2, True), Meeting.CROSSING, None, resume=None)
    assert task.step(_inputs(0.0, me)) == STOP and task.result is None, "the first tick knows where r2 is"
    task.peer_seen(Pose2D(0.5, -0.2, -math.pi / 2))
    assert task.step(_inputs(1.0, me)) == STOP and task.result is None, "still in front"
    task.peer_seen(Pose2D(0.5, -1.5, -math.pi / 2))
    task.step(_inputs(2.0, me))
    assert task.result is not None and task.result.outcome is Outcome.SUCCEEDED


def test_the_passing_place_is_off_the_corridor_behind_the_robot_that_gives_way() -> None:
    me = Pose2D(3.0, 3.0, 0.0)  # in the corridor heading east
    peer = Peer("r2", Pose2D(4.2, 3.0, math.pi), 0.2, True)
    place = passing_place(me, peer, CORRIDOR + HALL)
    assert place is not None
    assert place.x < 2.0 - 0.25, f"back out of the corridor's west end: {place}"
    way = peer_way(peer)[0]
    assert min(math.dist((place.x, place.y), p) for p in way) >= CLEAR_OF_WAY_M - 1e-9


def test_the_passing_place_follows_the_other_robots_plan_when_it_has_one() -> None:
    me = Pose2D(3.0, 3.0, 0.0)
    plan = np.array([[4.0, 3.0], [1.5, 3.0], [1.0, 1.0], [1.0, 0.5]])  # r2 turns south after the corridor
    peer = Peer("r2", Pose2D(4.2, 3.0, math.pi), 0.2, True, plan)
    place = passing_place(me, peer, CORRIDOR + HALL)
    assert place is not None and place.x < 1.8 and place.y > 3.5, f"north of the corridor's mouth: {place}"


def test_no_passing_place_in_a_dead_end() -> None:
    dead_end = [((0.0, 2.6), (6.0, 2.6)), ((0.0, 3.4), (6.0, 3.4)), ((0.0, 2.6), (0.0, 3.4))]
    me = Pose2D(1.0, 3.0, 0.0)
    assert passing_place(me, Peer("r2", Pose2D(2.0, 3.0, math.pi), 0.1, True), dead_end) is None


def _inputs(now: float, me: Pose2D | None, nav: NavStatus | None = None) -> TickInputs:
    return TickInputs(now_s=now, robot_pose=me, nav=nav or NavStatus())


def test_give_way_goes_to_the_place_waits_for_the_other_to_pass_then_ends() -> None:
    place = Pose2D(1.2, 4.0, 0.0)
    task = GiveWay(Peer("r2", Pose2D(4.0, 3.0, math.pi), 0.2, True), Meeting.HEAD_ON, place, resume=None)
    intent = task.step(_inputs(0.0, Pose2D(3.0, 3.0, 0.0)))
    assert isinstance(intent, Navigate) and intent.pose == place
    assert task.step(_inputs(5.0, place, NavStatus(intent.key, outcome=NavOutcome.SUCCEEDED))) == STOP
    task.peer_seen(Pose2D(2.2, 3.0, math.pi))  # coming through, close, heading at the place's side
    assert task.step(_inputs(6.0, place, NavStatus(intent.key, outcome=NavOutcome.SUCCEEDED))) == STOP
    assert task.result is None and task.holding == "giving way to r2"
    task.peer_seen(Pose2D(0.8, 2.0, -math.pi / 2))  # gone by: the place is behind it
    task.step(_inputs(8.0, None, NavStatus(intent.key, outcome=NavOutcome.SUCCEEDED)))
    assert task.result is None, "its own pose stale: it waits"
    task.step(_inputs(8.1, place, NavStatus(intent.key, outcome=NavOutcome.SUCCEEDED)))
    assert task.result is not None and task.result.outcome is Outcome.SUCCEEDED
    assert task.message == "r2 has gone by"


def test_give_way_ends_on_a_blocked_way_to_the_passing_place_when_the_other_has_gone_elsewhere() -> None:
    place = Pose2D(1.2, 4.0, 0.0)
    task = GiveWay(Peer("r2", Pose2D(4.0, 3.0, math.pi), 0.2, True), Meeting.HEAD_ON, place, resume=None)
    me = Pose2D(3.0, 3.0, 0.0)
    intent = task.step(_inputs(0.0, me))
    assert isinstance(intent, Navigate)
    running = NavStatus(intent.key, busy=True)  # the way to the place is blocked: the planner keeps trying
    task.peer_seen(Pose2D(7.5, 3.0, 0.0))  # 4.5 m off, driving away
    assert task.step(_inputs(5.0, me, running)) == intent, "a robot that passes by may turn back: not yet"
    task.peer_seen(Pose2D(4.5, 3.0, 0.0))  # back within 4 m
    assert task.step(_inputs(STILL_GIVING_WAY_S + 1.0, me, running)) == intent and task.result is None
    task.peer_seen(Pose2D(7.5, 3.0, 0.0))
    task.step(_inputs(STILL_GIVING_WAY_S + 2.0, me, running))
    assert task.result is not None and task.result.outcome is Outcome.SUCCEEDED
    assert task.message == "r2 went its way before the passing place"
    assert task.unresolved, "the way did not clear as meant: not stopped for r2 again for a while"


def test_give_way_ends_on_the_way_to_the_passing_place_once_the_other_has_driven_past() -> None:
    place = Pose2D(1.2, 4.0, 0.0)
    task = GiveWay(Peer("r2", Pose2D(4.0, 3.0, math.pi), 0.2, True), Meeting.HEAD_ON, place, resume=None)
    intent = task.step(_inputs(0.0, Pose2D(3.0, 3.0, 0.0)))
    me = Pose2D(2.5, 3.6, 2.0)  # backing out towards the place, not there yet
    running = NavStatus(intent.key, busy=True)
    task.peer_seen(Pose2D(2.9, 3.0, math.pi))  # coming through, beside this robot, not past it
    assert task.step(_inputs(3.0, me, running)) == intent and task.result is None
    task.peer_seen(Pose2D(1.6, 3.0, math.pi))  # past it: this robot is behind, on the side it came from
    task.step(_inputs(4.0, me, running))
    assert task.result is not None and task.result.outcome is Outcome.SUCCEEDED
    assert task.message == "r2 drove past before the passing place" and not task.unresolved


def test_give_way_on_a_blocked_way_to_the_passing_place_waits_for_its_own_pose() -> None:
    place = Pose2D(1.2, 4.0, 0.0)
    task = GiveWay(Peer("r2", Pose2D(9.0, 3.0, math.pi), 0.2, True), Meeting.HEAD_ON, place, resume=None)
    intent = task.step(_inputs(0.0, Pose2D(3.0, 3.0, 0.0)))
    running = NavStatus(intent.key, busy=True)
    assert task.step(_inputs(STILL_GIVING_WAY_S + 1.0, None, running)) == intent, (
        "its own pose stale: it keeps going"
    )
    task.step(_inputs(STILL_GIVING_WAY_S + 1.1, Pose2D(3.0, 3.0, 0.0), running))
    assert task.result is not None


def test_give_way_ends_when_the_other_robot_stops_driving() -> None:
    task = GiveWay(
        Peer("r2", Pose2D(2.0, 0.0, math.pi), 0.2, True), Meeting.HEAD_ON_PRIORITY, None, resume=None
    )
    me = Pose2D(0.0, 0.0, 0.0)
    task.step(_inputs(0.0, me))
    assert task.result is None
    task.peer_seen(Pose2D(2.0, 0.0, math.pi), active=False)  # it docked, or parked to wait for a dock
    task.step(_inputs(1.5, me))
    assert task.result is not None and task.result.outcome is Outcome.SUCCEEDED


def test_give_way_does_not_wait_for_ever() -> None:
    task = GiveWay(
        Peer("r2", Pose2D(1.5, 1.0, math.pi), 0.2, True), Meeting.HEAD_ON, Pose2D(1.0, 1.0, 0.0), resume=None
    )
    first = task.step(_inputs(0.0, Pose2D(1.0, 1.0, 0.0)))
    assert isinstance(first, Navigate)
    task.step(_inputs(1.0, Pose2D(1.0, 1.0, 0.0), NavStatus(first.key, outcome=NavOutcome.SUCCEEDED)))
    assert task.result is None
    task.step(_inputs(61.0, Pose2D(1.0, 1.0, 0.0), NavStatus(first.key, outcome=NavOutcome.SUCCEEDED)))
    assert task.result is not None and task.result.outcome is Outcome.SUCCEEDED


def test_two_robots_waiting_on_each_other_the_one_with_priority_carries_on_first() -> None:
    # Seen in a fleet run in the yard: r2 waited at its passing place, chosen off r3's plan, for r3 to go
    # by; r3 had turned meanwhile and found r2 on the line it headed along, so it waited for r2 to back out,
    # and both stood until r3's wait ran out (30 s).
    r3, r2 = Pose2D(1.82, 2.43, 0.72), Pose2D(4.37, 4.91, -3.12)
    waiting = GiveWay(
        Peer("r2", r2, 0.9, False, giving_way=True), Meeting.HEAD_ON_PRIORITY, None, resume=None
    )
    giving = GiveWay(Peer("r3", r3, 0.4, True), Meeting.HEAD_ON, r2, resume=None)
    going = giving.step(_inputs(0.0, r2))
    assert isinstance(going, Navigate)
    arrived = NavStatus(going.key, outcome=NavOutcome.SUCCEEDED)
    t = 0.0
    while waiting.result is None and t < STILL_PRIORITY_S + 1.0:
        waiting.peer_seen(r2, giving_way=True)
        giving.peer_seen(r3, giving_way=True)  # waiting for r2 to back out: giving way itself
        waiting.step(_inputs(t, r3))
        giving.step(_inputs(t, r2, arrived))
        t += 0.1
    assert waiting.result is not None and waiting.result.outcome is Outcome.SUCCEEDED
    assert waiting.unresolved and waiting.message.startswith("r2 stood still"), waiting.message
    assert t == pytest.approx(STILL_PRIORITY_S, abs=0.3)
    assert giving.result is None, "the one giving way waits longer than the one with priority"
    assert (
        must_give_way(r3, "r3", 0.4, [Peer("r2", r2, 0.9, False, giving_way=True)], [], carry_on={"r2"})
        is None
    )


def test_a_robot_that_stops_giving_way_but_stands_still_is_waited_for_as_one_stuck_from_then_on() -> None:
    # The robot with priority carries on after its own wait (6 s) but stays where it is a moment: the one
    # giving way to it still waits as for a robot giving way, so the one with priority moves first.
    place = Pose2D(1.2, 4.0, 0.0)
    other = Pose2D(4.0, 3.0, math.pi)
    task = GiveWay(Peer("r2", other, 0.2, True), Meeting.HEAD_ON, place, resume=None)
    going = task.step(_inputs(0.0, Pose2D(3.0, 3.0, 0.0)))
    arrived = NavStatus(going.key, outcome=NavOutcome.SUCCEEDED)
    t = 0.0
    while task.result is None and t < 30.0:
        task.peer_seen(other, giving_way=t < STILL_PRIORITY_S)
        task.step(_inputs(t, place, arrived))
        t += 0.1
    assert task.result is not None and task.unresolved
    assert t == pytest.approx(2 * STILL_PRIORITY_S, abs=0.3), "6 s after it stopped giving way, not at once"


def test_a_robot_stopped_for_a_crossing_carries_on_when_the_other_stands_still_but_not_while_it_moves() -> (
    None
):
    me = Pose2D(5.0, 5.0, 0.0)
    stuck = Pose2D(6.0, 5.2, math.pi / 2)  # in front, crossing, with priority; held up (by this robot, say)
    for waits, patience in ((False, STILL_PRIORITY_S), (True, STILL_GIVING_WAY_S)):
        task = GiveWay(Peer("r1", stuck, 0.2, True), Meeting.CROSSING, None, resume=None)
        t = 0.0
        while t < 30.0 and task.result is None:
            # Backing up and replanning, it stays within a few centimetres of one spot; or it waits, giving
            # way to a third robot.
            task.peer_seen(Pose2D(stuck.x, stuck.y - 0.2 * math.sin(t), stuck.yaw), giving_way=waits)
            task.step(_inputs(t, me))
            t += 0.1
        assert task.result is not None and task.unresolved, "waited out its time limit (60 s) instead"
        assert t == pytest.approx(patience, abs=0.3), f"giving way itself: {waits}"
    moving = GiveWay(Peer("r1", stuck, 0.2, True), Meeting.CROSSING, None, resume=None)
    for i in range(int(STILL_GIVING_WAY_S * 20)):  # manoeuvring to and fro across the way in front
        # (1.2 m each way in 2.5 s, about 0.5 m/s: a robot driving, not one rocking on the spot)
        moving.peer_seen(Pose2D(6.0, 5.0 + 0.6 * math.cos(0.125 * i), math.pi / 2))
        moving.step(_inputs(i * 0.1, me))
    assert moving.result is None, "a robot that moves is waited for"
