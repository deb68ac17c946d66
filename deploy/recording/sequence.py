"""Losses counted from sequence numbers: every zendock publisher numbers its samples 1, 2, 3, ...

A recorder compares what was published (the numbers) with what arrived. Each stream is one publisher on
one key. When a sample names its publisher (its attachment's publisher id) streams are exact; otherwise
a key's samples are matched to streams by continuity: a number continues the stream whose last number is
one less; a ``1`` is a publisher that (re)started; a first sight of a publisher (the recorder joined
late) starts a stream without counting a loss, as long as the key has fewer streams than publishers (the
graph's liveliness tokens say how many publishers a key has). Anything else is a gap in the stream whose
last number is closest below it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field


@dataclass(frozen=True)
class _Unnamed:
    """The id of a stream told apart by its numbers alone (its samples did not name their publisher)."""

    index: int


@dataclass
class Stream:
    """One publisher's numbers on one key, as seen by the recorder."""

    first: int
    last: int
    received: int = 1
    lost: int = 0
    gaps: list[tuple[int, int]] = field(default_factory=list)  # (first missing, last missing)
    restarts: int = 0
    last_seen_s: float = 0.0

    @property
    def expected(self) -> int:
        """Samples published from the first seen to the last seen (restarts counted as received)."""
        return self.received + self.lost


@dataclass
class KeyTally:
    """Counts for one key: received, unnumbered, lost, and the streams behind them."""

    key: str
    received: int = 0
    unnumbered: int = 0
    duplicates: int = 0
    streams: dict[object, Stream] = field(default_factory=dict)
    #: Streams whose publisher restarted or went away: kept for their counts.
    retired: list[Stream] = field(default_factory=list)

    def all_streams(self) -> list[Stream]:
        return [*self.retired, *self.streams.values()]

    @property
    def lost(self) -> int:
        return sum(s.lost for s in self.all_streams())

    @property
    def gaps(self) -> list[tuple[int, int]]:
        return [g for s in self.all_streams() for g in s.gaps]

    def retire(self, stream_id: object) -> None:
        self.retired.append(self.streams.pop(stream_id))


class SequenceTracker:
    """Feeds on ``(key, sequence, source)`` and keeps per-key tallies of received and lost samples.

    ``publishers_on`` (optional) says how many publishers the graph knows on a key; without it each key
    is assumed to have one (per source when sources are known).
    """

    #: A stream silent this long is taken for a publisher that went away when a new one must be placed.
    STALE_AFTER_S = 5.0

    def __init__(self, publishers_on: Callable[[str], int] | None = None) -> None:
        self._publishers_on: Callable[[str], int] = publishers_on or (lambda _key: 1)
        self.keys: dict[str, KeyTally] = {}
        self._next_anonymous = 0

    def feed(self, key: str, sequence: int | None, source: object | None = None, now_s: float = 0.0) -> int:
        """Account for one sample; returns how many samples it shows were lost just before it."""
        tally = self.keys.get(key)
        if tally is None:
            tally = self.keys[key] = KeyTally(key)
        tally.received += 1
        if sequence is None:
            tally.unnumbered += 1
            return 0
        if source is not None:
            return self._feed_known(tally, sequence, source, now_s)
        return self._feed_anonymous(tally, sequence, now_s)

    def _feed_known(self, tally: KeyTally, seq: int, source: object, now_s: float) -> int:
        stream = tally.streams.get(source)
        if stream is None:
            tally.streams[source] = Stream(seq, seq, last_seen_s=now_s)
            return 0
        return self._advance(tally, stream, seq, now_s)

    def _feed_anonymous(self, tally: KeyTally, seq: int, now_s: float) -> int:
        streams = {k: s for k, s in tally.streams.items() if isinstance(k, _Unnamed)}
        for stream in streams.values():
            if stream.last == seq - 1:
                return self._advance(tally, stream, seq, now_s)
        named = len(tally.streams) - len(streams)
        publishers = max(1, self._publishers_on(tally.key) - named)
        if seq == 1 or len(streams) < publishers:
            if seq == 1 and len(streams) >= publishers:
                # a publisher restarted (numbering from 1 again): retire the stream heard from longest ago
                tally.retire(min(streams, key=lambda k: streams[k].last_seen_s))
            self._new_unnamed(tally, seq, now_s)
            return 0
        below = [s for s in streams.values() if s.last < seq]
        if not below:
            stale = [k for k, s in streams.items() if now_s - s.last_seen_s > self.STALE_AFTER_S]
            if stale:  # a publisher went away and another took the key at a lower number
                tally.retire(stale[0])
                self._new_unnamed(tally, seq, now_s)
            else:
                tally.duplicates += 1
            return 0
        return self._advance(tally, max(below, key=lambda s: s.last), seq, now_s)

    def _new_unnamed(self, tally: KeyTally, seq: int, now_s: float) -> None:
        self._next_anonymous += 1
        tally.streams[_Unnamed(self._next_anonymous)] = Stream(seq, seq, last_seen_s=now_s)

    @staticmethod
    def _advance(tally: KeyTally, stream: Stream, seq: int, now_s: float) -> int:
        stream.last_seen_s = now_s
        if seq == stream.last + 1:
            stream.last = seq
            stream.received += 1
            return 0
        if seq <= stream.last:
            if seq == 1:  # the same publisher restarted
                stream.restarts += 1
                stream.last = seq
                stream.received += 1
            else:
                tally.duplicates += 1
            return 0
        missing = seq - stream.last - 1
        stream.gaps.append((stream.last + 1, seq - 1))
        stream.lost += missing
        stream.last = seq
        stream.received += 1
        return missing

    @property
    def total_received(self) -> int:
        return sum(t.received for t in self.keys.values())

    @property
    def total_lost(self) -> int:
        return sum(t.lost for t in self.keys.values())
