"""What the simulator says about its camera besides pixels: the calibration and where the camera sits.

``camera_info`` is the ideal pinhole of :class:`~services.simulator.camera.CameraParams` (no distortion,
``plumb_bob`` with zero coefficients as ROS drivers publish for rectified images). The camera's frames
follow REP 103: ``camera_link`` on base_link (x ahead, at the mount height, pitched about y) and
``camera_optical_frame`` under it (z ahead, x right, y down), which is the frame images are stamped in.
"""

from __future__ import annotations

import numpy as np

from services.simulator.camera import CameraParams
from shared import topics
from shared.messages import CameraInfo, Header, Quaternion, Time, Transform, TransformStamped, Vector3
from shared.rigid3 import OPTICAL_FROM_LINK_QUATERNION, quaternion_from_pitch


def camera_info(params: CameraParams) -> CameraInfo:
    K = params.intrinsics()
    P = np.hstack([K, np.zeros((3, 1))])
    return CameraInfo(
        header=Header(Time(), topics.CAMERA_OPTICAL_FRAME),
        height=params.height,
        width=params.width,
        distortion_model="plumb_bob",
        d=np.zeros(5),
        k=K.ravel(),
        r=np.eye(3).ravel(),
        p=P.ravel(),
    )


def camera_mount_transforms(params: CameraParams, stamp: Time) -> list[TransformStamped]:
    """base_link -> camera_link -> camera_optical_frame, for ``tf_static``."""
    mount = Transform(
        Vector3(params.mount_x_m, 0.0, params.mount_z_m), Quaternion(*quaternion_from_pitch(params.pitch_rad))
    )
    optical = Transform(Vector3(), Quaternion(*OPTICAL_FROM_LINK_QUATERNION))
    return [
        TransformStamped(Header(stamp, topics.BASE_FRAME), topics.CAMERA_FRAME, mount),
        TransformStamped(Header(stamp, topics.CAMERA_FRAME), topics.CAMERA_OPTICAL_FRAME, optical),
    ]
