"""A geometric surround sensor: the scene from the vehicles' outlines, not from SUMO's lanes.

SUMO's leader/follower queries are lane bookkeeping: while the ego straddles two lanes its
"leader" is already the target lane's car although its body still overlaps the car it is
leaving. This sensor never overstates clearance that way. Like a radar it looks once per
SUMO step (10 Hz by default): it takes the oriented boxes of the vehicles near the ego
(one libsumo context subscription, see :meth:`ego.sumo.bridge.SumoBridge.surroundings`),
expresses each in the frame of a reference lane (its extent along the lane ``[s_lo,
s_hi]`` and across it ``[d_lo, d_hi]``, its velocity along and across the lane) and, with
the ego's outline in the same frame (:meth:`SurroundSensor.scan`), finds

* ``front``: the nearest vehicle ahead whose extent across the lane overlaps the ego's path:
  the ego's own extent across the lane (in whatever lane, the car it is leaving during a
  lane change included) or the lane it is in (the one whose centre is nearest the middle of
  its front bumper) unless it is moving out of that lane. A car that intrudes into the ego's
  lane is a target from then on, as UN R157 judges a cut-in (the TTC at its intrusion into
  the lane, 5.2.5.2), not only once it is beside the ego; a lead leaving the lane (a
  cut-out) stops hiding what is ahead of it once it is clear of the ego's outline; ``gap`` from the ego's foremost point to its rearmost point (m,
  <= 0 when they overlap along the lane); ``speed`` its velocity along the lane (m/s),
  ``accel`` its acceleration;
* ``rear``: the same behind;
* :meth:`SurroundSensor.lane_neighbours`: the nearest vehicles ahead of and behind the
  ego overlapping a lane's band (gap acceptance, following a lane's leader).

Between two looks (:meth:`SurroundSensor.advance`, every control period) each detected
vehicle moves on at its speed and the ego by what its model integrated, as a tracker
carries a radar's objects between scans (a car braking at 6 m/s^2 is 3 cm behind that by
the next look, which corrects it).

Extents are exact for boxes on a straight reference lane; on a curved one they are those
of the box turned by its heading relative to the lane at its centre. A gap is the
separation of the two outlines' extents along the lane: the distance between the outlines
projected on the lane direction, which is never more than the distance between the
outlines themselves (a projection never lengthens a distance), so the sensor never
overstates clearance; while the ego is turned by a few degrees it is conservative by up
to its width times the sine of its heading error.

On a curved road the stations ``s`` are those of the reference (start) lane, and a lane
``D`` m to its left runs ``1 - kappa D`` m per metre of them: a gap is the arc length along
the centre line of the lane the ego is in (:meth:`SurroundSensor.scan`), the station
difference scaled by the turn between the two (``LanePolyline.place``); each car's length
and speed are scaled from its own line to that one where that shortens the gap, and its
inner corners' reach past its extent is left out, so the gap is never longer than the arc
along the ego's lane between the outlines.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from operator import itemgetter
from typing import Any

from ego.lane_frame import LanePolyline
from ego.native import NATIVE

INF = math.inf
_LOW_EDGE = itemgetter(1)  #: an object's rearmost extent along the lane: the sort key of a sync
#: :meth:`SurroundSensor.sync_within` in C, or None
_PLACE = None if NATIVE is None else NATIVE.place
#: the search's loops in C (the same arithmetic): the filter of :meth:`SurroundSensor.scan`
#: and ``_scan_lane``, and ``_nearest``
_NEAR = None if NATIVE is None else NATIVE.near
_NEAREST = None if NATIVE is None else NATIVE.nearest
#: LanePolyline.mean_curvature on a lane's packed data (ahead 0: curvature_at)
_MEAN_CURVATURE = None if NATIVE is None else NATIVE.lane_mean_curvature

#: a sensed vehicle in the lane frame: (id, s_lo, s_hi, d_lo, d_hi, v_s, v_d, a_s, heading
#: relative to the lane[, the lane's turn and curvature at its centre on a curved lane])
Obj = tuple[Any, ...]
#: a vehicle as the simulator reports it: (centre x, y in m, yaw rad, speed m/s, length, width m)
Row = tuple[float, ...]


class Detection:
    """One sensed vehicle: ``gap`` bumper to bumper along the lane (m; inf: none), ``speed``
    its velocity along the lane (m/s), ``accel`` its acceleration along the lane over the
    last SUMO step (m/s^2). ``overlap``, ``side`` and ``lateral_speed`` say how it sits
    across the band it was found in (for ``front`` and ``rear``: the ego's own extent)."""

    __slots__ = ("id", "gap", "speed", "accel", "gap0", "obj", "lo", "hi", "since", "line")

    def __init__(
        self,
        id: str = "",
        gap: float = INF,
        speed: float = 0.0,  # noqa: A002
        accel: float = 0.0,
    ) -> None:
        self.id, self.gap, self.speed, self.accel = id, gap, speed, accel
        self.gap0 = gap  #: the gap at the scan that found it
        self.obj: Obj | None = None
        self.lo = self.hi = self.since = 0.0
        #: on a curved road, the offset (m, + left of the reference lane) of the line its gap
        #: is measured along; None on a straight one
        self.line: float | None = None

    def __repr__(self) -> str:
        return f"Detection(id={self.id!r}, gap={self.gap!r}, speed={self.speed!r}, accel={self.accel!r})"

    def clear(self) -> None:
        self.id = ""
        self.gap = INF
        self.speed = 0.0
        self.accel = 0.0
        self.obj = None

    def _found(self, o: Obj, gap: float, lo: float, hi: float, since: float) -> None:
        self.id, self.gap, self.speed, self.accel = o[0], gap, o[5], o[7]
        self.gap0 = gap
        self.obj, self.lo, self.hi, self.since = o, lo, hi, since

    def _found_along(self, o: Obj, gap: float, lo: float, hi: float, since: float, d: float, speed: float) -> None:
        """:meth:`_found` on a curved road: the gap along the line ``d`` (m), ``speed`` the
        object's along that line (m/s)."""
        self.id, self.gap, self.speed, self.accel = o[0], gap, speed, o[7]
        self.gap0 = gap
        self.obj, self.lo, self.hi, self.since, self.line = o, lo, hi, since, d

    def _copy(self, other: Detection, gap: float) -> None:
        self.id, self.gap, self.speed, self.accel = other.id, gap, other.speed, other.accel
        self.gap0 = other.gap0
        self.obj, self.lo, self.hi, self.since = other.obj, other.lo, other.hi, other.since
        self.line = other.line

    @property
    def lateral_speed(self) -> float:
        """Its velocity across the lane (m/s, + left)."""
        if self.obj is None:
            return 0.0
        v_d: float = self.obj[6]
        return v_d

    @property
    def overlap(self) -> float:
        """How far its extent across the lane reaches into the band it was found in (m)."""
        if self.obj is None:
            return 0.0
        shift = self.obj[6] * self.since
        into: float = min(self.obj[4] + shift, self.hi) - max(self.obj[3] + shift, self.lo)
        return into

    @property
    def side(self) -> float:
        """+1 when its centre is left of the band's centre, -1 when right."""
        if self.obj is None:
            return 0.0
        shift = self.obj[6] * self.since
        return 1.0 if self.obj[3] + self.obj[4] + 2.0 * shift > self.lo + self.hi else -1.0


class SurroundSensor:
    """Oriented boxes near the ego in a reference lane's frame; see the module docstring.

    ``lane`` is the reference lane (:class:`ego.lane_frame.LanePolyline`); ``bands`` maps a lane
    index to (d_lo, d_hi), its edges in that frame (m); ``cg_to_front``, ``length`` and
    ``width`` are the ego's body (m).
    """

    __slots__ = (
        "lane",
        "bands",
        "cg_to_front",
        "cg_to_rear",
        "half_width",
        "front",
        "rear",
        "horizon",
        "reach",
        "_objects",
        "_near",
        "lanes",
        "_straight",
        "_place",
        "_placing",
        "_curvature_at",
        "along",
        "turn",
        "turn_scan",
        "rate",
        "_t_sync",
        "t",
        "t_scan",
        "s",
        "s_scan",
        "_ego",
        "_speeds",
        "_rows",
        "_seen",
    )

    def __init__(
        self,
        lane: LanePolyline,
        bands: dict[int, tuple[float, float]],
        cg_to_front: float,
        length: float,
        width: float,
        horizon: float = 0.1,
        reach: float = 1.0,
    ) -> None:
        self.lane = lane
        #: the time between two SUMO steps (s) and how far (m) the ego may move sideways in
        #: it (1 m: 10 m/s at 0.1 s, far beyond a lane change): what the front/rear scan
        #: looks at between two SUMO steps
        self.horizon = horizon
        self.reach = reach
        self._near: list[Obj] | None = None
        self.lanes: dict[int, tuple[Detection, Detection]] = {}  #: per lane, at the last scan
        self.t_scan = self.s = self.s_scan = 0.0
        self._straight = lane.straight() if hasattr(lane, "straight") else None
        #: on a curved lane: (x, y, yaw) -> (s, d, rel, turn, kappa) (LanePolyline.place);
        #: the objects then carry the lane's turn and curvature at their centre
        self._place = getattr(lane, "place", None) if self._straight is None else None
        #: what ego._native.place places the cars with: the lane (its packed data) or a callable
        self._placing = (lane if hasattr(lane, "packed") else self._place) if self._place is not None else lane.frame
        #: the lane's curvature at the ego's ends at a scan (LanePolyline.curvature_at): in C
        #: on a curved lane's packed data
        self._curvature_at = _MEAN_CURVATURE if self._place is not None and hasattr(lane, "packed") else None
        #: on a curved lane, at the last scan: (the innermost and outermost lines the gaps
        #: may be measured along, m; the lane's turn at the ego, rad; how far the ego's corners reach
        #: beyond its extent ahead and behind, m); None on a straight one
        self.along: tuple[float, float, float, float, float] | None = None
        self.turn = self.turn_scan = 0.0  #: the lane's turn at the ego now / at the last scan
        #: on a curved lane, at the last scan: the ego's speed along the line its gaps are
        #: measured along per m/s of its speed along the lane where it is
        self.rate = 1.0
        self.bands = dict(bands)
        self.cg_to_front = cg_to_front
        self.cg_to_rear = length - cg_to_front
        self.half_width = 0.5 * width
        self.front = Detection()
        self.rear = Detection()
        #: (id, s_lo, s_hi, d_lo, d_hi, v_s, v_d, a_s, heading relative to the lane[, the
        #: lane's turn and curvature at its centre on a curved lane]) at the last sync,
        #: ordered by s_lo
        self._objects: list[Obj] = []
        self._speeds: dict[str, float] = {}  #: id -> v_s at the last sync
        self._rows: dict[str, Row] | None = {}  #: id -> world row at the last sync
        self._seen: tuple[Sequence[str], Sequence[Row]] = ((), ())  #: ids, world rows at the last sync
        self._t_sync = 0.0
        self.t = 0.0
        self._ego = (0.0, 0.0, 0.0, 0.0)

    def sync(self, t: float, ids: Sequence[str], rows: Sequence[Row]) -> None:
        """The vehicles around the ego at a SUMO step, time ``t`` (s): ``rows`` of (centre x,
        y in m, yaw rad, speed m/s, length, width m) as
        :meth:`~ego.sumo.bridge.SumoBridge.surroundings` gives them."""
        cos, sin = math.cos, math.sin
        straight = self._straight
        frame = self.lane.frame
        place = self._place
        objects: list[Obj] = []
        add = objects.append
        previous = self._speeds.get
        dt = t - self._t_sync
        rated = dt > 0.0
        speeds: dict[str, float] = {}
        if straight is not None:  # one segment: the frame is a rotation
            x0, y0, ux, uy, s0, heading = straight
        for vid, (x, y, yaw, v, length, width) in zip(ids, rows):
            bend = None
            if straight is not None:
                dx, dy = x - x0, y - y0
                s, d = s0 + dx * ux + dy * uy, dy * ux - dx * uy
                rel = yaw - heading
            elif place is not None:
                s, d, rel, turn, kappa = place(x, y, yaw)
                bend = (turn, kappa)
            else:
                s, d, rel, _ = frame(x, y, yaw)
            c, sn = cos(rel), sin(rel)
            ac, asn = abs(c), abs(sn)
            hs = 0.5 * (length * ac + width * asn)
            hd = 0.5 * (length * asn + width * ac)
            vs = v * c
            prev = previous(vid)
            accel = (vs - prev) / dt if prev is not None and rated else 0.0
            speeds[vid] = vs
            if bend is None:
                add((vid, s - hs, s + hs, d - hd, d + hd, vs, v * sn, accel, rel))
            else:
                add((vid, s - hs, s + hs, d - hd, d + hd, vs, v * sn, accel, rel, *bend))
        objects.sort(key=_LOW_EDGE)
        self._objects = objects
        self._near = None
        self._speeds = speeds
        self._seen = (ids, rows)
        self._rows = None  # id -> row, made when box() first asks after this sync
        self._t_sync = t

    def sync_within(
        self, t: float, ids: list[str], rows: list[Row], front: tuple[float, float] | None, reach: float
    ) -> tuple[list[str], list[Row]]:
        """:meth:`sync` of the vehicles whose box centre lies within ``reach`` (m) of ``front``
        (x, y; every vehicle when None); returns their ids and rows. In C when the extension
        is built (``ego._native.place``: the same arithmetic)."""
        if _PLACE is None:
            if front is not None:
                x, y = front
                near = [i for i, r in enumerate(rows) if math.hypot(r[0] - x, r[1] - y) <= reach]
                ids, rows = [ids[i] for i in near], [rows[i] for i in near]
            self.sync(t, ids, rows)
            return ids, rows
        if type(ids) is not list or type(rows) is not list:
            ids, rows = list(ids), list(rows)
        dt = t - self._t_sync
        # on a curved lane the lane itself (its packed data: ego._native.place projects every
        # car in C, as LanePolyline.place does), else a callable placing one
        ids, rows, self._objects, self._speeds = _PLACE(
            ids,
            rows,
            front,
            reach,
            self._straight,
            self._placing,
            self._speeds,
            dt,
            dt > 0.0,
            _LOW_EDGE,
        )
        self._near = None
        self._seen = (ids, rows)
        self._rows = None
        self._t_sync = t
        return ids, rows

    def ego_extents(self, s: float, d: float, heading_error: float) -> tuple[float, float, float, float]:
        """(s_lo, s_hi, d_lo, d_hi) of the ego's body with its centre of gravity at (s, d),
        turned by ``heading_error`` from the lane (m)."""
        c, sn = math.cos(heading_error), math.sin(heading_error)
        hw = self.half_width
        ac, as_ = abs(c), abs(sn)
        # the CG is not the box centre: take the extreme corners
        f, r = self.cg_to_front, self.cg_to_rear
        fc, rc, fs, rs = f * c, r * c, f * sn, r * sn
        return (
            s + (fc if fc < -rc else -rc) - hw * as_,
            s + (fc if fc > -rc else -rc) + hw * as_,
            d + (fs if fs < -rs else -rs) - hw * ac,
            d + (fs if fs > -rs else -rs) + hw * ac,
        )

    def scan(self, t: float, s: float, d: float, heading_error: float, turn: float = 0.0, kappa: float = 0.0) -> None:
        """Look: ``front`` and ``rear`` for the ego's centre of gravity at (s, d) (m) with
        ``heading_error`` (rad) at time ``t`` (s); ``turn`` and ``kappa`` are the reference
        lane's turn and curvature there (rad, 1/m, ``LanePolyline.place``; curved lanes
        only, where ``s`` is the station). Called at every SUMO step (the sensor's rate);
        :meth:`advance` carries the gaps on in between.

        On a curved lane the gaps are arc lengths along the centre line of the lane the ego
        is in (the lane whose centre is nearest the middle of its front bumper, as SUMO
        maps it). A straight body's corners on the inner side reach past its extent along
        the lane by about its reach times ``kappa`` times how far they sit inside the line
        (1 cm for a car in an R 250 m arc): the gap leaves that out for both cars. The
        ego's speed along the line is ``ds`` times :attr:`_rate`."""
        ego = self._ego = self.ego_extents(s, d, heading_error)
        self.t = self.t_scan = t
        self.s = self.s_scan = s
        # the ego's lane: the one whose centre is nearest the middle of its front bumper
        # (where SUMO maps it too)
        nose = d + self.cg_to_front * math.sin(heading_error)
        own = min(self.bands.values(), key=lambda b: abs(0.5 * (b[0] + b[1]) - nose), default=None)
        # what counts as in the ego's path: its own extent across the lane and its lane (R157:
        # a car that intrudes into the ego's lane is a target, not only one already beside it)
        lo, hi = ego[2], ego[3]
        if own is not None:
            lo, hi = (own[0] if own[0] < lo else lo), (own[1] if own[1] > hi else hi)
        if self._place is not None:
            line = d if own is None else 0.5 * (own[0] + own[1])
            # its inner side beyond the line, its corners' reach per metre of its length: at
            # each end the larger curvature of the centre's and that end's (an end in an arc
            # the centre has not reached yet)
            reach = []
            lane, curvature_at = self.lane, self._curvature_at
            for end in (ego[1], ego[0]):
                if curvature_at is not None:
                    k = curvature_at(lane, end, 0.0)
                else:
                    k = lane.curvature_at(end) if hasattr(lane, "curvature_at") else kappa
                k = kappa if abs(kappa) >= abs(k) else k
                w = max(ego[3] - line if k > 0.0 else line - ego[2], 0.0)
                reach.append(abs(k) * w / (1.0 - abs(k) * w))
            self.along = (line, line, turn, (ego[1] - s) * reach[0], (s - ego[0]) * reach[1])
            self.turn = self.turn_scan = turn
            self.rate = (1.0 - kappa * line) / (1.0 - kappa * d)
        self.lanes = {}
        near = self._near
        if near is None:
            # the vehicles that can reach across into the ego's path before the next SUMO step:
            # the ego moves sideways by less than `reach` (m), each of them by |v_d| * horizon
            h, m = self.horizon, self.reach
            if _NEAR is not None and type(self._objects) is list:
                near = self._near = _NEAR(self._objects, lo, hi, h, m)
            else:
                near = self._near = [
                    o for o in self._objects if o[4] + abs(o[6]) * h + m > lo and o[3] - abs(o[6]) * h - m < hi
                ]
        front, rear = self.front, self.rear
        if own is not None:
            near = self._in_path(near, ego[2], ego[3], own)
        self._nearest(near, lo, hi, front, rear)
        # their overlap and side: with the ego's own extent, which it must clear sideways
        for det in (front, rear):
            if det.obj is not None:
                det.lo, det.hi = ego[2], ego[3]

    def _in_path(self, objects: list[Obj], e_lo: float, e_hi: float, own: tuple[float, float]) -> list[Obj]:
        """Of ``objects``, those in the ego's path at the last scan: overlapping the ego's own
        extent across the lane (``e_lo``, ``e_hi``), or intruding into its lane ``own`` (lo,
        hi) unless moving out of it. A car leaving the lane (a cut-out) stops hiding what is
        ahead of it once it is clear of the ego's outline, as a car entering it (a cut-in)
        is a target from its intrusion: both where the ego, keeping its line, could hit it."""
        since = self.t_scan - self._t_sync
        l_lo, l_hi = own
        twice_centre = l_lo + l_hi
        out = []
        for o in objects:
            shift = o[6] * since
            a, b = o[3] + shift, o[4] + shift
            if (b > e_lo and a < e_hi) or (b > l_lo and a < l_hi and (a + b - twice_centre) * o[6] <= 0.0):
                out.append(o)
        return out

    def advance(self, t: float, s: float, turn: float = 0.0) -> None:
        """Between two looks: the gaps at time ``t`` (s) with the ego's centre of gravity at
        ``s`` (m) along the lane (where the lane has turned by ``turn``, rad: curved lanes),
        each detected vehicle moving at its speed."""
        self.t, self.s, self.turn = t, s, turn
        front, rear = self.front, self.rear
        # _carried, inline: every control period
        moved = s - self.s_scan
        since = t - self.t_scan
        if front.obj is not None:
            line = front.line
            ahead = moved if line is None else moved - line * (turn - self.turn_scan)
            front.gap = front.gap0 + front.speed * since - ahead
        if rear.obj is not None:
            line = rear.line
            behind = moved if line is None else moved - line * (turn - self.turn_scan)
            rear.gap = rear.gap0 + behind - rear.speed * since

    def _carried(self, det: Detection, ahead: bool) -> float:
        """``det``'s gap carried on from the last scan to now: it moved at its speed, the ego
        by its arc along the line the gap is measured along."""
        moved = self.s - self.s_scan
        since = self.t - self.t_scan
        if det.line is not None:
            moved -= det.line * (self.turn - self.turn_scan)
        if ahead:
            return det.gap0 + det.speed * since - moved
        return det.gap0 + moved - det.speed * since

    def _nearest(self, objects: list[Obj], lo: float, hi: float, ahead: Detection, behind: Detection) -> None:
        """Nearest of ``objects`` ahead of and behind the ego overlapping [lo, hi] across the
        lane, at the last scan."""
        since = self.t_scan - self._t_sync
        e_lo, e_hi = self._ego[0], self._ego[1]
        along = self.along
        if _NEAREST is not None and type(objects) is list:
            _NEAREST(objects, lo, hi, e_lo, e_hi, since, ahead, behind, along)
            return
        if along is not None:
            self._nearest_along(objects, lo, hi, ahead, behind, since, along)
            return
        twice_mid = e_lo + e_hi
        best_ahead = best_behind = INF
        front = rear = None
        for o in objects:
            shift = o[6] * since
            if o[4] + shift <= lo or o[3] + shift >= hi:
                continue
            move = o[5] * since
            a, b = o[1] + move, o[2] + move
            if a + b >= twice_mid:  # its centre is ahead of the ego's
                if a - e_hi < best_ahead:
                    best_ahead, front = a - e_hi, o
            elif e_lo - b < best_behind:
                best_behind, rear = e_lo - b, o
        if front is None:
            ahead.clear()
        else:
            ahead._found(front, best_ahead, lo, hi, since)
        if rear is None:
            behind.clear()
        else:
            behind._found(rear, best_behind, lo, hi, since)

    def _nearest_along(
        self,
        objects: list[Obj],
        lo: float,
        hi: float,
        ahead: Detection,
        behind: Detection,
        since: float,
        along: tuple[float, float, float, float, float],
    ) -> None:
        """:meth:`_nearest` on a curved lane: each gap the shortest arc between the outlines
        along the lines ``along`` bounds (the innermost and outermost, m), the other car's
        length scaled from its line to that one where it grows there, its speed along it."""
        e_lo, e_hi = self._ego[0], self._ego[1]
        d_min, d_max, turn, ego_front, ego_rear = along
        twice_mid = e_lo + e_hi
        best_ahead = best_behind = INF
        front = rear = None
        d_ahead = d_behind = 0.0
        for o in objects:
            shift = o[6] * since
            if o[4] + shift <= lo or o[3] + shift >= hi:
                continue
            move = o[5] * since
            a, b = o[1] + move, o[2] + move
            kappa = o[10]
            bend = o[9] + kappa * move - turn  # the lane's turn from the ego to it
            d_o = 0.5 * (o[3] + o[4]) + shift
            half = 0.5 * (o[2] - o[1])
            grow = half * kappa / (1.0 - kappa * d_o)  # its half length's, per m inwards
            k, w = abs(kappa), 0.5 * (o[4] - o[3])
            corner = half * k * w / (1.0 - k * w)  # its inner corners' reach beyond its extent
            if a + b >= twice_mid:
                raw = a - e_hi
                g0, g1 = raw - d_min * bend, raw - d_max * bend
            else:
                raw = e_lo - b
                g0, g1 = raw + d_min * bend, raw + d_max * bend
            extra = grow * (d_o - d_min)
            if extra > 0.0:
                g0 -= extra
            extra = grow * (d_o - d_max)
            if extra > 0.0:
                g1 -= extra
            gap, line = (g1, d_max) if g1 < g0 else (g0, d_min)
            if a + b >= twice_mid:
                gap = gap - corner - ego_front
                if gap < best_ahead:
                    best_ahead, front, d_ahead = gap, o, line
            else:
                gap = gap - corner - ego_rear
                if gap < best_behind:
                    best_behind, rear, d_behind = gap, o, line
        for det, found, gap, line in ((ahead, front, best_ahead, d_ahead), (behind, rear, best_behind, d_behind)):
            if found is None:
                det.clear()
            else:
                kappa = found[10]
                rate = (1.0 - kappa * line) / (1.0 - kappa * (0.5 * (found[3] + found[4]) + found[6] * since))
                det._found_along(found, gap, lo, hi, since, line, found[5] * rate)

    def _scan_lane(self, lane: int, band: tuple[float, float]) -> tuple[Detection, Detection]:
        """The nearest vehicles ahead of and behind the ego overlapping ``band`` across the
        lane, at the last scan (kept for ``lane`` until the next)."""
        lo, hi, h = band[0], band[1], self.horizon
        if _NEAR is not None and type(self._objects) is list:
            near = _NEAR(self._objects, lo, hi, h, 0.0)  # x + 0.0 compares as x
        else:
            near = [o for o in self._objects if o[4] + abs(o[6]) * h > lo and o[3] - abs(o[6]) * h < hi]
        found = self.lanes[lane] = (Detection(), Detection())
        self._nearest(near, lo, hi, *found)
        return found

    def wandering(self) -> tuple[str, float, float, float]:
        """The vehicle ahead in a lane next to the ego's that has moved farthest from its own
        lane's centre towards the ego's lane, at the last look: (id, that lateral
        displacement in m, its bumper gap ahead of the ego in m, its speed along the lane in
        m/s); ("", -inf, inf, 0) when there is none. The ego's lane is the band holding
        the reference lane's centre line (d = 0): R157's careful driver perceives a cut-in
        when this displacement exceeds the lateral wandering distance."""
        best = ("", -INF, INF, 0.0)
        own = next(((lo, hi) for lo, hi in self.bands.values() if lo <= 0.0 < hi), None)
        if own is None:
            return best
        front = self._ego[1]
        for o in self._objects:
            gap = o[1] - front
            if gap < 0.0:
                continue
            centre = 0.5 * (o[3] + o[4])
            for lo, hi in self.bands.values():
                if (lo, hi) == own or not lo <= centre < hi:
                    continue
                mid = 0.5 * (lo + hi)
                towards = (centre - mid) if mid < 0.0 else (mid - centre)
                if towards > best[1]:
                    best = (o[0], towards, gap, o[5])
        return best

    def lane_neighbours(self, lane: int, leader: Detection, follower: Detection) -> bool:
        """Fill ``leader``/``follower`` with the nearest vehicles ahead of / behind the ego
        whose extent overlaps lane ``lane``'s band (seen at the last :meth:`scan`, gaps
        carried on to now); False (both cleared) when there is no such lane."""
        band = self.bands.get(lane)
        if band is None:
            leader.clear()
            follower.clear()
            return False
        found = self.lanes.get(lane) or self._scan_lane(lane, band)
        ahead, behind = found
        if ahead.obj is None:
            leader.clear()
        else:
            leader._copy(ahead, self._carried(ahead, True))
        if behind.obj is None:
            follower.clear()
        else:
            follower._copy(behind, self._carried(behind, False))
        return True

    def lane_leader(self, lane: int, leader: Detection) -> bool:
        """:meth:`lane_neighbours` for the leader alone (:meth:`lane_leader_now` gives its gap
        and speed alone)."""
        band = self.bands.get(lane)
        if band is None:
            leader.clear()
            return False
        found = self.lanes.get(lane) or self._scan_lane(lane, band)
        ahead = found[0]
        if ahead.obj is None:
            leader.clear()
        else:
            leader._copy(ahead, self._carried(ahead, True))
        return True

    def lane_leader_now(self, lane: int) -> tuple[float, float] | None:
        """(gap m, speed m/s) of :meth:`lane_leader`'s vehicle, or None when there is none or
        no such lane: the lane change's reference every control period, without filling a
        :class:`Detection`."""
        found = self.lanes.get(lane)
        if found is None:
            band = self.bands.get(lane)
            if band is None:
                return None
            found = self._scan_lane(lane, band)
        ahead = found[0]
        if ahead.obj is None:
            return None
        # _carried(ahead, True), inline: every control period of a lane change
        moved = self.s - self.s_scan
        line = ahead.line
        if line is not None:
            moved -= line * (self.turn - self.turn_scan)
        speed = ahead.speed
        return ahead.gap0 + speed * (self.t - self.t_scan) - moved, speed

    def tracks(self, t: float) -> list[tuple[float, float, float, float, float]]:
        """Every vehicle seen at the last SUMO step, moved on to time ``t`` (s) at its
        velocity: (s, d) of its box centre in the lane frame (m), its velocity along and across
        the lane (m/s, + left) and its heading relative to the lane (rad, + left)."""
        since = t - self._t_sync
        return [
            (0.5 * (o[1] + o[2]) + o[5] * since, 0.5 * (o[3] + o[4]) + o[6] * since, o[5], o[6], o[8])
            for o in self._objects
        ]

    def box(self, vid: str) -> tuple[float, float, float, float, float] | None:
        """World box (centre x, y in m, yaw rad, length, width in m) of a sensed vehicle now,
        moved on from the last SUMO step at its speed; None if it was not seen."""
        rows = self._rows
        if rows is None:
            rows = self._rows = dict(zip(*self._seen))
        row = rows.get(vid)
        if row is None:
            return None
        x, y, yaw, v, length, width = row
        since = self.t - self._t_sync
        return x + v * since * math.cos(yaw), y + v * since * math.sin(yaw), yaw, length, width
