"""A geometric surround sensor: the scene from the vehicles' outlines, not from SUMO's lanes.

SUMO's leader/follower queries are lane bookkeeping: while the ego straddles two lanes its
"leader" is already the target lane's car although its body still overlaps the car it is
leaving. This sensor never overstates clearance that way. Every SUMO step it takes the
oriented boxes of the vehicles near the ego (one libsumo context subscription, see
:meth:`ego.sumo.bridge.SumoBridge.surroundings`) and expresses each in the frame of a
reference lane: its extent along the lane ``[s_lo, s_hi]`` and across it ``[d_lo, d_hi]``
and its velocity along and across the lane. Between SUMO steps those extents move at those
velocities (the SUMO step is 10 control periods; a braking car moves 3 cm less in 0.1 s
at 6 m/s^2, which the next SUMO step corrects).

Each control step :meth:`SurroundSensor.scan` takes the ego's pose in the same frame:

* ``front``: the nearest vehicle ahead whose extent across the lane overlaps the ego's, in
  whatever lane; ``gap`` from the ego's foremost corner to its rearmost point (m, <= 0 when
  they overlap); ``speed`` its velocity along the lane (m/s);
* ``rear``: the same behind;
* :meth:`lane_leader` / :meth:`lane_follower`: the nearest vehicle ahead of / behind the ego
  overlapping a lane's band (gap acceptance, following a lane's leader).

Extents are exact for boxes on a straight reference lane; on a curved one they are those
of the box turned by its heading relative to the lane at its centre. A gap is the
separation of the two outlines' extents along the lane: the distance between the outlines
projected on the lane direction, which is never more than the distance between the
outlines themselves (a projection never lengthens a distance), so the sensor never
overstates clearance; while the ego is turned by a few degrees it is conservative by up
to its width times the sine of its heading error.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

INF = math.inf


@dataclass(slots=True)
class Detection:
    """One sensed vehicle: ``gap`` bumper to bumper along the lane (m; inf: none), ``speed``
    its velocity along the lane (m/s)."""

    id: str = ""
    gap: float = INF
    speed: float = 0.0
    accel: float = 0.0  #: its acceleration along the lane over the last SUMO step (m/s^2)
    #: how far its extent across the lane reaches into the band asked about (m)
    overlap: float = 0.0
    #: +1 when its centre is left of the band's centre, -1 when right (across the lane)
    side: float = 0.0
    lateral_speed: float = 0.0  #: its velocity across the lane (m/s, + left)

    def clear(self) -> None:
        self.id = ""
        self.gap = INF
        self.speed = 0.0
        self.accel = 0.0
        self.overlap = 0.0
        self.side = 0.0
        self.lateral_speed = 0.0

    def set(self, vid: str, gap: float, speed: float, accel: float, overlap: float, side: float,
            lateral_speed: float) -> None:
        self.id = vid
        self.gap = gap
        self.speed = speed
        self.accel = accel
        self.overlap = overlap
        self.side = side
        self.lateral_speed = lateral_speed


def box_extents(s: float, d: float, rel_heading: float, length: float, width: float,
                ) -> tuple[float, float, float, float]:
    """(s_lo, s_hi, d_lo, d_hi) of a box centred at (s, d) turned by ``rel_heading`` (rad)
    from the lane direction (m)."""
    c, sn = abs(math.cos(rel_heading)), abs(math.sin(rel_heading))
    hs = 0.5 * (length * c + width * sn)
    hd = 0.5 * (length * sn + width * c)
    return s - hs, s + hs, d - hd, d + hd


class SurroundSensor:
    """Oriented boxes near the ego in a reference lane's frame; see the module docstring.

    ``lane`` is the reference lane (:class:`ego.road.LanePolyline`); ``bands`` maps a lane
    index to (d_lo, d_hi), its edges in that frame (m); ``cg_to_front``, ``length`` and
    ``width`` are the ego's body (m).
    """

    __slots__ = ("lane", "bands", "cg_to_front", "cg_to_rear", "half_width", "front", "rear",
                 "_objects", "_t_sync", "_t", "_ego", "_count", "_speeds", "_rows")

    def __init__(self, lane, bands: dict[int, tuple[float, float]], cg_to_front: float,
                 length: float, width: float) -> None:
        self.lane = lane
        self.bands = dict(bands)
        self.cg_to_front = cg_to_front
        self.cg_to_rear = length - cg_to_front
        self.half_width = 0.5 * width
        self.front = Detection()
        self.rear = Detection()
        #: (id, s_lo, s_hi, d_lo, d_hi, v_s, v_d, a_s) at the last sync, ordered by s_lo
        self._objects: list[tuple] = []
        self._speeds: dict[str, float] = {}  #: id -> v_s at the last sync
        self._rows: dict[str, tuple] = {}  #: id -> world row at the last sync
        self._t_sync = 0.0
        self._t = 0.0
        self._ego = (0.0, 0.0, 0.0, 0.0)
        self._count = 0

    @property
    def count(self) -> int:
        """Vehicles seen at the last SUMO step."""
        return self._count

    def sync(self, t: float, ids: Sequence[str], rows: Sequence[tuple]) -> None:
        """The vehicles around the ego at a SUMO step, time ``t`` (s): ``rows`` of (centre x,
        y in m, yaw rad, speed m/s, length, width m) as
        :meth:`~ego.sumo.bridge.SumoBridge.surroundings` gives them."""
        frame = self.lane.frame
        cos, sin = math.cos, math.sin
        objects = []
        before = self._speeds
        dt = t - self._t_sync
        speeds = {}
        for vid, (x, y, yaw, v, length, width) in zip(ids, rows):
            s, d, rel, _ = frame(x, y, yaw)
            c, sn = cos(rel), sin(rel)
            hs = 0.5 * (length * abs(c) + width * abs(sn))
            hd = 0.5 * (length * abs(sn) + width * abs(c))
            vs = v * c
            prev = before.get(vid)
            accel = (vs - prev) / dt if prev is not None and dt > 0.0 else 0.0
            speeds[vid] = vs
            objects.append((vid, s - hs, s + hs, d - hd, d + hd, vs, v * sn, accel))
        objects.sort(key=lambda o: o[1])
        self._objects = objects
        self._speeds = speeds
        self._rows = dict(zip(ids, rows))
        self._count = len(objects)
        self._t_sync = t

    def ego_extents(self, s: float, d: float, heading_error: float) -> tuple[float, float, float, float]:
        """(s_lo, s_hi, d_lo, d_hi) of the ego's body with its centre of gravity at (s, d),
        turned by ``heading_error`` from the lane (m)."""
        c, sn = math.cos(heading_error), math.sin(heading_error)
        hw = self.half_width
        ac, as_ = abs(c), abs(sn)
        # the CG is not the box centre: take the extreme corners
        f, r = self.cg_to_front, self.cg_to_rear
        s_lo = s + min(f * c, -r * c) - hw * as_
        s_hi = s + max(f * c, -r * c) + hw * as_
        d_lo = d + min(f * sn, -r * sn) - hw * ac
        d_hi = d + max(f * sn, -r * sn) + hw * ac
        return s_lo, s_hi, d_lo, d_hi

    def scan(self, t: float, s: float, d: float, heading_error: float) -> None:
        """Update ``front`` and ``rear`` for the ego's centre of gravity at (s, d) (m) with
        ``heading_error`` (rad) at time ``t`` (s)."""
        ego = self._ego = self.ego_extents(s, d, heading_error)
        self._t = t
        self._nearest(ego[2], ego[3], self.front, self.rear)

    def _nearest(self, lo: float, hi: float, ahead: Detection, behind: Detection) -> None:
        """Nearest vehicle ahead of and behind the ego overlapping [lo, hi] across the lane."""
        since = self._t - self._t_sync
        e_lo, e_hi = self._ego[0], self._ego[1]
        e_mid = 0.5 * (e_lo + e_hi)
        best_ahead = best_behind = INF
        ahead.clear()
        behind.clear()
        for vid, s_lo, s_hi, d_lo, d_hi, vs, vd, acc in self._objects:
            shift = vd * since
            if d_hi + shift <= lo or d_lo + shift >= hi:
                continue
            move = vs * since
            a, b = s_lo + move, s_hi + move
            if a + b >= 2.0 * e_mid:  # its centre is ahead of the ego's
                gap = a - e_hi
                if gap < best_ahead:
                    best_ahead = gap
                    ahead.set(vid, gap, vs, acc, min(d_hi + shift, hi) - max(d_lo + shift, lo),
                              1.0 if d_lo + d_hi + 2.0 * shift > lo + hi else -1.0, vd)
            else:
                gap = e_lo - b
                if gap < best_behind:
                    best_behind = gap
                    behind.set(vid, gap, vs, acc, min(d_hi + shift, hi) - max(d_lo + shift, lo),
                               1.0 if d_lo + d_hi + 2.0 * shift > lo + hi else -1.0, vd)

    def lane_neighbours(self, lane: int, leader: Detection, follower: Detection) -> bool:
        """Fill ``leader``/``follower`` with the nearest vehicles ahead of / behind the ego
        whose extent overlaps lane ``lane``'s band (as of the last :meth:`scan`); False
        (both cleared) when there is no such lane."""
        band = self.bands.get(lane)
        if band is None:
            leader.clear()
            follower.clear()
            return False
        self._nearest(band[0], band[1], leader, follower)
        return True

    def box(self, vid: str) -> tuple[float, float, float, float, float] | None:
        """World box (centre x, y in m, yaw rad, length, width in m) of a sensed vehicle now,
        moved on from the last SUMO step at its speed; None if it was not seen."""
        row = self._rows.get(vid)
        if row is None:
            return None
        x, y, yaw, v, length, width = row
        since = self._t - self._t_sync
        return x + v * since * math.cos(yaw), y + v * since * math.sin(yaw), yaw, length, width

    def lane_of(self, d: float) -> int | None:
        """The lane whose band contains the lateral offset ``d`` (m), or None."""
        for lane, (lo, hi) in self.bands.items():
            if lo <= d < hi:
                return lane
        return None
