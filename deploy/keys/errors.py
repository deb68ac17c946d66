"""The one error the ``keys`` verbs raise: a one-line message and the exit code it maps to."""

from __future__ import annotations

#: Nothing answered, or the thing asked about does not exist on the bus.
EXIT_NOT_FOUND = 1
#: The user's input is wrong (a bad key, type, field or value); nothing was sent.
EXIT_USAGE = 2


class KeysError(Exception):
    """A verb cannot do what was asked; ``str(error)`` is the line printed to the user."""

    def __init__(self, message: str, exit_code: int = EXIT_NOT_FOUND) -> None:
        super().__init__(message)
        self.exit_code = exit_code
