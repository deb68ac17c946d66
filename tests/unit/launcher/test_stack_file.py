"""Stack files: durations, interpolation, .env, strict validation with the offending key's path."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from deploy.launcher.durations import format_duration, parse_duration
from deploy.launcher.stack_file import load_stack
from shared.config_errors import ConfigError
from shared.interpolation import InterpolationError, interpolate, parse_env_file

REPO_ROOT = Path(__file__).resolve().parents[3]
DEFAULT_STACK = REPO_ROOT / "deploy" / "stack.yaml"


def write(tmp_path: Path, text: str, name: str = "stack.yaml") -> Path:
    path = tmp_path / name
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path


def error_of(path: Path, env: dict[str, str] | None = None) -> str:
    with pytest.raises(ConfigError) as caught:
        load_stack(path, env=env or {}, project_dir=path.parent)
    return str(caught.value)


@pytest.mark.parametrize(
    ("text", "seconds"),
    [
        ("5s", 5.0),
        ("500ms", 0.5),
        ("1m", 60.0),
        ("1m30s", 90.0),
        ("1.5s", 1.5),
        ("2h", 7200.0),
        (3, 3.0),
        (0.25, 0.25),
    ],
)
def test_durations_read_as_people_write_them(text: object, seconds: float) -> None:
    assert parse_duration(text) == pytest.approx(seconds)
    assert parse_duration(format_duration(seconds)) == pytest.approx(seconds)


@pytest.mark.parametrize("text", ["", "5", "5 s", "s", "5sec", "-1s", "1s5", True, None, [1]])
def test_bad_durations_are_refused(text: object) -> None:
    with pytest.raises(ValueError):
        parse_duration(text)


def test_interpolation_forms_follow_compose() -> None:
    env = {"SET": "value", "EMPTY": ""}
    assert interpolate("${SET}", env) == "value"
    assert interpolate("$SET/x", env) == "value/x"
    assert interpolate("${UNSET:-fallback}", env) == "fallback"
    assert interpolate("${EMPTY:-fallback}", env) == "fallback"
    assert interpolate("${EMPTY-fallback}", env) == ""
    assert interpolate("${UNSET-fallback}", env) == "fallback"
    assert interpolate("${SET:+alt}|${UNSET:+alt}|${EMPTY+alt}", env) == "alt||alt"
    assert interpolate("${UNSET:-${SET}}-${UNSET:-${ALSO_UNSET:-deep}}", env) == "value-deep"
    assert interpolate("$$SET costs $$5", env) == "$SET costs $5"
    assert interpolate("${UNSET}", env) == ""
    assert interpolate("tcp/127.0.0.1:7447", env) == "tcp/127.0.0.1:7447"


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("${NEEDED:?give the world}", "required variable NEEDED is missing: give the world"),
        ("${OPEN", "unclosed"),
        ("${1X}", "invalid variable name"),
        ("${A*b}", "invalid interpolation"),
    ],
)
def test_interpolation_errors_say_what_is_wrong(text: str, message: str) -> None:
    with pytest.raises(InterpolationError, match=message.replace("$", r"\$").replace("{", r"\{")):
        interpolate(text, {})


def test_env_file_is_read_like_compose(tmp_path: Path) -> None:
    path = write(
        tmp_path,
        """\
        # a comment
        export WORLD=deploy/worlds/glass_room.yaml
        QUOTED="a ${WORLD} b"
        LITERAL='${WORLD}'
        TRAILING=plain # comment

        """,
        ".env",
    )
    values = parse_env_file(path, {})
    assert values == {
        "WORLD": "deploy/worlds/glass_room.yaml",
        "QUOTED": "a deploy/worlds/glass_room.yaml b",
        "LITERAL": "${WORLD}",
        "TRAILING": "plain",
    }
    bad = write(tmp_path, "NOT A PAIR\n", "bad.env")
    with pytest.raises(InterpolationError, match="bad.env:1"):
        parse_env_file(bad, {})


def test_dotenv_fills_variables_but_the_shell_wins(tmp_path: Path) -> None:
    write(tmp_path, "PORT=7450\nNS=from_file\n", ".env")
    path = write(
        tmp_path,
        """\
        namespace: ${NS}
        services:
          router: {command: [zendock, router, --listen, "tcp/127.0.0.1:${PORT}"]}
        """,
    )
    stack = load_stack(path, env={"NS": "from_shell"}, project_dir=tmp_path)
    assert stack.services["router"].command[-1] == "tcp/127.0.0.1:7450"
    assert stack.namespace == "from_shell"


def test_a_minimal_stack_gets_the_defaults(tmp_path: Path) -> None:
    path = write(tmp_path, "services:\n  one: {command: python -m services.battery}\n")
    stack = load_stack(path, env={}, project_dir=tmp_path)
    one = stack.services["one"]
    assert one.command == ["python", "-m", "services.battery"]
    assert str(one.restart) == "no" and one.stop_grace_period == 5.0 and one.healthcheck is None
    assert stack.connect == ("tcp/127.0.0.1:7447",)
    assert stack.namespace == ""
    assert stack.project_name == tmp_path.name.lower()
    assert load_stack(
        path, env={"ZENOH_CONNECT": "tcp/127.0.0.1:9000,tcp/127.0.0.1:9001"}, project_dir=tmp_path
    ).connect == (
        "tcp/127.0.0.1:9000",
        "tcp/127.0.0.1:9001",
    )


def test_long_and_short_forms_and_extensions(tmp_path: Path) -> None:
    path = write(
        tmp_path,
        """\
        name: robots
        x-common: &common {restart: "on-failure:3", stop_grace_period: 500ms}
        services:
          a:
            <<: *common
            command: [python, -c, "pass"]
            environment: [ONE=1, PASSED]
            healthcheck: {test: "true", interval: 1s, retries: 2}
            x-note: ignored
          b:
            command: [python, -c, "pass", 3, true]
            depends_on: [a]
            restart: no
            environment: {N: 3, FLAG: false}
            namespace: robot1
        """,
    )
    stack = load_stack(path, env={}, project_dir=tmp_path)
    a, b = stack.services["a"], stack.services["b"]
    assert str(a.restart) == "on-failure:3" and a.restart.max_retries == 3 and a.stop_grace_period == 0.5
    assert a.environment == {"ONE": "1", "PASSED": None}
    assert b.command == ["python", "-c", "pass", "3", "true"]
    assert b.depends_on["a"].condition == "service_started"
    assert str(b.restart) == "no"
    assert b.environment == {"N": "3", "FLAG": "false"}
    assert stack.project_name == "robots"


@pytest.mark.parametrize(
    ("service_yaml", "expected"),
    [
        (
            "restart: sometimes",
            "services.planner.restart: expected one of no, always, on-failure[:max], unless-stopped",
        ),
        ("restart: always:3", "services.planner.restart: only on-failure takes a maximum"),
        ("stop_grace_period: soon", "services.planner.stop_grace_period: expected a duration"),
        ("colour: red", "services.planner.colour: unknown key"),
        (
            "depends_on: {ghost: {condition: service_started}}",
            "services.planner.depends_on.ghost: unknown service",
        ),
        (
            "depends_on: {router: {condition: service_ready}}",
            "services.planner.depends_on.router.condition: invalid enum value 'service_ready'",
        ),
        (
            "depends_on: {router: {condition: service_healthy}}",
            "services.planner.depends_on.router.condition: service_healthy needs a healthcheck on router",
        ),
        (
            "healthcheck: {timeout: 5s}",
            "services.planner.healthcheck: give liveliness: true or a test command",
        ),
        (
            "healthcheck: {liveliness: true, retries: 0}",
            "services.planner.healthcheck.retries: must be at least 1",
        ),
        ("namespace: 'a/*'", "services.planner.namespace: namespace 'a/*'"),
        ("command: []", "services.planner.command: must not be empty"),
        ("profiles: viz", "services.planner.profiles: expected a list, got text"),
    ],
)
def test_errors_name_the_file_and_the_key(tmp_path: Path, service_yaml: str, expected: str) -> None:
    path = write(
        tmp_path,
        f"""\
        services:
          router: {{command: [zendock, router]}}
          planner:
            command: [python, -m, services.planner]
            {service_yaml}
        """,
    )
    message = error_of(path)
    assert message.startswith(f"{path}: "), message
    assert expected in message, message


def test_top_level_errors(tmp_path: Path) -> None:
    assert "stack.yaml: servics: unknown key" in error_of(
        write(tmp_path, "servics: {}\nservices: {a: {command: [x]}}\n")
    )
    assert "services: missing (required)" in error_of(write(tmp_path, "name: x\n"))
    assert "zenoh.connect: give at least one endpoint" in error_of(
        write(tmp_path, "zenoh: {connect: ['']}\nservices: {a: {command: [x]}}\n")
    )
    cycle = error_of(
        write(
            tmp_path,
            "services:\n  a: {command: [x], depends_on: [b]}\n  b: {command: [x], depends_on: [a]}\n",
        )
    )
    assert "services: dependency cycle: a -> b -> a" in cycle
    assert "invalid YAML" in error_of(write(tmp_path, "services: [unclosed\n"))
    assert "(top level): expected a mapping" in error_of(write(tmp_path, "- a list\n"))


def test_interpolation_errors_carry_the_key_path(tmp_path: Path) -> None:
    path = write(tmp_path, "services:\n  sim: {command: [python, '${WORLD:?set WORLD}']}\n")
    assert error_of(path) == f"{path}: services.sim.command.1: required variable WORLD is missing: set WORLD"


def test_several_problems_are_reported_together(tmp_path: Path) -> None:
    path = write(tmp_path, "services:\n  a: {command: [x], restart: bad, stop_grace_period: bad}\n")
    lines = error_of(path).splitlines()
    assert [line.split(": ")[1] for line in lines] == ["services.a.restart", "services.a.stop_grace_period"]


def test_selection_follows_profiles_names_and_dependencies(tmp_path: Path) -> None:
    path = write(
        tmp_path,
        """\
        services:
          viz: {command: [x], depends_on: [router], profiles: [viz]}
          planner: {command: [x], depends_on: [map, router]}
          map: {command: [x]}
          router: {command: [x]}
          debug: {command: [x], profiles: [debug]}
        """,
    )
    stack = load_stack(path, env={}, project_dir=tmp_path)
    assert stack.select() == ["map", "router", "planner"]
    assert stack.select(profiles=["viz"]) == ["map", "router", "viz", "planner"]
    assert stack.select(["viz"]) == ["router", "viz"]
    assert stack.select(["planner"]) == ["map", "router", "planner"]
    assert stack.profiles == ["debug", "viz"]
    with pytest.raises(ConfigError, match="no such service: ghost"):
        stack.select(["ghost"])


def test_the_default_stack_validates_with_its_services() -> None:
    stack = load_stack(DEFAULT_STACK, env={}, project_dir=REPO_ROOT)
    assert stack.project_name == "zendock"
    assert stack.namespace == ""
    assert stack.connect == ("tcp/127.0.0.1:7447",)
    assert stack.select() == [
        "router",
        "map",
        "simulator",
        "perception",
        "battery",
        "pose",
        "planner",
        "docking",
    ]
    assert stack.services["viz"].profiles == ("viz",)
    assert "viz" in stack.select(profiles=["viz"])
    assert stack.services["router"].command == ["zendock", "router", "--listen", "tcp/127.0.0.1:7447"]
    assert stack.services["planner"].depends_on["map"].condition == "service_completed_successfully"


def test_zendock_world_alone_switches_the_default_stack() -> None:
    world = "deploy/worlds/glass_room.yaml"
    stack = load_stack(DEFAULT_STACK, env={"ZENDOCK_WORLD": world}, project_dir=REPO_ROOT)
    mentions = {
        name: " ".join(spec.command)
        for name, spec in stack.services.items()
        if world in " ".join(spec.command)
    }
    assert set(mentions) == {"map", "simulator", "perception", "docking", "viz"}
    assert "seed_room" not in " ".join(" ".join(spec.command) for spec in stack.services.values())
    map_file = stack.services["map"].command[stack.services["map"].command.index("-o") + 1]
    assert f"map_yaml={map_file}" in stack.services["planner"].command


def test_router_endpoints_follow_the_variables() -> None:
    env = {"ZENOH_LISTEN": "tcp/127.0.0.1:7500", "ZENOH_CONNECT": "tcp/127.0.0.1:7500"}
    stack = load_stack(DEFAULT_STACK, env=env, project_dir=REPO_ROOT)
    assert stack.services["router"].command[-1] == "tcp/127.0.0.1:7500"
    assert stack.connect == ("tcp/127.0.0.1:7500",)


def test_zendock_detector_switches_who_reports_the_dock() -> None:
    for detector in ("aruco", "synthetic"):
        stack = load_stack(DEFAULT_STACK, env={"ZENDOCK_DETECTOR": detector}, project_dir=REPO_ROOT)
        assert f"detection.source={detector}" in stack.services["simulator"].command
        assert f"dock_detector={detector}" in stack.services["perception"].command
    default = load_stack(DEFAULT_STACK, env={}, project_dir=REPO_ROOT)
    assert "detection.source=aruco" in default.services["simulator"].command
