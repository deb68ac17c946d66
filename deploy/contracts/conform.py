"""``zendock conform SERVICE -- COMMAND``: run the rest of a stack with COMMAND in place of SERVICE, and
check the contract with named checks.

The rest of the stack (the router and the services the contract says it needs, zendock's own) runs on a
private router on a free loopback port, in a temporary working directory, in the robot namespace ``r1``
(the fleet service in the fleet's, the root). The program under test gets what the launcher would give
zendock's own service: the environment and the flags. Checks run in order: it starts, announces its
endpoints, publishes at the contract's rates, behaves as the contract says, refuses bad requests with an
error, survives malformed payloads, ends on SIGTERM, and comes back when started again.
"""

from __future__ import annotations

import os
import random
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from deploy.contracts.candidate import Candidate
from deploy.contracts.checks import (
    BEHAVIOURS,
    Check,
    Context,
    PlannedCheck,
    RunWatch,
    check_bad_requests,
    check_endpoints,
    check_event_rates,
    check_frames,
    check_malformed_burst,
    check_publishes,
    check_restart,
    check_sigterm,
    check_starts,
    run_in_turn,
    still_serving,
)
from deploy.contracts.probe import Probe
from deploy.launcher import Launcher, free_endpoint, load_stack
from deploy.launcher.launch import ModuleRun, run_words
from deploy.launcher.plan import resolve_argv
from deploy.launcher.stack_file import Stack
from deploy.paths import REPO_ROOT
from deploy.replacements import ROBOT_PLACEHOLDER, absolute_if_file
from shared.config_errors import ConfigError
from shared.contracts import CONTRACTS
from shared.session import SessionSpec, open_session
from shared.world import load_world

DEFAULT_STACK = REPO_ROOT / "deploy" / "stack.yaml"
DEFAULT_WORLD = REPO_ROOT / "deploy" / "worlds" / "seed_room.yaml"
ROBOT_NAMESPACE = "r1"
#: Services that live in the fleet's namespace, not a robot's.
FLEET_WIDE = ("fleet",)


@dataclass
class ConformOptions:
    world: Path = DEFAULT_WORLD
    rtf: str = "4"
    runs_dir: Path | None = None


@dataclass
class ConformReport:
    service: str
    command: list[str]
    #: The version of the contract the program was held to.
    contract_version: str = ""
    checks: list[Check] = field(default_factory=list)
    wall_s: float = 0.0
    log: str = ""

    @property
    def passed(self) -> bool:
        return bool(self.checks) and all(c.passed for c in self.checks)

    def failed(self) -> list[str]:
        return [c.name for c in self.checks if c.ran and not c.passed]

    def not_run(self) -> list[str]:
        return [c.name for c in self.checks if not c.ran]

    def as_dict(self) -> dict[str, Any]:
        return {
            "service": self.service,
            "contract_version": self.contract_version,
            "command": self.command,
            "passed": self.passed,
            "wall_s": round(self.wall_s, 1),
            "failed": self.failed(),
            "not_run": self.not_run(),
            "checks": [c.as_dict() for c in self.checks],
            "log": self.log,
        }


def _own_run(service: str, stack: Stack) -> ModuleRun:
    """zendock's own ``service`` as the stack file runs it (its interpreter and flags), or plainly."""
    launch = stack.services.get(service)
    return launch.run if launch is not None and isinstance(launch.run, ModuleRun) else ModuleRun(service)


def _flags_for(service: str, stack: Stack, world: Path) -> list[str]:
    """The flags the launcher gives zendock's own ``service`` (from the stack file), plus conform's own."""
    launch = stack.services.get(service)
    flags = list(_own_run(service, stack).flags) if launch is not None else []
    if launch is None and service == "fleet":
        flags = ["-p", f"world={world}"]
    if service == "viz":
        flags += ["-p", "port=0"]  # any free port: never the default a running viewer uses
    return flags


def _own_command(service: str, stack: Stack) -> list[str]:
    """zendock's own service as its stack file runs it (the DDS face: with .venv-ros2's interpreter)."""
    run = _own_run(service, stack)
    python = run.python
    if python != "python" and not Path(python).is_absolute():
        python = str(REPO_ROOT / python)  # relative to the repository, where zendock's stacks run
    return run_words(ModuleRun(run.service, (), python, run.python_options))


def run_conform(
    service: str,
    command: list[str] | None,
    options: ConformOptions,
    log: Callable[[str], None] = lambda _text: None,
) -> ConformReport:
    """Run every check of ``service``'s contract against ``command`` (default: zendock's own service)."""
    contract = CONTRACTS.get(service)
    if contract is None:
        raise ConfigError(f"no contract for {service!r} (one of: {', '.join(CONTRACTS)})")
    world_path = options.world.resolve()
    world = load_world(world_path)
    if not world.docks:
        raise ConfigError(f"--world {options.world}: conform needs a world with a dock")
    namespace = "" if service in FLEET_WIDE else ROBOT_NAMESPACE
    domain_id = random.randint(100, 200)
    endpoint = free_endpoint()
    env = {
        "ZENOH_LISTEN": endpoint,
        "ZENOH_CONNECT": endpoint,
        "ZENDOCK_WORLD": str(world_path),
        "ZENDOCK_RTF": options.rtf,
        "ZENDOCK_DETECTOR": "aruco" if service == "perception" else "synthetic",
        "ROS_DOMAIN_ID": str(domain_id),
    }
    runs_dir = options.runs_dir or Path(tempfile.gettempdir())
    runs_dir.mkdir(parents=True, exist_ok=True)
    run_dir = Path(tempfile.mkdtemp(prefix=f"conform-{service}-", dir=runs_dir))
    stack = load_stack(DEFAULT_STACK, env=env, project_dir=run_dir)
    words = command or _own_command(service, stack)
    argv = resolve_argv(
        [absolute_if_file(w.replace(ROBOT_PLACEHOLDER, namespace)) for w in words]
    ) + _flags_for(service, stack, world_path)
    report = ConformReport(service, argv, contract.version, log=str(run_dir / "candidate.log"))
    # what it needs, and what zendock's own waits for in the stack file (the planner: the map step)
    own_dependencies = set(stack.services[service].depends_on) if service in stack.services else set()
    rest = sorted((set(contract.needs) | own_dependencies) - {service}, key=list(stack.services).index)
    selected = stack.select(["router", *rest])
    candidate_env = {
        **os.environ,
        "ZENDOCK_CONNECT": endpoint,
        "ZENDOCK_NAMESPACE": namespace,
        "ROS_DOMAIN_ID": str(domain_id),
    }
    candidate = Candidate(argv, candidate_env, run_dir / "candidate.log", run_dir)
    start = time.monotonic()
    who = "zendock's own" if command is None else " ".join(words)
    log(
        f"{service}: {who}; beside it: {', '.join(rest) or 'the router'} on {endpoint}, run directory {run_dir}"
    )
    # Steps the service waits to see finish (the planner: the map written): a step still running counts as
    # ready to wait_healthy, and the candidate would start before the map is there.
    own = stack.services.get(service)
    own_steps = [
        name
        for name, dependency in (own.depends_on.items() if own else ())
        if dependency.condition == "service_completed_successfully"
    ]
    with Launcher(
        stack,
        services=selected,
        project_dir=run_dir / "stack",
        working_dir=run_dir,
        namespace=ROBOT_NAMESPACE,
        project_name="conform",
    ) as launcher:
        launcher.wait_healthy(timeout_s=90.0)
        for step in own_steps:
            launcher.wait_state(step, "exited", timeout_s=90.0)
        with open_session(SessionSpec(connect=(endpoint,))) as session:
            probe = Probe(session, ROBOT_NAMESPACE)
            ctx = Context(
                contract,
                candidate,
                probe,
                world,
                namespace,
                ROBOT_NAMESPACE,
                sim="simulator" in contract.needs or service == "simulator",
                domain_id=domain_id,
            )
            planned = _planned_checks(ctx)
            try:
                try:
                    candidate.start()
                except OSError as exc:  # no such program, not executable
                    why = f"could not run {argv[0]}: {exc.strerror or exc}"
                    report.checks.append(Check(planned[0].name, False, why))
                    report.checks += [check.not_run(why) for check in planned[1:]]
                else:
                    report.checks += run_in_turn(
                        planned, lambda row: log(f"{row.result}  {row.name}: {row.evidence}")
                    )
            finally:
                candidate.close()
                probe.close()
    report.wall_s = time.monotonic() - start
    return report


def _planned_checks(ctx: Context) -> list[PlannedCheck]:
    """Every check of the contract, in the order they run: each gets its row, run or not."""
    behaviour = BEHAVIOURS.get(ctx.contract.service)
    watch = RunWatch(ctx)  # from before the service starts, to the checks that read it
    return [
        check_starts(ctx),
        *check_endpoints(ctx),
        *check_publishes(ctx),
        *(behaviour(ctx) if behaviour is not None else []),
        *[check for check in (check_frames(ctx, watch), check_event_rates(ctx, watch)) if check is not None],
        check_bad_requests(ctx),
        check_malformed_burst(ctx, still_serving(ctx)),
        check_sigterm(ctx),
        check_restart(ctx),
    ]
