"""The peak-RSS sampler counts a service's whole process tree, read from one look at the process table."""

from __future__ import annotations

import subprocess
import sys

import psutil

from deploy.memory import PeakRssSampler

#: The grandchild holds this much, touched, so it is resident.
HELD_BYTES = 60_000_000

_PARENT = (
    "import subprocess, sys, time\n"
    f"child = subprocess.Popen([sys.executable, '-c', 'b = b\"x\" * {HELD_BYTES}; print(1, flush=True); "
    "import time; time.sleep(60)'], stdout=subprocess.PIPE)\n"
    "child.stdout.readline()\n"
    "print('ready', flush=True)\n"
    "time.sleep(60)\n"
)


def test_a_services_peak_includes_its_descendants_and_a_gone_pid_is_skipped() -> None:
    parent = subprocess.Popen([sys.executable, "-c", _PARENT], stdout=subprocess.PIPE, text=True)
    try:
        assert parent.stdout is not None
        assert parent.stdout.readline().strip() == "ready", "the test's process tree did not start"
        own_rss = psutil.Process(parent.pid).memory_info().rss
        gone = subprocess.Popen([sys.executable, "-c", "pass"])
        gone.wait()
        sampler = PeakRssSampler(lambda: [("svc", parent.pid), ("gone", gone.pid), ("unstarted", None)])
        sampler.sample()
        assert set(sampler.peak_mb) == {"svc"}, f"only the live service is measured: {sampler.peak_mb}"
        assert sampler.peak_mb["svc"] * 1e6 >= own_rss + HELD_BYTES, (
            f"the grandchild's {HELD_BYTES / 1e6:.0f} MB are missing from {sampler.peak_mb['svc']} MB "
            f"(the service's own process holds {own_rss / 1e6:.1f} MB)"
        )
    finally:
        tree = [psutil.Process(parent.pid)] if parent.poll() is None else []
        tree += [c for p in tree for c in p.children(recursive=True)]
        for proc in tree:
            try:
                proc.kill()
            except psutil.Error:
                pass
        _, alive = psutil.wait_procs(tree, timeout=10)
        parent.wait(timeout=10)
        assert not alive, f"left behind: {alive}"
