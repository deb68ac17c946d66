"""The run picture: a real PNG with the room's colours, the run's data from a recording, via ``zendock plot``."""

from __future__ import annotations

from pathlib import Path

import matplotlib.image as mpimg
import numpy as np

from deploy.cli import main as zendock
from deploy.plotting import (
    DOCK_COLOR,
    GLASS_COLOR,
    PLAN_COLOR,
    RECOVERY_COLOR,
    STAGING_COLOR,
    RunPicture,
    battery_from_set,
    draw_world,
    echo_arc,
    last_full_plan,
    plot_picture,
    plot_run,
    plot_trial_histograms,
)
from deploy.recording.reading import Recording
from deploy.recording.run_data import run_picture, sonar_echoes
from shared.geometry import Pose2D
from shared.world import load_world
from tests.support.processes import REPO_ROOT
from tests.unit.recording.synthetic import WALL_Y_M, write_run

GLASS_ROOM = REPO_ROOT / "deploy/worlds/glass_room.yaml"


def _rgb(hex_color: str) -> np.ndarray:
    return np.array([int(hex_color[i : i + 2], 16) for i in (1, 3, 5)], dtype=np.float64) / 255.0


def _pixels_near(image: np.ndarray, hex_color: str, tolerance: float = 0.08) -> int:
    distance = np.abs(image[:, :, :3] - _rgb(hex_color)).max(axis=2)
    return int((distance < tolerance).sum())


def test_the_picture_is_a_png_with_the_room_in_its_colours(tmp_path: Path) -> None:
    t = np.linspace(0.0, 20.0, 200)
    driven = np.column_stack([-1.0 + 0.5 * np.cos(t / 5.0), 4.0 - 0.15 * t])
    echoes = [(x, 2.0, np.pi / 2, 0.6, 0.5) for x in np.linspace(-1.5, 0.5, 30)]
    plan = [(-1.0, 4.2), (-2.4, 3.0), (-2.4, 2.0), (-1.0, 1.53)]
    path = plot_run(
        load_world(GLASS_ROOM),
        tmp_path / "run.png",
        driven=driven,
        driven_times_s=t,
        plans=[plan],
        sonar_echoes=echoes,
        battery=[(ti, 1.0 - 0.01 * ti) for ti in t],
        battery_set=(0.0, 1.0),
        events=[(5.0, "docking triggered")],
        title="test run",
        dpi=80,
    )
    image = mpimg.imread(path)
    height, width = image.shape[:2]
    assert width >= 800 and height >= 400
    assert _pixels_near(image, "#000000", 0.1) > 500  # walls
    for name, color in (
        ("glass", GLASS_COLOR),
        ("dock", DOCK_COLOR),
        ("staging", STAGING_COLOR),
        ("plan", PLAN_COLOR),
    ):
        assert _pixels_near(image, color) > 20, f"no {name} colour {color} in the picture"
    distinct = np.unique((image[:, :, :3] * 31).astype(np.int32).reshape(-1, 3), axis=0)
    assert len(distinct) > 50  # the trajectory's colour ramp, the battery fill, the room


def test_recoveries_are_marked_where_they_happened(tmp_path: Path) -> None:
    world = load_world(GLASS_ROOM)
    plain = mpimg.imread(plot_run(world, tmp_path / "plain.png", driven=[(-1.0, 4.0), (0.0, 3.0)], dpi=80))
    marked = mpimg.imread(
        plot_run(
            world,
            tmp_path / "marked.png",
            driven=[(-1.0, 4.0), (0.0, 3.0)],
            recoveries=[(0.0, 3.0), (1.0, 4.0)],
            dpi=80,
        )
    )
    assert _pixels_near(plain, RECOVERY_COLOR) == 0
    assert _pixels_near(marked, RECOVERY_COLOR) > 40


def test_an_empty_run_still_draws(tmp_path: Path) -> None:
    path = plot_picture(RunPicture(), tmp_path / "empty.png", dpi=60)
    assert path.stat().st_size > 1000
    path = plot_run(None, tmp_path / "plain.png", driven=[(0.0, 0.0), (1.0, 1.0)], dpi=60)
    assert path.stat().st_size > 1000


def test_an_echo_is_heard_from_where_the_sensor_was_when_it_listened() -> None:
    truth = np.array([[0.0, 0.0, 3.0, -np.pi / 2], [1.0, 0.0, 2.0, -np.pi / 2]])
    ranges = np.array([[0.5, 1.0, 0.5], [2.0, 1.0, 0.5]])  # the second is outside the poses' time span
    echoes = sonar_echoes(truth, ranges, Pose2D(0.2, 0.0, 0.0))
    assert echoes.shape == (1, 5)
    np.testing.assert_allclose(echoes[0], [0.0, 2.5 - 0.2, -np.pi / 2, 1.0, 0.5], atol=1e-9)
    picture = RunPicture(sonar_echoes=echoes)
    np.testing.assert_allclose(picture.sonar_hits, [[0.0, 2.5 - 0.2 - 1.0]], atol=1e-9)  # its axis point


def test_an_echo_is_drawn_as_the_arc_at_its_range_across_the_cone() -> None:
    arc = echo_arc(1.0, 2.0, np.pi / 2, 0.8, 0.5, points=9)
    assert arc.shape == (9, 2)
    np.testing.assert_allclose(np.hypot(arc[:, 0] - 1.0, arc[:, 1] - 2.0), 0.8)  # all at the range
    bearings = np.arctan2(arc[:, 1] - 2.0, arc[:, 0] - 1.0)
    np.testing.assert_allclose(
        [bearings[0], bearings[4], bearings[-1]], [np.pi / 2 - 0.25, np.pi / 2, np.pi / 2 + 0.25]
    )
    width_m = np.hypot(*(arc[-1] - arc[0]))
    assert abs(width_m - 2 * 0.8 * np.sin(0.25)) < 1e-9  # the cone's width at that range, not a point


def test_the_bold_plan_is_the_last_full_one_not_the_stub_at_the_goal() -> None:
    goal = (-1.0, 1.55)
    route = np.array([(1.8, 4.2), (0.0, 2.5), goal])
    again = np.array([(1.78, 4.19), (0.0, 2.5), goal])  # replanned before it had moved: still the whole way
    remainder = np.array([(0.5, 2.9), goal])
    stub = np.array([(-1.0, 1.65), goal])  # 10 cm
    assert last_full_plan([route, again, remainder, stub, stub]) == 1
    detour = np.array([(0.9, 3.4), (1.5, 2.0), (0.0, 1.2), goal])  # replanned round something: longer
    assert last_full_plan([route, remainder, detour, stub]) == 2
    elsewhere = np.array([(3.0, 3.0), (4.0, 3.0)])  # an earlier goal: not a plan to this one
    assert last_full_plan([elsewhere, remainder, stub]) == 1
    assert last_full_plan([stub]) == 0
    assert last_full_plan([]) is None
    assert last_full_plan([np.zeros((1, 2))]) is None


def test_the_battery_is_drawn_from_the_set_not_from_an_assumed_full_charge() -> None:
    battery = np.array([(0.0, 1.0), (1.0, 1.0), (2.0, 1.0), (2.1, 0.26), (3.0, 0.259), (4.0, 0.25)])
    np.testing.assert_allclose(
        battery_from_set(battery, 1.5, 0.26), battery[3:]
    )  # the 100 % on its way dropped
    np.testing.assert_allclose(battery_from_set(battery, 3.5, 0.5), battery[5:])  # no reading shows the set
    assert len(battery_from_set(np.zeros((0, 2)), 1.0, 0.26)) == 0


def test_zendock_plot_draws_a_recording(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    recording = tmp_path / "run.mcap"
    write_run(recording, steps=40)
    with Recording(recording) as r:
        picture = run_picture(r)
    assert len(picture.trajectory) == 40 and len(picture.battery) == 40
    assert picture.world is not None and picture.world.name == "seed_room"
    assert len(picture.planned_paths) == 1
    np.testing.assert_allclose(picture.sonar_hits[:, 1], WALL_Y_M, atol=1e-6)
    output = tmp_path / "run.png"
    assert zendock(["plot", str(recording), "-o", str(output), "--dpi", "60"]) == 0
    assert output.stat().st_size > 10_000
    assert "40 poses" in capsys.readouterr().out


def test_trial_histograms_draw_trials_that_took_all_but_the_same_time(tmp_path: Path) -> None:
    # A deterministic simulation docked two robots in 6.9 s and 6.900000000000002 s: numpy has no five
    # finite bins for that range, and the campaign failed after its last trial.
    from deploy.trials.records import TrialResult

    results = [
        TrialResult(0, "r0", (0.0, 0.0, 0.0), True, True, 6.900000000000002, 0.00045, 0.0018, 0, 2.0),
        TrialResult(1, "r1", (0.0, 0.0, 0.0), True, True, 6.9, 0.00105, 0.0018, 0, 2.0),
    ]
    path = tmp_path / "histograms.png"
    plot_trial_histograms(results, path)
    assert mpimg.imread(path).shape[2] in (3, 4)


def test_every_thing_drawn_in_the_room_is_in_the_legend() -> None:
    """The boxes, the dock and, at the dock's pose, the outline of the robot docked there (its centre is
    the dock's pose: the gap between the track's end and the dock's body is meant)."""
    import matplotlib.pyplot as plt

    world = load_world(REPO_ROOT / "deploy/worlds/seed_room.yaml")
    fig, ax = plt.subplots()
    try:
        draw_world(ax, world, staging_offset_m=0.7)
        labels = ax.get_legend_handles_labels()[1]
    finally:
        plt.close(fig)
    assert world.boxes and world.docks
    assert "box (an obstacle)" in labels and "walls" in labels and "staging pose" in labels, labels
    assert any(label.startswith("dock") for label in labels), labels
    assert "robot docked (centre at the dock's pose)" in labels, labels
