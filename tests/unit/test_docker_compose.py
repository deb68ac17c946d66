"""The container deployment is generated from the stack files (`zendock export compose`), and what it
generates keeps the stack's meaning (checked without a container engine; the containers themselves run in
`make test-containers`)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import yaml

from deploy.cli import main
from deploy.commands.export import export_compose
from deploy.export.compose import HOST_ONLY_VARIABLES

REPO_ROOT = Path(__file__).resolve().parents[2]
#: (stack file, committed file, --secure), as the committed files' headers name them.
GENERATED = [
    ("deploy/stack.yaml", "deploy/docker-compose.yml", False),
    ("deploy/stack-secure.yaml", "deploy/docker-compose.secure.yml", True),
]
COMPOSE = yaml.safe_load((REPO_ROOT / "deploy" / "docker-compose.yml").read_text())
SECURE = yaml.safe_load((REPO_ROOT / "deploy" / "docker-compose.secure.yml").read_text())
STACK = yaml.safe_load((REPO_ROOT / "deploy" / "stack.yaml").read_text())


def _variables(command: list[str]) -> set[str]:
    return set(re.findall(r"\$\{(\w+)", " ".join(command))) - set(HOST_ONLY_VARIABLES)


def _conditions(service: dict) -> dict[str, str]:
    depends = service.get("depends_on") or {}
    if isinstance(depends, list):
        return {name: "service_started" for name in depends}
    return {name: spec.get("condition", "service_started") for name, spec in depends.items()}


@pytest.mark.parametrize(("stack", "committed", "secure"), GENERATED)
def test_the_committed_compose_files_are_generated_from_the_stack_files(
    monkeypatch, stack, committed, secure
) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.chdir(REPO_ROOT)
    generated = export_compose(stack, secure=secure, output=committed)
    flag = " --secure" if secure else ""
    assert generated == (REPO_ROOT / committed).read_text(), (
        f"{committed} is out of date: zendock export compose{flag} -f {stack} -o {committed}"
    )


def test_export_writes_the_file_and_bad_stacks_exit_2(monkeypatch, tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.chdir(REPO_ROOT)
    out = tmp_path / "compose.yml"
    assert main(["export", "compose", "-o", str(out)]) == 0
    assert yaml.safe_load(out.read_text()) == COMPOSE
    assert main(["export", "compose", "--secure"]) == 0
    assert yaml.safe_load(capsys.readouterr().out) == SECURE
    assert main(["export", "compose", "-f", str(tmp_path / "missing.yaml")]) == 2
    assert capsys.readouterr().err.strip().count("\n") == 0
    bad = tmp_path / "bad.yaml"
    bad.write_text("services: {a: {command: [x], restart: sometimes}}\n")
    assert main(["export", "compose", "-f", str(bad)]) == 2
    assert "services.a.restart" in capsys.readouterr().err


def test_compose_and_the_stack_file_have_the_same_services() -> None:
    # A service run by a host virtualenv's interpreter (the ROS 2 DDS face, .venv-ros2) has no container.
    host_only = {name for name, spec in STACK["services"].items() if spec["command"][0].startswith(".venv")}
    assert host_only == {"ros2_dds"}
    only_compose = set(COMPOSE["services"]) - set(STACK["services"])
    only_stack = set(STACK["services"]) - set(COMPOSE["services"]) - host_only
    assert not only_compose and not only_stack, (
        f"only in compose: {only_compose}; only in the stack: {only_stack}"
    )


def test_each_service_has_the_stacks_dependencies_variables_and_profiles() -> None:
    for name, service in COMPOSE["services"].items():
        stack_service = STACK["services"][name]
        assert _conditions(service) == _conditions(stack_service), name
        assert _variables(service["command"]) == _variables(stack_service["command"]), name
        assert service.get("profiles") == stack_service.get("profiles"), name
        assert service.get("restart", "no") == stack_service.get("restart", "no"), name


def test_every_service_runs_from_the_one_image_on_the_bridge_network() -> None:
    for name, service in COMPOSE["services"].items():
        assert service.get("image") == "zendock:latest", name
        assert service.get("networks") == ["bus"], name
        assert service.get("init") is True, name  # SIGTERM and zombies handled even with a shell in between
        command = service["command"]
        if command[:2] == ["python", "-m"]:
            module = command[2].replace(".", "/")
            assert (REPO_ROOT / module).is_dir(), f"{name}: no {module}"
    assert COMPOSE["networks"]["bus"]["driver"] == "bridge"
    assert "build" in COMPOSE["services"]["router"]


def test_health_checks_watch_each_services_own_liveliness_token() -> None:
    for name, service in COMPOSE["services"].items():
        if "liveliness" in (STACK["services"][name].get("healthcheck") or {}):
            assert service["healthcheck"]["test"] == ["CMD", "zendock", "health", "-q", name], name
    assert "healthcheck" in COMPOSE["services"]["router"]


def test_the_map_volume_reaches_the_planner() -> None:
    map_service, planner = COMPOSE["services"]["map"], COMPOSE["services"]["planner"]
    assert "maps:/maps" in map_service["volumes"] and "maps:/maps" in planner["volumes"]
    out = map_service["command"][map_service["command"].index("-o") + 1]
    assert f"map_yaml={out}" in planner["command"]


def test_published_ports_stay_on_loopback_unless_the_operator_says_otherwise() -> None:
    for name, service in COMPOSE["services"].items():
        for port in service.get("ports", []):
            assert port.startswith(("127.0.0.1:", "${ZENOH_PUBLISH_ADDR:-127.0.0.1}:")), f"{name}: {port}"


def test_the_secure_override_gives_every_bus_service_its_own_user() -> None:
    bus_services = {name for name, s in COMPOSE["services"].items() if name not in ("router", "map")}
    assert set(SECURE["services"]) - {"router"} == bus_services
    for name in bus_services:
        config = SECURE["services"][name]["environment"]["ZENDOCK_ZENOH_CONFIG"]
        assert config == f"deploy/zenoh/secure/{name}.json5" and (REPO_ROOT / config).is_file(), name
    router = SECURE["services"]["router"]["command"]
    assert router[router.index("--config") + 1] == "deploy/zenoh/secure/router.json5"


def test_the_dockerfile_takes_its_base_as_an_argument_and_runs_as_a_user() -> None:
    text = (REPO_ROOT / "deploy" / "docker" / "Dockerfile").read_text()
    assert re.search(r"^ARG BASE=\S+", text, re.M) and re.search(r"^FROM \$\{BASE\}", text, re.M)
    user = re.findall(r"^USER (\S+)", text, re.M)
    assert user and user[-1] not in ("root", "0")


def test_the_shard_compose_file_runs_every_shard_once_without_a_network() -> None:
    shards = yaml.safe_load((REPO_ROOT / "deploy" / "batch" / "trials-shards.compose.yml").read_text())[
        "services"
    ]
    numbers = sorted(int(service["environment"]["SHARD"]) for service in shards.values())
    command = " ".join(next(iter(shards.values()))["command"])
    count = int(re.search(r"\$\{ZENDOCK_SHARDS:-(\d+)\}", command).group(1))  # type: ignore[union-attr]
    assert numbers == list(range(1, count + 1))
    assert '--shard "$$SHARD/' in command and "--runs-dir" in command and "--json" in command
    for service in shards.values():
        assert service["network_mode"] == "none" and service["image"] == "zendock:latest"


def test_the_kubernetes_job_is_indexed_and_gives_each_pod_its_shard() -> None:
    docs = list(yaml.safe_load_all((REPO_ROOT / "deploy" / "batch" / "trials-job.yaml").read_text()))
    job = next(d for d in docs if d["kind"] == "Job")
    spec = job["spec"]
    container = spec["template"]["spec"]["containers"][0]
    env = {e["name"]: e["value"] for e in container["env"]}
    assert spec["completionMode"] == "Indexed"
    assert spec["completions"] == spec["parallelism"] == int(env["ZENDOCK_SHARDS"])
    script = " ".join(container["args"])
    assert '--shard "$((JOB_COMPLETION_INDEX + 1))/$ZENDOCK_SHARDS"' in script
    claim = spec["template"]["spec"]["volumes"][0]["persistentVolumeClaim"]["claimName"]
    assert any(d["kind"] == "PersistentVolumeClaim" and d["metadata"]["name"] == claim for d in docs)
    assert spec["template"]["spec"]["securityContext"]["runAsUser"] != 0
