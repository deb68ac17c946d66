"""``zendock keys echo KEY``: print messages as they arrive, as ``ros2 topic echo`` does.

Wildcards are allowed (``robot1/**``); each message is then preceded by a ``# key [type]`` comment. A
payload that does not decode is printed as raw bytes with a note; echo never stops on bad input. Samples
are decoded and printed on the caller's thread; if printing falls behind, the oldest are dropped and the
count reported at the end.
"""

from __future__ import annotations

import sys
import threading
import time
from collections import deque
from dataclasses import dataclass, replace
from typing import TextIO

from deploy.keys.connection import BusOptions, has_wildcards, open_bus, resolve_key
from deploy.keys.decoding import decode_payload
from deploy.keys.errors import EXIT_USAGE, KeysError
from deploy.keys.render import EchoFormat, FieldNotFound, write_sample
from deploy.keys.sampling import KeyWatch, ReceivedSample

BACKLOG = 1000
_POLL_S = 0.2


@dataclass(frozen=True)
class EchoRequest:
    key: str
    fmt: EchoFormat = EchoFormat()
    count: int | None = None  # stop after this many messages (--once: 1)
    timeout_s: float | None = None  # give up after this long

    def check(self) -> None:
        if self.count is not None and self.count < 1:
            raise KeysError(f"--times must be at least 1, got {self.count}", EXIT_USAGE)
        if self.timeout_s is not None and not self.timeout_s > 0:
            raise KeysError(f"--timeout must be positive, got {self.timeout_s:g}", EXIT_USAGE)
        if self.fmt.raw and (self.fmt.csv or self.fmt.field):
            raise KeysError(
                "--raw prints whole payloads; it does not combine with --csv or --field", EXIT_USAGE
            )


class _Backlog:
    """Samples waiting to be printed; the oldest go first when printing falls behind."""

    def __init__(self) -> None:
        self._items: deque[ReceivedSample] = deque()
        self._cv = threading.Condition()
        self.dropped = 0

    def put(self, _index: int, sample: ReceivedSample) -> None:
        with self._cv:
            if len(self._items) >= BACKLOG:
                self._items.popleft()
                self.dropped += 1
            self._items.append(sample)
            self._cv.notify()

    def get(self, timeout_s: float) -> ReceivedSample | None:
        with self._cv:
            if not self._items:
                self._cv.wait(timeout_s)
            return self._items.popleft() if self._items else None


def run_echo(
    options: BusOptions,
    request: EchoRequest,
    out: TextIO,
    err: TextIO | None = None,
    stop: threading.Event | None = None,
) -> int:
    """Print messages on the key until the count is reached, the timeout passes, ``stop`` is set or Ctrl-C."""
    request.check()
    err = err or sys.stderr
    key = resolve_key(options.namespace, request.key)
    wildcard = has_wildcards(key)
    fmt = replace(request.fmt, show_key=request.fmt.show_key or wildcard, strict_field=not wildcard)
    backlog = _Backlog()
    shown = 0
    deadline = time.monotonic() + request.timeout_s if request.timeout_s is not None else None
    with open_bus(options) as session:
        watch = KeyWatch(session, [key], backlog.put)
        try:
            while request.count is None or shown < request.count:
                if stop is not None and stop.is_set():
                    break
                remaining = deadline - time.monotonic() if deadline is not None else _POLL_S
                if remaining <= 0:
                    break
                sample = backlog.get(min(remaining, _POLL_S))
                if sample is None:
                    continue
                decoded = decode_payload(sample.key, sample.payload, sample.encoding, sample.sequence)
                try:
                    write_sample(out, decoded, fmt)
                except FieldNotFound as exc:
                    raise KeysError(f"--field {fmt.field}: {exc}", EXIT_USAGE) from None
                shown += 1
        except KeyboardInterrupt:
            pass
        finally:
            watch.close()
    if backlog.dropped:
        err.write(f"zendock keys echo: {backlog.dropped} message(s) dropped because printing fell behind\n")
    if shown == 0 and deadline is not None:
        raise KeysError(
            f"no message on {key} within {request.timeout_s:g} s "
            "(is anything publishing? 'zendock keys list -v' shows the keys in use)"
        )
    return 0
