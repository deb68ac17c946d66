"""``zendock export compose``: the stack file as a Compose file (one container per service), or the secure
overlay of a secure stack file, as honcho exports a Procfile to systemd units."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from deploy.export.compose import (
    compose_document,
    compose_header,
    render,
    secure_header,
    secure_overlay_document,
)
from deploy.launcher.stack_file import load_stack
from shared.config_errors import ConfigError

DEFAULT_STACK = "deploy/stack.yaml"
DEFAULT_SECURE_STACK = "deploy/stack-secure.yaml"


def export_compose(source: str, *, secure: bool = False, output: str | None = None) -> str:
    """The generated file's text: the Compose file of stack file ``source``, or with ``secure`` its overlay.

    ``source`` and ``output`` are named in the header as given, so the committed files do not depend on
    where the repository is checked out.
    """
    path = Path(source)
    if not path.is_file():
        raise ConfigError(f"{source}: no such stack file")
    stack = load_stack(path, env={}, project_dir=path.parent, interpolate=False)
    if secure:
        return render(secure_overlay_document(stack), secure_header(source, output))
    return render(compose_document(stack), compose_header(source, output))


def _compose(args: argparse.Namespace) -> int:
    source = args.file or (DEFAULT_SECURE_STACK if args.secure else DEFAULT_STACK)
    text = export_compose(source, secure=args.secure, output=args.output)
    if args.output:
        try:
            Path(args.output).write_text(text, encoding="utf-8")
        except OSError as exc:
            raise ConfigError(f"-o {args.output}: {exc.strerror}") from None
    else:
        sys.stdout.write(text)
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "export",
        help="write the stack as another tool's configuration (compose)",
        description="Generate another tool's configuration from the stack file, the one description of the "
        "deployment.",
    )
    formats = parser.add_subparsers(dest="format", metavar="FORMAT")
    formats.required = True
    compose = formats.add_parser(
        "compose",
        help="a Compose file: the router and each service in a container",
        description="Write the Compose file of a stack file (default: deploy/stack.yaml), or with --secure the "
        "secure overlay of a secure stack file (default: deploy/stack-secure.yaml). Variables stay as written, "
        "for Compose to interpolate.",
    )
    compose.add_argument("-f", "--file", metavar="STACK", help="the stack file")
    compose.add_argument(
        "--secure",
        action="store_true",
        help="the secure overlay (each service's own Zenoh user), layered on the compose file",
    )
    compose.add_argument("-o", "--output", metavar="FILE", help="write to FILE (default: standard output)")
    compose.set_defaults(func=_compose)
