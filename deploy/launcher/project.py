"""Which stack and which project a ``zendock`` command is about, from its options (shared by the commands).

The project directory (default: the current one) holds ``.env`` and ``.zendock/<project>/``; the stack file
defaults to ``$ZENDOCK_STACK_FILE``, else the first of ``stack.yaml``, ``zendock.yaml``, ``deploy/stack.yaml``
found there; the project is named by ``-p``, else the stack's ``name``, else the directory's name.
"""

from __future__ import annotations

import argparse
import os
from dataclasses import replace
from pathlib import Path

from deploy.launcher.overrides import apply_sets
from deploy.launcher.runtime import RUNTIME_DIRNAME, RuntimePaths
from deploy.launcher.stack_file import Stack, load_stack, project_name_from_dir, read_document
from deploy.replacements import apply_replacements
from shared.config_errors import ConfigError
from shared.suggestions import each_with_a_guess

STACK_FILE_NAMES = ("stack.yaml", "zendock.yaml", "deploy/stack.yaml")


def add_project_options(parser: argparse.ArgumentParser, *, short_file_flag: bool = True) -> None:
    flags = ("-f", "--file") if short_file_flag else ("--file",)
    parser.add_argument(
        *flags, dest="file", metavar="FILE", help="the stack file (default: deploy/stack.yaml)"
    )
    parser.add_argument(
        "-p", "--project-name", metavar="NAME", help="the project name (default: the stack's name)"
    )
    parser.add_argument(
        "--project-directory", metavar="DIR", help="where .env and .zendock/ live (default: .)"
    )


def add_stack_options(parser: argparse.ArgumentParser) -> None:
    """Options that change what the stack file resolves to (up, config)."""
    parser.add_argument(
        "--env-file", metavar="FILE", help="variables for interpolation (default: ./.env if present)"
    )
    parser.add_argument(
        "--profile", action="append", default=[], metavar="PROFILE", help="enable a profile (repeatable)"
    )


def project_dir(args: argparse.Namespace) -> Path:
    return Path(getattr(args, "project_directory", None) or ".").resolve()


def find_stack_file(args: argparse.Namespace) -> Path | None:
    if getattr(args, "file", None):
        return Path(args.file)
    from_env = os.environ.get("ZENDOCK_STACK_FILE")
    if from_env:
        return Path(from_env)
    for name in STACK_FILE_NAMES:
        candidate = project_dir(args) / name
        if candidate.is_file():
            return candidate
    return None


def no_stack_file(path: Path | None) -> ConfigError:
    """The error of a command that needs a stack file and found none (or not the one it was given)."""
    if path is not None:
        return ConfigError(f"{path}: no such stack file")
    return ConfigError(f"no stack file: pass -f FILE or create one of {', '.join(STACK_FILE_NAMES)}")


def load_project_stack(args: argparse.Namespace) -> Stack:
    path = find_stack_file(args)
    if path is None:
        raise no_stack_file(path)
    env_file = getattr(args, "env_file", None)
    stack = load_stack(path, env_file=env_file, project_dir=project_dir(args), project_name=args.project_name)
    # ``--set SERVICE.NAME=VALUE`` first: a replacement then gets the overridden flags as zendock's own would.
    stack = apply_sets(stack, getattr(args, "sets", None) or [])
    replacements = getattr(args, "replacements", None) or []
    namespace = getattr(args, "namespace", None)
    if replacements and namespace is not None:  # {robot} is the namespace the service will run in
        return replace(
            apply_replacements(replace(stack, namespace=namespace), replacements), namespace=stack.namespace
        )
    return apply_replacements(stack, replacements)


def active_profiles(args: argparse.Namespace, stack: Stack | None = None) -> list[str]:
    """``--profile`` options, else ``$ZENDOCK_PROFILES`` (comma-separated).

    With ``stack``, a profile none of its services has is a :class:`ConfigError` with a "did you mean": it
    would otherwise start the stack without what the profile was asked for, and say nothing."""
    profiles = list(getattr(args, "profile", None) or [])
    source = "--profile"
    if not profiles and os.environ.get("ZENDOCK_PROFILES"):
        profiles = [p.strip() for p in os.environ["ZENDOCK_PROFILES"].split(",") if p.strip()]
        source = "ZENDOCK_PROFILES"
    if stack is not None:
        unknown = [p for p in profiles if p not in stack.profiles]
        if unknown:
            known = f"its profiles: {', '.join(stack.profiles)}" if stack.profiles else "it has no profiles"
            raise ConfigError(
                f"{source} {each_with_a_guess(unknown, stack.profiles)}: no service of {stack.source} "
                f"has that profile ({known})"
            )
    return profiles


def resolve_project(args: argparse.Namespace) -> tuple[str, RuntimePaths, Stack | None]:
    """The project's name, runtime paths and (when it loads) its stack, for commands on a running stack.

    An unreadable or invalid stack file does not stop ``down`` or ``ps``: the name then comes from the
    file's ``name`` key, the only project under ``.zendock/``, or the directory's name.
    """
    directory = project_dir(args)
    stack: Stack | None = None
    name = args.project_name
    path = find_stack_file(args)
    if path is not None and path.is_file():
        try:
            stack = load_stack(path, project_dir=directory, project_name=name)
            name = stack.project_name
        except ConfigError:
            raw_name = _raw_name(path)
            name = name or raw_name
    if name is None:
        existing = sorted(p.name for p in (directory / RUNTIME_DIRNAME).glob("*") if p.is_dir())
        name = existing[0] if len(existing) == 1 else project_name_from_dir(directory)
    return name, RuntimePaths.for_project(directory, name), stack


def _raw_name(path: Path) -> str | None:
    try:
        value = read_document(path).get("name")
    except ConfigError:
        return None
    return value if isinstance(value, str) and "$" not in value else None
