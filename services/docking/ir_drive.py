"""Infrared docking: Kobuki's auto-docking state machine on three receivers' bit fields.

The reference is Yujin Robot's ``kobuki_dock_drive`` (kobuki_core, ``dock_drive_states.cpp``): no map,
no camera, only what the right, central and left receivers see of the dock's six beacon fields (left,
centre, right; near and far; see :mod:`shared.messages.DockInfraRed`), and how far the robot has turned
(odometry). The states, as there:

- SCAN: turn on the spot (counter-clockwise). The central receiver seeing the centre field means the
  robot faces the dock from its axis: ALIGNED. Seeing a side field counts which side of the dock the
  robot is on. After a whole turn without the centre: FIND_STREAM.
- FIND_STREAM: turn to face across the dock's axis (clockwise on the dock's right, counter-clockwise
  on its left) until the receiver on the dock's side sees that side's field, then GET_STREAM.
- GET_STREAM: drive across the axis until the receiver on that side sees the other side's field (the
  axis is crossed), then SCAN (slowly) to face the dock.
- ALIGNED (near or far): drive at the dock on the central receiver, steering back towards the axis
  whenever it sees a side field, until contact (charging). Losing the beacon in the near field (a
  robot off the axis close to the dock has the emitter outside its central receiver's view), it backs
  away until the beacon is back in view, instead of scanning: a turn on the spot next to the dock sweeps
  a corner into it.

The side receivers also say roughly where the emitter is: the right one sees it from 5 to 115 degrees
to the robot's right, the central one within 25 degrees either side, the left one from 5 to 115 degrees
to the left. The approach uses that as three bins of the emitter's bearing, where the reference
drives on the central receiver alone:

- turning towards the axis stops while the emitter already stands 5 or more degrees to the other side
  (the robot then drives on, holding its heading), so the correction cannot turn the emitter out of the
  central receiver's view; without it the robot turned, lost the beacon, backed off and turned again, a
  loop that could last until the run's time limit;
- a beacon lost from the central receiver but seen by a side one is turned back to (on the spot far
  from the dock, backing off while turning near it), instead of a whole new scan or a straight back-off;
- a back-off ends once the central receiver sees the centre field again, or the far field alone (out of
  the near field there is room to correct), after ``min_back_off_s``.

The obstacle checks (lidar and sonar; the reference has only its bumper) stop a drive for the axis that
heads into a wall, a box or a pane; the robot then homes in from where it is: the next scan takes the
first field the central receiver sees as the way in, and the approach's side corrections curve it onto
the axis. Homing in from the far field, an obstacle ahead cannot be the dock: the robot backs away
(further each time) and drives across the axis from there. Near the dock the approach is not checked,
since the dock it drives at is an obstacle to the lidar; one behind ends a back-off.

FIND_STREAM also waits until the central receiver has lost the beacon: a side receiver sees the emitter
from 5 degrees off the heading, so the reference's rule alone can send the drive for the axis almost at
the dock (into the side of a glass alcove, say) instead of across the axis.

Differences from the reference, each a choice of this implementation: the speeds are parameters
(faster far from the dock than Kobuki's 0.1 m/s, as slow near it); a scan that sees nothing at all in
``max_blind_turns`` turns reports that no dock is in sight instead of turning for ever; a drive for the
axis that loses the beacon or lasts ``max_get_stream_s`` scans again instead of driving on; readings are
OR-ed over ``filter_window`` ticks, as the reference filters its raw signals, so a flickering bit does
not throw the robot out of ALIGNED. No bumper here: the run ends on charging.
"""

from __future__ import annotations

import enum
import math
from collections import deque
from dataclasses import dataclass

from shared.messages import DockInfraRed

#: The receivers' field bits, as the message defines them.
NEAR_LEFT, NEAR_CENTER, NEAR_RIGHT = DockInfraRed.NEAR_LEFT, DockInfraRed.NEAR_CENTER, DockInfraRed.NEAR_RIGHT
FAR_CENTER, FAR_LEFT, FAR_RIGHT = DockInfraRed.FAR_CENTER, DockInfraRed.FAR_LEFT, DockInfraRed.FAR_RIGHT
LEFT = NEAR_LEFT | FAR_LEFT
CENTER = NEAR_CENTER | FAR_CENTER
RIGHT = NEAR_RIGHT | FAR_RIGHT
NEAR = NEAR_LEFT | NEAR_CENTER | NEAR_RIGHT
FAR = FAR_LEFT | FAR_CENTER | FAR_RIGHT


class IrState(enum.Enum):
    SCAN = "scan"
    FIND_STREAM = "find_stream"
    GET_STREAM = "get_stream"
    ALIGNED_FAR = "aligned_far"
    ALIGNED_NEAR = "aligned_near"
    BACK_OFF = "back_off"
    LOST = "lost"


@dataclass(frozen=True, slots=True)
class IrDriveParams:
    scan_turn_radps: float = 0.66
    slow_scan_turn_radps: float = 0.10
    find_turn_radps: float = 0.33
    get_stream_mps: float = 0.10
    far_mps: float = 0.15
    far_turn_radps: float = 0.3
    near_mps: float = 0.05
    near_turn_radps: float = 0.1
    filter_window: int = 3
    max_blind_turns: float = 2.0
    #: Driving for the axis this long (s) without crossing it, or losing the beacon on the way: scan again.
    max_get_stream_s: float = 15.0
    #: Losing the beacon near the dock, back away (a turn on the spot there sweeps the robot's corners
    #: into the dock) until the central receiver sees the centre or the far field alone, for at most this
    #: long (s) ...
    max_back_off_s: float = 8.0
    #: ... and at least this long (s), so that the approach has room to bring the robot onto the axis.
    min_back_off_s: float = 1.0
    back_off_mps: float = 0.08
    #: Backing away from an obstacle on the way in lasts this long (s) before driving across the axis; twice
    #: as long the second time, three times from the third on.
    clear_back_off_s: float = 4.0
    #: Turning back to a beacon a side receiver still sees (rad/s).
    reacquire_turn_radps: float = 0.4

    def __post_init__(self) -> None:
        if self.filter_window < 1:
            raise ValueError("filter_window must be at least 1")


@dataclass(frozen=True, slots=True)
class IrCommand:
    linear_mps: float
    angular_radps: float
    state: IrState


class IrDockDrive:
    """Steps the state machine once per control tick: receivers' readings and turn in, a command out."""

    def __init__(self, params: IrDriveParams = IrDriveParams()) -> None:
        self.params = params
        self.state = IrState.SCAN
        #: Side of the dock the robot is on, from the scan: > 0 its right, < 0 its left, 0 unknown.
        self.dock_detector = 0
        #: Turns made in this scan (counter-clockwise positive).
        self.rotated_turns = 0.0
        self._blind_turns = 0.0
        #: Which way the scan turns: counter-clockwise (+1) unless a crossing set it to turn back (-1); the
        #: first tick of such a scan is slow, as the reference's.
        self._scan_direction = 1.0
        self._timed_state = self.state
        #: Set when the way to the axis is blocked: the next scan takes any field as a heading to follow.
        self._home_in = False
        #: Time spent in the current state (s).
        self._state_s = 0.0
        self._history: deque[tuple[int, int, int]] = deque(maxlen=params.filter_window)
        #: The side of the dock's axis the approach last saw itself on (+1 its left, -1 its right, 0 unknown).
        self._side = 0
        #: A back-off from an obstacle on the way in: then drive across the axis (FIND_STREAM) instead.
        self._cross_after_back_off = False
        self._obstacles_met = 0

    def _filtered(self, readings: tuple[int, int, int]) -> tuple[int, int, int]:
        self._history.append(readings)
        right = mid = left = 0
        for r, m, lf in self._history:
            right, mid, left = right | r, mid | m, left | lf
        return right, mid, left

    def obstacle_ahead(self) -> IrCommand | None:
        """Something other than the dock blocks the way. Driving for the axis, turn and look again. Homing in
        from out of the near field, it cannot be the dock either (the dock stands behind its emitter, over
        0.6 m away): a box or a pane between the robot and the dock, off the axis; back away, then drive
        across the axis and approach along it. Near the dock, the obstacle check cannot tell the dock from
        a wall: nothing to avoid."""
        if self.state is IrState.GET_STREAM:
            self._home_in = True  # the way across the axis is blocked: home in on the beacon from here
            return self._restart_scan(self.params.scan_turn_radps)
        if self.state is IrState.ALIGNED_FAR and self._side:
            self.dock_detector = -self._side  # > 0: on the dock's right, as the scan counts it
            self._cross_after_back_off = True
            self._obstacles_met += 1  # each time further out: the crossing then passes further from the dock
            return self._to(IrState.BACK_OFF, -self.params.back_off_mps, 0.0)
        return None

    def obstacle_behind(self) -> IrCommand | None:
        """Something blocks a back-off: end it where it is (then cross the axis, or look again)."""
        if self.state is not IrState.BACK_OFF:
            return None
        if self._cross_after_back_off:
            self._cross_after_back_off = False
            return self._to(IrState.FIND_STREAM, 0.0, 0.0)
        return self._restart_scan(self.params.scan_turn_radps)

    def step(self, readings: tuple[int, int, int], turned_rad: float, dt_s: float = 0.05) -> IrCommand:
        """``readings``: ``(right, central, left)`` bit fields; ``turned_rad``: heading change since the last
        step, ``dt_s`` the time since it."""
        right, mid, left = self._filtered(readings)
        self._state_s = self._state_s + dt_s if self.state is self._timed_state else 0.0
        self._timed_state = self.state
        p = self.params
        if right or mid or left:
            self._blind_turns = 0.0
        else:
            self._blind_turns += abs(turned_rad) / (2.0 * math.pi)
        if self._blind_turns > p.max_blind_turns:
            self.state = IrState.LOST
            return IrCommand(0.0, 0.0, IrState.LOST)
        if self.state is IrState.LOST:
            self.state = IrState.SCAN
        if self.state is IrState.SCAN:
            return self._scan(mid, turned_rad)
        if self.state is IrState.FIND_STREAM:
            return self._find_stream(right, mid, left)
        if self.state is IrState.BACK_OFF and self._cross_after_back_off:
            if self._state_s < p.clear_back_off_s * min(self._obstacles_met, 3):
                return self._to(IrState.BACK_OFF, -p.back_off_mps, 0.0)
            self._cross_after_back_off = False
            return self._to(IrState.FIND_STREAM, 0.0, 0.0)
        if self.state is IrState.BACK_OFF:
            if (
                mid & (CENTER | FAR)
                and (mid & CENTER or not mid & NEAR)
                and self._state_s >= p.min_back_off_s
            ):
                return self._aligned(
                    right, mid, left
                )  # on the axis again, or out where there is room to correct
            if self._state_s < p.max_back_off_s:
                return self._to(IrState.BACK_OFF, -p.back_off_mps, self._towards_beacon(right, mid, left))
            return self._restart_scan(p.scan_turn_radps)
        if self.state is IrState.GET_STREAM:
            if not (right or mid or left) or self._state_s > p.max_get_stream_s:
                return self._restart_scan(p.scan_turn_radps)  # drifted off, or driving away: look again
            return self._get_stream(right, left)
        return self._aligned(right, mid, left)

    def _to(self, state: IrState, linear: float, angular: float) -> IrCommand:
        self.state = state
        return IrCommand(linear, angular, state)

    def _restart_scan(self, angular: float) -> IrCommand:
        """Scan again, first turning ``angular`` (then at the scan's rate, the same way)."""
        self.dock_detector = 0
        self.rotated_turns = 0.0
        self._scan_direction = 1.0 if angular >= 0 else -1.0
        return self._to(IrState.SCAN, 0.0, angular)

    def _scan(self, mid: int, turned_rad: float) -> IrCommand:
        p = self.params
        self.rotated_turns += turned_rad / (2.0 * math.pi)
        if mid & CENTER or (self._home_in and mid):
            self._home_in = False
            return self._to(IrState.ALIGNED_FAR, p.near_mps, 0.0)
        turn = self._scan_direction * p.scan_turn_radps
        if mid & LEFT:
            self.dock_detector -= 1
            return self._to(IrState.SCAN, 0.0, turn)
        if mid & RIGHT:
            self.dock_detector += 1
            return self._to(IrState.SCAN, 0.0, turn)
        if abs(self.rotated_turns) > 1.0 and self.dock_detector != 0:
            return self._to(IrState.FIND_STREAM, 0.0, 0.0)
        return self._to(IrState.SCAN, 0.0, turn)

    def _find_stream(self, right: int, mid: int, left: int) -> IrCommand:
        # ... and the central receiver no longer sees the beacon: the emitter is then at least 25 degrees to
        # the side, and the drive crosses the axis instead of heading at the dock
        p = self.params
        if (
            self.dock_detector > 0
        ):  # on the dock's right: turn clockwise until the left receiver sees the right field
            if left & RIGHT and not mid:
                return self._to(IrState.GET_STREAM, p.get_stream_mps, 0.0)
            return self._to(IrState.FIND_STREAM, 0.0, -p.find_turn_radps)
        if (
            right & LEFT and not mid
        ):  # on the dock's left: counter-clockwise until the right receiver sees the left field
            return self._to(IrState.GET_STREAM, p.get_stream_mps, 0.0)
        return self._to(IrState.FIND_STREAM, 0.0, p.find_turn_radps)

    def _get_stream(self, right: int, left: int) -> IrCommand:
        p = self.params
        crossed = (left & LEFT) if self.dock_detector > 0 else (right & RIGHT)
        if crossed:
            # past the axis: turn back towards the dock until the central receiver sees the centre
            return self._restart_scan(
                p.slow_scan_turn_radps if self.dock_detector > 0 else -p.slow_scan_turn_radps
            )
        return self._to(IrState.GET_STREAM, p.get_stream_mps, 0.0)

    def _towards_beacon(self, right: int, mid: int, left: int) -> float:
        """A turn that brings the emitter (back) to the central receiver: towards the side receiver that
        sees it (0 when only the central one does, or none)."""
        if mid and not (left or right):
            return 0.0
        if left and not right:
            return self.params.reacquire_turn_radps
        if right and not left:
            return -self.params.reacquire_turn_radps
        return 0.0

    def _aligned(self, right: int, mid: int, left: int) -> IrCommand:
        p = self.params
        near_now = self.state in (IrState.ALIGNED_NEAR, IrState.BACK_OFF)
        if not mid:
            turn = self._towards_beacon(right, mid, left)
            if near_now:  # back away on the same line, turning back to the beacon if a side receiver sees it
                return self._to(IrState.BACK_OFF, -p.back_off_mps, turn)
            if turn:  # far from the dock: turn back to it on the spot
                return self._to(IrState.ALIGNED_FAR, 0.0, turn)
            return self._restart_scan(p.scan_turn_radps)
        near = bool(mid & NEAR)
        bits = mid & (NEAR if near else FAR)
        side = (1 if bits & LEFT else 0) - (1 if bits & RIGHT else 0)  # +1: the dock's left, -1: its right
        state, speed, turn = (
            (IrState.ALIGNED_NEAR, p.near_mps, p.near_turn_radps)
            if near
            else (IrState.ALIGNED_FAR, p.far_mps, p.far_turn_radps)
        )
        if side:
            self._side = side
            # on the dock's left, turn left: towards the axis; but not while the emitter already stands 5 or
            # more degrees to the right (the right receiver sees it), or the turn takes it out of view
            turned_enough = right if side > 0 else left
            return self._to(state, speed, 0.0 if turned_enough else side * turn)
        if bits & CENTER:
            return self._to(state, speed, 0.0)
        return self._restart_scan(p.scan_turn_radps)


__all__ = ["CENTER", "FAR", "LEFT", "NEAR", "RIGHT", "IrCommand", "IrDockDrive", "IrDriveParams", "IrState"]
