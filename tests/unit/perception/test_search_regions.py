"""Searching only around last frame's markers: the same corners as a whole-frame search, and the rules
that bring the whole frame back (a missed box, a new marker's turn, a stale memory)."""

from __future__ import annotations

import numpy as np

from services.perception.markers import MarkerFinder, MarkerSighting
from services.perception.search_regions import SearchRegions
from services.simulator.camera import CameraParams, CameraRenderer, build_scene
from shared.geometry import Pose2D
from shared.world import parse_world


def _image(robot: Pose2D) -> tuple[np.ndarray, str]:
    world = parse_world(
        {
            "name": "regions",
            "bounds": [-5.0, -5.0, 5.0, 5.0],
            "robot": {"start": [-1.0, 0.0, 0.0]},
            "docks": [{"id": "home", "pose": [0.0, 0.0, 0.0]}],
        }
    )
    return CameraRenderer(build_scene(world), CameraParams(), np.random.default_rng(3)).render(
        robot
    ), world.aruco_dictionary


def test_a_box_around_last_frames_marker_finds_the_same_corners_as_the_whole_frame() -> None:
    image, dictionary = _image(Pose2D(-1.3, 0.15, -0.1))
    finder = MarkerFinder(dictionary)
    whole = finder.find(image)
    assert len(whole) == 1
    regions = SearchRegions()
    regions.update(whole, stamp_s=10.0, whole_frame=True)
    boxes = regions.boxes(10.066, image.shape[1], image.shape[0])
    assert boxes is not None and len(boxes) == 1
    x0, y0, x1, y1 = boxes[0]
    assert (x1 - x0) * (y1 - y0) < 0.25 * image.size, f"box {boxes[0]} is not much smaller than the frame"
    boxed = finder.find(image, boxes)
    assert [s.marker_id for s in boxed] == [whole[0].marker_id]
    np.testing.assert_allclose(boxed[0].corners, whole[0].corners, atol=0.01)
    assert regions.complete(boxed)


def test_a_box_that_misses_its_marker_is_incomplete() -> None:
    image, dictionary = _image(Pose2D(-1.3, 0.15, -0.1))
    finder = MarkerFinder(dictionary)
    whole = finder.find(image)
    regions = SearchRegions()
    # Last frame saw the marker far to the left: the box there holds no marker now.
    regions.update(
        [MarkerSighting(whole[0].marker_id, whole[0].corners - (250.0, 0.0))], 10.0, whole_frame=True
    )
    boxes = regions.boxes(10.066, image.shape[1], image.shape[0])
    assert boxes is not None
    assert not regions.complete(finder.find(image, boxes))


def test_the_whole_frame_is_searched_without_a_recent_marker_and_every_few_frames() -> None:
    corners = np.array([[300.0, 200.0], [340.0, 200.0], [340.0, 240.0], [300.0, 240.0]])
    regions = SearchRegions(memory_s=0.5, full_search_every=4)
    assert regions.boxes(0.0, 640, 480) is None  # nothing seen yet
    regions.update([MarkerSighting(7, corners)], 1.0, whole_frame=True)
    assert regions.boxes(1.6, 640, 480) is None  # the marker was seen too long ago
    searched = []
    for frame in range(1, 9):
        stamp = 1.0 + frame / 15.0
        boxes = regions.boxes(stamp, 640, 480)
        searched.append("whole" if boxes is None else "boxes")
        regions.update([MarkerSighting(7, corners)], stamp, whole_frame=boxes is None)
    assert searched == ["boxes", "boxes", "boxes", "whole", "boxes", "boxes", "boxes", "whole"]


def test_a_whole_frame_search_that_finds_nothing_forgets_the_markers() -> None:
    corners = np.array([[300.0, 200.0], [340.0, 200.0], [340.0, 240.0], [300.0, 240.0]])
    regions = SearchRegions()
    regions.update([MarkerSighting(7, corners)], 1.0, whole_frame=True)
    regions.update([], 1.07, whole_frame=True)
    assert regions.boxes(1.1, 640, 480) is None
