"""``zendock bench record``: record everything, camera included, through a docking campaign; count the gaps.

A trials campaign runs (the real stack, ArUco by default, so the camera streams 300 kB frames at 15 Hz
and perception its debug images); once the stack is healthy, ``zendock record`` starts as its own
process on the campaign's router, as a user would run it, and records every key until the last trial
ends. The recording's own summary (per key: recorded, and lost by the publishers' sequence numbers) is
the result, with the recorder's CPU and peak RSS.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import psutil

from deploy.bench.messages import robot_relative
from deploy.memory import PeakRssSampler
from deploy.recording.reading import Recording

#: Where a big sample's loss shows first: the camera's frames and perception's debug images.
IMAGE_KEYS = ("camera/image_raw", "aruco/debug_image")
#: How long the recorder may take to write what it holds and close the file once asked to stop.
STOP_TIMEOUT_S = 60.0


@dataclass
class RecordingTap:
    """Runs ``zendock record`` beside a campaign (``run_trials``' ``tap``) into ``output``."""

    output: Path
    world: Path
    robots: list[str] = field(default_factory=list)
    peak_rss_mb: float = 0.0
    cpu_s: float = 0.0
    wall_s: float = 0.0
    recorder_output: str = ""

    @contextmanager
    def tap(self, session: Any, robots: list[str], processes: Any, endpoint: str) -> Iterator[None]:
        self.robots = list(robots)
        command = [
            sys.executable,
            "-m",
            "deploy.cli",
            "record",
            "-o",
            str(self.output),
            "--world",
            str(self.world),
            "--connect",
            endpoint,
        ]
        env = {**os.environ, "ZENDOCK_NAMESPACE": ""}
        recorder = subprocess.Popen(
            command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env
        )
        started = time.monotonic()
        sampler = PeakRssSampler(lambda: [("recorder", recorder.pid)])  # as the campaign samples its services
        try:
            self._wait_recording(recorder)
            with sampler:
                yield
        finally:
            try:  # before it stops: the recording's cost, not the file's closing
                self.peak_rss_mb = sampler.peak_mb.get("recorder", 0.0)
                times = psutil.Process(recorder.pid).cpu_times()
                self.cpu_s = times.user + times.system
            except psutil.Error:
                pass
            self.wall_s = time.monotonic() - started
            recorder.send_signal(signal.SIGINT)
            try:
                out, _ = recorder.communicate(timeout=STOP_TIMEOUT_S)
            except subprocess.TimeoutExpired:
                recorder.kill()
                out, _ = recorder.communicate()
            self.recorder_output = out or ""

    @staticmethod
    def _wait_recording(recorder: subprocess.Popen[str]) -> None:
        """Until the recorder says it records (its subscriptions are declared), or fails."""
        assert recorder.stdout is not None
        for line in recorder.stdout:
            if line.startswith("recording to "):
                return
        raise RuntimeError(f"zendock record exited with code {recorder.wait()} before recording")

    def report(self) -> dict[str, Any]:
        """Per key (robots' keys under one name): recorded and lost; totals; the recorder's cost."""
        if not self.output.is_file():
            raise RuntimeError(f"the recorder wrote no file: {self.recorder_output[-2000:]}")
        with Recording(self.output) as recording:
            summary = recording.summary()
        keys: dict[str, dict[str, int]] = {}
        for key, row in summary.items():
            entry = keys.setdefault(robot_relative(key, self.robots), {"recorded": 0, "lost": 0, "gaps": 0})
            entry["recorded"] += int(row["received"])
            entry["lost"] += int(row["lost"])
            entry["gaps"] += len(row["gaps"])
        images = {k: keys[k] for k in IMAGE_KEYS if k in keys}
        return {
            "recorded": sum(r["recorded"] for r in keys.values()),
            "lost": sum(r["lost"] for r in keys.values()),
            "gaps": sum(r["gaps"] for r in keys.values()),
            "images_recorded": sum(r["recorded"] for r in images.values()),
            "images_lost": sum(r["lost"] for r in images.values()),
            "recorder_peak_rss_mb": round(self.peak_rss_mb, 1),
            "recorder_cpu_fraction": round(self.cpu_s / self.wall_s, 3) if self.wall_s > 0 else None,
            "file_mb": round(self.output.stat().st_size / 1e6, 1),
            "keys": dict(sorted(keys.items(), key=lambda kv: (-kv[1]["lost"], kv[0]))),
        }
