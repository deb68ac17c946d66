"""A marked pane is carried on along its own line through floor the sonar never looked at, and no further."""

from __future__ import annotations

import math

import numpy as np
import pytest

from services.planner.costmap import LETHAL_OBSTACLE, CostmapParams
from services.planner.glass_memory import HEARD_LINE_EXTENSION_M, GlassMemory
from services.planner.grid_frame import GridFrame
from services.planner.pane_extension import pane_extensions, pane_runs
from services.planner.rasterize import map_from_world
from shared.world import parse_world

RES = 0.05


def _pane(shape: tuple[int, int] = (40, 80), row: int = 20, cols: range = range(10, 30)) -> np.ndarray:
    marks = np.zeros(shape, dtype=bool)
    marks[row, cols.start : cols.stop] = True
    marks[row + 1, cols.start + 3 : cols.start + 6] = True  # a pane's marks are a band, not a line
    return marks


def test_a_pane_goes_on_along_its_line_for_the_extension_past_both_ends() -> None:
    marks = _pane()
    extended = pane_extensions(marks, np.zeros_like(marks), RES, extension_m=0.5)
    columns = np.nonzero(extended.any(axis=0))[0]
    assert set(range(30, 40)) <= set(columns.tolist())  # 0.5 m = 10 cells past the right end ...
    assert set(range(0, 10)) <= set(columns.tolist())  # ... and past the left end
    assert not extended[:, 41:].any()  # no further
    assert not extended[marks].any()  # the marks stay marks
    rows = np.nonzero(extended.any(axis=1))[0]
    assert set(rows.tolist()) <= {20, 21}  # along the pane's own line, not sideways


def test_the_extension_stops_at_floor_the_sonar_looked_at_and_at_walls() -> None:
    marks = _pane()
    looked_at = np.zeros_like(marks)
    looked_at[:, 34] = True  # the sonar looked here and heard nothing: the pane ended before
    walls = np.zeros_like(marks)
    walls[:, 5] = True
    extended = pane_extensions(marks, looked_at, RES, extension_m=1.0, blocked=walls)
    columns = set(np.nonzero(extended.any(axis=0))[0].tolist())
    assert columns == set(range(30, 34)) | set(range(6, 10))


def test_spots_and_short_runs_are_not_extended_and_a_blob_only_along_its_long_side() -> None:
    spot = np.zeros((40, 80), dtype=bool)
    spot[20, 20:28] = True  # 0.4 m: no direction to speak of
    assert not pane_extensions(spot, np.zeros_like(spot), RES, extension_m=1.0).any()
    assert not pane_extensions(_pane(), np.zeros((40, 80), dtype=bool), RES, extension_m=0.0).any()


def test_false_glass_beside_a_pane_does_not_tilt_its_line() -> None:
    marks = _pane(cols=range(10, 40))
    marks[21:26, 36:40] = True  # a clump of false glass in front of the pane's end, as the sonar leaves them
    runs = pane_runs(marks, RES)
    assert runs, "the pane is found"
    _, direction, _ = runs[0]
    assert abs(direction[1]) < 0.05, f"the pane's line is tilted: {direction}"
    extended = pane_extensions(marks, np.zeros_like(marks), RES, extension_m=0.5)
    assert not extended[24:, :].any(), "the extension cuts across the floor in front of the pane"


def test_a_diagonal_pane_keeps_its_angle_and_collinear_runs_are_each_a_pane() -> None:
    marks = np.zeros((60, 60), dtype=bool)
    for i in range(10, 25):
        marks[i, i] = True  # a 45 degree pane: its cells touch only at corners
        marks[i, i + 1] = True
    extended = pane_extensions(marks, np.zeros_like(marks), RES, extension_m=0.4)
    assert extended[30, 30] and extended[5, 5] and not extended[40, 40]
    two = np.zeros((20, 100), dtype=bool)
    two[10, 5:20] = True
    two[10, 60:75] = True  # the same line 2 m on: two panes, four ends
    assert len(pane_runs(two, RES)) == 4


def _hear_a_pane_along_y_1(memory: GlassMemory) -> None:
    """Facing +y from x = 0.6 .. 1.4, three pings each: a pane along y = 1.0, marked from x 0.4 to 1.6."""
    for x in (0.6, 0.8, 1.0, 1.2, 1.4):
        for _ in range(3):
            memory.add_reading((x, 0.4, math.pi / 2), 0.6, 0.5, 0.02, 3.0)


def test_glass_memory_counts_a_marked_panes_unseen_continuation_as_glass() -> None:
    frame = GridFrame(RES, (0.0, 0.0, 0.0), 80, 40)
    memory = GlassMemory(frame, CostmapParams(), suspicion_radius_m=0.0, pane_extension_m=0.5)
    _hear_a_pane_along_y_1(memory)
    ix, iy = frame.world_to_cell(1.8, 1.0)
    assert memory.glass_mask()[iy, ix], "the pane goes on past its last mark"
    assert not (memory.sonar_layer == 254)[iy, ix], "... but that is not what the sonar marked"
    memory.add_reading((1.8, 0.4, math.pi / 2), math.inf, 0.5, 0.02, 3.0)  # the sonar looks: nothing there
    assert not memory.glass_mask()[iy, ix]
    off = GlassMemory(frame, CostmapParams(), suspicion_radius_m=0.0)
    with pytest.raises(ValueError, match="pane_extension_m"):
        GlassMemory(frame, CostmapParams(), pane_extension_m=-1.0)
    assert off.pane_extension_m == 0.0


def test_an_extension_leaves_the_robot_a_way_between_the_pane_and_a_wall() -> None:
    frame = GridFrame(RES, (0.0, 0.0, 0.0), 80, 40)
    memory = GlassMemory(frame, CostmapParams(), suspicion_radius_m=0.0, pane_extension_m=2.0)
    _hear_a_pane_along_y_1(memory)
    walls = np.zeros(frame.shape, dtype=bool)
    walls[:, 70] = True  # a wall across the pane's line at x = 3.5
    memory.set_walls(walls)
    glass = memory.glass_mask()
    row = frame.world_to_cell(0.0, 1.0)[1]
    assert glass[row, frame.world_to_cell(2.5, 1.0)[0]]  # the pane goes on ...
    gap = 2.0 * CostmapParams().circumscribed_radius_m
    assert not glass[:, frame.world_to_cell(3.5 - gap, 1.0)[0] :].any()  # ... but leaves a way past its end
    with pytest.raises(ValueError, match="walls"):
        memory.set_walls(np.zeros((3, 3), dtype=bool))


def test_a_pane_does_not_extend_back_into_floor_a_recovery_cleared() -> None:
    frame = GridFrame(RES, (0.0, 0.0, 0.0), 80, 40)
    memory = GlassMemory(frame, CostmapParams(), suspicion_radius_m=0.0, pane_extension_m=1.0)
    _hear_a_pane_along_y_1(memory)
    ix, iy = frame.world_to_cell(2.1, 1.0)
    assert memory.glass_mask()[iy, ix]
    memory.clear_around((2.3, 1.0), 0.4)  # a recovery beside the pane's end forgets the glass round the robot
    assert not memory.glass_mask()[iy, ix], "the extension came back into the floor the recovery cleared"
    assert memory.glass_mask()[frame.world_to_cell(1.0, 1.0)[1], frame.world_to_cell(1.0, 1.0)[0]]
    memory.clear()
    assert not memory.glass_mask().any()


def test_two_panes_extensions_leave_the_gap_between_their_ends_open() -> None:
    marks = np.zeros((60, 80), dtype=bool)
    for i in range(20):
        marks[10 + i, 20 + i] = marks[10 + i, 21 + i] = True  # a pane up to (41, 30), at 45 degrees
    marks[52, 30:60] = True  # another, across its line 1 m on: the gap between them is a robot's way
    clearance = 0.6
    extended = pane_extensions(marks, np.zeros_like(marks), RES, extension_m=1.5, clearance_m=clearance)
    iy, ix = np.nonzero(extended)
    others = np.nonzero(marks[52])[0]
    for x, y in zip(ix.tolist(), iy.tolist(), strict=True):
        if x >= 30 and y < 50:  # the diagonal pane's extension, heading for the other pane
            nearest = min(math.hypot(x - o, y - 52) for o in others.tolist())
            assert nearest * RES >= clearance - RES, (x, y)
    assert extended[32, 43], "the diagonal pane still goes on, short of the other"


def _hall_frame() -> GridFrame:
    """The grid of an empty 8 x 5 m hall."""
    world = parse_world(
        {"name": "hall", "bounds": [0.0, 0.0, 8.0, 5.0], "walls": [], "robot": {"start": [1.0, 1.0, 0.0]}}
    )
    return map_from_world(world).frame


def test_suspicion_follows_a_heard_pane_along_its_line_past_the_last_cell_heard() -> None:
    """A pane heard only from afar holds evidence too weak to mark, and none toward its end: the robot
    rounding that end found suspicion stopping short of it. Unlooked-at floor along the heard run's line,
    past its end, is suspect too; floor the sonar looked at is not, and neither is floor further on."""
    frame = _hall_frame()
    memories = {
        extension: GlassMemory(frame, CostmapParams(), suspicion_radius_m=0.3, pane_extension_m=extension)
        for extension in (0.0, 1.5)
    }
    for memory in memories.values():
        for x in np.arange(1.0, 2.05, 0.2):  # driving along x, the sonar facing a pane 2.6 m off to +y
            memory.add_reading((float(x), 0.5, math.pi / 2), 2.6, 0.5, 0.02, 3.0)
    with_line, without = memories[1.5], memories[0.0]
    heard = with_line.heard_cells_xy()
    assert len(heard) and not (with_line.sonar_layer == LETHAL_OBSTACLE).any(), "heard, not marked"
    end_x, line_y = float(heard[:, 0].max()), float(np.median(heard[:, 1]))

    def glass(memory: GlassMemory, x: float, y: float) -> bool:
        ix, iy = frame.world_to_cell(x, y)
        return bool(memory.glass_mask()[iy, ix])

    beyond = (end_x + 0.6, line_y + 0.2)  # behind the pane's line, where the sonar never looked
    assert glass(with_line, *beyond) and not glass(without, *beyond)
    assert not glass(with_line, end_x + 0.6, line_y - 0.5)  # the side the sonar looked through
    assert not glass(with_line, end_x + HEARD_LINE_EXTENSION_M + 0.5, line_y + 0.2)  # no further


def test_a_pane_heard_in_patches_goes_on_past_its_last_patch() -> None:
    """A pane heard only at a slant is heard in patches, a few tenths of a metre apart. Cut into runs at the
    marks' gap of a few cells, the patches past the first made no run long enough to be a pane, and the
    heard line stopped short of the last cell heard, a metre short of the pane's end: the glass room's
    robot now and then met that end (measurement 115)."""
    frame = _hall_frame()
    memory = GlassMemory(frame, CostmapParams(), suspicion_radius_m=0.3, pane_extension_m=1.5)
    heard = np.zeros(frame.shape, dtype=bool)
    row = frame.world_to_cell(1.0, 2.6)[1]
    patches_m = [(1.0, 2.2), (2.65, 2.95), (3.25, 3.4)]  # gaps of 0.45 and 0.3 m
    for start, stop in patches_m:
        first, last = frame.world_to_cell(start, 2.6)[0], frame.world_to_cell(stop, 2.6)[0]
        heard[row, first : last + 1] = True
    line = memory.heard_line_mask(heard)
    ix_last = frame.world_to_cell(3.4, 2.6)[0]
    beyond = np.nonzero(line[row - 1 : row + 2, ix_last + 1 :].any(axis=0))[0] + ix_last + 1
    assert len(beyond), "the heard line stops at the last patch"
    reach_m = (beyond.max() - ix_last) * frame.resolution_m
    assert HEARD_LINE_EXTENSION_M - 0.1 <= reach_m <= HEARD_LINE_EXTENSION_M + 0.05, reach_m
    assert not line[heard].any(), "the heard cells stay heard cells"


def test_a_heard_run_lengthened_by_a_few_cells_draws_its_line_again_from_the_new_end() -> None:
    """The heard lines are reused while few heard cells change, but a robot driving along a pane hears its
    end a few cells at a time: the run grew by a metre in five cells, and the line still went on from the
    old end, leaving the last 0.3 m of the glass room's pane unsuspected (measurement 117)."""
    frame = _hall_frame()
    memory = GlassMemory(frame, CostmapParams(), suspicion_radius_m=0.3, pane_extension_m=1.5)
    heard = np.zeros(frame.shape, dtype=bool)
    row = frame.world_to_cell(1.0, 2.6)[1]
    heard[row, frame.world_to_cell(1.0, 2.6)[0] : frame.world_to_cell(2.2, 2.6)[0] + 1] = True
    memory.heard_line_mask(heard)
    grown = heard.copy()
    for x in (2.5, 2.8, 3.1, 3.4, 3.7):  # patches 0.3 m apart: one run, a metre and a half longer
        grown[row, frame.world_to_cell(x, 2.6)[0]] = True
    line = memory.heard_line_mask(grown)
    ix_last = frame.world_to_cell(3.7, 2.6)[0]
    beyond = np.nonzero(line[row - 1 : row + 2, ix_last + 1 :].any(axis=0))[0]
    assert len(beyond), "the line still goes on from the run's old end"
    reach_m = (beyond.max() + 1) * frame.resolution_m
    assert HEARD_LINE_EXTENSION_M - 0.1 <= reach_m <= HEARD_LINE_EXTENSION_M + 0.05, reach_m
    # a few cells heard away from any line change nothing: the lines drawn are reused
    aside = grown.copy()
    aside[frame.world_to_cell(5.0, 4.0)[1], frame.world_to_cell(5.0, 4.0)[0]] = True
    assert memory.heard_line_mask(aside) is line


def test_suspicion_from_a_heard_line_leaves_the_robot_its_gap_before_a_wall() -> None:
    """A heard line stopped a robot's gap short of a wall, and then seeded suspicion that grew by its radius
    toward the wall: 0.3 m was left between the two, and the glass room's robot squeezed through it,
    stopping for "collision ahead" again and again (measurement 117). The suspected floor now ends the
    robot's gap short of the wall, as a marked pane's extension does."""
    frame = _hall_frame()
    memory = GlassMemory(frame, CostmapParams(), suspicion_radius_m=0.3, pane_extension_m=1.5)
    walls = np.zeros(frame.shape, dtype=bool)
    wall_col = frame.world_to_cell(3.0, 2.6)[0]
    walls[:, wall_col] = True
    memory.set_walls(walls)
    heard = np.zeros(frame.shape, dtype=bool)
    row = frame.world_to_cell(1.0, 2.6)[1]
    heard[row, frame.world_to_cell(0.2, 2.6)[0] : frame.world_to_cell(1.4, 2.6)[0] + 1] = True
    line = memory.heard_line_mask(heard)
    assert line[row, frame.world_to_cell(1.6, 2.6)[0]], "the line still goes on past the run's end"
    last = int(np.nonzero(line[row - 2 : row + 3, :wall_col].any(axis=0))[0].max())
    # what the line's suspicion leaves before the wall: the cells between, less the suspicion radius
    gap_m = (wall_col - last - 1) * frame.resolution_m - memory.suspicion_radius_m
    robot_gap_m = 2.0 * CostmapParams().circumscribed_radius_m + 0.1
    assert gap_m >= robot_gap_m - frame.resolution_m, f"{gap_m:.2f} m left between suspicion and wall"
