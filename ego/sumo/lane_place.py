"""A controlled vehicle placed on SUMO's lanes by ego, without SUMO's map matching.

``vehicle.moveToXY`` (:meth:`ego.sumo.bridge.SumoBridge.push`'s default) maps the pose it is
given onto SUMO's lanes: every step it walks the whole shape of every lane of every edge
near the vehicle several times (``libsumo::Helper::moveToXYMap``) and then moves the matched
lane's whole shape sideways to tell left from right. On a straight edge of two shape points
that is cheap; on the curved motorways (then ~200 m edges, 4 m chords: ~50 points a lane) it
was 10 % of a whole run (docs/performance.md, issue 38); placed by ego, they are one edge each.

:class:`LanePlacer` does that matching on the route's lanes itself, the way ``moveToXY``
scores them for a vehicle that stays on the road: the lane whose centre line is nearest (the
vehicle's present lane, or its neighbour once the point is past the lanes' common edge),
the nearest point of that lane's polyline (a vertex where the point lies outside a bend),
its offset along the shape scaled to SUMO's lane length, and the distance to it, signed
positive to the left. It then leaves SUMO as ``moveToXY`` does after the next step:

* before the step, where SUMO's drivers plan, the vehicle stays where it was (``moveToXY``
  applies its pose after the step), with the speed pushed (``setPreviousSpeed``, as before);
* ``setSpeed(d / dt)``, ``d`` the distance along its lane to the new position (over a joint
  onto the next edge's lane): SUMO's step drives it there (speed mode 0: the speed as
  given), and SUMO's speed and acceleration after the step are ``moveToXY``'s (the distance
  moved over the step, and its change from the pushed speed);
* after the step, ``setLateralLanePosition``: the offset from the lane's centre line; and
  where it is past the lanes' common edge, ``moveTo`` the neighbouring lane first, as
  ``moveToXY`` reinserts it there.

What differs (``tests/test_curved_roads.py`` compares every car of SUMO, step by step, with
``moveToXY``'s: the same to rounding): SUMO's own angle of the vehicle is its lane's
(``moveToXY`` takes the one given; the bridge reports the pose pushed for a placed vehicle,
:meth:`~ego.sumo.bridge.SumoBridge.pose`), and the step it changes lanes SUMO's speed of it
is the distance along the lane over the step, where ``moveToXY``'s is not (28.3 m/s at
14.2 m/s in that test's run; no driver reads it: the next push sets the speed they see). Moving backwards (which SUMO does not drive), it
is put there at once, standing.
"""

from __future__ import annotations

import math

#: a point farther than this from the previous answer's segment (m^2) is searched for anew
_FAR2 = 100.0


class LanePlacer:
    """Places ``vid`` on the lanes of its route (every lane index of the route's edges; the
    edges must continue one another lane by lane, as the curved motorways' do)."""

    def __init__(self, libsumo, vid: str, step_length: float) -> None:
        self._veh = libsumo.vehicle
        self.vid = vid
        self.dt = float(step_length)
        lane = libsumo.lane
        edges = [e for e in self._veh.getRoute(vid) if not e.startswith(":")]
        n_lanes = libsumo.edge.getLaneNumber(edges[0])
        if any(libsumo.edge.getLaneNumber(e) != n_lanes for e in edges):
            raise ValueError(f"lane placement needs edges of equal lane counts, route of {vid!r}: {edges}")
        #: lane index -> its segments along the route: (x0, y0, ux, uy, length, offset along
        #: the lane's shape, lane id, SUMO's lane length / shape length, the lane's length)
        self.lanes: list[list[tuple]] = []
        self.half_width: list[float] = []
        for i in range(n_lanes):
            segs: list[tuple] = []
            for e in edges:
                lid = f"{e}_{i}"
                pts = lane.getShape(lid)
                length = lane.getLength(lid)
                rows, g = [], 0.0
                for (xa, ya), (xb, yb) in zip(pts, pts[1:]):
                    seg = math.hypot(xb - xa, yb - ya)
                    if seg > 0.0:
                        rows.append((xa, ya, (xb - xa) / seg, (yb - ya) / seg, seg, g))
                        g += seg
                # SUMO's interpolateGeometryPosToLanePos: MAX2(eps, length) / MAX2(eps, shape length)
                scale = max(1e-1, length) / max(1e-1, g)
                segs.extend((*r, lid, scale, length) for r in rows)
            self.lanes.append(segs)
            self.half_width.append(0.5 * lane.getWidth(f"{edges[0]}_{i}"))
        self.index = self._veh.getLaneIndex(vid)
        self._hint = [0] * n_lanes
        self._lat = 0.0
        #: where SUMO has the vehicle after the step (lane id, position) and the lane it
        #: moves to after it (or None)
        self._at: tuple[str, float] | None = None
        self._switch: tuple[str, float] | None = None

    def _nearest(self, i: int, x: float, y: float) -> tuple[int, float, float, float]:
        """(segment, offset along it, distance^2, signed offset across it) of the nearest point
        of lane ``i``'s polyline to (x, y), searched outward from the previous answer."""
        segs = self.lanes[i]
        n = len(segs)

        def local(j: int) -> tuple[float, float, float]:
            x0, y0, ux, uy, length = segs[j][:5]
            dx, dy = x - x0, y - y0
            along = dx * ux + dy * uy
            across = dy * ux - dx * uy
            if along < 0.0:
                return 0.0, dx * dx + dy * dy, across
            if along > length:
                ex, ey = dx - length * ux, dy - length * uy
                return length, ex * ex + ey * ey, across
            return along, across * across, across

        j = self._hint[i]
        best = local(j)
        if best[1] > _FAR2:
            for k in range(n):
                cand = local(k)
                if cand[1] < best[1]:
                    j, best = k, cand
        for step in (1, -1):
            k = j + step
            while 0 <= k < n:
                cand = local(k)
                if cand[1] < best[1]:
                    j, best = k, cand
                    k += step
                else:
                    break
        self._hint[i] = j
        return j, *best

    def place(self, x: float, y: float, speed: float, accel: float | None) -> None:
        """The vehicle's front bumper at (x, y) (m) after SUMO's next step, driving at
        ``speed`` (m/s, >= 0) along its lane."""
        veh, vid = self._veh, self.vid
        if self._at is None:  # where SUMO has it now
            self._at = (veh.getLaneID(vid), veh.getLanePosition(vid))
        i = self.index
        j, along, dist2, across = self._nearest(i, x, y)
        segs = self.lanes[i]
        lid, pos = self._position(segs[j], along)
        # SUMO's step drives it there along its lane (over a joint onto the next edge's)
        at, was = self._at
        if lid == at:
            move = pos - was
        else:
            k = j
            while k > 0 and segs[k][6] == lid:
                k -= 1
            move = pos + segs[k][8] - was if segs[k][6] == at else pos - was - segs[j][8]
        if move >= 0.0:
            veh.setSpeed(vid, move / self.dt)
        else:  # backwards, which SUMO does not drive: put there now, standing
            veh.moveTo(vid, lid, pos, 1)
            veh.setSpeed(vid, 0.0)
        if accel is None:
            veh.setPreviousSpeed(vid, speed)
        else:
            veh.setPreviousSpeed(vid, speed, accel)
        # past the lanes' common edge: its neighbour's, after the step (as moveToXY's)
        self._switch = None
        if across > self.half_width[i] and i + 1 < len(self.lanes):
            i += 1
        elif -across > self.half_width[i] and i > 0:
            i -= 1
        if i != self.index:
            self.index = i
            j, along, dist2, across = self._nearest(i, x, y)
            lid, pos = self._position(self.lanes[i][j], along)
            self._switch = (lid, pos)
        self._at = (lid, pos)
        self._lat = math.copysign(math.sqrt(dist2), across)

    @staticmethod
    def _position(seg: tuple, along: float) -> tuple[str, float]:
        """(lane id, SUMO's position along it) of the point ``along`` m along segment ``seg``."""
        return seg[6], min(max((seg[5] + along) * seg[7], 0.0), seg[8] - 0.1)

    def after_step(self) -> None:
        """After SUMO's step: the lane, when it changed, and the lateral offset (moveToXY
        applies its pose then too)."""
        veh, vid = self._veh, self.vid
        if self._switch is not None:
            veh.moveTo(vid, *self._switch, 1)
        veh.setLateralLanePosition(vid, self._lat)
