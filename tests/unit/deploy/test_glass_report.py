"""The glass report: false marks and pane length found, against a world's panes."""

from __future__ import annotations

import math

import numpy as np

from deploy.glass_report import GLASS_MARK, glass_marks, glass_report, panes_heard
from shared.world import World, parse_world


def _world(glass: list) -> World:  # type: ignore[type-arg]
    return parse_world(
        {
            "name": "w",
            "bounds": [0.0, 0.0, 4.0, 3.0],
            "walls": [],
            "glass": glass,
            "boxes": [],
            "docks": [],
            "robot": {"start": [0.5, 0.5, 0.0]},
        }
    )


def test_marks_on_the_pane_are_true_and_marks_away_from_it_false() -> None:
    world = _world([[[1.0, 1.0], [3.0, 1.0]]])  # a pane along y = 1 from x = 1 to 3
    layer = np.full((60, 80), 255, dtype=np.uint8)  # 5 cm cells, origin (0, 0)
    layer[20, 20:40] = GLASS_MARK  # y = 1.025, x from 1.0 to 2.0: half the pane
    layer[30, 10] = GLASS_MARK  # (0.525, 1.525): false, 0.5 m from the pane
    report = glass_report(layer, 0.05, (0.0, 0.0), world)
    assert report.false_glass_cells == 1 and report.marked_cells == 21
    assert 0.45 <= report.glass_coverage <= 0.55


def test_a_world_without_glass_has_no_coverage_and_every_mark_is_false() -> None:
    layer = np.full((60, 80), 255, dtype=np.uint8)
    layer[5, 5] = GLASS_MARK
    report = glass_report(layer, 0.05, (0.0, 0.0), _world([]))
    assert report.false_glass_cells == 1 and math.isnan(report.glass_coverage)


def test_panes_heard_are_those_an_echo_came_from_and_found_are_those_marked() -> None:
    # Two panes along x = 2 and x = 3.5 (the second behind the first as seen from the left), one at y = 2.5.
    world = _world([[[2.0, 0.5], [2.0, 1.5]], [[3.5, 0.5], [3.5, 1.5]], [[1.0, 2.5], [3.0, 2.5]]])
    fov = 0.5
    echoes = [
        (1.0, 1.0, 0.0, 1.0, fov),  # the near pane, 1 m ahead: heard
        (1.0, 1.0, 0.0, 2.5, fov),  # a range the geometry does not give (the pane behind): not a pane's
        (2.0, 2.0, math.pi / 2, 0.5, fov),  # the pane along y = 2.5, 0.5 m ahead: heard
        (1.0, 1.0, math.pi, 1.0, fov),  # the boundary wall at x = 0: not a pane
    ]
    layer = np.full((60, 80), 255, dtype=np.uint8)
    layer[20, 40] = GLASS_MARK  # (2.025, 1.025): on the near pane
    report = glass_marks(layer, 0.05, (0.0, 0.0), world).report(echoes)
    assert (report.panes_heard, report.panes_found) == (2, 1)
    assert panes_heard(echoes, world) == {0, 2}
    assert panes_heard([], world) == set()
    assert panes_heard([(1.0, 1.0, 0.0, 1.0, 0.0), (1.0, 1.0, 0.0, 1.0, math.nan)], world) == set()
