"""An interrupted command says so and exits 130; an interrupted demo leaves its run directory marked incomplete."""

from __future__ import annotations

from pathlib import Path

import pytest

from deploy import cli, demo
from deploy.commands import demo as demo_command
from deploy.paths import REPO_ROOT


def test_an_interrupted_command_says_interrupted_and_exits_130(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    def interrupted(_args: object) -> int:
        raise KeyboardInterrupt

    monkeypatch.setattr(demo_command, "_run", interrupted)
    assert cli.main(["demo"]) == 130
    assert capsys.readouterr().err.strip() == "zendock demo: interrupted"


def test_an_interrupted_demo_marks_its_run_directory_incomplete(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    def interrupted() -> str:
        raise KeyboardInterrupt

    monkeypatch.setattr(demo, "free_endpoint", interrupted)  # the first step after the directory is made
    options = demo.DemoOptions(world=REPO_ROOT / "deploy" / "worlds" / "seed_room.yaml", runs_dir=tmp_path)
    with pytest.raises(KeyboardInterrupt):
        demo.run_demo(options, log=lambda _text: None)
    (run_dir,) = tmp_path.iterdir()
    assert (run_dir / demo.INCOMPLETE_MARK).is_file() and not (run_dir / "report.json").exists()
