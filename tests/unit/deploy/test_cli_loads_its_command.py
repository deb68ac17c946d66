"""A command loads its own code: ``zendock keys`` does not hold the recorder, the fuzzer or Foxglove.

Each check runs in a fresh interpreter, since this test process has long imported every command."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[3]

_PROBE = """
import contextlib, io, json, sys
from deploy.cli import main
out = io.StringIO()
try:
    with contextlib.redirect_stdout(out):
        main(sys.argv[1:])
except SystemExit:
    pass
commands = sorted(m.rsplit(".", 1)[1] for m in sys.modules if m.startswith("deploy.commands."))
print(json.dumps({"commands": commands, "foxglove": "foxglove" in sys.modules, "usage": out.getvalue()}))
"""


def _loaded(*argv: str) -> dict[str, object]:
    done = subprocess.run(
        [sys.executable, "-c", _PROBE, *argv],
        cwd=REPO_ROOT,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 0, f"zendock {' '.join(argv)} in a fresh interpreter failed:\n{done.stderr}"
    return json.loads(done.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("command", ["keys", "fleet", "ps"])
def test_a_command_by_its_module_name_loads_that_module_alone(command: str) -> None:
    loaded = _loaded(command, "--help")
    assert loaded["commands"] == [command]
    assert loaded["foxglove"] is False, "Foxglove's library is the recorder's, not this command's"
    assert f"usage: zendock {command}" in str(loaded["usage"])


def test_top_level_help_still_lists_every_command() -> None:
    loaded = _loaded("--help")
    assert "record" in loaded["commands"] and "keys" in loaded["commands"]
    assert "undock" in str(loaded["usage"])


def test_a_command_registered_by_another_module_is_still_found() -> None:
    """``undock`` lives in the ``dock`` module: the whole parser is built and finds it."""
    loaded = _loaded("undock", "--help")
    assert "usage: zendock undock" in str(loaded["usage"])


def test_a_module_name_that_is_no_command_is_refused_among_every_command() -> None:
    """``lifecycle`` is a module (it registers start, stop, restart, kill), not a command: the error lists
    every command, as for any other word that is none."""
    done = subprocess.run(
        [sys.executable, "-m", "deploy.cli", "lifecycle"],
        cwd=REPO_ROOT,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 2
    assert "invalid choice: 'lifecycle'" in done.stderr
    assert "'trials'" in done.stderr and "'start'" in done.stderr
