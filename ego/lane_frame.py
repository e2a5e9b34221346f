"""Lane coordinates: project a pose onto a lane's centre line.

A lane is the polyline SUMO gives for it (``lane.getShape``). For a point (x, y) the
projection returns

* ``s`` - arc length along the centre line to the closest point (m);
* ``d`` - signed lateral offset of the point from the centre line (m, positive to the
  LEFT of the driving direction; on a left-hand arc of radius R a point at distance rho
  from the centre has d = R - rho, so report 002's e_d = rho - R is -d). It is measured
  to the constant-curvature arc each segment stands for (the chord plus the sagitta
  profile kappa u (L - u) / 2), not to the chord: a car driving the true curve then sees
  a smooth d instead of a sawtooth of the chords' sagitta every segment;
* ``heading`` - the centre line's direction there (rad, counter-clockwise from +x),
  interpolated between the tangents at the vertices (exact on an evenly sampled circle);
* ``curvature`` - signed curvature there (1/m, positive turning left): the derivative
  of that interpolated heading, constant along each segment (its heading change over
  its length), so a long straight meeting an arc stays straight up to the junction.

:meth:`LanePolyline.frame` adds the heading error ``psi - heading`` of a pose (rad,
positive when the vehicle points left of the lane).
"""

from __future__ import annotations

import math
from array import array
from collections.abc import Sequence

_TWO_PI = 2.0 * math.pi


def wrap_angle(a: float) -> float:
    """Angle in (-pi, pi]."""
    a = math.fmod(a + math.pi, _TWO_PI)
    if a <= 0.0:
        a += _TWO_PI
    return a - math.pi


#: m, the cell of a lane's segment index (LanePolyline._grid)
GRID = 10.0


class LanePolyline:
    """A lane centre line made of straight segments, with a fast local projection."""

    __slots__ = ("lane_id", "width", "points", "_seg", "hint", "_single", "_grid", "at", "packed")

    def __init__(self, points: Sequence[tuple[float, float]], width: float = 3.5, lane_id: str = "") -> None:
        if len(points) < 2:
            raise ValueError("a lane needs at least two points")
        self.lane_id = lane_id
        self.width = float(width)
        pts = []
        for x, y in points:
            p = (float(x), float(y))
            if not pts or p != pts[-1]:
                pts.append(p)
        if len(pts) < 2:
            raise ValueError("a lane needs two distinct points")
        self.points = pts
        raw = []
        s0 = 0.0
        for (x0, y0), (x1, y1) in zip(pts, pts[1:]):
            length = math.hypot(x1 - x0, y1 - y0)
            raw.append((x0, y0, (x1 - x0) / length, (y1 - y0) / length, length, s0, math.atan2(y1 - y0, x1 - x0)))
            s0 += length
        n = len(raw)
        # tangent heading and discrete curvature at every vertex (ends: the end segment's).
        # The tangent splits the turn in proportion to the OTHER side's length: equal
        # chords of a sampled curve share it evenly, while where a long straight meets
        # short chords (an arc starting at the vertex) the tangent stays the straight's.
        heading = [raw[0][6]]
        for i in range(1, n):
            before, after = raw[i - 1][4], raw[i][4]
            turn = wrap_angle(raw[i][6] - raw[i - 1][6])
            heading.append(raw[i - 1][6] + turn * after / (before + after))
        heading.append(raw[-1][6])
        # segment: x0, y0, ux, uy, length, s0, direction, heading at start, heading
        # change along it, curvature, the lane's turn (unwrapped heading change) from its
        # start to the segment's
        self._seg = []
        turn = 0.0
        for i in range(n):
            change = wrap_angle(heading[i + 1] - heading[i])
            self._seg.append((*raw[i], heading[i], change, change / raw[i][4], turn))
            turn += change
        self.hint = 0
        self.at = [0, 0]  #: the segments :meth:`_segment_at` found last, per slot
        #: (cell of GRID m) -> the segments passing through it, so a point far from the
        #: previous answer (the surround sensor projecting one car after another along a
        #: curve) starts its search next to its own segment instead of walking there
        self._grid: dict[tuple[int, int], list[int]] = {}
        for i, (x0, y0, ux, uy, length) in enumerate(s[:5] for s in raw):
            for k in range(int(length // (0.5 * GRID)) + 2):
                u = min(k * 0.5 * GRID, length)
                cell = (int(math.floor((x0 + u * ux) / GRID)), int(math.floor((y0 + u * uy) / GRID)))
                self._grid.setdefault(cell, [i])  # one segment per cell: the search walks on
        #: one straight segment: frame() is a rotation, done without a search
        self._single = self._seg[0] if n == 1 else None
        #: the segments and the grid as plain arrays, for ego._native (road_frame, place):
        #: the same projection in C, without a Python call per point
        cells = sorted(self._grid)
        self.packed = (
            array("d", [v for seg in self._seg for v in seg]),
            array("q", [c[0] for c in cells]),
            array("q", [c[1] for c in cells]),
            array("q", [self._grid[c][0] for c in cells]),
        )

    def straight(self) -> tuple[float, float, float, float, float, float] | None:
        """(x0, y0, ux, uy, s0, heading) when the lane is one straight segment (its frame is a
        rotation: s = s0 + (p - p0).u, d = u x (p - p0)), else None."""
        if self._single is None:
            return None
        x0, y0, ux, uy, _, s0, heading = self._single[:7]
        return x0, y0, ux, uy, s0, heading

    @property
    def length(self) -> float:
        last = self._seg[-1]
        return last[5] + last[4]

    def _local(self, i: int, x: float, y: float) -> tuple[float, float, float]:
        """(along, across, distance^2) of (x, y) relative to segment i, along clamped."""
        x0, y0, ux, uy, length = self._seg[i][:5]
        dx, dy = x - x0, y - y0
        along = dx * ux + dy * uy
        across = uy * -dx + ux * dy
        if along < 0.0:
            return along, across, dx * dx + dy * dy
        if along > length:
            ex, ey = dx - length * ux, dy - length * uy
            return along, across, ex * ex + ey * ey
        return along, across, across * across

    def _closest(self, x: float, y: float) -> tuple[int, float, float]:
        """(segment, along, across) of the closest point, searching outward from the
        previous answer's segment so successive calls along a trajectory cost O(1)."""
        seg = self._seg
        n = len(seg)
        i = self.hint
        best = self._local(i, x, y)
        if best[2] > GRID * GRID:  # far from the previous answer: start next to this point
            cx, cy = int(math.floor(x / GRID)), int(math.floor(y / GRID))
            grid = self._grid
            near = grid.get((cx, cy))
            if near is None:
                near = [j for a in (-1, 0, 1) for b in (-1, 0, 1) for j in grid.get((cx + a, cy + b), ())]
            for j in near:
                cand = self._local(j, x, y)
                if cand[2] < best[2]:
                    i, best = j, cand
        for step in (1, -1):
            j = i + step
            while 0 <= j < n:
                cand = self._local(j, x, y)
                if cand[2] < best[2]:
                    i, best = j, cand
                    j += step
                else:
                    break
        self.hint = i
        along, across, _ = best
        length = seg[i][4]
        if 0 < i and along < 0.0:
            along = 0.0
        if i < n - 1 and along > length:
            along = length
        return i, along, across

    def project(self, x: float, y: float) -> tuple[float, float, float]:
        """(s, d, heading) of the closest point of the centre line to (x, y); beyond the
        ends the first/last segment is extended."""
        i, along, across = self._closest(x, y)
        seg = self._seg[i]
        u = min(max(along, 0.0), seg[4])
        return seg[5] + along, across + seg[9] * u * (seg[4] - u) * 0.5, seg[7] + u / seg[4] * seg[8]

    def frame(self, x: float, y: float, psi: float) -> tuple[float, float, float, float]:
        """(s, d, heading error psi - heading, curvature) of a pose (m, m, rad, 1/m)."""
        single = self._single
        if single is not None:
            x0, y0, ux, uy, _, s0, heading = single[:7]
            dx, dy = x - x0, y - y0
            err = psi - heading
            if not -math.pi < err <= math.pi:
                err = wrap_angle(err)
            return s0 + dx * ux + dy * uy, dy * ux - dx * uy, err, 0.0
        i, along, across = self._closest(x, y)
        seg = self._seg[i]
        u = min(max(along, 0.0), seg[4])
        return (
            seg[5] + along,
            across + seg[9] * u * (seg[4] - u) * 0.5,
            wrap_angle(psi - seg[7] - u / seg[4] * seg[8]),
            seg[9],
        )

    def place(self, x: float, y: float, yaw: float) -> tuple[float, float, float, float, float]:
        """(station, d, heading error, turn, curvature) of a pose, for the surround sensor:
        :meth:`frame`'s offset, heading error and curvature, the lane's turn from its start
        to there (rad, unwrapped: the heading change it has curved through; :meth:`turn_at`)
        and the point's station: its arc length along the centre line where the radius
        through it meets it (``s`` projects on the chord: off a curved lane by d it is off
        by up to d kappa L / 2 within each segment of length L; the station is not).

        The arc length between stations s0 and s1 along the line ``d`` m left of the centre
        line is then ``s1 - s0 - d (turn(s1) - turn(s0))``: each segment is an arc of its
        curvature, and a parallel line d m to its left runs ``1 - kappa d`` as far."""
        s, d, err, kappa, turn, station = self.locate(x, y, yaw)
        return station, d, err, turn, kappa

    def locate(self, x: float, y: float, psi: float) -> tuple[float, float, float, float, float, float]:
        """:meth:`frame`'s (s, d, heading error, curvature), then the turn and the station of
        :meth:`place`."""
        i, along, across = self._closest(x, y)
        seg = self._seg[i]
        length = seg[4]
        u = min(max(along, 0.0), length)
        kappa = seg[9]
        d = across + kappa * u * (length - u) * 0.5
        frac = u / length
        s = seg[5] + along
        station = s
        if kappa != 0.0:
            q = 1.0 - kappa * d
            if q > 0.5:  # the point nearer the line than half the radius: the arc's station
                half = 0.5 * length
                # along the chord unclamped: outside a bend's vertex the closest point is
                # the vertex for a few cm, the radius through the point moves on
                along = (x - seg[0]) * seg[2] + (y - seg[1]) * seg[3]
                station = seg[5] + half + (along - half) / q
        return s, d, wrap_angle(psi - seg[7] - frac * seg[8]), kappa, seg[10] + frac * seg[8], station

    def turn_at(self, s: float) -> float:
        """The lane's turn from its start to arc length ``s`` (rad, unwrapped, + left): the
        integral of its curvature; constant beyond the ends."""
        seg = self._seg[self._segment_at(s)]
        return seg[10] + min(max((s - seg[5]) / seg[4], 0.0), 1.0) * seg[8]

    def heading_at(self, s: float, slot: int = 0) -> float:
        """The centre line's (interpolated tangent) heading at arc length ``s`` (rad);
        ``slot``: which of :meth:`_segment_at`'s remembered segments to start from."""
        seg = self._seg[self._segment_at(s, slot)]
        t = min(max((s - seg[5]) / seg[4], 0.0), 1.0)
        return wrap_angle(seg[7] + t * seg[8])

    def mean_curvature(self, s: float, ahead: float) -> float:
        """Mean curvature over [s, s + ahead] (1/m): the lane's turn there over ``ahead``
        (every control period: the two ends each from where their last call found them)."""
        if ahead <= 0.0:
            return self.curvature_at(s)
        return wrap_angle(self.heading_at(s + ahead, 1) - self.heading_at(s)) / ahead

    def curvature_at(self, s: float) -> float:
        """Signed curvature (1/m) at arc length ``s``."""
        return self._seg[self._segment_at(s)][9]

    def _segment_at(self, s: float, slot: int = 0) -> int:
        """The last segment starting at or before ``s`` (the first when none does); ``slot``
        (0 or 1) is which remembered answer to try first (two lookups moving along together
        each keep their own)."""
        seg = self._seg
        last = len(seg) - 1
        at = self.at
        i = at[slot]
        if seg[i][5] <= s and (i == last or s < seg[i + 1][5]):  # where the last call was
            return i
        if i < last and seg[i + 1][5] <= s and (i + 1 == last or s < seg[i + 2][5]):  # the next one
            at[slot] = i + 1
            return i + 1
        lo, hi = 0, last
        while lo < hi:
            mid = (lo + hi + 1) // 2
            if seg[mid][5] <= s:
                lo = mid
            else:
                hi = mid - 1
        at[slot] = lo
        return lo

    def curved_spans(self, min_curvature: float = 1e-3) -> list[tuple[float, float, float]]:
        """(s_start, s_end, mean curvature) of every run of segments curving by more than
        ``min_curvature`` (1/m) the same way: where the lane's arcs are."""
        spans = []
        run: list[tuple[float, float, float]] = []
        for seg in self._seg:
            kappa = seg[9]
            if abs(kappa) > min_curvature and (not run or (kappa > 0) == (run[0][2] > 0)):
                run.append((seg[5], seg[5] + seg[4], kappa))
                continue
            if run:
                spans.append(run)
            run = [(seg[5], seg[5] + seg[4], kappa)] if abs(kappa) > min_curvature else []
        if run:
            spans.append(run)
        return [(r[0][0], r[-1][1], sum(k * (b - a) for a, b, k in r) / (r[-1][1] - r[0][0])) for r in spans]

    def offset_point(self, s: float, d: float) -> tuple[float, float]:
        """World point at arc length ``s`` and lateral offset ``d`` (m), the inverse of
        :meth:`project`."""
        seg = self._seg[self._segment_at(s)]
        x0, y0, ux, uy, length, s0 = seg[:6]
        along = s - s0
        u = min(max(along, 0.0), length)
        across = d - seg[9] * u * (length - u) * 0.5
        return x0 + along * ux - across * uy, y0 + along * uy + across * ux


#: the lane marking's width (m) the departure is measured to the outer edge of (a motorway's
#: broken line, 0.15 m, centred on the lane boundary SUMO's lane widths run to)
MARKING_WIDTH = 0.15
#: the trace's ``phase`` of a commanded lane change (``ego.scenarios.manoeuvre.LANE_CHANGE``)
LANE_CHANGE_PHASE = 1


def lane_departure(d, d_ref, phase, lane_width: float, body_width: float, signed: bool = False):
    """How far (m, >= 0, per sample) the ego's outline reaches beyond the outer edge of its
    lane's marking: ``|d| + body_width / 2 - (lane_width / 2 + MARKING_WIDTH / 2)`` floored at
    0, with ``d`` the centre of gravity's offset from the centre line of the lane it keeps (m).
    Samples of a commanded lateral motion count 0: a lane change (``phase``
    :data:`LANE_CHANGE_PHASE`) or a reference off the lane centre (``d_ref`` != 0), and so do
    the samples right after one while the ego is still settling into its lane (until its
    outline is first back inside the marking: a slow controller that lags the lane change's
    reference has not left its lane, it has not arrived yet). With
    ``signed`` nothing is floored: inside the lane the value is minus the margin left, and a
    commanded sample is -inf (a requirement's robustness then reads the smallest margin).

    UN R157 5.2.1 measures the outer edge of the front tyre; this measures the body's side at
    the centre of gravity (half its width, which the tyres sit inside: never less than R157's
    figure on a straight lane) and leaves the heading out (at a heading error psi the front
    tyre sits lf sin(psi) further out: 0.03 m at 0.02 rad)."""
    import numpy as np

    d = np.asarray(d, float)
    out = np.abs(d) + 0.5 * body_width - 0.5 * (lane_width + MARKING_WIDTH)
    commanded = (np.asarray(phase) == LANE_CHANGE_PHASE) | (np.asarray(d_ref, float) != 0.0)
    outside = out > 0.0
    for i in np.flatnonzero(commanded[:-1] & ~commanded[1:] & outside[1:]) + 1:  # a command's settling
        stop = np.flatnonzero(~outside[i:] | commanded[i:])
        commanded[i : i + (stop[0] if len(stop) else len(outside) - i)] = True
    if signed:
        return np.where(commanded, -np.inf, out)
    return np.where(commanded | ~(out > 0.0), 0.0, out)
