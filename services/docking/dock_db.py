"""The dock database: known docks by id, read from YAML, as Nav2's opennav_docking dock database.

The file format is ``docks: [{id: home, pose: [x, y, yaw], type: charger}, ...]``. A world file
(``deploy/worlds/*.yaml``) is a valid dock database as it is: only its ``docks`` list is read and the
other top-level keys are ignored. Entries are validated with the world file's :class:`~shared.world.Dock`.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

from services.docking.errors import DockingError, DockingErrorCode
from shared.config_errors import ConfigError, read_yaml_file
from shared.geometry import Pose2D
from shared.structs import validate
from shared.world import Dock, World

log = logging.getLogger(__name__)


class DockDatabase:
    """An immutable set of docks with unique ids, in file order."""

    def __init__(self, docks: Iterable[Dock], source: str | Path = "<docks>") -> None:
        self.source = str(source)
        self._docks: dict[str, Dock] = {}
        for i, dock in enumerate(docks):
            if dock.id in self._docks:
                raise ConfigError(f"{self.source}: docks.{i}.id: dock id {dock.id!r} appears twice")
            self._docks[dock.id] = dock

    @classmethod
    def from_world(cls, world: World, source: str | Path | None = None) -> DockDatabase:
        return cls(world.docks, source or f"world {world.name!r}")

    def __len__(self) -> int:
        return len(self._docks)

    def __iter__(self) -> Iterator[Dock]:
        return iter(self._docks.values())

    def __contains__(self, dock_id: object) -> bool:
        return dock_id in self._docks

    @property
    def ids(self) -> list[str]:
        return list(self._docks)

    def get(self, dock_id: str) -> Dock:
        """The dock with this id; raises :class:`DockingError` with ``DOCK_NOT_IN_DB`` (901) when there is none."""
        try:
            return self._docks[dock_id]
        except KeyError:
            raise DockingError(
                DockingErrorCode.DOCK_NOT_IN_DB,
                f"dock {dock_id!r} is not in the dock database {self.source} (known: {self.ids})",
            ) from None

    def nearest(self, pose: Pose2D, dock_type: str | None = None) -> Dock:
        """The dock (of ``dock_type`` when given) whose pose is closest to ``pose``.

        Raises :class:`DockingError` with ``DOCK_NOT_VALID`` (902) when no dock qualifies.
        """
        candidates = [d for d in self._docks.values() if dock_type is None or d.type == dock_type]
        if not candidates:
            what = f"of type {dock_type!r} " if dock_type is not None else ""
            raise DockingError(
                DockingErrorCode.DOCK_NOT_VALID, f"no dock {what}in the dock database {self.source}"
            )
        return min(candidates, key=lambda d: pose.distance_to(d.pose2d))

    def choose(
        self, dock_id: str | None = None, robot_pose: Pose2D | None = None, dock_type: str | None = None
    ) -> Dock:
        """By id when one is given, otherwise the nearest to ``robot_pose`` (or the only dock)."""
        if dock_id:
            return self.get(dock_id)
        if robot_pose is not None:
            return self.nearest(robot_pose, dock_type)
        candidates = [d for d in self._docks.values() if dock_type is None or d.type == dock_type]
        if len(candidates) == 1:
            return candidates[0]
        raise DockingError(
            DockingErrorCode.DOCK_NOT_VALID,
            f"no dock id given and no robot pose to pick the nearest of {len(candidates)} docks in {self.source}",
        )


def parse_dock_db(data: Any, source: str | Path = "<docks>") -> DockDatabase:
    """Validate a decoded dock database (or world) document; raises :class:`ConfigError` naming file and field."""
    if not isinstance(data, dict):
        raise ConfigError(
            f"{source}: a dock database must be a mapping with a 'docks' list; got {type(data).__name__}"
        )
    if "docks" not in data:
        raise ConfigError(
            f"{source}: docks: missing (expected docks: [{{id, pose: [x, y, yaw], type}}, ...])"
        )
    entries = data["docks"]
    if not isinstance(entries, list):
        raise ConfigError(f"{source}: docks: must be a list of docks, got {type(entries).__name__}")
    if not entries:
        raise ConfigError(f"{source}: docks: the list is empty; at least one dock is needed")
    docks = []
    for i, entry in enumerate(entries):
        if not isinstance(entry, dict):
            raise ConfigError(
                f"{source}: docks.{i}: must be a mapping {{id, pose, type}}, got {type(entry).__name__}"
            )
        docks.append(validate(Dock, entry, source, root=f"docks.{i}"))
    return DockDatabase(docks, source)


def load_dock_db(path: str | Path) -> DockDatabase:
    """Read and validate a dock database file (or a world file)."""
    return parse_dock_db(read_yaml_file(path, "dock database"), Path(path))
