"""The glass report: false marks and pane length found, against a world's panes."""

from __future__ import annotations

import math

import numpy as np

from deploy.glass_report import GLASS_MARK, glass_report
from shared.world import World


def _world(glass: list) -> World:  # type: ignore[type-arg]
    return World.model_validate(
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
