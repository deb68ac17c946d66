"""``zendock config``: the validated, interpolated stack, as the launcher will run it."""

from __future__ import annotations

import argparse

import yaml

from deploy.launcher.project import (
    active_profiles,
    add_project_options,
    add_stack_options,
    load_project_stack,
)


def main(args: argparse.Namespace) -> int:
    stack = load_project_stack(args)
    if args.quiet:
        return 0
    if args.services:
        profiles = active_profiles(args, stack)
        print("\n".join(stack.select((), profiles) if profiles else stack.services))
    elif args.profiles:
        print("\n".join(stack.profiles))
    else:
        print(yaml.safe_dump(stack.to_dict(), sort_keys=False, default_flow_style=None, width=110), end="")
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "config",
        help="validate the stack file and print it interpolated",
        description="Validate the stack file and print it with variables substituted and defaults filled in. "
        "Exit 2 with 'FILE: path.of.key: reason' lines when it is invalid.",
    )
    add_project_options(parser)
    add_stack_options(parser)
    group = parser.add_mutually_exclusive_group()
    group.add_argument("-q", "--quiet", action="store_true", help="only validate")
    group.add_argument("--services", action="store_true", help="list the service names")
    group.add_argument("--profiles", action="store_true", help="list the profiles")
    parser.set_defaults(func=main)
