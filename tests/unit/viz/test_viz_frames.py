"""A fleet in one view: each robot's frames under its name, the shared map as it is."""

from __future__ import annotations

from shared.foxglove_view.frames import prefix_frames, robot_frame
from shared.messages import Header, Path, PoseStamped, TFMessage, TransformStamped


def test_every_frame_of_a_robot_goes_under_its_name_but_the_map() -> None:
    tf = TFMessage(
        [
            TransformStamped(Header(frame_id="map"), "odom"),
            TransformStamped(Header(frame_id="odom"), "base_link"),
        ]
    )
    seen = prefix_frames(tf, "r2")
    assert [(t.header.frame_id, t.child_frame_id) for t in seen.transforms] == [
        ("map", "r2/odom"),
        ("r2/odom", "r2/base_link"),
    ]
    assert [(t.header.frame_id, t.child_frame_id) for t in tf.transforms] == [
        ("map", "odom"),
        ("odom", "base_link"),
    ], "the received message is shared with other subscriptions: it must not change"
    path = Path(Header(frame_id="map"), [PoseStamped(Header(frame_id="base_link"))])
    seen = prefix_frames(path, "r1")
    assert seen.header.frame_id == "map" and seen.poses[0].header.frame_id == "r1/base_link"
    assert path.poses[0].header.frame_id == "base_link"
    assert robot_frame("", "base_link") == "base_link", "a lone robot keeps its frames"
    assert robot_frame("r1", "") == ""
