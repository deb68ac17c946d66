"""``zendock config``: the validated, interpolated stack; errors exit 2 with the file and the key."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from deploy.cli import main

REPO_ROOT = Path(__file__).resolve().parents[3]


def test_config_prints_the_interpolated_default_stack(monkeypatch, capsys) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.chdir(REPO_ROOT)
    monkeypatch.setenv("ZENDOCK_WORLD", "deploy/worlds/glass_room.yaml")
    monkeypatch.setenv("ZENOH_LISTEN", "tcp/127.0.0.1:7555")
    monkeypatch.delenv("ZENOH_CONNECT", raising=False)
    assert main(["config"]) == 0
    printed = yaml.safe_load(capsys.readouterr().out)
    assert printed["name"] == "zendock"
    assert printed["zenoh"] == {"connect": ["tcp/127.0.0.1:7447"]}
    assert "deploy/worlds/glass_room.yaml" in printed["services"]["simulator"]["command"]
    assert "deploy/worlds/glass_room.yaml" in printed["services"]["map"]["command"]
    assert printed["services"]["router"]["command"][-1] == "tcp/127.0.0.1:7555"
    assert printed["services"]["planner"]["depends_on"]["map"] == {
        "condition": "service_completed_successfully"
    }
    assert printed["services"]["simulator"]["healthcheck"]["liveliness"] is True
    assert "x-service" not in printed


def test_config_lists_services_and_profiles(monkeypatch, capsys) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.chdir(REPO_ROOT)
    assert main(["config", "--services"]) == 0
    assert capsys.readouterr().out.split() == [
        "router",
        "map",
        "simulator",
        "perception",
        "battery",
        "pose",
        "planner",
        "docking",
        "viz",
        "ros2_bridge",
        "ros2_dds",
    ]
    assert main(["config", "--profiles"]) == 0
    assert capsys.readouterr().out.split() == ["ros2", "ros2-dds", "viz"]


def test_config_errors_exit_2_naming_file_and_key(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    bad = tmp_path / "stack.yaml"
    bad.write_text("services:\n  planner: {command: [x], restart: sometimes}\n", encoding="utf-8")
    assert main(["config", "-f", str(bad), "-q"]) == 2
    err = capsys.readouterr().err
    assert f"{bad}: services.planner.restart: expected one of" in err


def test_config_reads_the_env_file_option(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    stack = tmp_path / "stack.yaml"
    stack.write_text("services:\n  a: {command: [echo, '${GREETING:?needed}']}\n", encoding="utf-8")
    env_file = tmp_path / "vars.env"
    env_file.write_text("GREETING=hello\n", encoding="utf-8")
    assert main(["config", "-f", str(stack), "--project-directory", str(tmp_path)]) == 2
    assert "services.a.command.1: required variable GREETING is missing: needed" in capsys.readouterr().err
    assert main(["config", "-f", str(stack), "--env-file", str(env_file)]) == 0
    assert yaml.safe_load(capsys.readouterr().out)["services"]["a"]["command"] == ["echo", "hello"]


@pytest.mark.parametrize("argv", [["up", "--help"], ["ps", "--help"], ["logs", "--help"], ["down", "--help"]])
def test_launcher_commands_are_registered(argv: list[str], capsys) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(SystemExit) as caught:
        main(argv)
    assert caught.value.code == 0
    assert argv[0] in capsys.readouterr().out


def test_kill_takes_signal_names_or_numbers() -> None:
    from deploy.cli import build_parser

    parser = build_parser()
    assert parser.parse_args(["kill", "-s", "TERM", "planner"]).signal == 15
    assert parser.parse_args(["kill", "-s", "SIGINT", "planner"]).signal == 2
    assert parser.parse_args(["kill", "planner"]).signal == 9
    with pytest.raises(SystemExit):
        parser.parse_args(["kill", "-s", "NOPE", "planner"])
