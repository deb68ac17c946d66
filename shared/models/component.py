"""The base of the simulator's per-component parameters (``lidar``, ``drive``, ``camera``, ...).

Each component's settings class IS its parameter model: the one place its defaults and bounds are
written, whether it is built by the service from ``-p lidar.noise_m=0.02`` or by a test as
``LidarParams(noise_m=0.0)``. Strict (an unknown name is an error, as for :class:`ServiceParams`),
frozen (the physics shares one instance between steps) and finite (``inf`` and ``nan`` are errors).
Pure: pydantic only, nothing from Zenoh.
"""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict


class ComponentParams(BaseModel):
    """Strict, frozen, finite parameters of one part of the simulated robot."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


__all__ = ["ComponentParams"]
