"""Loss accounting from sequence numbers: exact streams, late joins, restarts, several publishers on a key."""

from __future__ import annotations

from deploy.recording.sequence import SequenceTracker


def feed_all(tracker: SequenceTracker, key: str, numbers: list[int], source: object | None = None) -> int:
    return sum(tracker.feed(key, n, source, now_s=i * 0.01) for i, n in enumerate(numbers))


def test_a_whole_stream_joined_late_loses_nothing() -> None:
    tracker = SequenceTracker()
    assert feed_all(tracker, "scan", list(range(40, 140))) == 0
    tally = tracker.keys["scan"]
    assert (tally.received, tally.lost, tally.gaps) == (100, 0, [])


def test_gaps_are_counted_and_named() -> None:
    tracker = SequenceTracker()
    numbers = [1, 2, 3, 7, 8, 10]
    assert feed_all(tracker, "tf", numbers) == 4
    assert tracker.keys["tf"].gaps == [(4, 6), (9, 9)]
    assert tracker.total_lost == 4


def test_a_restart_is_not_a_loss() -> None:
    tracker = SequenceTracker()
    assert feed_all(tracker, "odom", [50, 51, 52, 1, 2, 3]) == 0
    tally = tracker.keys["odom"]
    assert tally.received == 6 and tally.lost == 0


def test_losses_before_a_restart_are_kept() -> None:
    tracker = SequenceTracker()
    feed_all(tracker, "odom", [1, 2, 5, 1, 2])
    assert tracker.keys["odom"].lost == 2


def test_two_publishers_on_one_key_interleave_without_false_gaps() -> None:
    tracker = SequenceTracker(publishers_on=lambda key: 2 if key == "cmd_vel" else 1)
    numbers = []
    for i in range(20):
        numbers += [100 + i, 7 + i]  # the second publisher joined later: lower numbers
    assert feed_all(tracker, "cmd_vel", numbers) == 0
    assert len(tracker.keys["cmd_vel"].streams) == 2


def test_two_publishers_still_show_a_real_gap() -> None:
    tracker = SequenceTracker(publishers_on=lambda key: 2)
    feed_all(tracker, "cmd_vel", [100, 7, 101, 8, 103, 9])
    assert tracker.keys["cmd_vel"].gaps == [(102, 102)]


def test_known_sources_are_tracked_apart() -> None:
    tracker = SequenceTracker()
    tracker.feed("k", 5, source="a")
    tracker.feed("k", 5, source="b")
    tracker.feed("k", 6, source="a")
    assert tracker.feed("k", 9, source="b") == 3
    assert tracker.keys["k"].lost == 3


def test_unnumbered_samples_are_counted_not_judged() -> None:
    tracker = SequenceTracker()
    tracker.feed("raw", None)
    tracker.feed("raw", None)
    tally = tracker.keys["raw"]
    assert (tally.received, tally.unnumbered, tally.lost) == (2, 2, 0)


def test_a_repeated_number_is_a_duplicate() -> None:
    tracker = SequenceTracker()
    feed_all(tracker, "k", [3, 4, 4, 5])
    tally = tracker.keys["k"]
    assert tally.duplicates == 1 and tally.lost == 0


def test_named_and_unnamed_publishers_on_one_key_do_not_mix() -> None:
    tracker = SequenceTracker(publishers_on=lambda key: 2)
    for n in range(10, 20):
        tracker.feed("k", n, source="replay")
        tracker.feed("k", n - 9)  # an unnamed publisher whose numbers would continue the named one's
    assert tracker.keys["k"].lost == 0 and len(tracker.keys["k"].streams) == 2
