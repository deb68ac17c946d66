"""``zendock bench startup``: where a service's start-up time goes, the time a killed service is down.

For each service, several times over, on a router of its own: a bare interpreter (``python -c pass``),
the import of the service's node module (timed inside the interpreter), and the whole service from
``exec`` to its liveliness token on the bus (what the launcher's health check waits for). The differences are the phases: interpreter,
imports, and the rest (parameters, session open, declarations, ready). ``-X importtime`` then names the
imports that cost most, so a cut can aim at them. Last, the same service from a warm standby
(:mod:`deploy.standby`, ``--standby``): from ``go`` to the token, the floor of a restart that starts from one.
"""

from __future__ import annotations

import contextlib
import os
import select
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any, BinaryIO

from deploy.bench.processes import free_port
from deploy.launcher.launch import STANDBY_MODULE
from deploy.launcher.process import live_group_members
from deploy.paths import REPO_ROOT
from deploy.percentiles import median
from deploy.standby import GO, STATUS_FD_ENV
from shared.names import node_token_key
from shared.session import SessionSpec, open_session

SEED_ROOM = REPO_ROOT / "deploy" / "worlds" / "seed_room.yaml"


def _service_args(map_yaml: Path) -> dict[str, list[str]]:
    world = str(SEED_ROOM)
    return {
        "battery": ["-p", "use_sim_time=true"],
        "pose": ["-p", "use_sim_time=true"],
        "planner": ["-p", "use_sim_time=true", "-p", f"map_yaml={map_yaml}"],
        "docking": ["-p", "use_sim_time=true", "-p", f"dock_database={world}"],
        "perception": ["-p", f"dock_database={world}"],
        "simulator": ["--world", world],
    }


def _timed(argv: list[str]) -> float:
    start = time.perf_counter()
    subprocess.run(argv, cwd=REPO_ROOT, check=True, capture_output=True, timeout=120)
    return time.perf_counter() - start


def _import_s(module: str) -> tuple[float, int, int]:
    """Seconds the import itself takes, timed inside the interpreter (its exit, which unloads Zenoh and
    numpy, is not part of a service's start); then how many zendock modules it imported, and how many of
    those it compiled from source for want of a fresh bytecode cache (:mod:`deploy.bench.bytecode`)."""
    code = (
        f"import time; t = time.perf_counter(); import {module}; took = time.perf_counter() - t; "
        "from pathlib import Path; from deploy.bench.bytecode import compiled_from_source; "
        f"print(took, *compiled_from_source(Path({str(REPO_ROOT)!r})))"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], cwd=REPO_ROOT, check=True, capture_output=True, text=True, timeout=120
    )
    took, modules, compiled = done.stdout.strip().splitlines()[-1].split()
    return float(took), int(modules), int(compiled)


def _report(reports: BinaryIO, timeout_s: float = 60.0) -> list[bytes]:
    """The standby's next report (``ready``, ``started PID``), waiting at most ``timeout_s``."""
    ready, _, _ = select.select([reports], [], [], timeout_s)
    if not ready:
        raise RuntimeError(f"the standby said nothing for {timeout_s:g} s")
    return reports.readline().split()


def _stop_group(pgid: int, proc: subprocess.Popen[bytes] | None = None) -> None:
    """SIGINT to a process group, SIGKILL after 10 s; ``proc`` (the supervisor's child) is reaped."""
    with contextlib.suppress(ProcessLookupError):
        os.killpg(pgid, signal.SIGINT)
    deadline = time.monotonic() + 10.0
    while time.monotonic() < deadline:
        if proc is not None and proc.poll() is not None or proc is None and not live_group_members(pgid):
            return
        time.sleep(0.02)
    with contextlib.suppress(ProcessLookupError):
        os.killpg(pgid, signal.SIGKILL)
    if proc is not None:
        proc.wait()


def _to_token(
    service: str, args: list[str], endpoint: str, namespace: str, session: Any, standby: bool = False
) -> float:
    """Wall seconds from starting ``python -m services.<service>`` to its node token reaching the router;
    with ``standby``, from telling an idle warm standby ``go`` (:mod:`deploy.standby`)."""
    key = node_token_key(namespace, service)
    seen = threading.Event()
    watcher = session.liveliness().declare_subscriber(key, lambda sample: seen.set())
    flags = ["--connect", endpoint, "--namespace", namespace, *args]
    status_r, status_w = os.pipe()
    try:
        start = time.perf_counter()
        proc = subprocess.Popen(
            [sys.executable, "-m", STANDBY_MODULE, f"services.{service}", *flags]
            if standby
            else [sys.executable, "-m", f"services.{service}", *flags],
            cwd=REPO_ROOT,
            stdin=subprocess.PIPE if standby else subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            start_new_session=True,
            env={**os.environ, STATUS_FD_ENV: str(status_w)},
            pass_fds=(status_w,),
        )
        os.close(status_w)
        service_pgid = proc.pid
        reports = os.fdopen(status_r, "rb", buffering=0)
        try:
            if standby:
                assert proc.stdin is not None
                if _report(reports) != [b"ready"]:
                    raise RuntimeError(f"the {service} standby did not get ready")
                start = time.perf_counter()
                proc.stdin.write(GO)
                proc.stdin.flush()
                words = _report(reports)
                if words[:1] != [b"started"]:
                    raise RuntimeError(f"the {service} standby did not fork: {words!r}")
                service_pgid = int(words[1])
            if not seen.wait(60.0):
                raise RuntimeError(f"{service} never declared its token")
            return time.perf_counter() - start
        finally:
            if standby:
                _stop_group(service_pgid)
                assert proc.stdin is not None
                proc.stdin.close()
            _stop_group(proc.pid, proc)
            reports.close()
    finally:
        watcher.undeclare()


def top_imports(module: str, count: int = 5) -> list[tuple[str, float]]:
    """The module's heaviest direct imports by cumulative time (ms), from ``python -X importtime``."""
    done = subprocess.run(
        [sys.executable, "-X", "importtime", "-c", f"import {module}"],
        cwd=REPO_ROOT,
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    )
    rows = []
    for line in done.stderr.splitlines():
        if not line.startswith("import time:") or "cumulative" in line:
            continue
        _, _, rest = line.partition("import time:")
        parts = [p for p in rest.split("|")]
        if len(parts) != 3:
            continue
        name = parts[2]
        depth = (len(name) - len(name.lstrip(" "))) // 2
        if depth <= 1 and not name.strip().startswith("_") and name.strip() != module:
            rows.append((name.strip(), int(parts[1]) / 1000.0))
    return sorted(rows, key=lambda r: -r[1])[:count]


def run_startup_bench(repeats: int = 5, services: list[str] | None = None) -> dict[str, Any]:
    with tempfile.TemporaryDirectory(prefix="zendock-bench-startup-") as tmp:
        map_yaml = Path(tmp) / "map.yaml"
        subprocess.run(
            [
                sys.executable,
                "-m",
                "services.planner.map_save",
                "--world",
                str(SEED_ROOM),
                "-o",
                str(map_yaml),
            ],
            cwd=REPO_ROOT,
            check=True,
            capture_output=True,
            timeout=120,
        )
        commands = _service_args(map_yaml)
        wanted = services or list(commands)
        unknown = sorted(set(wanted) - set(commands))
        if unknown:
            raise ValueError(f"unknown service(s) {', '.join(unknown)}; choose from {', '.join(commands)}")
        endpoint = f"tcp/127.0.0.1:{free_port()}"
        report: dict[str, Any] = {"repeats": repeats, "services": {}}
        with (
            open_session(SessionSpec(mode="router", connect=(), listen=(endpoint,))),
            open_session(SessionSpec(mode="client", connect=(endpoint,))) as session,
        ):
            interpreter = median(_timed([sys.executable, "-c", "pass"]) for _ in range(repeats))
            report["interpreter_ms"] = round(1000 * interpreter, 1)
            for service in wanted:
                module = f"services.{service}.node"
                samples = [_import_s(module) for _ in range(repeats)]
                imports = median(took for took, _, _ in samples)
                ready = [
                    _to_token(service, commands[service], endpoint, f"startup{i}", session)
                    for i in range(repeats)
                ]
                warm = [
                    _to_token(service, commands[service], endpoint, f"standby{i}", session, standby=True)
                    for i in range(repeats)
                ]
                report["services"][service] = {
                    "interpreter_ms": round(1000 * interpreter, 1),
                    "imports_ms": round(1000 * imports, 1),
                    # zendock's own modules the import loaded, and how many it compiled from source
                    "own_modules": samples[-1][1],
                    "compiled_from_source": max(compiled for _, _, compiled in samples),
                    # parameters, the session, the node's declarations, the token's trip to the router
                    "session_and_ready_ms": round(1000 * (median(ready) - interpreter - imports), 1),
                    "to_token_ms": round(1000 * median(ready), 1),
                    "to_token_max_ms": round(1000 * max(ready), 1),
                    "from_standby_ms": round(1000 * median(warm), 1),
                    "from_standby_max_ms": round(1000 * max(warm), 1),
                    "top_imports_ms": dict(top_imports(module)),
                }
        return report
