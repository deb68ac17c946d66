"""The sonar's range model: its law, and what it makes of an oblique pane seen from several poses."""

from __future__ import annotations

import logging
import math

import numpy as np
import pytest

from services.planner.costmap import CostmapParams
from services.planner.costmap_updater import CostmapUpdater, glass_speed_limit
from services.planner.glass_memory import GlassMemory
from services.planner.grid_frame import GridFrame
from services.planner.occupancy_map import OCC_FREE, OccupancyMap
from services.planner.params import Params
from services.planner.range_sensor_model import (
    RangeSensorModel,
    angular_weight,
    log_odds,
    range_weight,
    reading_evidence,
)
from shared import structs, topics
from shared.geometry import Pose2D
from shared.messages import Header, Range, Time
from shared.pose_tracking import OdometrySample, PoseTrack

MODEL = RangeSensorModel()
HALF_FOV = 0.25


def _updater_on_open_floor(track: PoseTrack, params: Params | None = None) -> CostmapUpdater:
    """A costmap updater over a 6 x 4 m map of open floor, with its glass memory."""
    layers = CostmapUpdater(params or Params(), track, logging.getLogger("test"))
    layers.set_map(OccupancyMap(0.05, (0.0, 0.0, 0.0), np.full((80, 120), OCC_FREE, dtype=np.int8)))
    assert layers.glass is not None
    return layers


def test_occupied_evidence_falls_off_with_the_angle_from_the_axis() -> None:
    bearings = np.linspace(0.0, HALF_FOV * 1.2, 13)
    _, occupied = reading_evidence(np.full(13, 1.0), bearings, 1.0, HALF_FOV, True, MODEL)
    near_hit = 0.5 + (MODEL.hit_probability - 0.5) * range_weight(1.0, MODEL.trusted_range_m)
    assert occupied[0] == pytest.approx(log_odds(near_hit))
    assert np.all(np.diff(occupied) <= 1e-12), occupied  # never rises away from the axis
    assert np.all(occupied[bearings >= HALF_FOV] == 0.0)  # outside the cone: nothing
    assert np.all(angular_weight(-bearings, HALF_FOV) == angular_weight(bearings, HALF_FOV))  # symmetric


def test_cells_seen_through_get_free_evidence_and_nothing_beyond_the_echo() -> None:
    distances = np.array([0.2, 0.5, 0.9, 1.0, 1.2, 2.0])
    free, occupied = reading_evidence(distances, np.zeros(6), 1.0, HALF_FOV, True, MODEL)
    assert np.all(free[:3] < 0.0) and np.all(free[3:] == 0.0)
    assert occupied[3] > 0.0 and np.all(occupied[[0, 1, 2, 4, 5]] == 0.0)
    free, occupied = reading_evidence(distances, np.zeros(6), 3.0, HALF_FOV, False, MODEL)  # no echo
    assert np.all(free < 0.0) and not occupied.any()


def test_an_echo_from_afar_gives_its_arc_less_evidence() -> None:
    """An echo's arc is ``fov * r`` wide and one of its cells made it: from 0.5 m one echo marks, from the
    trusted range (Nav2's phi; 2 m here) it gives half the evidence, from 3 m next to none."""
    on_axis = {
        r: reading_evidence(np.array([r]), np.zeros(1), r, HALF_FOV, True, MODEL)[1][0]
        for r in (0.5, 1.0, MODEL.trusted_range_m, 2.5, 3.0)
    }
    assert on_axis[0.5] >= MODEL.mark_log_odds and on_axis[1.0] >= MODEL.mark_log_odds  # near: one echo marks
    assert on_axis[0.5] > on_axis[1.0] > on_axis[MODEL.trusted_range_m] > on_axis[2.5] > on_axis[3.0] > 0.0
    assert range_weight(MODEL.trusted_range_m, MODEL.trusted_range_m) == pytest.approx(0.5)
    assert on_axis[3.0] < 0.02 * on_axis[0.5]
    free, _ = reading_evidence(np.array([2.0]), np.zeros(1), 3.0, HALF_FOV, True, MODEL)
    assert free[0] == pytest.approx(log_odds(MODEL.miss_probability))  # seeing through is as sure from afar


@pytest.mark.parametrize(
    "bad",
    [
        {"hit_probability": 0.4},
        {"miss_probability": 1.2},
        {"mark_threshold": 0.3},
        {"range_band_m": 0.0},
        {"trusted_range_m": 0.0},
    ],
)
def test_a_model_that_contradicts_itself_is_refused(bad: dict[str, float]) -> None:
    with pytest.raises(ValueError, match="RangeSensorModel"):
        RangeSensorModel(**bad)  # type: ignore[arg-type]


def _nearest_echo(sensor: tuple[float, float, float], pane: tuple[np.ndarray, np.ndarray]) -> float:
    """The simulator's sonar: the nearest point of the pane inside the cone (inf when none)."""
    a, b = pane
    points = a + np.linspace(0.0, 1.0, 400)[:, None] * (b - a)
    dx, dy = points[:, 0] - sensor[0], points[:, 1] - sensor[1]
    bearing = np.abs((np.arctan2(dy, dx) - sensor[2] + math.pi) % (2 * math.pi) - math.pi)
    seen = np.hypot(dx, dy)[bearing <= HALF_FOV]
    return float(seen.min()) if len(seen) else math.inf


def _marked_xy(memory: GlassMemory) -> np.ndarray:
    """Centres ``(N, 2)`` of the cells the memory marks as glass."""
    return memory.frame.cells_to_world(np.argwhere(memory.sonar_layer == 254)[:, ::-1])


def _false_marks(memory: GlassMemory, pane: tuple[np.ndarray, np.ndarray], tolerance_m: float = 0.1) -> int:
    xy = _marked_xy(memory)
    if len(xy) == 0:
        return 0
    a, b = pane
    t = np.clip(((xy - a) @ (b - a)) / float((b - a) @ (b - a)), 0.0, 1.0)
    off = np.hypot(*(xy - (a + t[:, None] * (b - a))).T)
    return int(np.count_nonzero(off > tolerance_m))


def _coverage(memory: GlassMemory, pane: tuple[np.ndarray, np.ndarray], tolerance_m: float = 0.1) -> float:
    """The fraction of the pane's length within ``tolerance_m`` of a mark."""
    xy = _marked_xy(memory)
    if len(xy) == 0:
        return 0.0
    a, b = pane
    points = a + np.linspace(0.0, 1.0, 100)[:, None] * (b - a)
    nearest = np.min(
        np.hypot(points[:, None, 0] - xy[None, :, 0], points[:, None, 1] - xy[None, :, 1]), axis=1
    )
    return float(np.mean(nearest <= tolerance_m))


def test_an_oblique_pane_converges_as_the_robot_looks_from_several_poses() -> None:
    """A pane at 40 degrees to the robot's path, its nearest echo at the cone's edge: the first looks
    put marks in front of it; looks from further along see through them and pin the echoes on the pane.
    (Marking the whole arc at the echo's range left 6 cells more than 10 cm in front of this pane.)"""
    frame = GridFrame(0.05, (0.0, 0.0, 0.0), 120, 80)
    memory = GlassMemory(frame, CostmapParams(), suspicion_radius_m=0.0)
    pane = (np.array([3.0, 1.0]), np.array([4.5, 2.26]))  # 40 degrees to +x
    most_false = 0
    for x in np.arange(0.5, 3.0, 0.1):  # driving along +x, the sonar swept across the pane's side
        for yaw in (0.35, 0.6, 0.85):
            sensor = (float(x), 1.2, yaw)
            memory.add_reading(sensor, _nearest_echo(sensor, pane), 2 * HALF_FOV, 0.02, 3.0)
        most_false = max(most_false, _false_marks(memory, pane))
    final_false = _false_marks(memory, pane)
    assert final_false <= 3, f"{final_false} cells marked more than 10 cm in front of the pane"
    # (With the far echoes trusted less, the first looks may put no false marks there at all.)
    assert final_false == 0 or final_false < most_false, (
        "looks from further along should clear the early false marks"
    )
    # Its far end is heard only from beyond the trusted range (2 m) here: it waits for nearer looks.
    assert _coverage(memory, pane) >= 0.55, f"only {_coverage(memory, pane):.0%} of the pane is marked"


def test_glass_heard_ahead_slows_the_robot_near_it() -> None:
    params = structs.validate(
        Params, {"glass_slowdown_radius_m": 0.8, "glass_slowdown_min_speed_mps": 0.1}, "params"
    )
    layers = _updater_on_open_floor(PoseTrack(), params)
    assert layers.glass is not None
    assert layers.glass_speed_limit_mps(Pose2D(2.0, 2.0, 0.0)) is None  # nothing heard yet
    # An echo at 1 m: the arc's middle is marked, its flanks (weaker evidence) are only suspected.
    layers.glass.add_reading((1.0, 2.0, 0.0), 1.0, 0.5, 0.02, 3.0)
    layers.apply_glass()
    suspected = layers.glass.suspected_cells_xy()
    assert len(suspected) > 0
    marked = layers.glass.sonar_layer == 254
    ix, iy = layers.glass.frame.world_to_cells(suspected).T
    assert not marked[iy, ix].any()
    far = layers.glass_speed_limit_mps(Pose2D(0.5, 0.5, 0.0))
    near = layers.glass_speed_limit_mps(Pose2D(1.6, 2.0, 0.0))
    assert far is None
    assert near is not None and 0.1 <= near < params.max_linear_vel_mps
    # Driving away from it, with the heard glass behind: no limit; nor passing it broadside.
    assert layers.glass_speed_limit_mps(Pose2D(1.6, 2.0, math.pi)) is None
    assert layers.glass_speed_limit_mps(Pose2D(2.0, 1.3, 0.0)) is None
    # Marked glass counts as much as suspected glass: facing the arc's marked middle from 0.3 m.
    assert layers.glass_speed_limit_mps(Pose2D(1.7, 2.0, 0.0)) == pytest.approx(
        params.max_linear_vel_mps * 0.3 / 0.8, abs=0.05
    )
    # The node reads the limit from the heard cells the costmap thread hands over, round where the last
    # update placed the robot: the same answers there and half a metre on.
    assert len(layers.heard_glass_xy()) == 0, "before an update placed the robot nothing is handed over"
    for pose in (
        Pose2D(0.5, 0.5, 0.0),
        Pose2D(1.6, 2.0, 0.0),
        Pose2D(1.6, 2.0, math.pi),
        Pose2D(2.0, 1.3, 0.0),
        Pose2D(1.7, 2.0, 0.0),
    ):
        for dx in (0.0, -0.5):
            layers.last_pose = Pose2D(pose.x + dx, pose.y, pose.yaw)
            assert glass_speed_limit(params, pose, layers.heard_glass_xy()) == layers.glass_speed_limit_mps(
                pose
            ), pose


def test_an_echo_from_cells_known_free_is_held_as_glass_for_a_while() -> None:
    """The evidence gives an echo's weight to arc cells not known to be free: after clear looks, the arc's
    middle (seen through whole) gets none and its ends (only partly inside those cones) get it all. The
    echo's whole arc is held as glass for echo_hold_s all the same, never written into the evidence,
    then lapses."""
    frame = GridFrame(0.05, (0.0, 0.0, 0.0), 80, 60)
    memory = GlassMemory(frame, CostmapParams(), suspicion_radius_m=0.0, echo_hold_s=2.0)
    sensor = (0.5, 1.5, 0.0)
    for _ in range(3):
        memory.add_reading(sensor, math.inf, 2 * HALF_FOV, 0.02, 3.0, stamp_s=9.0)  # clear out to 3 m
    memory.add_reading(sensor, 1.0, 2 * HALF_FOV, 0.02, 3.0, stamp_s=10.0)
    evidence = memory.sonar_layer == 254
    middle = frame.world_to_cells(np.array([[1.5, 1.5]]))[0]
    assert not evidence[middle[1], middle[0]], "the evidence puts the echo on no cell known to be free"
    assert evidence.any(), "the echo came from the part of the arc not seen through"
    marked_y = frame.cells_to_world(np.argwhere(evidence)[:, ::-1])[:, 1]
    assert np.all(np.abs(marked_y - 1.5) > 0.15), "only the arc's ends"
    assert memory.held_mask()[middle[1], middle[0]] and memory.glass_mask()[middle[1], middle[0]]
    assert not memory.expire(11.9)
    assert memory.glass_mask()[middle[1], middle[0]]
    assert memory.expire(12.0)
    assert np.array_equal(memory.glass_mask(), memory.sonar_layer == 254)


def test_a_pane_end_in_a_corner_of_a_cell_never_becomes_known_free() -> None:
    """The cone's edge sweeps past a pane's end look after look while the echo comes from elsewhere. The
    end's cell lies partly inside each cone; were its centre enough to clear it, it would become known
    free and, explained away, never be credited with the echo its glass makes later."""
    frame = GridFrame(0.05, (0.0, 0.0, 0.0), 80, 60)
    memory = GlassMemory(frame, CostmapParams(), suspicion_radius_m=0.0)
    end = np.array([2.0, 1.5 + 0.26 * 1.5])  # just outside the cone of a sensor at (0.5, 1.5) facing +x
    end_cell = frame.world_to_cells(end[None, :])[0]
    for _ in range(200):
        memory.add_reading((0.5, 1.5, 0.0), 2.5, 2 * HALF_FOV, 0.02, 3.0)  # the echo from a wall behind
    memory.add_reading((1.0, end[1], 0.0), 1.0, 2 * HALF_FOV, 0.02, 3.0)  # now facing the end from 1 m
    assert memory.sonar_layer[end_cell[1], end_cell[0]] == 254


def test_a_held_arc_never_covers_the_robot_and_a_clock_that_goes_back_drops_it() -> None:
    frame = GridFrame(0.05, (0.0, 0.0, 0.0), 80, 60)
    memory = GlassMemory(frame, CostmapParams(), suspicion_radius_m=0.0, echo_hold_s=2.0)
    memory.add_reading((0.5, 1.5, 0.0), 0.5, 2 * HALF_FOV, 0.02, 3.0, stamp_s=5.0)
    held = memory.held_mask()
    assert held.any()
    memory.observe_footprint((1.0, 1.5, 0.0))  # the robot now stands on the arc
    assert memory.held_mask().sum() < held.sum()
    under = frame.world_to_cells(np.array([[1.0, 1.5]]))[0]
    assert not memory.glass_mask()[under[1], under[0]]
    assert memory.expire(1.0)  # a new run restarted the clock
    assert not memory.held_mask().any()
    with pytest.raises(ValueError, match="echo_hold_s"):
        GlassMemory(frame, CostmapParams(), echo_hold_s=-1.0)


def test_far_echoes_at_the_cone_edge_mark_no_floor_and_the_pane_is_found_up_close() -> None:
    """A large room: the robot passes a long pane 2.5 m off, looking across it obliquely, so each echo comes
    from the cone's edge and its 1.3 m arc lies mostly on open floor in front of the pane (before the range
    trust, those looks left 15 cells marked more than 10 cm from the pane). Then it drives at the pane and
    stops 0.3 m short: the pane is marked where it came near, the first time it hears it within 1 m."""
    frame = GridFrame(0.05, (0.0, 0.0, 0.0), 120, 120)
    memory = GlassMemory(frame, CostmapParams(), suspicion_radius_m=0.0)
    pane = (np.array([4.5, 1.0]), np.array([4.5, 5.0]))
    for y in np.arange(0.5, 5.5, 0.1):
        for yaw in (0.5, 0.8, -0.5, -0.8):
            sensor = (1.8, float(y), yaw)
            memory.add_reading(sensor, _nearest_echo(sensor, pane), 2 * HALF_FOV, 0.02, 3.0)
    assert _false_marks(memory, pane) == 0
    ahead = frame.world_to_cells(np.array([[4.5, 3.0]]))[0]
    for x in np.arange(1.8, 4.0, 0.05):
        sensor = (float(x), 3.0, 0.0)
        memory.add_reading(sensor, _nearest_echo(sensor, pane), 2 * HALF_FOV, 0.02, 3.0)
        if 4.5 - x <= 1.0:
            assert memory.sonar_layer[ahead[1], ahead[0]] == 254, f"not marked from {4.5 - x:.2f} m"
            break
    for x in np.arange(3.5, 4.2, 0.05):
        sensor = (float(x), 3.0, 0.0)
        memory.add_reading(sensor, _nearest_echo(sensor, pane), 2 * HALF_FOV, 0.02, 3.0)
    assert _false_marks(memory, pane) <= 2
    marked_y = _marked_xy(memory)[:, 1]
    assert marked_y.min() <= 2.85 and marked_y.max() >= 3.15, "the part of the pane faced up close is marked"


def test_a_sonar_reading_newer_than_odometry_waits_to_be_placed_by_it() -> None:
    """Placed before odometry reached it, a reading taken while the robot turned was put where the robot
    had faced: a reading facing just past a pane's end (no echo) cleared the floor behind the glass. It
    waits for the update that has the odometry of its time."""
    track = PoseTrack()
    layers = _updater_on_open_floor(track)
    assert layers.glass is not None
    track.add_odom(OdometrySample(1.0, Pose2D(1.0, 2.0, 0.0), 0.0, 1.0))  # turning left at 1 rad/s
    track.add_pose(1.0, Pose2D(1.0, 2.0, 0.0))
    header = Header(stamp=Time.from_sec(1.3), frame_id=topics.ULTRASONIC_FRAME)
    layers.add_range(Range(header=header, field_of_view=0.5, min_range=0.02, max_range=3.0, range=1.0))
    layers.update(1.3)
    assert len(layers.glass.heard_cells_xy()) == 0, "placed before odometry reached it"
    track.add_odom(OdometrySample(1.35, Pose2D(1.0, 2.0, 0.35), 0.0, 1.0))
    layers.update(1.35)
    heard = layers.glass.heard_cells_xy()
    assert len(heard) > 0
    sensor_x, sensor_y = 1.0 + 0.2 * math.cos(0.3), 2.0 + 0.2 * math.sin(0.3)  # the mount, facing 0.3 rad
    bearing = math.atan2(float(np.mean(heard[:, 1])) - sensor_y, float(np.mean(heard[:, 0])) - sensor_x)
    assert bearing == pytest.approx(0.3, abs=0.05)
    # With no odometry at all (a robot reporting only its map pose) nothing waits.
    bare = PoseTrack()
    alone = _updater_on_open_floor(bare)
    assert alone.glass is not None
    bare.add_pose(1.3, Pose2D(1.0, 2.0, 0.0))
    alone.add_range(Range(header=header, field_of_view=0.5, min_range=0.02, max_range=3.0, range=1.0))
    alone.update(1.3)
    assert len(alone.glass.heard_cells_xy()) > 0
