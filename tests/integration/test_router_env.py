"""A bare ``zendock router`` listens where ZENOH_LISTEN says, in the environment or in ./.env, as the rest of
zendock reads it."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from deploy.launcher import free_tcp_port
from tests.support.processes import wait_until


def _accepts(port: int) -> bool:
    with socket.socket() as probe:
        probe.settimeout(0.2)
        return probe.connect_ex(("127.0.0.1", port)) == 0


@pytest.mark.parametrize("where", ["environment", "dotenv"])
def test_a_bare_router_listens_on_zenoh_listen(where: str, tmp_path: Path) -> None:
    port = free_tcp_port()
    env = {k: v for k, v in os.environ.items() if k != "ZENOH_LISTEN"}
    if where == "environment":
        env["ZENOH_LISTEN"] = f"tcp/127.0.0.1:{port}"
    else:
        (tmp_path / ".env").write_text(f"# the bus\nexport ZENOH_LISTEN=tcp/127.0.0.1:{port}\n")
    router = subprocess.Popen(
        [sys.executable, "-m", "deploy.cli", "router"],
        cwd=tmp_path,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        start_new_session=True,
    )
    try:
        wait_until(
            lambda: _accepts(port) or router.poll() is not None,
            timeout_s=20.0,
            describe=lambda: f"the router did not listen on {port} (exit code {router.poll()})",
        )
        assert router.poll() is None and _accepts(port), "the router exited instead of listening"
    finally:
        router.terminate()
        try:
            router.wait(timeout=10.0)
        except subprocess.TimeoutExpired:
            router.kill()
            router.wait()
        assert router.stdout is not None
        router.stdout.close()
