"""The observer marks where navigation began each recovery, from the action's feedback on the bus."""

from __future__ import annotations

import time

import numpy as np

from deploy.observer import RunObserver
from shared import topics
from shared.action import action_key
from shared.geometry import Pose2D
from shared.interface_types import UUID
from shared.interfaces.navigation import NAVIGATE_TO_POSE, NavigateToPoseFeedback
from shared.messages import Header, Pose, PoseStamped, Time
from shared.names import topic_key
from shared.session import SessionSpec, open_session

NS = "obs_recoveries"


def _wait(predicate, timeout_s: float = 5.0) -> bool:  # type: ignore[no-untyped-def]
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.01)
    return predicate()


def test_each_new_recovery_is_marked_where_the_robot_stood() -> None:
    # A lone peer with no endpoints: its subscribers get its own puts, and nothing leaves the process.
    with open_session(SessionSpec(mode="peer", connect=())) as session:
        observer = RunObserver(session, NS)
        try:
            observer.arm()
            feedback_key = topic_key(NS, action_key(topics.NAVIGATE_TO_POSE, "feedback"))

            def truth(t: float, x: float, y: float) -> None:
                msg = PoseStamped(
                    Header(Time.from_sec(t), topics.MAP_FRAME), Pose.from_pose2d(Pose2D(x, y, 0.0))
                )
                session.put(topic_key(NS, topics.GROUND_TRUTH_POSE), msg.encode())

            def feedback(goal: UUID, t: float, recoveries: int) -> None:
                pose = PoseStamped(Header(Time.from_sec(t), topics.MAP_FRAME), Pose.from_pose2d(Pose2D()))
                msg = NAVIGATE_TO_POSE.feedback_message(
                    goal_id=goal,
                    feedback=NavigateToPoseFeedback(current_pose=pose, number_of_recoveries=recoveries),
                )
                session.put(feedback_key, msg.encode())

            first, second = UUID.random(), UUID.random()
            truth(1.0, 1.0, 2.0)
            assert _wait(lambda: len(observer.snapshot().driven) == 1)
            feedback(first, 1.0, 0)
            feedback(first, 1.0, 1)  # the first recovery, with the robot at (1, 2)
            feedback(first, 1.0, 1)  # the same count again: no new mark
            truth(2.0, 3.0, 2.5)
            assert _wait(lambda: len(observer.snapshot().driven) == 2)
            feedback(first, 2.0, 2)
            feedback(second, 2.0, 1)  # a new goal counts from zero again
            session.put(feedback_key, b"\x00not msgpack")  # ignored, never fatal
            assert _wait(lambda: len(observer.snapshot().recovery_points) == 3), (
                observer.snapshot().recovery_points
            )
            np.testing.assert_allclose(
                observer.snapshot().recovery_points, [(1.0, 2.0), (3.0, 2.5), (3.0, 2.5)]
            )
        finally:
            observer.close()
