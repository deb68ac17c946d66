"""The pytest plugin (entry point ``pytest11: zendock``): fixtures that give a test a whole zendock stack.

Users test their own services against the real system the way zendock's end-to-end tests do: a fresh
stack per test, a robot handle to drive it, a raw bus session to watch it, and the stack's logs in the
report when the test fails, since a failure across a dozen processes means little without them.

* ``zendock_stack`` (:class:`~deploy.testing.stack.ZendockStack`): the default stack, up and healthy,
  configured by ``@pytest.mark.zendock(...)`` and ``--zendock-service`` / ``--zendock-rtf``
  (:mod:`deploy.testing.config`); always brought down.
* ``zendock_robot`` (:class:`~deploy.testing.robot.Robot`): dock, undock, nav, battery, pose, waits.
* ``zendock_bus``: a plain ``zenoh.Session`` on the stack's router (explicit endpoint, no multicast).

Fixture names carry the ``zendock_`` prefix so they never shadow a project's own (zendock's tests have a
``bus``). Heavy imports (Zenoh, the launcher) wait until a fixture is used: the plugin loads in every
pytest run of an environment where zendock is installed.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest

from deploy.testing.config import StackConfig, merge_markers, parse_rtf, parse_services, stack_config

if TYPE_CHECKING:
    import zenoh

    from deploy.testing.robot import Robot
    from deploy.testing.stack import ZendockStack

MARKER = "zendock"
#: How many lines of each service's log a failed test's report shows.
LOG_TAIL_LINES = 40
STACK_KEY = pytest.StashKey["ZendockStack"]()
LOGS_ATTACHED_KEY = pytest.StashKey[bool]()


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("zendock", "zendock stacks (the zendock_stack fixture)")
    group.addoption(
        "--zendock-service",
        action="append",
        default=[],
        metavar="NAME=COMMAND",
        help="run COMMAND in place of zendock's service NAME in every stack of the run "
        "(repeatable; overrides a marker's services for the same NAME)",
    )
    group.addoption(
        "--zendock-rtf",
        default=None,
        metavar="RTF",
        help="the simulator's real-time factor in every stack of the run (overrides markers; "
        "default: the marker's, else 4)",
    )


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers",
        f"{MARKER}(world=, rtf=, detector=, controller=, seed=, localisation_error=, services={{name: command}}, "
        "healthy_timeout_s=): the stack the zendock_stack fixture brings up for this test",
    )
    try:  # a mistyped option stops the run before any stack starts
        parse_services(config.getoption("zendock_service"), "--zendock-service")
        rtf = config.getoption("zendock_rtf")
        if rtf is not None:
            parse_rtf(rtf)
    except ValueError as exc:
        raise pytest.UsageError(str(exc)) from None


def config_for(item: pytest.Item, config: pytest.Config) -> StackConfig:
    """The stack ``item`` asks for: its ``zendock`` markers (closest wins), then the command line."""
    markers = list(item.iter_markers(MARKER))  # closest first
    if any(marker.args for marker in markers):
        raise ValueError("@pytest.mark.zendock takes keyword arguments only (world=..., services=...)")
    merged = merge_markers([marker.kwargs for marker in reversed(markers)])
    return stack_config(
        merged, config.getoption("zendock_service"), config.getoption("zendock_rtf"), config.rootpath
    )


def attach_logs(report: Any, logs_dir: Path, services: Sequence[str], lines: int = LOG_TAIL_LINES) -> int:
    """Add each service's last ``lines`` log lines to ``report`` as a section; returns how many were added."""
    from deploy.testing.stack import log_texts  # noqa: PLC0415 - the launcher only once a stack ran

    added = 0
    for service in services:
        texts = log_texts(logs_dir, service, lines)
        if texts:
            report.sections.append((f"zendock log: {service} (last {len(texts)} lines)", "\n".join(texts)))
            added += 1
    return added


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo[None]) -> Any:
    """A failed test (or set-up, or teardown) of a zendock stack shows every service's log tail, once."""
    report = yield
    stack = item.stash.get(STACK_KEY, None)
    if stack is not None and report.failed and not item.stash.get(LOGS_ATTACHED_KEY, False):
        item.stash[LOGS_ATTACHED_KEY] = True
        attach_logs(report, stack.logs_dir, stack.services)
    return report


@pytest.fixture
def zendock_stack(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[ZendockStack]:
    """The default zendock stack, healthy, in ``tmp_path/zendock``; down when the test ends, pass or fail."""
    from deploy.testing.stack import StackUnhealthy, ZendockStack  # noqa: PLC0415

    try:
        stack = ZendockStack(
            config_for(request.node, request.config), tmp_path / "zendock", request.config.rootpath
        )
    except ValueError as exc:  # a marker's or an option's mistake, a ConfigError from the stack file
        problem = f"zendock stack: {exc}"
    else:
        request.node.stash[STACK_KEY] = stack
        try:
            stack.up()
            problem = ""
        except StackUnhealthy as exc:
            problem = str(exc)
    if problem:  # failed outside the except blocks: one line, not a chain of tracebacks
        pytest.fail(problem, pytrace=False)
    try:
        yield stack
    finally:
        stack.down()


@pytest.fixture
def zendock_robot(zendock_stack: ZendockStack) -> Iterator[Robot]:
    """A handle on the stack's robot (its own Zenoh session); closed after the test."""
    from deploy.testing.robot import Robot  # noqa: PLC0415

    robot = Robot(zendock_stack.endpoint, zendock_stack.namespace)
    try:
        yield robot
    finally:
        robot.close()


@pytest.fixture
def zendock_bus(zendock_stack: ZendockStack) -> Iterator[zenoh.Session]:
    """A plain Zenoh client session on the stack's router (explicit endpoint, no multicast scouting)."""
    from shared.session import SessionSpec, open_session  # noqa: PLC0415

    with open_session(SessionSpec(mode="client", connect=(zendock_stack.endpoint,))) as session:
        yield session
