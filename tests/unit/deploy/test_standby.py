"""The warm standby: it imports its service once, forks it at each ``go`` and reports each child's exit."""

from __future__ import annotations

import ast
import os
import subprocess
import sys
from pathlib import Path

import pytest

from deploy.launcher.plan import ZENDOCK_ROOT
from deploy.standby import STATUS_FD_ENV

STANDBY = [sys.executable, "-m", "deploy.standby"]


def _run(args: list[str], stdin: bytes) -> tuple[subprocess.CompletedProcess[bytes], list[str]]:
    """Run a standby to the end of ``stdin``; its output and its reports."""
    read_fd, write_fd = os.pipe()
    try:
        done = subprocess.run(
            [*STANDBY, *args],
            input=stdin,
            capture_output=True,
            cwd=ZENDOCK_ROOT,
            timeout=60,
            env={**os.environ, STATUS_FD_ENV: str(write_fd)},
            pass_fds=(write_fd,),
        )
    finally:
        os.close(write_fd)
    with os.fdopen(read_fd, "rb") as reports:
        return done, reports.read().decode().splitlines()


def test_each_go_forks_its_service_with_the_flags_it_was_given() -> None:
    """Two ``go``: two children, each printing the battery's usage and exiting 0, each reported."""
    done, reports = _run(["services.battery", "--help"], b"go\ngo\n")
    assert done.returncode == 0, done.stderr.decode()
    assert done.stdout.count(b"usage:") == 2 and b"battery" in done.stdout
    started = [int(line.split()[1]) for line in reports if line.startswith("started ")]
    assert len(started) == 2 and len(set(started)) == 2, reports
    assert b"RuntimeWarning" not in done.stderr  # runpy: the entry module runs afresh, not twice-loaded


def test_a_child_that_exits_is_reported_with_its_code() -> None:
    """The standby is still reading when the child exits, so the exit is reported (here: argparse's 2)."""
    read_fd, write_fd = os.pipe()
    proc = subprocess.Popen(
        [*STANDBY, "services.battery", "--no-such-flag"],
        stdin=subprocess.PIPE,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        cwd=ZENDOCK_ROOT,
        env={**os.environ, STATUS_FD_ENV: str(write_fd)},
        pass_fds=(write_fd,),
    )
    os.close(write_fd)
    assert proc.stdin is not None
    try:
        proc.stdin.write(b"go\n")
        proc.stdin.flush()
        with os.fdopen(read_fd, "rb") as reports:
            assert reports.readline() == b"ready\n"  # its imports done, before any fork
            started = reports.readline().decode().split()
            exited = reports.readline().decode().split()
        assert started[0] == "started" and exited == ["exited", started[1], "2"]
    finally:
        proc.stdin.close()
        proc.wait(30)
    assert proc.returncode == 0


def test_at_end_of_input_it_exits_quietly_without_running_its_service() -> None:
    done, reports = _run(["services.battery", "--help"], b"")
    assert (done.returncode, done.stdout, done.stderr, reports) == (0, b"", b"", ["ready"])


@pytest.mark.parametrize("args", [[], ["shared.node"]])
def test_it_stands_in_only_for_zendocks_services(args: list[str]) -> None:
    done, _ = _run(args, b"go\n")
    assert done.returncode == 2 and b"python -m deploy.standby services.<name>" in done.stderr


def test_an_import_that_fails_is_said_in_one_line() -> None:
    done, reports = _run(["services.nowhere"], b"go\n")
    assert done.returncode == 1 and reports == []
    assert done.stderr.decode().strip().startswith("warm standby: cannot import services.nowhere")


def _main_is_guarded(path: Path) -> bool:
    """Module level holds imports and plain calls only; ``main`` runs under ``if __name__ == "__main__"``."""
    for node in ast.parse(path.read_text(encoding="utf-8")).body:
        if isinstance(node, ast.If):
            test = node.test
            if (
                isinstance(test, ast.Compare)
                and isinstance(test.left, ast.Name)
                and test.left.id == "__name__"
            ):
                continue
            return False
        if isinstance(node, ast.Expr) and "main" in ast.unparse(node):
            return False
    return True


@pytest.mark.parametrize(
    "entry", sorted((ZENDOCK_ROOT / "services").glob("*/__main__.py")), ids=lambda p: p.parent.name
)
def test_every_services_entry_runs_main_only_as_the_main_module(entry: Path) -> None:
    """A standby imports ``services.<name>.__main__`` ahead of time: its main must wait for ``go``."""
    assert _main_is_guarded(entry), f"{entry}: call main() only under if __name__ == '__main__'"


def test_before_any_fork_the_service_s_messages_are_compiled_and_its_objects_frozen() -> None:
    """What a child would redo on its way to ready is done once: classes made dataclasses, codecs compiled,
    and the import's objects kept out of the children's collections."""
    code = (
        "import gc, importlib\n"
        "import deploy.standby as standby\n"
        "importlib.import_module('services.battery.__main__')\n"
        "from shared import schema\n"
        "assert schema._DEFERRED, 'the battery defines no deferred message class'\n"
        "standby._prepare_for_forks()\n"
        "types = schema.registered_types().values()\n"
        "print(len(schema._DEFERRED), all(isinstance(c.__dict__['_FIELDS'], tuple) for c in types))\n"
        "print(gc.get_freeze_count() > 10_000)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ZENDOCK_ROOT, timeout=60
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["0", "True", "True"]
