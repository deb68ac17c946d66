"""The battery's charge kept on disk, so a restarted battery service reports the charge the robot has.

A real battery keeps its charge whatever happens to the process that reads it; a simulated one kept only
in memory would come back full (or at ``initial_percentage``) after a crash, and whatever waits for the
low-battery threshold would wait for ever. The state is a small JSON object written atomically (a
temporary file, then a rename); a missing or damaged file means "start from the parameters".
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass
from pathlib import Path

from shared.files import write_atomically


@dataclass(frozen=True)
class StoredCharge:
    percentage: float
    drain_scale: float
    charge_scale: float
    frozen: bool


def load_charge(path: Path) -> StoredCharge | None:
    """What the file holds, or None when it is absent, unreadable or out of range."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        stored = StoredCharge(
            float(data["percentage"]),
            float(data["drain_scale"]),
            float(data["charge_scale"]),
            bool(data["frozen"]),
        )
    except (OSError, ValueError, KeyError, TypeError):
        return None
    values_ok = 0.0 <= stored.percentage <= 1.0 and all(
        math.isfinite(v) and v >= 0.0 for v in (stored.drain_scale, stored.charge_scale)
    )
    return stored if values_ok else None


def save_charge(path: Path, charge: StoredCharge) -> None:
    write_atomically(path, json.dumps(asdict(charge)).encode("utf-8"))
