"""Lane coordinates: project a pose onto a lane's centre line.

A lane is the polyline SUMO gives for it (``lane.getShape``). For a point (x, y) the
projection returns the arc length ``s`` along the centre line to the closest point (m),
the signed lateral offset ``d`` of the point from the centre line (m, positive to the
LEFT of the driving direction) and the centre line's heading there (rad,
counter-clockwise from +x).
"""

from __future__ import annotations

import math
from collections.abc import Sequence


class LanePolyline:
    """A lane centre line made of straight segments, with a fast local projection."""

    __slots__ = ("lane_id", "width", "points", "_seg", "_hint")

    def __init__(self, points: Sequence[tuple[float, float]], width: float = 3.5,
                 lane_id: str = "") -> None:
        if len(points) < 2:
            raise ValueError("a lane needs at least two points")
        self.lane_id = lane_id
        self.width = float(width)
        self.points = [(float(x), float(y)) for x, y in points]
        seg = []
        s0 = 0.0
        for (x0, y0), (x1, y1) in zip(self.points, self.points[1:]):
            length = math.hypot(x1 - x0, y1 - y0)
            if length == 0.0:
                continue
            ux, uy = (x1 - x0) / length, (y1 - y0) / length
            seg.append((x0, y0, ux, uy, length, s0, math.atan2(uy, ux)))
            s0 += length
        if not seg:
            raise ValueError("a lane needs two distinct points")
        self._seg = seg
        self._hint = 0

    @property
    def length(self) -> float:
        x0, y0, ux, uy, length, s0, _ = self._seg[-1]
        return s0 + length

    def _local(self, i: int, x: float, y: float) -> tuple[float, float, float]:
        """(along, across, distance^2) of (x, y) relative to segment i, along clamped."""
        x0, y0, ux, uy, length, _, _ = self._seg[i]
        dx, dy = x - x0, y - y0
        along = dx * ux + dy * uy
        across = uy * -dx + ux * dy
        if along < 0.0:
            return along, across, dx * dx + dy * dy
        if along > length:
            ex, ey = dx - length * ux, dy - length * uy
            return along, across, ex * ex + ey * ey
        return along, across, across * across

    def project(self, x: float, y: float) -> tuple[float, float, float]:
        """(s, d, heading) of the closest point of the centre line to (x, y).

        Searches outward from the previous answer's segment, so successive calls along a
        trajectory cost O(1); beyond the ends the first/last segment is extended.
        """
        seg = self._seg
        n = len(seg)
        i = self._hint
        best = self._local(i, x, y)
        # walk towards the closer neighbour while it improves
        for step in (1, -1):
            j = i + step
            while 0 <= j < n:
                cand = self._local(j, x, y)
                if cand[2] < best[2]:
                    i, best = j, cand
                    j += step
                else:
                    break
        self._hint = i
        along, across, _ = best
        _, _, _, _, length, s0, heading = seg[i]
        if 0 < i and along < 0.0:
            along = 0.0
        if i < n - 1 and along > length:
            along = length
        return s0 + along, across, heading

    def offset_point(self, s: float, d: float) -> tuple[float, float]:
        """World point at arc length ``s`` and lateral offset ``d`` (m)."""
        seg = self._seg
        i = 0
        while i < len(seg) - 1 and s > seg[i][5] + seg[i][4]:
            i += 1
        x0, y0, ux, uy, _, s0, _ = seg[i]
        along = s - s0
        return x0 + along * ux - d * uy, y0 + along * uy + d * ux
