"""Service flags and parameters: strict, with one clear message and exit code 2 for bad input."""

from __future__ import annotations

import re
import signal
import subprocess
import sys
import threading
from pathlib import Path
from typing import Annotated

import msgspec
import pytest
import yaml
from msgspec import Meta

from shared.config_errors import ConfigError
from shared.parameters import ServiceParams
from shared.runtime import (
    ServiceOptions,
    build_arg_parser,
    load_params,
    options_from_args,
    parse_parameter_value,
    run_service,
)
from shared.waiting import wait_interruptibly


class DemoParams(ServiceParams):
    rate_hz: float = 10.0
    target_frame: str = "base_link"


class LidarPart(msgspec.Struct, forbid_unknown_fields=True, frozen=True, kw_only=True):
    rate_hz: Annotated[float, Meta(gt=0)] = 10.0
    noise_m: Annotated[float, Meta(ge=0)] = 0.01


class NestedParams(ServiceParams):
    """A service with a part, as the simulator nests ``lidar``."""

    world: str = "room.yaml"
    lidar: LidarPart = msgspec.field(default_factory=LidarPart)


def _options(*argv: str) -> ServiceOptions:
    return options_from_args(build_arg_parser("demo").parse_args(list(argv)))


def test_defaults_and_env(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ZENDOCK_CONNECT", "tcp/127.0.0.1:9000,tcp/127.0.0.1:9001")
    monkeypatch.setenv("ZENDOCK_NAMESPACE", "/robot1/")
    opts = _options()
    assert opts.connect == ("tcp/127.0.0.1:9000", "tcp/127.0.0.1:9001")
    assert opts.namespace == "robot1"
    assert _options("--connect", "tcp/127.0.0.1:1", "--namespace", "r2").connect == ("tcp/127.0.0.1:1",)


def test_overrides_are_typed_yaml_scalars() -> None:
    params = load_params(
        DemoParams, _options("-p", "rate_hz=20", "-p", "use_sim_time=true", "-p", "target_frame=lidar_link")
    )
    assert params.rate_hz == 20.0 and params.use_sim_time is True and params.target_frame == "lidar_link"


def test_unknown_parameter_is_an_error() -> None:
    with pytest.raises(ConfigError, match="rate: unknown key"):
        load_params(DemoParams, _options("-p", "rate=3"))


def test_bad_value_is_an_error() -> None:
    with pytest.raises(ConfigError, match="rate_hz"):
        load_params(DemoParams, _options("-p", "rate_hz=fast"))


def test_malformed_override() -> None:
    with pytest.raises(ConfigError, match="NAME=VALUE"):
        _options("-p", "nonsense")


def test_bad_namespace() -> None:
    with pytest.raises(ConfigError, match="--namespace"):
        _options("--namespace", "robot*")


def test_config_file_flat_and_ros_style(tmp_path: Path) -> None:
    flat = tmp_path / "flat.yaml"
    flat.write_text("rate_hz: 5\n")
    assert load_params(DemoParams, _options("--config", str(flat))).rate_hz == 5
    ros = tmp_path / "ros.yaml"
    ros.write_text("demo:\n  ros__parameters:\n    rate_hz: 7\n")
    assert load_params(DemoParams, _options("--config", str(ros), "-p", "target_frame=x")).rate_hz == 7
    bad = tmp_path / "bad.yaml"
    bad.write_text("rate_hz: [1\n")
    with pytest.raises(ConfigError, match="not valid YAML"):
        load_params(DemoParams, _options("--config", str(bad)))
    with pytest.raises(ConfigError, match="cannot read"):
        load_params(DemoParams, _options("--config", str(tmp_path / "missing.yaml")))


def test_run_service_exits_2_on_bad_parameter(capsys: pytest.CaptureFixture[str]) -> None:
    def never_built(node, params):  # type: ignore[no-untyped-def]
        raise AssertionError("must not start with bad parameters")

    assert run_service("demo", DemoParams, never_built, ["-p", "bogus=1"]) == 2
    err = capsys.readouterr().err
    assert "bogus: unknown key" in err and err.count("\n") == 1


def test_dotted_override_sets_one_field_of_a_part() -> None:
    params = load_params(NestedParams, _options("-p", "lidar.noise_m=0.02"))
    assert params.lidar == LidarPart(noise_m=0.02)  # the part's other fields keep their defaults


def test_dotted_overrides_merge_with_a_nested_config_file(tmp_path: Path) -> None:
    config = tmp_path / "sim.yaml"
    config.write_text("lidar: {rate_hz: 5}\n")
    params = load_params(NestedParams, _options("--config", str(config), "-p", "lidar.noise_m=0.02"))
    assert params.lidar == LidarPart(rate_hz=5, noise_m=0.02)
    dotted = tmp_path / "dotted.yaml"
    dotted.write_text("lidar.rate_hz: 4\n")
    assert load_params(
        NestedParams, _options("--config", str(dotted), "-p", "lidar={noise_m: 0}")
    ).lidar == LidarPart(rate_hz=4, noise_m=0)


@pytest.mark.parametrize(
    ("override", "message"),
    [
        ("lidr.noise_m=0.02", "lidr.noise_m: unknown group 'lidr' (groups: lidar)"),
        ("lidar.noise=0.02", "lidar.noise: unknown key"),
        ("lidar.noise_m=-1", "lidar.noise_m: must be at least 0"),
        ("lidar.noise_m=loud", "lidar.noise_m: expected float, got text"),
        ("world.name=x", "world.name: 'world' is a single parameter, not a group"),
        ("lidar..noise_m=1", "lidar..noise_m: not a parameter name"),
    ],
)
def test_bad_dotted_overrides_name_the_parameter(override: str, message: str) -> None:
    with pytest.raises(ConfigError, match=re.escape(message)):
        load_params(NestedParams, _options("-p", override))


def test_run_service_exits_2_on_a_bad_dotted_parameter(capsys: pytest.CaptureFixture[str]) -> None:
    def never_built(node, params):  # type: ignore[no-untyped-def]
        raise AssertionError("must not start with bad parameters")

    assert run_service("demo", NestedParams, never_built, ["-p", "lidar.noise=1"]) == 2
    err = capsys.readouterr().err
    assert "lidar.noise: unknown key" in err and err.count("\n") == 1


_STOPPED_BY_A_SIGNAL_ON_ANOTHER_THREAD = """
import signal, sys, threading
from shared.waiting import wait_interruptibly
stop = threading.Event()
signal.signal(signal.SIGINT, lambda *_: stop.set())
threading.Thread(target=threading.Event().wait, args=(60,), daemon=True).start()
# the kernel now hands SIGINT to the other thread, as it may to one of Zenoh's
signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
print("waiting", flush=True)
wait_interruptibly(stop)
print("stopped", flush=True)
"""


def test_wait_interruptibly_times_out_or_returns_once_set() -> None:
    event = threading.Event()
    assert wait_interruptibly(event, 0.05) is False
    threading.Timer(0.05, event.set).start()
    assert wait_interruptibly(event, 10.0) is True
    assert wait_interruptibly(event) is True


def test_wait_interruptibly_runs_a_handler_whose_signal_went_to_another_thread() -> None:
    proc = subprocess.Popen(
        [sys.executable, "-c", _STOPPED_BY_A_SIGNAL_ON_ANOTHER_THREAD],
        cwd=Path(__file__).resolve().parents[3],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout is not None
        assert proc.stdout.readline().strip() == "waiting"
        proc.send_signal(signal.SIGINT)
        out, _ = proc.communicate(timeout=10)
        assert out.strip() == "stopped" and proc.returncode == 0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


@pytest.mark.parametrize(
    "text",
    [
        "true",
        "false",
        "True",
        "yes",
        "off",
        "12",
        "-3",
        "0",
        "-0",
        "007",
        "1.5",
        "-0.25",
        "0.",
        ".5",
        "1e3",
        "1.0e+3",
        "0x1f",
        "[0.1, 0, 0]",
        "{a: 1}",
        "abc",
        "/tmp/world-1.yaml",
        "r1/base_link",
        "graceful",
        "On",
        "NULL",
        "Y",
        ".inf",
        "_x",
        "a:b",
        "~",
        "null",
        "",
        "  ",
    ],
)
def test_a_parameter_value_reads_as_yaml_reads_it(text: str) -> None:
    """Plain scalars skip the YAML parser; the value and its type must be the parser's all the same."""
    expected = yaml.safe_load(text) if text.strip() else ""
    got = parse_parameter_value(text)
    assert got == expected and type(got) is type(expected)
