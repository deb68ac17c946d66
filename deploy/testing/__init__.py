"""zendock's pytest plugin: test your own services against a whole zendock stack.

Installed with zendock, it loads by itself (entry point ``pytest11: zendock``, :mod:`deploy.testing.plugin`)
and gives a test ``zendock_stack`` (the default stack on a free port, torn down after the test),
``zendock_robot`` (:class:`~deploy.testing.robot.Robot`: dock, undock, nav, battery, pose, waits) and
``zendock_bus`` (a raw Zenoh session on the stack). ``@pytest.mark.zendock(world=..., rtf=..., services=...)``
chooses the stack; ``--zendock-service NAME=COMMAND`` puts a replacement into every stack of a run.

It lives in ``deploy`` because it starts stacks (the launcher's floor); the robot handle uses only
``shared``, as a service would. See ``docs/testing.md``.
"""

from __future__ import annotations

import importlib
from typing import Any

#: Public names and their modules, imported on first use: pytest imports this package (for the plugin) in
#: every run of an environment with zendock installed, and Zenoh and the launcher are slow to import.
_EXPORTS = {
    "StackConfig": "deploy.testing.config",
    "NavOutcome": "deploy.testing.robot",
    "Robot": "deploy.testing.robot",
    "WaitTimeout": "deploy.testing.robot",
    "is_charging": "deploy.testing.robot",
    "StackUnhealthy": "deploy.testing.stack",
    "ZendockStack": "deploy.testing.stack",
}
__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    if name not in _EXPORTS:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(_EXPORTS[name]), name)
