"""Reading ``@pytest.mark.zendock(...)`` and the ``--zendock-*`` options into a stack configuration."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from deploy.testing.config import WORLDS_DIR, StackConfig, merge_markers, resolve_world, stack_config


def test_defaults_are_the_stack_files_but_a_test_friendly_rtf() -> None:
    config = stack_config({})
    assert config == StackConfig()
    assert config.world == WORLDS_DIR / "seed_room.yaml" and config.rtf == "4"
    assert (config.detector, config.controller, config.services) == ("aruco", "graceful", ())


def test_marker_arguments_become_the_stack(tmp_path: Path) -> None:
    config = stack_config(
        {
            "world": "corridor",
            "rtf": 8,
            "detector": "synthetic",
            "controller": "seed",
            "seed": 3,
            "localisation_error": [0.03, -0.02, 0.02],
            "services": {"docking": "python my.py"},
            "healthy_timeout_s": 30,
        }
    )
    assert config.world == WORLDS_DIR / "corridor.yaml"
    assert (config.rtf, config.detector, config.controller, config.seed) == ("8", "synthetic", "seed", 3)
    assert config.localisation_error == (0.03, -0.02, 0.02) and config.healthy_timeout_s == 30.0
    assert [(r.name, r.command) for r in config.services] == [("docking", "python my.py")]
    env = config.environment("tcp/127.0.0.1:40000", tmp_path)
    assert env["ZENOH_LISTEN"] == env["ZENOH_CONNECT"] == "tcp/127.0.0.1:40000"
    assert env["ZENDOCK_WORLD"] == str(WORLDS_DIR / "corridor.yaml") and env["ZENDOCK_RTF"] == "8"
    assert json.loads(env["ZENDOCK_LOCALISATION_ERROR"]) == [0.03, -0.02, 0.02]
    assert env["ZENDOCK_GLASS_MEMORY"].startswith(str(tmp_path))


def test_the_command_line_wins_over_the_marker() -> None:
    config = stack_config(
        {"rtf": 8, "services": {"docking": "python mine.py", "pose": "python pose.py"}},
        cli_services=["docking=python theirs.py --fast"],
        cli_rtf="2",
    )
    assert config.rtf == "2"
    assert {r.name: r.command for r in config.services} == {
        "docking": "python theirs.py --fast",
        "pose": "python pose.py",
    }


def test_the_closest_marker_wins_and_unknown_arguments_are_named() -> None:
    assert merge_markers([{"world": "corridor", "rtf": 2}, {"rtf": 8}]) == {"world": "corridor", "rtf": 8}
    with pytest.raises(ValueError, match=r"unknown argument\(s\) wrold .*known: world"):
        merge_markers([{"wrold": "corridor"}])


def test_a_world_is_a_shipped_name_or_a_file_under_the_rootdir(tmp_path: Path) -> None:
    (tmp_path / "mine.yaml").write_text("name: mine\n")
    assert resolve_world("mine.yaml", tmp_path) == (tmp_path / "mine.yaml").resolve()
    assert resolve_world(str(tmp_path / "mine.yaml"), Path("/")) == (tmp_path / "mine.yaml").resolve()
    with pytest.raises(ValueError, match=r"no shipped world of that name \(one of: .*seed_room"):
        resolve_world("seed_rom", tmp_path)
    with pytest.raises(ValueError, match="is not a file"):
        resolve_world("worlds/absent.yaml", tmp_path)


@pytest.mark.parametrize(
    ("marker", "message"),
    [
        ({"rtf": 0}, "rtf=0: expected a positive number or 'max'"),
        ({"rtf": "fast"}, "rtf='fast'"),
        ({"detector": "lidar"}, r"no dock detector 'lidar' \(one of: aruco, synthetic\)"),
        ({"controller": "gracefull"}, r"no docking controller 'gracefull' \(one of: graceful, seed, ir\)"),
        ({"localisation_error": [0.1, 0.2]}, r"expected \(x_m, y_m, yaw_rad\)"),
        ({"healthy_timeout_s": 0}, "healthy_timeout_s=0.0"),
        ({"services": {"router": "python r.py"}}, "no replaceable service 'router'"),
        ({"services": {"docking": ""}}, "the command is empty"),
        ({"services": "docking=python x.py"}, "services must be a dict"),
    ],
)
def test_a_mistake_is_one_line_naming_it(marker: dict[str, object], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        stack_config(marker)


def test_a_service_replaced_twice_on_the_command_line_is_refused() -> None:
    with pytest.raises(ValueError, match="--zendock-service docking is given twice"):
        stack_config({}, cli_services=["docking=python a.py", "docking=python b.py"])
    assert stack_config({"rtf": "max"}).rtf == "max"
