"""The ``zendock`` command: one subcommand per module in :mod:`deploy.commands`.

Each command module defines ``register(subparsers)``, which adds its parser(s) and sets ``func`` to a
callable taking the parsed arguments and returning an exit code. Bad arguments exit 2 with argparse's
message, naming a misspelled option or choice with the closest one (:mod:`deploy.parser`); a
:class:`~shared.config_errors.ConfigError` from a command prints one line and exits 2.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.metadata
import pkgutil
import signal
import sys
from collections.abc import Sequence
from typing import Any, cast

from deploy import commands
from deploy.parser import ZendockParser, command_parser, error_in_command
from shared.config_errors import CONFIG_ERROR_EXIT, ConfigError
from shared.memory import keep_blas_single_threaded, keep_openssl_out


def installed_version() -> str:
    """The version of the installed ``zendock`` distribution (its package metadata)."""
    try:
        return importlib.metadata.version("zendock")
    except importlib.metadata.PackageNotFoundError:
        return "unknown (not installed)"


class _ShowsDefaults(argparse.HelpFormatter):
    """Adds ``(default: X)`` to an option's help, unless the help already speaks of its default or there is
    nothing worth saying (no default, a flag that is off, an empty list)."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        default = action.default
        if (
            not action.option_strings
            or "default" in text.lower()
            or default is None
            or default is False
            or default == argparse.SUPPRESS
            or (isinstance(default, list | tuple) and not default)
            or text == argparse.SUPPRESS
        ):
            return action.help
        return f"{text} (default: %(default)s)"


def _show_defaults(parser: argparse.ArgumentParser) -> None:
    """Every parser, subcommands' too, shows its options' defaults, keeping its own formatter otherwise."""
    # argparse types formatter_class as a callable; every parser here is given a HelpFormatter class.
    own = cast(type[argparse.HelpFormatter], parser.formatter_class)
    if not issubclass(own, _ShowsDefaults):
        parser.formatter_class = cast(Any, type("ShowsDefaults", (_ShowsDefaults, own), {}))
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                _show_defaults(sub)


#: Commands that run as long-lived processes of a stack (the router, a container of composed services): like
#: every command they load only their own module (:func:`command_module`), and OpenSSL not at all (as in the
#: services), so the process holds only what it uses (what that saves the router: measurement 61).
LEAN_COMMANDS = frozenset({"container", "router"})


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The ``zendock`` parser: every command's, or with ``only`` that one command module's alone."""
    parser = ZendockParser(
        prog="zendock",
        description="Autonomous docking for a two-wheeled robot, as services over Zenoh.",
    )
    parser.add_argument("--version", action="version", version=f"zendock {installed_version()}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    subparsers.required = True
    for info in sorted(pkgutil.iter_modules(commands.__path__), key=lambda m: m.name):
        if only is not None and info.name != only:
            continue
        module = importlib.import_module(f"{commands.__name__}.{info.name}")
        register = getattr(module, "register", None)
        if callable(register):
            register(subparsers)
    _show_defaults(parser)
    return parser


def _terminate_like_interrupt(signum: int, _frame: object) -> None:
    raise KeyboardInterrupt(f"signal {signum}")


def command_module(argv: Sequence[str]) -> str | None:
    """The command module ``argv`` names, when its first word is one (``fleet``, ``keys``), else None.

    A command module registers its own command under its own name, so that module alone parses the line:
    a run holds only the code of the command it runs. Anything else (``--help``, ``undock``, a misspelled
    command, and ``lifecycle``, a module whose commands have other names: :func:`main` checks) is parsed by
    every command's parser, so the usage and the "did you mean" see them all."""
    if not argv or argv[0].startswith("-"):
        return None
    names = {info.name for info in pkgutil.iter_modules(commands.__path__)}
    return argv[0] if argv[0] in names else None


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv[:1] and argv[0] in LEAN_COMMANDS:
        # A container runs services in this process, so it starts them as their own ``__main__`` would.
        keep_openssl_out()
        keep_blas_single_threaded()
    module = command_module(argv)
    parser = build_parser(only=module)
    if module is not None and command_parser(parser, [module]) is parser:
        parser = build_parser()  # a module that registers other names (``lifecycle``): not a command
    args, extra = parser.parse_known_args(argv)
    # A command that runs another program (``conform SERVICE -- COMMAND ...``) takes everything after ``--``.
    if extra and getattr(args, "takes_command", False) and extra[0] == "--":
        args.command_words = extra[1:]
    elif extra:
        error_in_command(parser, argv, extra)
    # SIGTERM (kill, a CI timeout, a supervisor) unwinds like Ctrl-C, so every ``with Launcher(...)`` brings
    # its stack down instead of leaving the services it started running. Commands that handle signals
    # themselves (``up`` in the foreground) install their own handlers over this one.
    if signal.getsignal(signal.SIGTERM) is signal.SIG_DFL:
        signal.signal(signal.SIGTERM, _terminate_like_interrupt)
    try:
        return int(args.func(args) or 0)
    except ConfigError as exc:
        print(f"zendock {getattr(args, 'command_path', args.command)}: {exc}", file=sys.stderr)
        return CONFIG_ERROR_EXIT
    except KeyboardInterrupt as exc:
        why = f" ({exc})" if str(exc) else ""
        print(f"zendock {getattr(args, 'command_path', args.command)}: interrupted{why}", file=sys.stderr)
        return 130
    except TimeoutError as exc:
        from deploy.launcher.api import StackNotReady  # noqa: PLC0415 - lean commands never load the launcher

        if not isinstance(exc, StackNotReady):
            raise
        # One line: which service was not ready and the last line it printed.
        print(f"zendock {getattr(args, 'command_path', args.command)}: {exc.summary}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
