"""A mistake on the command line names itself, with the closest thing zendock knows, in its own command's usage."""

from __future__ import annotations

import pytest

from deploy import cli
from deploy.paths import REPO_ROOT
from deploy.world_names import find_world, shipped_worlds


def _error(capsys: pytest.CaptureFixture[str], *argv: str) -> str:
    with pytest.raises(SystemExit) as exited:
        cli.main(list(argv))
    assert exited.value.code == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return err.strip().splitlines()[-1]


def test_a_misspelled_flag_is_named_with_the_closest_one(capsys: pytest.CaptureFixture[str]) -> None:
    # Without the parser's help this read "argument merge: invalid choice: '2'": the 2 taken for a subcommand.
    assert _error(capsys, "trials", "--wrokers", "2") == (
        "zendock trials: error: unknown option --wrokers; did you mean --workers?"
    )
    assert (
        _error(capsys, "up", "--detatch")
        == "zendock up: error: unknown option --detatch; did you mean --detach?"
    )


def test_a_misspelled_subcommand_gets_the_closest_and_the_usage_is_its_commands(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert _error(capsys, "demp").endswith("did you mean 'demo'?")
    assert _error(capsys, "keys", "ech").startswith(
        "zendock keys: error: argument VERB: invalid choice: 'ech'"
    )
    assert _error(capsys, "demo", "stray").startswith("zendock demo: error: unrecognized arguments: stray")


def test_a_world_is_found_by_its_name_and_an_unknown_one_lists_the_shipped_worlds(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert find_world("seed_room") == REPO_ROOT / "deploy" / "worlds" / "seed_room.yaml"
    assert find_world("fleet/depot") == REPO_ROOT / "deploy" / "worlds" / "fleet" / "depot.yaml"
    assert find_world("hall") == shipped_worlds()["unseen/hall"]
    line = _error(capsys, "trials", "--world", "seed_rom")
    assert "no world file or shipped world 'seed_rom'; did you mean seed_room?" in line
    assert "shipped: angled_dock, clutter, corridor" in line


@pytest.mark.parametrize("command", [("demo",), ("fleet",), ("conform", "simulator"), ("bench", "messages")])
def test_a_directory_where_one_room_is_run_names_itself_and_a_file_in_it(
    capsys: pytest.CaptureFixture[str], command: tuple[str, ...]
) -> None:
    # trials and bench ir take a directory as all its worlds; these run one room, and said "no such file".
    line = _error(capsys, *command, "--world", "unseen")
    assert "unseen is a directory of worlds: give one world file such as " in line, line
    assert "deploy/worlds/unseen/" in line and line.endswith(".yaml"), line
