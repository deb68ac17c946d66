"""Two "hosts" on one machine: network namespaces joined by a veth pair, and processes run inside them.

The pair carries IPv4 link-local addresses only (169.254.77.1/30 and .2/30, never routed), each
namespace has its own loopback, and nothing else is reachable from inside: traffic stays between the
two namespaces and their loopbacks. Cutting the link is ``ip link set <veth> down`` in one namespace.
Teardown kills every process still inside a namespace, then deletes both namespaces (the veth goes
with them).
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from tests.support.processes import ServiceProcess

HOST_A_ADDRESS = "169.254.77.1"
HOST_B_ADDRESS = "169.254.77.2"
PREFIX_LENGTH = 30


class NetnsUnavailable(RuntimeError):
    """This machine cannot create network namespaces (no iproute2, no privilege)."""


def _ip(*args: str, check: bool = True) -> subprocess.CompletedProcess[str]:
    done = subprocess.run(["ip", *args], capture_output=True, text=True, timeout=10)
    if check and done.returncode != 0:
        raise RuntimeError(f"ip {' '.join(args)}: {done.stderr.strip() or done.returncode}")
    return done


@dataclass
class HostPair:
    """Namespaces ``a`` and ``b`` with veth ends ``veth_a`` (169.254.77.1) and ``veth_b`` (169.254.77.2)."""

    a: str
    b: str
    veth_a: str
    veth_b: str

    @classmethod
    def create(cls, tag: str) -> HostPair:
        """Create both namespaces and the link; raises :class:`NetnsUnavailable` when the machine cannot."""
        if shutil.which("ip") is None:
            raise NetnsUnavailable("the ip command (iproute2) is not installed")
        pair = cls(a=f"{tag}a", b=f"{tag}b", veth_a=f"{tag}a0", veth_b=f"{tag}b0")
        first = _ip("netns", "add", pair.a, check=False)
        if first.returncode != 0:
            raise NetnsUnavailable(f"ip netns add failed: {first.stderr.strip()}")
        try:
            _ip("netns", "add", pair.b)
            _ip(
                "link",
                "add",
                pair.veth_a,
                "netns",
                pair.a,
                "type",
                "veth",
                "peer",
                "name",
                pair.veth_b,
                "netns",
                pair.b,
            )
            for ns, dev, address in (
                (pair.a, pair.veth_a, HOST_A_ADDRESS),
                (pair.b, pair.veth_b, HOST_B_ADDRESS),
            ):
                _ip("-n", ns, "link", "set", "lo", "up")
                _ip("-n", ns, "addr", "add", f"{address}/{PREFIX_LENGTH}", "dev", dev)
                _ip("-n", ns, "link", "set", dev, "up")
        except Exception:
            pair.delete()
            raise
        return pair

    def set_link(self, up: bool) -> None:
        """Bring host A's end of the link up or down (the peer loses carrier with it)."""
        _ip("-n", self.a, "link", "set", self.veth_a, "up" if up else "down")

    def leftover_pids(self) -> list[int]:
        pids: list[int] = []
        for ns in (self.a, self.b):
            done = _ip("netns", "pids", ns, check=False)
            pids += [int(p) for p in done.stdout.split() if p.strip().isdigit()]
        return pids

    def delete(self) -> None:
        """Kill whatever still runs inside, then remove both namespaces; safe to call twice."""
        for pid in self.leftover_pids():
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                continue
        for ns in (self.a, self.b):
            _ip("netns", "del", ns, check=False)

    def exists(self) -> bool:
        listed = _ip("netns", "list", check=False).stdout.split()
        return self.a in listed or self.b in listed


class NetnsProcess(ServiceProcess):
    """``ip netns exec NS python -m <module> ...``: a :class:`ServiceProcess` living inside a namespace.

    ``ip netns exec`` replaces itself with the command, so the child's pid is python's and its new
    session's process group holds everything it starts; :meth:`stop` signals that group.
    """

    def __init__(
        self, netns: str, module: str, args: Sequence[str], log_path: Path, env: dict[str, str] | None = None
    ) -> None:
        self.netns = netns
        super().__init__(module, args, log_path, env)

    def argv(self) -> list[str]:
        return ["ip", "netns", "exec", self.netns, *super().argv()]
