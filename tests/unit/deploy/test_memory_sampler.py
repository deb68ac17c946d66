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


_BURNER = (
    "import time\n"
    "start = time.process_time()\n"
    "while time.process_time() - start < 0.3:\n"
    "    pass\n"
    "print('burnt', flush=True)\n"
    "time.sleep(60)\n"
)


def test_a_services_cpu_time_counts_each_process_it_ran() -> None:
    """A service restarted under a new pid keeps the CPU its earlier process used."""
    first = subprocess.Popen([sys.executable, "-c", _BURNER], stdout=subprocess.PIPE, text=True)
    second = subprocess.Popen([sys.executable, "-c", _BURNER], stdout=subprocess.PIPE, text=True)
    running = [first.pid]
    try:
        for proc in (first, second):
            assert proc.stdout is not None and proc.stdout.readline().strip() == "burnt"
        sampler = PeakRssSampler(lambda: [("svc", running[0])])
        sampler.sample()
        assert 0.3 <= sampler.cpu_s["svc"] < 5.0, sampler.cpu_s
        first.kill()
        first.wait(timeout=10)
        running[0] = second.pid  # the restart
        sampler.sample()
        assert sampler.cpu_s["svc"] >= 0.6, f"the first process's CPU was lost: {sampler.cpu_s}"
    finally:
        for proc in (first, second):
            proc.kill()
            proc.wait(timeout=10)
