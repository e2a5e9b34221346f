"""The references that storyboard actions on the ego give ego's controller under test.

ego does not script its own vehicle: an action addressed to the ego moves the references its
controller tracks (a SpeedAction the speed reference, a LaneChangeAction the lateral one:
:mod:`ego.openscenario.actions`). The laws here are the ones with more state than a
:class:`~ego.openscenario.dynamics.Transition`:

* :class:`SpeedKnots` - a SpeedProfileAction: the speed reference through its knots;
* :class:`EgoPath` - a FollowTrajectoryAction: the lateral reference is the trajectory's
  offset from the ego's lane frame at the ego's reference point's ``s`` (where the path
  first passes it after the part already passed), and, when the trajectory is timed, the
  longitudinal reference (position and speed) is the trajectory's ``s`` at the time;
* :class:`EgoGap` - a LongitudinalDistanceAction: a reference point driven by the standard's
  law for the held distance or time gap (the one a scripted entity drives by, within the
  action's dynamic constraints), which the ego's longitudinal reference follows.

Positions are in the ego's lane frame (``s`` along its start road, ``d`` + left, m), speeds m/s.
"""

from __future__ import annotations

from bisect import bisect_right

import numpy as np

EPS = 1e-9


class SpeedKnots:
    """A speed reference linear between knots (``ts`` s, ``vs`` m/s), then the last speed:
    the ``value``/``done`` of a :class:`~ego.openscenario.dynamics.Transition`."""

    def __init__(self, ts: list[float], vs: list[float]) -> None:
        self.ts, self.vs = ts, vs

    def value(self, t: float) -> float:
        return self.vs[-1] if t >= self.ts[-1] else max(float(np.interp(t, self.ts, self.vs)), 0.0)

    def done(self, t: float) -> bool:
        return t >= self.ts[-1] - EPS


class EgoPath:
    """A trajectory as the ego's references: its points ``s``, ``d`` (the entity's reference
    point, in the ego's lane frame) and, when timed, their times."""

    def __init__(
        self, s: list[float], d: list[float], times: list[float] | None, lead_in: tuple[float, float] | None = None
    ) -> None:
        if len(s) < 2:
            raise ValueError("a trajectory needs two points")
        self.s, self.d, self.times = s, d, times
        #: a timed path's (time, s) the longitudinal reference starts from when the action
        #: starts before the path's first time: the ego then goes to the first point at the
        #: constant speed that reaches it on time
        self.lead_in = lead_in
        self.i = 0  #: the segment the ego's reference point has reached
        self.frozen: float | None = None  #: the lateral reference held once the action stopped
        self.last = d[0]  #: the offset last looked up
        self.slope = 0.0  #: and the path's dd/ds there (its rate is the slope times the speed along s)

    def d_at(self, s: float) -> float:
        """The path's offset where it passes ``s`` (m), going on from the segment reached: before
        its start its first offset, after its end its last; a part running backwards along the
        road is passed over (the ego drives forwards)."""
        if self.frozen is not None:
            self.slope = 0.0
            return self.frozen
        ps, pd = self.s, self.d
        n = len(ps)
        i = self.i
        while i < n - 1 and ps[i + 1] <= s:
            i += 1
        self.i = i
        self.slope = 0.0
        if i == n - 1:
            out = pd[-1]
        else:
            s0, s1 = ps[i], ps[i + 1]
            if s <= s0 or s1 <= s0:
                out = pd[i]
            else:
                self.slope = (pd[i + 1] - pd[i]) / (s1 - s0)
                out = pd[i] + self.slope * (s - s0)
        self.last = out
        return out

    def passed(self, s: float) -> bool:
        """Whether the ego's reference point at ``s`` has passed the path's end."""
        return self.i == len(self.s) - 1 or (self.i == len(self.s) - 2 and s >= self.s[-1])

    def longitudinal(self, t: float) -> tuple[float, float]:
        """A timed path's (s, speed along s) at ``t``: linear between the points' times; after
        the last, on at the last segment's speed (before the first: from the lead-in, else
        standing at the start)."""
        times, ps = self.times, self.s
        assert times is not None
        if t <= times[0]:
            if self.lead_in is None:
                return ps[0], 0.0
            t0, s0 = self.lead_in
            v = (ps[0] - s0) / (times[0] - t0)
            return ps[0] + v * (t - times[0]), max(v, 0.0)
        k = min(bisect_right(times, t) - 1, len(times) - 2)
        v = (ps[k + 1] - ps[k]) / (times[k + 1] - times[k]) if times[k + 1] > times[k] else 0.0
        return ps[k] + v * (t - times[k]), max(v, 0.0)

    def done(self, t: float, s: float) -> bool:
        """The action's end: a timed path at its last time, any path once passed."""
        if self.times is not None and t >= self.times[-1] - EPS:
            return True
        return self.passed(s)

    def stop(self) -> None:
        """The action stopped: the lateral reference stays where the path had it."""
        self.frozen = self.last


class EgoGap:
    """A LongitudinalDistanceAction's reference point for the ego: its ``s`` (the actor's box
    centre, m) and speed, moved every storyboard step by the law a scripted actor drives by
    (:func:`ego.openscenario.actions.distance_speed`); between steps on at its speed."""

    def __init__(self, t: float, s: float, v: float) -> None:
        self.t, self.s, self.v = t, s, v
        self.h, self.v_after = 0.0, v  #: the step of the speed ``v``, and the speed after it
        self.stopped = False

    def advance(self, t: float, v_next: float, h: float, v_after: float) -> None:
        """The reference point's speed over [t, t + h] is ``v_next``, and after that (until the
        next step's law) ``v_after``, the referenced entity's speed."""
        if self.stopped:
            return
        self.s, _ = self.longitudinal(t)
        self.t, self.v, self.h, self.v_after = t, v_next, h, v_after

    def longitudinal(self, t: float) -> tuple[float, float]:
        """(s, speed) of the reference point at ``t``."""
        dt = t - self.t
        if dt <= self.h:
            return self.s + self.v * dt, self.v
        return self.s + self.v * self.h + self.v_after * (dt - self.h), self.v_after

    def stop(self) -> None:
        """The action stopped: the reference point drives on at its speed."""
        self.stopped = True


def to_lane_frame(road_frame, xy: list[tuple[float, float]]) -> tuple[list[float], list[float]]:
    """``xy`` points in the ego's lane frame (``road_frame(x, y) -> (s, d)``)."""
    s, d = [], []
    for x, y in xy:
        ps, pd = road_frame(x, y)
        s.append(ps)
        d.append(pd)
    return s, d
