"""Service output with a coloured, aligned ``name |`` prefix, as ``docker compose up`` prints it.

The printer writes to any text stream, so tests pass a ``StringIO`` (colour off).
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from typing import TextIO

_COLOURS = ("36", "33", "32", "35", "34", "96", "93", "92", "95", "94")
_RESET = "\033[0m"


def colour_wanted(stream: TextIO) -> bool:
    """Colour on a terminal unless ``NO_COLOR`` is set; ``FORCE_COLOR`` forces it."""
    if os.environ.get("NO_COLOR"):
        return False
    if os.environ.get("FORCE_COLOR"):
        return True
    isatty = getattr(stream, "isatty", None)
    return bool(isatty and isatty())


class Printer:
    def __init__(self, stream: TextIO, names: Iterable[str], colour: bool | None = None) -> None:
        self.stream: TextIO | None = stream
        self.colour = colour_wanted(stream) if colour is None else colour
        self._width = 0
        self._colours: dict[str, str] = {}
        for name in names:
            self.add_name(name)

    def add_name(self, name: str) -> None:
        if name not in self._colours:
            self._colours[name] = _COLOURS[len(self._colours) % len(_COLOURS)]
            self._width = max(self._width, len(name))

    def prefix(self, name: str) -> str:
        self.add_name(name)
        text = f"{name.ljust(self._width)} | "
        return f"\033[{self._colours[name]}m{text}{_RESET}" if self.colour else text

    def line(self, name: str, text: str) -> None:
        """Print one line; a closed stream (``zendock up | head``) silences the printer, not the stack."""
        if self.stream is None:
            return
        try:
            self.stream.write(f"{self.prefix(name)}{text}\n")
            self.stream.flush()
        except (BrokenPipeError, ValueError, OSError):
            self.stream = None
