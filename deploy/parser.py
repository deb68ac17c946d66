"""zendock's argument parser: a mistake names itself, with a "did you mean", in the usage of its own command.

argparse alone reports ``zendock trials --wrokers 2`` as ``argument merge: invalid choice: '2'`` (the ``2``
taken for a subcommand once the misspelled flag was set aside), and every unrecognised argument in the
top-level usage. This parser remembers the words it was given, so its error names the option it does not
know and the closest it does (:func:`difflib.get_close_matches`), and an invalid choice the closest choice;
:func:`error_in_command` reports leftovers in the usage of the subcommand they were typed under.
"""

from __future__ import annotations

import argparse
import re
from collections.abc import Sequence
from typing import NoReturn

from shared.suggestions import closest_names

_INVALID_CHOICE = re.compile(
    r"argument (?P<arg>.+?): invalid choice: '(?P<value>.*?)' \(choose from (?P<choices>.*)\)"
)


def _closest(word: str, candidates: Sequence[str]) -> str | None:
    found = closest_names(word, candidates)
    return found[0] if found else None


class ZendockParser(argparse.ArgumentParser):
    """An :class:`argparse.ArgumentParser` whose errors name the misspelled option or choice."""

    _words: list[str]

    def parse_known_args(  # type: ignore[override]
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> tuple[argparse.Namespace, list[str]]:
        self._words = list(args) if args is not None else []
        return super().parse_known_args(args, namespace)

    def options(self) -> list[str]:
        """Every option string this parser knows (``--workers``, ``-n``)."""
        return list(self._option_string_actions)

    def unknown_options(self, words: Sequence[str]) -> list[str]:
        """The words that look like options of this parser's and are none (before any ``--``)."""
        found = []
        for word in words:
            if word == "--":
                break
            name = word.split("=", 1)[0]
            if name.startswith("-") and not _is_number(name) and name not in self._option_string_actions:
                found.append(name)
        return found

    def explain(self, message: str) -> str:
        """``message`` with the misspelling named, where one is to blame."""
        words = getattr(self, "_words", [])
        unknown = self.unknown_options(words)
        choice = _INVALID_CHOICE.match(message)
        if choice is not None:
            value = choice["value"]
            before = words[words.index(value) - 1] if value in words[1:] else None
            if before is not None and before.split("=", 1)[0] in unknown:
                return self.unknown_message(before.split("=", 1)[0])  # the misspelled option's value
            choices = [c.strip().strip("'") for c in choice["choices"].split(",")]
            close = _closest(value, choices)
            return f"{message}; did you mean {close!r}?" if close else message
        if message.startswith("unrecognized arguments:") and unknown:
            return "; ".join(self.unknown_message(word) for word in unknown)
        return message

    def unknown_message(self, option: str) -> str:
        close = _closest(option, [o for o in self.options() if o.startswith("--")] or self.options())
        return f"unknown option {option}" + (f"; did you mean {close}?" if close else "")

    def error(self, message: str) -> NoReturn:
        super().error(self.explain(message))


def _is_number(word: str) -> bool:
    try:
        float(word)
    except ValueError:
        return False
    return True


def command_parser(parser: argparse.ArgumentParser, words: Sequence[str]) -> argparse.ArgumentParser:
    """The (sub)command parser the words were typed under: ``zendock trials merge ...`` -> trials merge's."""
    current = parser
    rest = list(words)
    while True:
        sub = next((a for a in current._actions if isinstance(a, argparse._SubParsersAction)), None)
        if sub is None:
            return current
        chosen = next((i for i, w in enumerate(rest) if w in sub.choices), None)
        if chosen is None:
            return current
        current, rest = sub.choices[rest[chosen]], rest[chosen + 1 :]


def error_in_command(parser: argparse.ArgumentParser, words: Sequence[str], extra: Sequence[str]) -> NoReturn:
    """Report the leftover ``extra`` words in the usage of the command they were typed under."""
    target = command_parser(parser, words)
    if isinstance(target, ZendockParser):
        target._words = list(words)
    target.error(f"unrecognized arguments: {' '.join(extra)}")
