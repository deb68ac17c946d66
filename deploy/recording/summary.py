"""The recording's account: per key, how many samples arrived and how many the sequence numbers say were lost."""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass

from deploy.recording.sequence import SequenceTracker

#: Gaps listed per key in the printed summary (all are counted).
GAPS_SHOWN = 5


@dataclass(frozen=True)
class KeySummary:
    key: str
    type_name: str
    received: int
    lost: int
    gaps: tuple[tuple[int, int], ...]
    publishers: int
    unnumbered: int
    duplicates: int

    @property
    def published(self) -> int:
        """What the publishers sent while the recorder listened (numbered samples), by their numbers."""
        return self.received - self.unnumbered - self.duplicates + self.lost


def summarize(tracker: SequenceTracker, type_of: Callable[[str], str]) -> list[KeySummary]:
    rows = []
    for key in sorted(tracker.keys):
        tally = tracker.keys[key]
        rows.append(
            KeySummary(
                key=key,
                type_name=type_of(key),
                received=tally.received,
                lost=tally.lost,
                gaps=tuple(tally.gaps),
                publishers=len(tally.streams),
                unnumbered=tally.unnumbered,
                duplicates=tally.duplicates,
            )
        )
    return rows


def format_summary(rows: list[KeySummary], duration_s: float) -> str:
    """A table for the terminal, and one line saying whether anything was lost."""
    if not rows:
        return "nothing received"
    width = max(len(r.key) for r in rows)
    lines = [f"{'key':<{width}}  {'type':<34} {'recorded':>9} {'published':>9} {'lost':>6} {'Hz':>7}"]
    for r in rows:
        rate = r.received / duration_s if duration_s > 0 else 0.0
        published = str(r.published) if r.received > r.unnumbered else "-"
        lines.append(
            f"{r.key:<{width}}  {r.type_name or '-':<34} {r.received:>9} {published:>9} {r.lost:>6} {rate:>7.1f}"
        )
        if r.gaps:
            shown = ", ".join(f"{a}" if a == b else f"{a}-{b}" for a, b in r.gaps[:GAPS_SHOWN])
            more = f" and {len(r.gaps) - GAPS_SHOWN} more" if len(r.gaps) > GAPS_SHOWN else ""
            lines.append(f"{'':<{width}}    missing sequence numbers: {shown}{more}")
    total = sum(r.received for r in rows)
    lost = sum(r.lost for r in rows)
    verdict = "no gaps" if lost == 0 else f"{lost} message(s) lost in {sum(len(r.gaps) for r in rows)} gap(s)"
    lines.append(f"{total} messages on {len(rows)} keys in {duration_s:.1f} s: {verdict}")
    return "\n".join(lines)


def summary_metadata(rows: list[KeySummary], duration_s: float) -> dict[str, str]:
    """The summary as MCAP metadata: one JSON record per key, plus totals."""
    values = {
        r.key: json.dumps(
            {
                "type": r.type_name,
                "received": r.received,
                "lost": r.lost,
                "publishers": r.publishers,
                "unnumbered": r.unnumbered,
                "duplicates": r.duplicates,
                "gaps": [list(g) for g in r.gaps],
            }
        )
        for r in rows
    }
    values["total_received"] = str(sum(r.received for r in rows))
    values["total_lost"] = str(sum(r.lost for r in rows))
    values["duration_s"] = f"{duration_s:.3f}"
    return values
