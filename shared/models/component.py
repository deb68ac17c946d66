"""The base of the simulator's per-component parameters (``lidar``, ``drive``, ``camera``, ...).

Each component's settings class IS its parameter record: the one place its defaults and bounds are
written, whether it is built by the service from ``-p lidar.noise_m=0.02`` or by a test as
``LidarParams(noise_m=0.0)``. Strict (an unknown name is an error, as for :class:`ServiceParams`),
frozen (the physics shares one instance between steps) and finite (``inf`` and ``nan`` are errors).
Pure: msgspec only, nothing from Zenoh.
"""

from __future__ import annotations

import msgspec

from shared.structs import non_finite


class ComponentParams(msgspec.Struct, forbid_unknown_fields=True, frozen=True, kw_only=True):
    """Strict, frozen, finite parameters of one part of the simulated robot.

    A subclass with checks of its own defines ``__post_init__`` and calls this one first."""

    def __post_init__(self) -> None:
        for name in non_finite(self):
            raise ValueError(f"{name}: must be a finite number")


__all__ = ["ComponentParams"]
