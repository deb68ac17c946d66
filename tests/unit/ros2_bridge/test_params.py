"""The bridge's ROS namespace is rcl's canonical form or the bridge does not start."""

from __future__ import annotations

import pytest

from services.ros2_bridge.node import SERVICE
from shared.config_errors import CONFIG_ERROR_EXIT


@pytest.mark.parametrize("namespace", ["robot", "/robot/", "//r", "/r-1"])
def test_a_non_canonical_namespace_is_refused_at_start_up_in_one_line(
    namespace: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """rmw_zenoh takes namespaces from rcl, canonical (``/robot``), and mangles them as they are
    (liveliness_utils.cpp, ``mangle_name``); another form would make keys no ROS 2 node makes."""
    assert SERVICE.run(["-p", f"ros_namespace={namespace}"]) == CONFIG_ERROR_EXIT
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "ros_namespace" in err and "not a canonical ROS namespace" in err, err


@pytest.mark.parametrize("namespace", ["/", "/robot", "/fleet/robot_1"])
def test_a_canonical_namespace_is_taken(namespace: str) -> None:
    _options, params = SERVICE.parse(["-p", f"ros_namespace={namespace}"])
    assert params.ros_namespace == namespace  # type: ignore[attr-defined]
