"""``make test-containers``: the container deployment, run for real with rootful podman and podman-compose.

Steps, each timed: make sure podman can run here (install and configure it when missing; "skipped" and exit
0 where containers cannot run), build the registry-free base and the image, bring the compose stack up,
wait for every container's health check, check that each service is its own network host and that the map
volume reached the planner, dock from the host through the published router port and wait for CHARGING,
kill a service's process and see its container come back without losing the dock, bring it down and check
nothing is left; then the same for the secure profile (and a container without credentials refused), and a
trials campaign in two shard containers merged on the host, which must have the unsharded campaign's starts.

Outside ``make test``: it needs root and several minutes. Exit 0 passed or skipped, 1 failed.
"""

from __future__ import annotations

import json
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[2]
COMPOSE = REPO_ROOT / "deploy" / "docker-compose.yml"
SECURE = REPO_ROOT / "deploy" / "docker-compose.secure.yml"
SHARDS = REPO_ROOT / "deploy" / "batch" / "trials-shards.compose.yml"
BASE_SCRIPT = REPO_ROOT / "deploy" / "docker" / "base-image.sh"
CONTAINERS_CONF = Path("/etc/containers/containers.conf")
#: What this kind of sandbox needs (crun refuses its hybrid cgroups; the default ulimits exceed root's).
CONF_TEXT = """# Written by zendock's make test-containers: what podman needs in this sandbox.
[containers]
default_ulimits = ["nofile=20000:20000", "nproc=32768:32768"]

[engine]
runtime = "runc"
"""
IMAGE = "zendock:latest"
BASE_IMAGE = os.environ.get("ZENDOCK_BASE_IMAGE", "zendock-base:bookworm")
SERVICES = ("simulator", "perception", "battery", "pose", "planner", "docking")
USER_UID = 10001


class Skip(Exception):
    """Containers cannot run on this machine (said once, exit 0)."""


class CheckFailed(AssertionError):
    pass


def run(
    argv: list[str],
    *,
    env: dict[str, str] | None = None,
    timeout: float = 600.0,
    check: bool = True,
    cwd: Path = REPO_ROOT,
) -> subprocess.CompletedProcess[str]:
    done = subprocess.run(
        argv, capture_output=True, text=True, timeout=timeout, cwd=cwd, env={**os.environ, **(env or {})}
    )
    if check and done.returncode != 0:
        tail = "\n".join((done.stdout + done.stderr).strip().splitlines()[-15:])
        raise CheckFailed(f"{' '.join(argv)} exited {done.returncode}:\n{tail}")
    return done


def wait_until(predicate: Callable[[], bool], timeout_s: float, what: str, interval_s: float = 1.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not predicate():
        if time.monotonic() > deadline:
            raise CheckFailed(f"{what}: not within {timeout_s:g} s")
        time.sleep(interval_s)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class Steps:
    """Times each step and prints it as it ends."""

    def __init__(self) -> None:
        self.times: list[tuple[str, float]] = []

    @contextmanager
    def step(self, name: str) -> Iterator[None]:
        print(f"-- {name} ...", flush=True)
        start = time.monotonic()
        yield
        elapsed = time.monotonic() - start
        self.times.append((name, elapsed))
        print(f"   {name}: {elapsed:.1f} s", flush=True)

    def table(self) -> str:
        width = max(len(n) for n, _ in self.times)
        return "\n".join(f"{n:<{width}}  {t:7.1f} s" for n, t in self.times)


# --- podman here -----------------------------------------------------------------------------------------


def ensure_podman() -> None:
    """Podman installed and configured for this sandbox, or ``Skip`` saying why it cannot be."""
    if os.geteuid() != 0:
        raise Skip("containers need root here (rootful podman); run make test-containers as root")
    if shutil.which("podman") is None or shutil.which("debootstrap") is None:
        if shutil.which("apt-get") is None:
            raise Skip("podman is not installed and there is no apt-get to install it")
        print("installing podman, runc, catatonit and debootstrap from Debian's packages", flush=True)
        env = {"DEBIAN_FRONTEND": "noninteractive"}
        if (
            run(["apt-get", "update", "-qq"], env=env, check=False).returncode != 0
            or run(
                ["apt-get", "install", "-y", "-qq", "podman", "runc", "catatonit", "debootstrap"],
                env=env,
                check=False,
                timeout=900,
            ).returncode
            != 0
        ):
            raise Skip("podman could not be installed from Debian's packages")
    if not CONTAINERS_CONF.exists():
        CONTAINERS_CONF.parent.mkdir(parents=True, exist_ok=True)
        CONTAINERS_CONF.write_text(CONF_TEXT)
        print(f"wrote {CONTAINERS_CONF} (runc; ulimits root may set)", flush=True)
    info = run(["podman", "info", "--format", "{{.Host.OCIRuntime.Name}}"], check=False)
    if info.returncode != 0:
        raise Skip(f"podman cannot run here: {(info.stderr.strip().splitlines() or ['?'])[-1]}")


def compose_command() -> list[str]:
    beside = Path(sys.executable).parent / "podman-compose"
    found = str(beside) if beside.exists() else shutil.which("podman-compose")
    if found is None:
        raise CheckFailed("podman-compose is not installed (make test-containers installs it into .venv)")
    return [found]


def zendock(*args: str, timeout: float = 600.0, check: bool = True) -> subprocess.CompletedProcess[str]:
    return run([sys.executable, "-m", "deploy.cli", *args], timeout=timeout, check=check)


# --- one compose project ----------------------------------------------------------------------------------


class Project:
    """A compose project with its own name and published port, always brought down."""

    def __init__(self, name: str, files: list[Path], env: dict[str, str]) -> None:
        self.name, self.files, self.env = name, files, env
        self.base = [*compose_command(), "-p", name]
        for file in files:
            self.base += ["-f", str(file)]

    def compose(self, *args: str, timeout: float = 600.0) -> subprocess.CompletedProcess[str]:
        return run([*self.base, *args], env=self.env, timeout=timeout)

    def container(self, service: str) -> str:
        return f"{self.name}_{service}_1"

    def containers(self) -> list[str]:
        out = run(
            [
                "podman",
                "ps",
                "-a",
                "--filter",
                f"label=io.podman.compose.project={self.name}",
                "--format",
                "{{.Names}}",
            ]
        ).stdout
        return out.split()

    def leftovers(self) -> list[str]:
        left = [f"container {c}" for c in self.containers()]
        networks = run(["podman", "network", "ls", "--format", "{{.Name}}"]).stdout.split()
        left += [f"network {n}" for n in networks if n.startswith(f"{self.name}_")]
        volumes = run(["podman", "volume", "ls", "--format", "{{.Name}}"]).stdout.split()
        left += [f"volume {v}" for v in volumes if v.startswith(f"{self.name}_")]
        return left

    def down(self) -> None:
        run([*self.base, "down", "-v", "-t", "5"], env=self.env, check=False, timeout=300)

    @contextmanager
    def up(self, steps: Steps, label: str) -> Iterator[None]:
        """The project for the block's length: always brought down after it, then nothing of it may be left."""
        try:
            yield
        finally:
            with steps.step(f"{label} down, nothing left"):
                self.down()
                left = self.leftovers()
        if left:
            raise CheckFailed(f"left after down: {', '.join(left)}")

    def healthy(self, service: str) -> bool:
        return (
            run(["podman", "healthcheck", "run", self.container(service)], check=False, timeout=60).returncode
            == 0
        )

    def wait_healthy(self, services: tuple[str, ...], timeout_s: float = 180.0) -> None:
        pending = ["router", *services]
        start = time.monotonic()
        deadline, said = start + timeout_s, start
        while pending:
            pending = [s for s in pending if not self.healthy(s)]
            if pending and time.monotonic() - said > 15.0:
                said = time.monotonic()
                print(
                    f"   after {said - start:.0f} s still waiting for {', '.join(pending)} "
                    f"({pending[0]}: {self.last_health_output(pending[0])})",
                    flush=True,
                )
            if pending and time.monotonic() > deadline:
                raise CheckFailed(
                    f"{self.name}: not healthy within {timeout_s:g} s: {', '.join(pending)}\n"
                    + self.logs(pending[0])
                )
            if pending:
                time.sleep(2.0)

    def last_health_output(self, service: str) -> str:
        state = self.inspect(service)["State"]
        health = state.get("Health") or state.get("Healthcheck") or {}
        log = health.get("Log") or []
        return log[-1].get("Output", "").strip()[-300:] if log else "no health check run yet"

    def logs(self, service: str, tail: int = 20) -> str:
        done = run(["podman", "logs", "--tail", str(tail), self.container(service)], check=False)
        return f"last output of {service}:\n{done.stdout}{done.stderr}"

    def inspect(self, service: str) -> dict:
        return json.loads(run(["podman", "inspect", self.container(service)]).stdout)[0]


def wait_charging(
    endpoint: str, timeout_s: float, zenoh_config: str | None = None, full_too: bool = False
) -> None:
    """A ``battery_status`` saying CHARGING arrives on a session opened now (so it is a new one); with
    ``full_too``, FULL also counts (a restarted battery starts full, and says FULL only while mated)."""
    from shared.messages import BatteryState
    from shared.session import SessionSpec, open_session
    from tests.support.bus import KeyRecorder

    spec = SessionSpec(connect=(endpoint,), config_file=zenoh_config)
    with open_session(spec) as session:
        recorder = KeyRecorder(session, "battery_status", BatteryState)
        try:
            on_charger = {BatteryState.POWER_SUPPLY_STATUS_CHARGING}
            if full_too:
                on_charger.add(BatteryState.POWER_SUPPLY_STATUS_FULL)
            recorder.wait_for(lambda m: m.power_supply_status in on_charger, timeout_s)
        except AssertionError as exc:
            raise CheckFailed(str(exc)) from None
        finally:
            recorder.close()


def kill_service_process(project: Project, service: str) -> int:
    """SIGKILL the service's own process (the child of the container's init), as a crash would; returns the
    container's restart count before."""
    details = project.inspect(service)
    state, before = details["State"], int(details.get("RestartCount", 0))
    children = run(["ps", "--ppid", str(state["Pid"]), "-o", "pid="]).stdout.split()
    if not children:
        raise CheckFailed(f"{service}: no process under the container's init (pid {state['Pid']})")
    os.kill(int(children[0]), 9)
    return before


# --- the checks -------------------------------------------------------------------------------------------


def check_default_stack(steps: Steps, tag: str) -> None:
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    project = Project(
        f"zendock{tag}",
        [COMPOSE],
        {"ZENOH_PUBLISH_PORT": str(port), "ZENDOCK_RTF": "4", "ZENDOCK_CONTROLLER": "graceful"},
    )
    with project.up(steps, "stack"):
        with steps.step("stack up (compose up -d)"):
            project.compose("up", "-d")
        with steps.step("every container healthy"):
            project.wait_healthy(SERVICES)
        with steps.step("own network hosts, map volume"):
            addresses = {}
            for service in ("router", *SERVICES):
                networks = project.inspect(service)["NetworkSettings"]["Networks"]
                if list(networks) != [f"{project.name}_bus"]:
                    raise CheckFailed(f"{service}: on networks {list(networks)}, not only {project.name}_bus")
                addresses[service] = networks[f"{project.name}_bus"]["IPAddress"]
            if len(set(addresses.values())) != len(addresses):
                raise CheckFailed(f"services share addresses: {addresses}")
            run(["podman", "exec", project.container("planner"), "test", "-s", "/maps/map.yaml"])
            if "map from /maps/map.yaml" not in project.logs("planner", tail=500):
                raise CheckFailed("the planner did not load /maps/map.yaml:\n" + project.logs("planner"))
            user = run(["podman", "exec", project.container("docking"), "id", "-u"]).stdout.strip()
            if user != str(USER_UID):
                raise CheckFailed(f"services run as uid {user}, not the image's user {USER_UID}")
            print(f"   addresses: {addresses}")
        with steps.step("dock from the host (zendock dock, then CHARGING)"):
            zendock("dock", "--connect", endpoint, "--timeout", "300")
            wait_charging(endpoint, 60.0)
        with steps.step("kill -9 the battery service; back, still charging"):
            before = kill_service_process(project, "battery")
            wait_until(
                lambda: int(project.inspect("battery").get("RestartCount", 0)) > before,
                60.0,
                "the battery container restarting",
            )
            project.wait_healthy(("battery",), 90.0)
            wait_charging(endpoint, 60.0, full_too=True)
        with steps.step("SIGTERM stops every service cleanly (compose stop)"):
            project.compose("stop", "-t", "10")
            codes = {s: project.inspect(s)["State"]["ExitCode"] for s in ("router", *SERVICES)}
            if any(codes.values()):
                raise CheckFailed(
                    f"exit codes after SIGTERM (0 expected; 137: killed at the timeout): {codes}"
                )


def check_secure_stack(steps: Steps, tag: str) -> None:
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    # another world than the default one: ZENDOCK_WORLD switches the simulator, the map and the docks
    project = Project(
        f"zendocksecure{tag}",
        [COMPOSE, SECURE],
        {"ZENOH_PUBLISH_PORT": str(port), "ZENDOCK_RTF": "4", "ZENDOCK_WORLD": "deploy/worlds/corridor.yaml"},
    )
    secure = REPO_ROOT / "deploy" / "zenoh" / "secure"
    with project.up(steps, "secure stack"):
        with steps.step("secure stack up and healthy"):
            project.compose("up", "-d")
            project.wait_healthy(SERVICES)
            if "world corridor" not in project.logs("simulator", tail=500):
                raise CheckFailed("ZENDOCK_WORLD did not reach the simulator:\n" + project.logs("simulator"))
        with steps.step("secure: no credentials refused, operator docks (corridor)"):
            network = f"{project.name}_bus"
            plain = run(
                [
                    "podman",
                    "run",
                    "--rm",
                    "--network",
                    network,
                    IMAGE,
                    "zendock",
                    "health",
                    "simulator",
                    "--connect",
                    "tcp/router:7447",
                    "--connect-timeout",
                    "3",
                ],
                check=False,
                timeout=120,
            )
            if plain.returncode == 0:
                raise CheckFailed("a container without credentials got a session on the secure router")
            viewer = run(
                [
                    "podman",
                    "run",
                    "--rm",
                    "--network",
                    network,
                    "-e",
                    "ZENDOCK_ZENOH_CONFIG=deploy/zenoh/secure/viewer.json5",
                    IMAGE,
                    "zendock",
                    "health",
                    "simulator",
                    "--connect",
                    "tcp/router:7447",
                ],
                check=False,
                timeout=120,
            )
            if viewer.returncode != 0:
                raise CheckFailed(f"the viewer user was refused: {viewer.stderr.strip()}")
            if (
                zendock(
                    "health", "simulator", "--connect", endpoint, "--connect-timeout", "3", check=False
                ).returncode
                == 0
            ):
                raise CheckFailed("the host got a session on the secure router without credentials")
            zendock(
                "dock",
                "--connect",
                endpoint,
                "--zenoh-config",
                str(secure / "operator.json5"),
                "--timeout",
                "300",
            )
            wait_charging(endpoint, 60.0, zenoh_config=str(secure / "viewer.json5"))


def check_sharded_trials(steps: Steps, tag: str) -> None:
    from deploy.trials import reachable_starts
    from shared.world import load_world

    n, seed = 4, 3
    runs = Path(tempfile.mkdtemp(prefix="zendock-shards-"))
    os.chown(runs, USER_UID, USER_UID)
    project = Project(
        f"zendocktrials{tag}",
        [SHARDS],
        {
            "ZENDOCK_RUNS_DIR": str(runs),
            "ZENDOCK_TRIALS": str(n),
            "ZENDOCK_SEED": str(seed),
            "ZENDOCK_SHARDS": "2",
            "ZENDOCK_DETECTOR": "synthetic",
            "ZENDOCK_RTF": "8",
        },
    )
    try:
        with steps.step("two shard containers, trials each"):
            project.compose("up", timeout=1200)
            exits = {s: project.inspect(s)["State"]["ExitCode"] for s in ("shard-1", "shard-2")}
            if any(exits.values()):
                raise CheckFailed(f"shard containers failed: {exits}\n" + project.logs("shard-1"))
        with steps.step("merge on the host, same starts"):
            merged = zendock("trials", "merge", str(runs), "--runs-dir", str(runs / "merged"), "--json")
            summary = json.loads(merged.stdout.strip().splitlines()[-1])
            report = json.loads(next((runs / "merged").rglob("trials.json")).read_text())
            world = REPO_ROOT / "deploy" / "worlds" / "seed_room.yaml"
            want = [list(s.as_tuple()) for s in reachable_starts(world, load_world(world), n, seed)]
            got = [t["start"] for t in report["trials"]]
            if summary["n"] != n or got != want:
                raise CheckFailed(
                    f"merged shards: n {summary['n']}, starts {got}; the unsharded starts are {want}"
                )
            print(f"   merged: {summary['successes']}/{summary['n']} docked, starts as unsharded")
    finally:
        project.down()
        shutil.rmtree(runs, ignore_errors=True)


def main() -> int:
    steps = Steps()
    tag = str(os.getpid())
    try:
        with steps.step("podman ready"):
            ensure_podman()
        if BASE_IMAGE == "zendock-base:bookworm":
            with steps.step("base image (debootstrap, no registry)"):
                run(["bash", str(BASE_SCRIPT), BASE_IMAGE], timeout=900)
        with steps.step("image build"):
            run(
                [
                    "podman",
                    "build",
                    "--build-arg",
                    f"BASE={BASE_IMAGE}",
                    "-f",
                    "deploy/docker/Dockerfile",
                    "-t",
                    IMAGE,
                    ".",
                ],
                timeout=1800,
            )
        size = int(run(["podman", "image", "inspect", "--format", "{{.Size}}", IMAGE]).stdout.strip())
        print(f"   image {IMAGE}: {size / 1e6:.0f} MB", flush=True)
        check_default_stack(steps, tag)
        check_secure_stack(steps, tag)
        check_sharded_trials(steps, tag)
    except Skip as exc:
        print(f"test-containers: skipped: {exc}")
        return 0
    except (CheckFailed, subprocess.TimeoutExpired) as exc:
        print(f"\ntest-containers: FAILED: {exc}\n\n{steps.table()}", file=sys.stderr)
        return 1
    print(f"\ntest-containers: passed\n{steps.table()}\nimage size {size / 1e6:.0f} MB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
