"""The contracts: the committed documents are what the code renders, the launcher hands each service only
flags its contract names, and a node refuses an endpoint its contract does not name."""

from __future__ import annotations

import json

import msgpack
import pytest

from deploy.contracts.document import contract_json, stale_files
from deploy.fleet.stack import FleetOptions, fleet_stack
from deploy.launcher.launch import GroupRun, ModuleRun
from deploy.launcher.stack_file import Stack, load_stack
from deploy.paths import REPO_ROOT
from deploy.trials.records import TrialOptions
from deploy.trials.stack import trials_stack
from shared.contracts import CONTRACTS, ContractViolation
from shared.contracts.wire_schema import json_schema
from shared.messages import BatteryState

WORLD = REPO_ROOT / "deploy" / "worlds" / "seed_room.yaml"


def test_the_committed_contract_documents_are_what_the_code_renders() -> None:
    assert stale_files() == [], "docs/contracts/ is stale: run python -m deploy.docs_site"


def _launched_parameters(stack: Stack) -> dict[str, set[str]]:
    """``-p`` names each zendock service gets in a stack, by service (a group's members each)."""
    found: dict[str, set[str]] = {}
    for launch in stack.services.values():
        runs = launch.run.members if isinstance(launch.run, GroupRun) else (launch.run,)
        for run in runs:
            if not isinstance(run, ModuleRun):
                continue
            flags = run.flags
            names = {flags[i + 1].split("=", 1)[0] for i, word in enumerate(flags[:-1]) if word == "-p"}
            if "--world" in flags:
                names.add("world")
            found.setdefault(run.service, set()).update(names)
    return found


@pytest.mark.parametrize("source", ["stack.yaml", "trials", "fleet"])
def test_the_launcher_hands_a_service_only_parameters_its_contract_names(source: str, tmp_path) -> None:  # type: ignore[no-untyped-def]
    if source == "stack.yaml":
        stack = load_stack(REPO_ROOT / "deploy" / "stack.yaml", env={}, project_dir=tmp_path)
    elif source == "trials":
        stack = trials_stack(TrialOptions(world=WORLD), "tcp/127.0.0.1:1", ["r0"], tmp_path)
    else:
        stack = fleet_stack(FleetOptions(world=WORLD), "tcp/127.0.0.1:1", WORLD, ["r0"], tmp_path)
    launched = _launched_parameters(stack)
    assert {"simulator", "battery", "pose", "planner", "docking"} <= set(launched)
    for service, names in launched.items():
        named = {flag.name for flag in CONTRACTS[service].flags}
        assert names <= named, (
            f"{service}: the launcher passes {sorted(names - named)}, its contract does not name them"
        )


def test_a_node_may_declare_what_its_contract_names_and_nothing_else() -> None:
    docking = CONTRACTS["docking"]
    docking.check_endpoint("pub", "geometry_msgs/msg/Twist", "robot1/cmd_vel", "docking")
    docking.check_endpoint("sub", "std_msgs/msg/Float64MultiArray", "*/map_to_base_link_pose2d", "docking")
    docking.check_endpoint("srv", "zendock_msgs/srv/GetParameter", "robot1/docking/_param/get", "docking")
    docking.check_endpoint("sub", "rosgraph_msgs/msg/Clock", "robot1/clock", "docking")
    with pytest.raises(ContractViolation, match="docking: declares pub robot1/map"):
        docking.check_endpoint("pub", "nav_msgs/msg/OccupancyGrid", "robot1/map", "docking")
    with pytest.raises(ContractViolation, match="does not name"):  # the right key with the wrong type
        docking.check_endpoint("pub", "std_msgs/msg/String", "robot1/cmd_vel", "docking")


def test_the_json_form_carries_every_type_it_names_with_its_schema() -> None:
    for contract in CONTRACTS.values():
        body = contract_json(contract)
        json.dumps(body)  # plain JSON
        named = {t["type"] for t in body["publishes"] + body["subscribes"]}
        assert named <= set(body["types"]), contract.service


def test_a_schema_names_every_field_a_payload_carries() -> None:
    payload = msgpack.unpackb(BatteryState(percentage=0.5).encode())
    schema = json_schema(BatteryState)
    assert set(schema["required"]) == set(payload) == set(schema["properties"])
    assert schema["additionalProperties"] is False
    assert schema["properties"]["percentage"] == {"type": "number", "minimum": 0.0, "maximum": 1.0}
    header = schema["$defs"]["std_msgs.msg.Header"]
    assert header["properties"]["stamp"] == {"$ref": "#/$defs/builtin_interfaces.msg.Time"}


def test_in_a_known_namespace_the_key_must_be_there() -> None:
    """conform knows where the program runs: ``cmd_vel`` in the wrong namespace is not the contract's."""
    docking = CONTRACTS["docking"]
    docking.check_endpoint("pub", "geometry_msgs/msg/Twist", "r1/cmd_vel", "docking", "r1")
    with pytest.raises(ContractViolation):
        docking.check_endpoint("pub", "geometry_msgs/msg/Twist", "other/cmd_vel", "docking", "r1")
