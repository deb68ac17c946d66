"""``zendock completion bash|zsh``: print a shell completion script generated from zendock's own parser.

Usage: ``source <(zendock completion bash)`` (or zsh) in the shell's rc file. See :mod:`deploy.completion`.
"""

from __future__ import annotations

import argparse
import sys

from deploy.completion import bash_script, command_tree, zsh_script

SHELLS = {"bash": bash_script, "zsh": zsh_script}


def _run(args: argparse.Namespace) -> int:
    from deploy.cli import build_parser  # noqa: PLC0415 - the CLI imports this module to build itself

    sys.stdout.write(SHELLS[args.shell](command_tree(build_parser()), "zendock"))
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "completion",
        help="print a shell completion script (bash or zsh)",
        description="Print a completion script for zendock's subcommands and options, generated from its "
        "argument parser. Load it with: source <(zendock completion bash)",
    )
    p.add_argument("shell", choices=sorted(SHELLS), help="the shell to complete in")
    p.set_defaults(func=_run)
