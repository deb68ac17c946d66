"""The documentation's generated pages: the committed measurements page is the one its JSON renders, every
measurement file carries its command and commit, and the CLI reference covers every subcommand."""

from __future__ import annotations

import argparse

from deploy.cli import build_parser
from deploy.docs_site import (
    HEADLINE_MAX_CHARS,
    MEASUREMENTS_PAGE,
    cli_reference,
    load_measurements,
    measurement_detail_page,
    measurement_stem,
    measurements_page,
)


def test_committed_measurements_page_is_current():
    rendered = measurements_page(load_measurements())
    assert MEASUREMENTS_PAGE.read_text(encoding="utf-8") == rendered, (
        "docs/measurements.md is stale: run python -m deploy.docs_site"
    )


def test_every_measurement_names_its_command_and_commit():
    records = load_measurements()
    assert records, "no measurements under docs/measurements/"
    assert len({r["id"] for r in records}) == len(records)
    assert sorted(r["order"] for r in records) == list(range(1, len(records) + 1))
    for record in records:
        assert record["command"].strip(), record["id"]
        assert record["commit"] or record["recorded_in"], record["id"]
        assert "2-core" in record["machine"], record["id"]


def test_each_measurement_is_one_row_linking_to_a_page_with_its_whole_story():
    records = load_measurements()
    page = measurements_page(records)
    rows = [
        line for line in page.splitlines() if line.startswith("| ") and not line.startswith(("| #", "| ---"))
    ]
    assert len(rows) == len(records)
    for record in records:
        (row,) = [line for line in rows if line.startswith(f"| {record['order']} |")]
        assert f"](measurements/{measurement_stem(record)}.md)" in row
        assert len(record["headline"]) <= HEADLINE_MAX_CHARS and record["headline"] in row
        assert record["result"] not in row or len(record["result"]) <= HEADLINE_MAX_CHARS
        detail = measurement_detail_page(record)
        for field in ("headline", "what", "result", "machine"):
            assert str(record[field]) in detail, (record["id"], field)
        assert f'"{next(iter(record["numbers"]))}"' in detail, record["id"]


def _commands(parser: argparse.ArgumentParser, path: tuple[str, ...] = ()):
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield (*path, name)
                yield from _commands(sub, (*path, name))


def test_cli_reference_covers_every_subcommand():
    parser = build_parser()
    page = cli_reference(parser)
    for path in _commands(parser):
        assert f"usage: zendock {' '.join(path)}" in page, path
