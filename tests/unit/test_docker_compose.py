"""The multi-machine compose file stays in step with the default stack (no Docker engine needed)."""

from __future__ import annotations

from pathlib import Path

import yaml

REPO_ROOT = Path(__file__).resolve().parents[2]


def test_compose_runs_the_default_stack_services_from_one_image() -> None:
    compose = yaml.safe_load((REPO_ROOT / "deploy" / "docker-compose.yml").read_text())
    stack = yaml.safe_load((REPO_ROOT / "deploy" / "stack.yaml").read_text())
    assert set(compose["services"]) == set(stack["services"])
    for name, service in compose["services"].items():
        assert service.get("image") == "zendock:latest", name
        command = service["command"]
        if command[:2] == ["python", "-m"]:
            module = command[2].replace(".", "/")
            assert (REPO_ROOT / module).is_dir(), f"{name}: no {module}"
    # published ports stay on loopback unless the operator says otherwise
    for name, service in compose["services"].items():
        for port in service.get("ports", []):
            assert port.startswith(("127.0.0.1:", "${ZENOH_PUBLISH_ADDR:-127.0.0.1}:")), f"{name}: {port}"
