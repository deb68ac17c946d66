"""Shipped worlds by name: ``--world seed_room`` (the name every report uses) finds deploy/worlds/seed_room.yaml.

A ``--world`` value is a world file or a directory of them as given, else the name of a shipped world
(its file's stem, or its path under ``deploy/worlds`` without ``.yaml``: ``fleet/depot``,
``unseen/hall``). An unknown one is refused naming the closest shipped worlds and where the list is.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from deploy.paths import REPO_ROOT
from shared.suggestions import closest_names, did_you_mean

WORLDS_DIR = REPO_ROOT / "deploy" / "worlds"


def shipped_worlds() -> dict[str, Path]:
    """Every shipped world by name: its path under deploy/worlds without ``.yaml`` and, where no two share
    it, its stem alone."""
    by_path = {str(p.relative_to(WORLDS_DIR).with_suffix("")): p for p in sorted(WORLDS_DIR.rglob("*.yaml"))}
    stems: dict[str, list[Path]] = {}
    for path in by_path.values():
        stems.setdefault(path.stem, []).append(path)
    return {**{stem: paths[0] for stem, paths in stems.items() if len(paths) == 1}, **by_path}


def find_world(text: str) -> Path:
    """The world file or directory ``text`` names; a ``ValueError`` naming the closest shipped worlds."""
    given = Path(text)
    if given.exists():
        return given
    if not given.is_absolute():
        for candidate in (REPO_ROOT / given, WORLDS_DIR / given):
            if candidate.exists():
                return candidate
    names = shipped_worlds()
    name = text.removesuffix(".yaml").removeprefix("deploy/worlds/")
    if name in names:
        return names[name]
    if given.is_absolute() or text.startswith("."):
        raise ValueError(f"{text}: no such file or directory")
    close = closest_names(name, names, n=3)
    hint = f"did you mean {' or '.join(close)}? " if close else ""
    top = ", ".join(sorted(p.stem for p in WORLDS_DIR.glob("*.yaml")))
    raise ValueError(
        f"no world file or shipped world {text!r}; {hint}shipped: {top} "
        "(and those in deploy/worlds/fleet and deploy/worlds/unseen)"
    )


def world_argument(text: str) -> str:
    """``--world``'s type: the path of the world file (or directory) ``text`` names."""
    try:
        return str(find_world(text))
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def world_file_argument(text: str) -> str:
    """``--world``'s type where one room is run: as :func:`world_argument`, refusing a directory of worlds."""
    path = Path(world_argument(text))
    if path.is_dir():
        first = next(iter(sorted(path.glob("*.yaml"))), None)
        example = f" such as {first}" if first is not None else ""
        raise argparse.ArgumentTypeError(f"{text} is a directory of worlds: give one world file{example}")
    return str(path)


#: ``--world generated:KIND``: rooms drawn from the campaign's seed.
GENERATED_PREFIX = "generated:"


def generated_kind(text: str) -> str | None:
    """The KIND of a ``generated:KIND`` world argument; None for any other."""
    return text.removeprefix(GENERATED_PREFIX) if text.startswith(GENERATED_PREFIX) else None


def campaign_world(text: str) -> str:
    """``zendock trials --world``'s type: as :func:`world_argument`, ``all`` for every shipped world, and
    ``generated:KIND`` for rooms drawn from the campaign's seed (:mod:`deploy.generated_worlds`)."""
    if text == "all":
        return text
    kind = generated_kind(text)
    if kind is not None:
        from shared.world_gen import KINDS  # noqa: PLC0415 - only a generated campaign needs it

        if kind not in KINDS:
            raise argparse.ArgumentTypeError(
                f"no kind of generated world {kind!r}{did_you_mean(kind, KINDS)} "
                f"(generated:KIND, KIND one of: {', '.join(KINDS)})"
            )
        return text
    return world_argument(text)
