"""Costmap updates off the control thread: one worker thread folds the sensors in and re-inflates.

An update (the scan, the sonar, inflation) takes a few milliseconds of CPU, and far more wall time when
robots share a busy machine. On the node's one executor it held the 20 Hz control tick behind it;
the simulator, which waits for a robot whose command is late, then held the whole world (measurement 74).
Here updates run on a thread of their own, as A* already does (:mod:`services.planner.planning_worker`):
the control tick waits at most for the interpreter, not for a whole update.

What the two threads share, and how:

- The layers (:class:`~services.planner.costmap_updater.CostmapUpdater`) are touched only under
  :attr:`CostmapThread.lock`: by the worker for an update, by the executor for the rare changes (a new
  map, a clearing, a turning circle, parameters) through :meth:`CostmapThread.change`. The sensor
  hand-overs (``add_scan``, ``add_range``, ``add_mounts``) only append to deques the update empties.
- What the executor reads every tick is published after each update or change as snapshots that are
  never changed afterwards: the inflated :class:`~services.planner.costmap.CostGrid` and the cells the
  sonar heard glass in (:attr:`CostmapThread.grid`, :attr:`CostmapThread.heard_glass_xy`).
- The pose track: the executor adds samples holding :attr:`LockedPoseTrack.lock`; the worker takes a
  snapshot of it under the same lock at the start of each update and places every reading with that.

After each update the worker calls ``on_updated(now)`` (the node passes its ``post``, so the navigation run
hears of the new costmap on the executor, never concurrently with its callbacks).
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from typing import TypeVar

import numpy as np

from services.planner.costmap import CostGrid
from services.planner.costmap_updater import CostmapUpdater
from shared.geometry import Pose2D
from shared.pose_tracking import PoseTrack

T = TypeVar("T")


class LockedPoseTrack:
    """The pose track as another thread reads it: each read under :attr:`lock`, which the thread that
    adds samples holds while it adds them."""

    def __init__(self, track: PoseTrack) -> None:
        self.track = track
        self.lock = threading.Lock()

    def current_pose(self, now_s: float, max_odom_age_s: float) -> Pose2D | None:
        with self.lock:
            return self.track.current_pose(now_s, max_odom_age_s)

    def pose_now_at(self, t_s: float) -> Pose2D | None:
        with self.lock:
            return self.track.pose_now_at(t_s)

    def snapshot(self) -> PoseTrack:
        with self.lock:
            return self.track.snapshot()


class CostmapThread:
    """Runs :meth:`CostmapUpdater.update` on its own thread when asked; see the module docstring."""

    def __init__(
        self,
        layers: CostmapUpdater,
        on_updated: Callable[[float], None],
        log: logging.Logger,
        record_cpu_s: Callable[[float], None] = lambda _s: None,
    ) -> None:
        self.layers = layers
        self.lock = threading.Lock()
        #: The newest inflated cost grid (None before a map), and the cells the sonar heard glass in.
        self.grid: CostGrid | None = None
        self.heard_glass_xy: np.ndarray = np.zeros((0, 2))
        self._on_updated = on_updated
        self._log = log
        self._record_cpu_s = record_cpu_s
        self._wake = threading.Condition()
        #: The time of the update asked for and not yet started (None: none waiting).
        self._due_s: float | None = None
        self._stopping = False
        self._thread = threading.Thread(target=self._run, name="costmap-worker", daemon=True)
        self._thread.start()

    def request_update(self, now: float) -> None:
        """Fold in what has arrived, as of ``now``; asked again before it starts, it runs once, as of the
        newer time."""
        with self._wake:
            self._due_s = now
            self._wake.notify()

    def change(self, fn: Callable[..., T], *args: object) -> T:
        """Run ``fn(*args)`` on the layers under the lock (waiting for an update under way), then publish
        the snapshots it changed."""
        with self.lock:
            result = fn(*args)
            self._publish()
        return result

    def close(self, timeout_s: float = 2.0) -> None:
        with self._wake:
            self._stopping = True
            self._wake.notify()
        self._thread.join(timeout=timeout_s)

    def _publish(self) -> None:
        """Under the lock: the snapshots the executor reads, from the layers as they are now."""
        if self.layers.costmap is not None:
            self.grid = self.layers.grid()
            self.heard_glass_xy = self.layers.heard_glass_xy()

    def _run(self) -> None:
        while True:
            with self._wake:
                while self._due_s is None and not self._stopping:
                    self._wake.wait()
                now = self._due_s
                if self._stopping or now is None:
                    return
                self._due_s = None
            started = time.thread_time()
            try:
                with self.lock:
                    self.layers.update(now)
                    self._publish()
            except (
                Exception
            ):  # a bug in one update must not end the costmap: report it, keep the last snapshot
                self._log.exception("costmap update failed")
                continue
            self._record_cpu_s(time.thread_time() - started)
            self._on_updated(now)
