"""The documentation site's generated pages: the CLI reference, the measurements page and the contracts.

One source, generated views. The CLI reference is written from ``deploy/cli.py``'s parser and its
subparsers (every command's ``--help``), so it cannot drift from the code; the measurements page is
rendered from ``docs/measurements/*.json`` (one file per measurement: what, result, command, commit,
date, machine and the numbers).

- ``mkdocs build`` loads this module as a hook (``mkdocs.yml``: ``hooks``): :func:`on_files` adds
  ``cli.md`` to the site, generated at build time and never committed (the CLI changes often).
- ``docs/measurements.md`` is committed, so it reads on GitHub too; ``python -m deploy.docs_site``
  rewrites it and ``--check`` exits 1 when it is stale (``tests/unit/test_docs_site.py`` checks the same).
- ``docs/contracts/`` (every service's contract and every message type's JSON Schema) is committed too,
  rendered from ``shared/contracts`` by :mod:`deploy.contracts.document`; the same command rewrites it.
- ``python -m deploy.docs_site --cli FILE`` writes the CLI reference to a file.

Pure apart from reading the JSON files and writing the page: no bus, no services.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from deploy.contracts.document import stale_files, write_files
from deploy.paths import REPO_ROOT
from shared.config_errors import ConfigError

DOCS_DIR = REPO_ROOT / "docs"
MEASUREMENTS_DIR = DOCS_DIR / "measurements"
MEASUREMENTS_PAGE = DOCS_DIR / "measurements.md"
#: Help is wrapped at this width whatever the terminal, so the reference is the same on every machine.
HELP_COLUMNS = "100"
MEASUREMENT_FIELDS = (
    "id",
    "order",
    "section",
    "status",
    "headline",
    "what",
    "result",
    "command",
    "commit",
    "recorded_in",
    "date",
    "machine",
    "numbers",
)
STATUSES = ("current", "history")


# --- the CLI reference -------------------------------------------------------------------------


def _subcommands(parser: argparse.ArgumentParser) -> Iterator[tuple[str, str, argparse.ArgumentParser]]:
    """(name, one-line help, parser) of each subcommand of ``parser``, in the order they were added."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            helps = {choice.dest: choice.help or "" for choice in action._choices_actions}
            seen: set[int] = set()
            for name, sub in action.choices.items():
                if id(sub) in seen:  # an alias of a command already listed
                    continue
                seen.add(id(sub))
                yield name, helps.get(name, ""), sub


def _walk(
    parser: argparse.ArgumentParser, path: tuple[str, ...]
) -> Iterator[tuple[tuple[str, ...], str, argparse.ArgumentParser]]:
    for name, help_text, sub in _subcommands(parser):
        yield (*path, name), help_text, sub
        yield from _walk(sub, (*path, name))


def _help_text(parser: argparse.ArgumentParser) -> str:
    previous = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = HELP_COLUMNS
    try:
        return parser.format_help().rstrip()
    finally:
        if previous is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = previous


def cli_reference(parser: argparse.ArgumentParser | None = None) -> str:
    """The CLI reference page (Markdown): an index of commands, then each command's ``--help``."""
    if parser is None:
        from deploy.cli import build_parser  # noqa: PLC0415 - the CLI imports every command module

        parser = build_parser()
    commands = list(_walk(parser, ()))
    out = [
        "# CLI reference",
        "",
        "<!-- Generated from deploy/cli.py's parsers by deploy/docs_site.py while the site builds. "
        "Do not edit. -->",
        "",
        "Every command below is `zendock COMMAND ...`, installed in `.venv/bin/zendock` by `make run` or "
        "`make test`. This page is generated from the parsers themselves, so it is what `--help` prints.",
        "",
        "| command | what it does |",
        "| --- | --- |",
    ]
    for path, help_text, _ in commands:
        anchor = "zendock-" + "-".join(path)
        out.append(
            f"| [`zendock {' '.join(path)}`](#{anchor}) | {_cell(help_text).replace('<', '&lt;').replace('>', '&gt;')} |"
        )
    out += ["", "## zendock", "", "```text", _help_text(parser), "```"]
    for path, _, sub in commands:
        level = "#" * min(2 + len(path) - 1, 4)
        anchor = "zendock-" + "-".join(path)
        out += ["", f"{level} zendock {' '.join(path)} {{#{anchor}}}", "", "```text", _help_text(sub), "```"]
    return "\n".join(out) + "\n"


# --- the measurements page ---------------------------------------------------------------------


def load_measurements(directory: Path = MEASUREMENTS_DIR) -> list[dict[str, Any]]:
    """Every measurement file, checked (the fields, the status), in the page's order."""
    records = []
    for path in sorted(directory.glob("*.json")):
        record = json.loads(path.read_text(encoding="utf-8"))
        missing = [field for field in MEASUREMENT_FIELDS if field not in record]
        if missing:
            raise ValueError(f"{path}: missing {', '.join(missing)}")
        if record["status"] not in STATUSES:
            raise ValueError(f"{path}: status must be one of {', '.join(STATUSES)}, not {record['status']!r}")
        headline = record["headline"]
        if (
            not isinstance(headline, str)
            or "\n" in headline
            or not headline.strip()
            or len(headline) > HEADLINE_MAX_CHARS
        ):
            raise ValueError(f"{path}: headline must be one line of at most {HEADLINE_MAX_CHARS} characters")
        if not isinstance(record["numbers"], dict) or not record["numbers"]:
            raise ValueError(f"{path}: numbers must be a non-empty object")
        record["_file"] = path.name
        records.append(record)
    return sorted(records, key=lambda r: r["order"])


def _cell(text: str) -> str:
    return " ".join(str(text).split()).replace("|", "\\|")


#: The longest headline a row of the measurements page carries (the story is on the measurement's own page).
HEADLINE_MAX_CHARS = 100


def measurement_stem(record: dict[str, Any]) -> str:
    """The measurement's file name without ``.json``: its own page is ``measurements/<stem>.md``."""
    return str(record["_file"]).removesuffix(".json")


def commands_of(record: dict[str, Any]) -> list[str]:
    """The commands a measurement names (its backquoted spans), or its whole command text if none is quoted."""
    spans = re.findall(r"`([^`]+)`", str(record["command"]))
    return spans or [" ".join(str(record["command"]).split())]


#: A commit as measurements name it: 7 to 40 hex digits.
_COMMIT_RE = re.compile(r"\b[0-9a-f]{7,40}\b")


def _commit_cell(record: dict[str, Any], *, hashes_only: bool = False) -> str:
    """The commit the measurement names (``hashes_only``: just its hashes, for a row of the table; its own
    page keeps the asides, "(before)", "(after; ...)"), else the one that recorded it."""
    commit = record["commit"]
    if not commit:
        return f"recorded in `{record['recorded_in']}`"
    hashes = _COMMIT_RE.findall(str(commit)) if hashes_only else []
    return ", ".join(f"`{h}`" for h in hashes) if hashes else f"`{commit}`"


def measurements_page(records: list[dict[str, Any]]) -> str:
    """The measurements page (Markdown): one line per measurement (its headline figure, its first command, its
    commit), current figures first, then the history; each row links to the measurement's own page."""
    out = [
        "# Measurements",
        "",
        "<!-- Generated from docs/measurements/*.json by `python -m deploy.docs_site`. Do not edit: "
        "edit the JSON and regenerate. -->",
        "",
        "Each figure the documentation reports comes from one file under `docs/measurements/` "
        "(the command, the commit, the date, the machine and the numbers); this page is rendered from "
        "them, one line per measurement. Each row links to the measurement's own page: what was measured, "
        "the whole result, every command, and the structured numbers. Everything was measured on the 2-core "
        "development machine, which other jobs shared (so timings are noisy). Trials run the whole "
        "distributed stack, two robots sharing one simulator, with sensor noise and a map->odom "
        "localisation error of (0.03 m, -0.02 m, 0.02 rad) on; `--world all` runs every shipped world "
        "(rows say how many there were then).",
        "",
        '*commit* is the commit the measurement names; where it names none ("the final code"), the '
        "commit that recorded the row is given instead, marked *recorded in*.",
        "",
    ]
    for status, title, intro in (
        ("current", "Current", "Figures on the code as it is (or the latest run of that measurement)."),
        (
            "history",
            "History",
            "Earlier code, superseded designs and before/after comparisons, kept as "
            "the record of why the code is as it is.",
        ),
    ):
        out += [
            f"## {title}",
            "",
            intro,
            "",
            "| # | figure | command | commit | date |",
            "| --- | --- | --- | --- | --- |",
        ]
        for r in records:
            if r["status"] != status:
                continue
            commands = commands_of(r)
            command = f"`{_cell(commands[0])}`" + (
                f" (+{len(commands) - 1} more)" if len(commands) > 1 else ""
            )
            link = f"[{_cell(r['headline'])}](measurements/{measurement_stem(r)}.md)"
            commit = _commit_cell(r, hashes_only=True)
            out.append(f"| {r['order']} | {link} | {command} | {commit} | {r['date']} |")
        out.append("")
    out += ["Each run's per-trial data, histograms and logs land in `runs/`.", ""]
    return "\n".join(out)


def measurement_detail_page(record: dict[str, Any]) -> str:
    """One measurement's own page: the story its row on the measurements page stands for."""
    numbers = json.dumps(record["numbers"], indent=2, ensure_ascii=False)
    out = [
        f"# {record['order']}. {record['headline']}",
        "",
        f"<!-- Generated from docs/measurements/{record['_file']} by deploy/docs_site.py. -->",
        "",
        f"*{record['section']}* · {record['status']} · {_commit_cell(record)} · {record['date']} · "
        f"[all measurements](../measurements.md)",
        "",
        "## What was measured",
        "",
        str(record["what"]),
        "",
        "## Result",
        "",
        str(record["result"]),
        "",
        "## Commands",
        "",
        *[f"```\n{command}\n```\n" for command in commands_of(record)],
        f"As the file gives them: {record['command']}",
        "",
        f"## Machine\n\n{record['machine']}",
        "",
        f"## Numbers\n\nFrom [`{record['_file']}`]({record['_file']}):\n\n```json\n{numbers}\n```",
        "",
    ]
    return "\n".join(out)


# --- the mkdocs hook and the command line ------------------------------------------------------


def on_files(files: Any, config: Any) -> Any:
    """mkdocs hook: add the generated CLI reference as ``cli.md`` and each measurement's own page."""
    from mkdocs.structure.files import File  # noqa: PLC0415 - mkdocs is there only while the site builds

    files.append(File.generated(config, "cli.md", content=cli_reference()))
    for record in load_measurements():
        path = f"measurements/{measurement_stem(record)}.md"
        files.append(File.generated(config, path, content=measurement_detail_page(record)))
    return files


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m deploy.docs_site", description=__doc__.splitlines()[0])
    parser.add_argument(
        "--check", action="store_true", help="exit 1 if docs/measurements.md or docs/contracts/ is stale"
    )
    parser.add_argument("--cli", metavar="FILE", help="also write the CLI reference to FILE")
    args = parser.parse_args(argv)
    page = measurements_page(load_measurements())
    if args.check:
        stale = (
            [str(MEASUREMENTS_PAGE)] if MEASUREMENTS_PAGE.read_text(encoding="utf-8") != page else []
        ) + [f"docs/contracts/{name}" for name in stale_files()]
        if stale:
            print(f"stale: {', '.join(stale)}: run python -m deploy.docs_site", file=sys.stderr)
            return 1
    else:
        MEASUREMENTS_PAGE.write_text(page, encoding="utf-8")
        write_files()
    if args.cli:
        Path(args.cli).write_text(cli_reference(), encoding="utf-8")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except ConfigError as exc:  # a contract changed under its version: say which and how to fix it
        print(f"python -m deploy.docs_site: {exc}", file=sys.stderr)
        sys.exit(2)
