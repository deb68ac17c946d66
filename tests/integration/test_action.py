"""The action protocol over a real router: accept, feedback, result, cancel, preempt, reject."""

from __future__ import annotations

import threading
from collections.abc import Iterator

import pytest

from shared.action import ActionClient, ActionServer, ClientGoal, ServerGoalHandle, spin_in_background
from shared.interface_types import ActionType, GoalStatusCode
from shared.messages import Float64, String
from shared.node import Node
from shared.session import SessionSpec, open_session

COUNT = ActionType("zendock_msgs/action/CountTo", Float64, String, Float64)


class Counter:
    """A toy server: counts up to the goal at one step per tick, one goal at a time."""

    def __init__(self, node: Node) -> None:
        self.goal: ServerGoalHandle | None = None
        self.value = 0.0
        self.server = ActionServer(
            node, COUNT, "count_to", on_goal=self.check, on_accepted=self.start, on_cancel=self.cancel
        )
        node.create_timer(0.01, self.step, wall=True)

    def check(self, goal: Float64) -> None:
        if goal.data < 0:
            raise ValueError("cannot count to a negative number")

    def start(self, handle: ServerGoalHandle) -> None:
        if handle.active:
            self.goal, self.value = handle, 0.0
            handle.execute()

    def cancel(self, handle: ServerGoalHandle) -> None:
        handle.canceled(String(f"stopped at {self.value:g}"))

    def step(self) -> None:
        goal = self.goal
        if goal is None or not goal.active:
            return
        self.value += 1
        goal.publish_feedback(Float64(self.value))
        if self.value >= goal.goal.data:
            goal.succeed(String(f"reached {self.value:g}"))


@pytest.fixture
def client_and_server(router_endpoint: str, namespace: str) -> Iterator[ActionClient]:
    with (
        open_session(SessionSpec(connect=(router_endpoint,))) as s1,
        open_session(SessionSpec(connect=(router_endpoint,))) as s2,
    ):
        server_node, client_node = Node("counter", s1, namespace), Node("client", s2, namespace)
        Counter(server_node)
        server_node.declare_ready()
        threads = [spin_in_background(server_node), spin_in_background(client_node)]
        yield ActionClient(client_node, COUNT, "count_to")
        for node in (server_node, client_node):
            node.shutdown()
        for t in threads:
            t.join(5)


def _send(client: ActionClient, target: float) -> tuple[ClientGoal, threading.Event, list[float]]:
    done = threading.Event()
    feedback: list[float] = []
    handle = client.send_goal(
        Float64(target), on_feedback=lambda f: feedback.append(f.data), on_done=lambda _h: done.set()
    )
    return handle, done, feedback


def test_server_ready_waits_for_a_server_that_comes_up_while_it_asks(
    router_endpoint: str, namespace: str
) -> None:
    """A liveliness query sees only the tokens the router has when it arrives: ``server_ready`` asks again
    until its timeout, so a server that starts a moment after the client began waiting is found."""
    with (
        open_session(SessionSpec(connect=(router_endpoint,))) as s1,
        open_session(SessionSpec(connect=(router_endpoint,))) as s2,
    ):
        client_node = Node("client", s2, namespace)
        client = ActionClient(client_node, COUNT, "count_to")
        assert not client.server_ready(0.2), "a server answered before any was started"
        asking, answers = threading.Event(), []

        def wait_for_server() -> None:
            asking.set()
            answers.append(client.server_ready(10.0))

        waiter = threading.Thread(target=wait_for_server)
        waiter.start()
        assert asking.wait(5.0)
        server_node = Node("counter", s1, namespace)
        Counter(server_node)
        server_node.declare_ready()
        thread = spin_in_background(server_node)
        waiter.join(15.0)
        server_node.shutdown()
        thread.join(5)
        client_node.shutdown()
    assert answers == [True], "server_ready gave up on a server that started while it waited"


def test_goal_runs_to_success_with_feedback(client_and_server: ActionClient) -> None:
    client = client_and_server
    assert client.server_ready(2.0)
    handle, done, feedback = _send(client, 5)
    assert done.wait(10), "goal did not finish"
    assert handle.accepted and handle.status == GoalStatusCode.SUCCEEDED
    assert handle.result is not None and handle.result.data == "reached 5"
    # Feedback travels on its own key and the client stops listening at the result, so the last one or
    # two may be cut off; what did arrive came in order and counted towards the goal.
    assert feedback, "no feedback arrived"
    assert feedback == sorted(set(feedback)) and set(feedback) <= {1.0, 2.0, 3.0, 4.0, 5.0}, feedback


def test_rejected_goal_carries_the_reason(client_and_server: ActionClient) -> None:
    handle, done, _ = _send(client_and_server, -1)
    assert done.wait(5)
    assert handle.accepted is False and "negative" in handle.rejection


def test_cancel_and_preempt(client_and_server: ActionClient) -> None:
    client = client_and_server
    first, first_done, _ = _send(client, 1e9)
    second, second_done, feedback = _send(client, 1e9)
    assert first_done.wait(5), "the first goal was not preempted"
    assert first.status == GoalStatusCode.CANCELED
    # wait for the second goal to make progress before cancelling it
    deadline = threading.Event()
    for _ in range(100):
        if feedback:
            break
        deadline.wait(0.05)
    assert feedback, "no feedback from the second goal"
    client.cancel_goal(second)
    assert second_done.wait(5)
    assert second.status == GoalStatusCode.CANCELED and second.result is not None
    assert second.result.data.startswith("stopped at")
