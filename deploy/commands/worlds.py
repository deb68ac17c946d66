"""``zendock worlds generate``: rooms nobody tuned for, drawn from a seed (see :mod:`shared.world_gen`).

Each room is written as a world file, one per seed, and kept only when the dock can be reached (the
planner's lower-bound tool says so); ``zendock trials --world generated:KIND`` makes its rooms the same way.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from deploy.arg_types import count, seed
from shared.config_errors import ConfigError
from shared.world_gen import KINDS


def _generate(args: argparse.Namespace) -> int:
    from deploy.generated_worlds import generate_rooms  # noqa: PLC0415 - the planner's tool only when used

    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise ConfigError(f"--out {out}: not a directory")
    try:
        paths = generate_rooms(args.kind, args.seed, args.count, out)
    except RuntimeError as exc:
        raise ConfigError(str(exc)) from None
    except OSError as exc:  # a parent that is a file, no permission, a read-only place
        raise ConfigError(f"--out {out}: cannot write rooms there: {exc.strerror or exc}") from None
    for path in paths:
        print(path)
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("worlds", help="generated rooms: worlds drawn from a seed")
    verbs = parser.add_subparsers(dest="worlds_command", metavar="VERB")
    verbs.required = True
    generate = verbs.add_parser(
        "generate",
        help="write rooms of a kind, one per seed, each with a reachable dock",
        description="Draw rooms from seeds and write each as a world file (name generated-KIND-SEED). "
        "room: ordinary rooms with partitions and boxes; glass: glass-heavy rooms up to 18 x 13 m halls, "
        "panes at any angle, alcoves of glass round the dock, glass partitions. "
        "Example: zendock worlds generate --kind glass --seed 1 --count 20 --out rooms/",
    )
    generate.add_argument(
        "--kind", choices=KINDS, default="glass", help="what rooms to draw (default: glass)"
    )
    generate.add_argument("--seed", type=seed, default=0, help="the first room's seed (default: 0)")
    generate.add_argument("--count", type=count, default=1, help="how many rooms, seeds on from --seed")
    generate.add_argument("--out", default=".", metavar="DIR", help="where to write them (default: .)")
    generate.set_defaults(func=_generate)
