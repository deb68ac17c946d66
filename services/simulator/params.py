"""The simulator's parameters: a few for the whole world, then one model per component (``-p lidar.noise_m=0.02``).

Each component's model owns its values, bounds and its publishing rate, once: the sensor, drive, camera,
infrared, contact and pacing models are the settings classes their pure modules use
(:class:`~services.simulator.sensors.LidarParams` and so on); the ones below add what only the service
needs (the clock, odometry, tf, ground truth, the synthetic detector's latency, the drive's watchdog).
Names follow Nav2's ``component.parameter`` style; the dotted form is described in :mod:`shared.runtime`.
"""

from __future__ import annotations

import math
from typing import Annotated

import msgspec
from msgspec import Meta

from services.simulator.camera import CameraParams
from services.simulator.pacing import PacingParams
from services.simulator.physics import SimParams
from services.simulator.robot_model import DiffDriveParams
from services.simulator.sensors import FiducialCameraParams, LidarParams, UltrasonicParams
from shared.controllers import DetectorName
from shared.geometry import Pose2D
from shared.models.component import ComponentParams
from shared.models.dock_contact import DockContactParams
from shared.models.infrared import InfraredParams
from shared.names import normalise_namespace
from shared.parameters import ServiceParams
from shared.structs import blaming
from shared.world import load_world


class ClockParams(ComponentParams, frozen=True):
    rate_hz: Annotated[
        float,
        Meta(
            gt=0,
            description="sim-time clock rate: the stack's fastest sim-time timer "
            "(planner and docking control, 20 Hz); every sim-time node receives every tick",
        ),
    ] = 20.0


class OdomParams(ComponentParams, frozen=True):
    rate_hz: Annotated[
        float, Meta(gt=0, description="odometry rate: the control timers' 20 Hz (they read the latest)")
    ] = 20.0
    noise: Annotated[
        float, Meta(ge=0, description="relative std dev of each wheel's travel per step (0: exact)")
    ] = 0.0


class TfParams(ComponentParams, frozen=True):
    rate_hz: Annotated[
        float, Meta(gt=0, description="tf rate: twice the pose service's 10 Hz, on the clock's ticks")
    ] = 20.0
    static_rate_hz: Annotated[float, Meta(gt=0, description="tf_static (sensor mounts) rate")] = 1.0


class GroundTruthParams(ComponentParams, frozen=True):
    rate_hz: Annotated[float, Meta(gt=0)] = 20.0


class LocalisationParams(ComponentParams, frozen=True):
    #: map->odom is off by this much (in base_link at the start), like a drifting localiser.
    error: Annotated[tuple[float, float, float], Meta(description="x_m, y_m, yaw_rad")] = (0.0, 0.0, 0.0)
    #: An initial pose (set_localisation, ROS 2's /initialpose) is refused when fewer of the lidar's beams
    #: agree with the map seen from it (0: take any): a localiser would not converge there.
    initial_pose_min_agreement: Annotated[
        float,
        Meta(
            ge=0.0,
            le=1.0,
            description="refuse an initial pose on which fewer lidar beams agree with the map (0: take any)",
        ),
    ] = 0.25


class DriveParams(DiffDriveParams, frozen=True):
    """The drive's geometry and limits (Gazebo diff_drive / ros2_control names) and its command watchdog."""

    cmd_vel_timeout_s: Annotated[
        float,
        Meta(
            gt=0,
            description="watchdog: brake when no command for this long (standing still 0.5 s after the last)",
        ),
    ] = 0.3


class DetectionParams(FiducialCameraParams, frozen=True):
    """The dock detector's camera model, and who publishes detected_dock_pose."""

    #: ``aruco`` leaves it to the perception service (which reads camera/image_raw); ``synthetic`` publishes
    #: detected_dock_pose from the true pose plus noise.
    source: DetectorName = "synthetic"
    #: The synthetic detector sees the marker down to 2 cm (the camera is 5 cm from it when docked).
    range_min_m: Annotated[float, Meta(ge=0)] = 0.02
    rate_hz: Annotated[float, Meta(gt=0, description="synthetic detections per second (sim time)")] = 15.0
    latency_s: Annotated[
        float, Meta(ge=0, description="a synthetic detection is published this long after capture")
    ] = 0.05


def _rtf(value: float | str) -> float | str:
    """A positive finite real-time factor, or ``"max"`` (flat out)."""
    if isinstance(value, str):
        if value.strip().lower() == "max":
            return "max"
        try:
            value = float(value)
        except ValueError:
            raise ValueError(f"rtf: must be a positive number or 'max', got {value!r}") from None
    if not (value > 0 and math.isfinite(value)):
        raise ValueError(f"rtf: must be a positive number or 'max', got {value}")
    return value


class Params(ServiceParams):
    """Simulator parameters (``-p name=value``, ``-p component.name=value``)."""

    world: Annotated[str, Meta(description="world file (deploy/worlds/*.yaml)")]
    rtf: Annotated[float | str, Meta(description="real-time factor: a positive number, or 'max'")] = 1.0
    robots: Annotated[list[str], Meta(description="robot namespaces served (empty: the node's own)")] = (
        msgspec.field(default_factory=list)
    )
    seed: int = 0
    dt_s: Annotated[float, Meta(gt=0, le=0.05)] = 0.01
    clock: ClockParams = ClockParams()
    odom: OdomParams = OdomParams()
    tf: TfParams = TfParams()
    ground_truth: GroundTruthParams = GroundTruthParams()
    localisation: LocalisationParams = LocalisationParams()
    pacing: PacingParams = PacingParams()
    drive: DriveParams = DriveParams()
    lidar: LidarParams = LidarParams()
    ultrasonic: UltrasonicParams = UltrasonicParams()
    detection: DetectionParams = DetectionParams()
    camera: CameraParams = CameraParams()
    ir: InfraredParams = InfraredParams()
    contact: DockContactParams = DockContactParams()

    def __post_init__(self) -> None:
        self.rtf = _rtf(self.rtf)
        with blaming("world"):
            load_world(self.world)  # a ConfigError (a ValueError) names the file and the problem
        names = [normalise_namespace(v) for v in self.robots]
        if any(not n for n in names) or len(set(names)) != len(names):
            raise ValueError("robots: must be distinct, non-empty namespaces")
        self.robots = names

    def sim_params(self, robot_index: int = 0) -> SimParams:
        """The physics' settings for the ``robot_index``-th robot (each draws from its own seed)."""
        return SimParams(
            dt_s=self.dt_s,
            odom_noise=self.odom.noise,
            seed=self.seed + robot_index,
            lidar=self.lidar,
            ultrasonic=self.ultrasonic,
            camera=self.detection,
            infrared=self.ir,
            contact=self.contact,
            localisation_error=Pose2D(*self.localisation.error),
        )


__all__ = [
    "ClockParams",
    "DetectionParams",
    "DriveParams",
    "GroundTruthParams",
    "LocalisationParams",
    "OdomParams",
    "Params",
    "TfParams",
]
