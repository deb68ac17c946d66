"""Completion scripts generated from an argparse parser: the tree read from it, and the scripts run in bash
(and zsh, where installed) with the shells' completion entry points stubbed."""

from __future__ import annotations

import argparse
import shutil
import subprocess

import pytest

from deploy.cli import build_parser
from deploy.completion import bash_script, command_tree, zsh_script


def _demo_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="demo")
    parser.add_argument("--version", action="version", version="1")
    sub = parser.add_subparsers(dest="command")
    keys = sub.add_parser("keys", help="keys: on the bus")
    verbs = keys.add_subparsers(dest="verb")
    echo = verbs.add_parser("echo", help="print messages")
    echo.add_argument("key")
    echo.add_argument("--times", type=int, help="print N (default %(default)s)", default=3)
    echo.add_argument("--style", choices=["yaml", "csv"])
    echo.add_argument("--once", action="store_true")
    shell = sub.add_parser("completion", help="a script")
    shell.add_argument("shell", choices=["bash", "zsh"])
    sub.add_parser("hidden", help=argparse.SUPPRESS)
    return parser


def test_the_tree_has_subcommands_options_and_choices() -> None:
    tree = command_tree(_demo_parser())
    assert list(tree.subcommands) == ["keys", "completion", "hidden"]
    echo = tree.subcommands["keys"].subcommands["echo"]
    assert echo.path == ("keys", "echo") and echo.help == "print messages"
    options = {o.flags[-1]: o for o in echo.options}
    assert options["--times"].takes_value and options["--times"].help == "print N (default 3)"
    assert options["--style"].choices == ("yaml", "csv")
    assert not options["--once"].takes_value
    assert tree.subcommands["completion"].words == ["bash", "zsh"]


def _bash_complete(script: str, *words: str) -> list[str]:
    words_text = " ".join(f"'{w}'" for w in words)
    probe = (
        f"{script}\nCOMP_WORDS=({words_text}); COMP_CWORD={len(words) - 1}; _demo; "
        'printf "%s\\n" "${COMPREPLY[@]}"'
    )
    result = subprocess.run(["bash", "-c", probe], capture_output=True, text=True, timeout=30, check=True)
    return result.stdout.split()


def test_bash_completes_subcommands_options_and_choices() -> None:
    script = bash_script(command_tree(_demo_parser()), "demo")
    assert "complete -o bashdefault -o default -F _demo demo" in script
    assert _bash_complete(script, "demo", "") == ["keys", "completion", "hidden"]
    assert _bash_complete(script, "demo", "k") == ["keys"]
    assert _bash_complete(script, "demo", "keys", "") == ["echo"]
    assert _bash_complete(script, "demo", "keys", "echo", "--s") == ["--style"]
    assert _bash_complete(script, "demo", "keys", "echo", "--style", "") == ["yaml", "csv"]
    assert _bash_complete(script, "demo", "keys", "echo", "--times", "") == []  # a free value: files
    assert _bash_complete(script, "demo", "completion", "") == ["bash", "zsh"]
    assert _bash_complete(script, "demo", "--v") == ["--version"]


@pytest.mark.skipif(shutil.which("zsh") is None, reason="zsh is not installed")
def test_zsh_completes_with_descriptions() -> None:
    script = zsh_script(command_tree(_demo_parser()), "demo")
    stubs = (
        "compdef() { :; }\n"
        "_describe() { local arr=$4; print -rl -- ${(P)arr}; }\n"
        "compadd() { shift; print -rl -- $@; }\n"
        "_files() { print -r -- '<files>'; }\n"
    )

    def complete(*words: str) -> list[str]:
        quoted = " ".join(f"'{w}'" for w in words)
        probe = f"{stubs}{script}\nwords=({quoted}); CURRENT={len(words)}; _demo"
        result = subprocess.run(
            ["zsh", "-f", "-c", probe], capture_output=True, text=True, timeout=30, check=True
        )
        return result.stdout.splitlines()

    assert complete("demo", "") == ["keys:keys: on the bus", "completion:a script", "hidden"]
    assert complete("demo", "keys", "echo", "--st") == [
        "-h:show this help message and exit",
        "--help:show this help message and exit",
        "--times:print N (default 3)",
        "--style",
        "--once",
    ]
    assert complete("demo", "keys", "echo", "--style", "") == ["yaml", "csv"]
    assert complete("demo", "keys", "echo", "--times", "") == ["<files>"]


def test_zendocks_own_parser_gives_a_script_with_every_command() -> None:
    parser = build_parser()
    tree = command_tree(parser)
    assert {"nodes", "param", "completion", "keys"} <= set(tree.subcommands)
    assert list(tree.subcommands["param"].subcommands) == ["list", "get", "set"]
    for script in (bash_script(tree), zsh_script(tree)):
        assert '"param")' in script or "'param')" in script
