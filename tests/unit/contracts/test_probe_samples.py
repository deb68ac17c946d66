"""The conform kit's tally of one key: the most events in any one second."""

from __future__ import annotations

from deploy.contracts.probe import Samples


def test_the_peak_counts_events_in_any_one_second_whatever_order_they_came_in() -> None:
    # stamped times: a burst delivered together after the world was held still lies where it was stamped
    samples = Samples("k", times=[0.0, 0.5, 0.3, 1.2, 1.1, 2.5])
    assert samples.peak_per_s() == 4  # 0.3, 0.5, 1.1 and 1.2 lie within one second
    assert Samples("k", times=[1.0] * 5).peak_per_s() == 5  # five with the same stamp: a burst
    assert Samples("k").peak_per_s() == 0
