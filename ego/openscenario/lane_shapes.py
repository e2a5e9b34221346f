"""Lanes whose width or offset changes along an OpenDRIVE road, put where the road says.

A SUMO lane has one width, and netconvert places an edge's lanes side by side at those widths
from the edge's shape (OpenDRIVE's reference line moved by the lane offset, the offset taken
only at the shape's points: a straight ``<line>`` under a cubic ``laneOffset`` becomes one
chord). Where a lane opens or closes along a lane section (a 2+1 road's overtaking lane, a
merge lane that narrows to nothing) the lanes beside it are then where the constant widths put
them: on esmini's two_plus_one.xodr the outer lane of the 2+1 stretch sits up to 1.4 m off its
OpenDRIVE centre and jumps 1.5 m from one of netconvert's pieces to the next, and SUMO's cars
and the ego's lane frame follow that sawtooth.

:func:`exact_lane_shapes` rewrites, in the converted network, the shape of every lane of a
road with a width record or a lane offset that changes along it: its points every
:data:`STEP` m on the OpenDRIVE lane centre (:class:`ReferenceLine` for the plan view, the
lane offset and the widths of the lanes between it and the reference line, border and
shoulder lanes included, and half its own), over the same stretch of road as netconvert's
lane (its ends where the junctions cut it). The junctions' internal lanes that join a moved
lane move with its ends (between two lane sections of one road: onto the two lanes' centres).
SUMO's cars and the ego then drive the same lanes, the road's own. A
lane keeps its SUMO ``width`` (one number) and ``length`` (SUMO's positions along it).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

#: m between the points of a rewritten lane
STEP = 0.5
#: m: a lane end this close to an internal lane's end is where the internal lane starts or ends
SAME = 1e-3


@dataclass(frozen=True)
class Poly:
    """One OpenDRIVE cubic record from road s ``start`` (m): a + b x + c x^2 + d x^3, x = s - start."""

    start: float
    a: float
    b: float
    c: float
    d: float

    def at(self, s: float) -> float:
        x = s - self.start
        return self.a + x * (self.b + x * (self.c + x * self.d))


def _num(node: ET.Element, key: str, default: float = 0.0) -> float:
    try:
        return float(node.get(key, default))
    except ValueError:
        return default


def _value(polys: list[Poly], s: float) -> float:
    """The piecewise cubic at road s (the last record starting at or before s; 0 with none)."""
    here = None
    for p in polys:
        if here is None or p.start <= s + 1e-9:
            here = p
    return 0.0 if here is None else here.at(s)


def _changes(polys: list[Poly]) -> bool:
    return any(p.b or p.c or p.d for p in polys) or len({p.a for p in polys}) > 1


class ReferenceLine:
    """A road's plan view sampled every ``step`` m (and at every geometry's start): points,
    headings and s, for the reference line's point and heading at any s (linear between the
    samples: 0.1 m apart, a chord of R = 20 m is 6e-5 m off its arc) and a point's s.

    Geometries: ``line``, ``arc``, ``spiral`` (curvature linear in s, integrated numerically),
    ``poly3`` (v = a + b u + c u^2 + d u^3 in the local u, v frame, s the arc length along it)
    and ``paramPoly3`` (u, v cubic in p; ``pRange`` ``arcLength``: p = s - s0, else
    ``normalized``: p = (s - s0) / length). Raises ValueError on another."""

    def __init__(self, plan: ET.Element, step: float = 0.1) -> None:
        s_all: list[np.ndarray] = []
        xy_all: list[np.ndarray] = []
        h_all: list[np.ndarray] = []
        for g in plan.iterfind("geometry"):
            s0, x0, y0, h0, length = (_num(g, k) for k in ("s", "x", "y", "hdg", "length"))
            if length <= 0.0:
                continue
            n = max(2, math.ceil(length / step) + 1)
            u = np.linspace(0.0, length, n)
            kind = next(iter(g), None)
            if kind is None:
                raise ValueError("a geometry without its shape")
            local, heading = self._local(kind, u, length)
            c, s = math.cos(h0), math.sin(h0)
            xy_all.append(
                np.column_stack((x0 + c * local[:, 0] - s * local[:, 1], y0 + s * local[:, 0] + c * local[:, 1]))
            )
            h_all.append(h0 + heading)
            s_all.append(s0 + u)
        if not s_all:
            raise ValueError("a plan view without geometry")
        self.s = np.concatenate(s_all)
        self.xy = np.concatenate(xy_all)
        self.heading = np.unwrap(np.concatenate(h_all))
        keep = np.concatenate(([True], np.diff(self.s) > 1e-9))
        self.s, self.xy, self.heading = self.s[keep], self.xy[keep], self.heading[keep]
        from ego.lane_frame import LanePolyline

        self._line = LanePolyline([tuple(p) for p in self.xy])
        self._at = np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(self.xy, axis=0).T))))

    @staticmethod
    def _local(kind: ET.Element, u: np.ndarray, length: float) -> tuple[np.ndarray, np.ndarray]:
        """(u, v) points and heading change along one geometry of ``length``, at arc lengths ``u``."""
        tag = kind.tag
        if tag == "line":
            return np.column_stack((u, np.zeros_like(u))), np.zeros_like(u)
        if tag == "arc":
            k = _num(kind, "curvature")
            if k == 0.0:
                return np.column_stack((u, np.zeros_like(u))), np.zeros_like(u)
            return np.column_stack((np.sin(k * u) / k, (1.0 - np.cos(k * u)) / k)), k * u
        if tag == "spiral":
            k0, k1 = _num(kind, "curvStart"), _num(kind, "curvEnd")
            theta = k0 * u + 0.5 * (k1 - k0) / length * u * u
            return _integrate(u, theta), theta
        if tag == "poly3":
            a, b, c, d = (_num(kind, k) for k in "abcd")
            return _by_arc_length(u, lambda p: p, lambda p: a + p * (b + p * (c + p * d)))
        if tag == "paramPoly3":
            cu = [_num(kind, f"{k}U") for k in "abcd"]
            cv = [_num(kind, f"{k}V") for k in "abcd"]
            scale = 1.0 if kind.get("pRange", "arcLength") == "arcLength" else 1.0 / length
            p = u * scale

            def cubic(co, q):
                return co[0] + q * (co[1] + q * (co[2] + q * co[3]))

            def slope(co, q):
                return co[1] + q * (2.0 * co[2] + q * 3.0 * co[3])

            return np.column_stack((cubic(cu, p), cubic(cv, p))), np.arctan2(slope(cv, p), slope(cu, p))
        raise ValueError(f"a plan view geometry <{tag}>")

    def pose(self, s: float) -> tuple[float, float, float]:
        """(x, y, heading) of the reference line at road s."""
        x = float(np.interp(s, self.s, self.xy[:, 0]))
        y = float(np.interp(s, self.s, self.xy[:, 1]))
        return x, y, float(np.interp(s, self.s, self.heading))

    def s_of(self, x: float, y: float) -> float:
        """Road s of the reference line's point nearest to (x, y)."""
        along = self._line.project(x, y)[0]
        return float(np.interp(along, self._at, self.s))


def _integrate(u: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Points along a curve of heading ``theta`` at arc lengths ``u`` (trapezoid on a 10x finer grid)."""
    fine = np.linspace(u[0], u[-1], 10 * (len(u) - 1) + 1)
    th = np.interp(fine, u, theta)  # theta is smooth (quadratic): linear between samples is enough
    dx, dy = np.cos(th), np.sin(th)
    du = np.diff(fine)
    x = np.concatenate(([0.0], np.cumsum(0.5 * (dx[1:] + dx[:-1]) * du)))
    y = np.concatenate(([0.0], np.cumsum(0.5 * (dy[1:] + dy[:-1]) * du)))
    return np.column_stack((x[::10], y[::10]))


def _by_arc_length(u: np.ndarray, fu, fv) -> tuple[np.ndarray, np.ndarray]:
    """Points and headings of the local curve (fu(p), fv(p)) at arc lengths ``u``."""
    p = np.linspace(0.0, u[-1], 20 * len(u))
    pts = np.column_stack((fu(p), fv(p)))
    arc = np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(pts, axis=0).T))))
    q = np.interp(u, arc, p)
    out = np.column_stack((fu(q), fv(q)))
    h = np.gradient(fv(p), p), np.gradient(fu(p), p)
    return out, np.interp(u, arc, np.arctan2(*h))


@dataclass(frozen=True)
class Section:
    s: float
    widths: dict[int, list[Poly]]  #: OpenDRIVE lane id -> its width records (road s)


@dataclass
class Road:
    ref: ReferenceLine
    offset: list[Poly]
    sections: list[Section]

    def section(self, s: float) -> Section:
        return next((x for x in reversed(self.sections) if x.s <= s + 1e-9), self.sections[0])

    def centre(self, lane: int, s: float, section: Section | None = None) -> tuple[float, float]:
        """The OpenDRIVE centre of ``lane`` at road s (x, y), with the widths of ``section``
        (default: the lane section at s; a lane's own, for its points up to the section's end)."""
        widths = (section or self.section(s)).widths
        inner = sum(_value(w, s) for j, w in widths.items() if (j < 0) == (lane < 0) and abs(j) < abs(lane))
        t = _value(self.offset, s) + math.copysign(inner + 0.5 * _value(widths.get(lane, []), s), lane)
        x, y, h = self.ref.pose(s)
        return x - t * math.sin(h), y + t * math.cos(h)


def changing_roads(xodr: bytes) -> dict[str, Road]:
    """The roads of an OpenDRIVE file with a lane offset or a lane width that changes along
    them (their plan view, offset and widths), by id; a road whose plan view ego cannot read
    is left out (netconvert's lanes stay)."""
    out: dict[str, Road] = {}
    for road in ET.fromstring(xodr).iterfind("road"):
        offset = sorted(
            (Poly(_num(o, "s"), *(_num(o, k) for k in "abcd")) for o in road.iterfind("lanes/laneOffset")),
            key=lambda p: p.start,
        )
        sections = []
        for sec in road.iterfind("lanes/laneSection"):
            s0 = _num(sec, "s")
            widths: dict[int, list[Poly]] = {}
            for lane in sec.iterfind("*/lane"):
                try:
                    lid = int(lane.get("id", "0"))
                except ValueError:
                    continue
                recs = [Poly(s0 + _num(w, "sOffset"), *(_num(w, k) for k in "abcd")) for w in lane.iterfind("width")]
                if lid and recs:
                    widths[lid] = sorted(recs, key=lambda p: p.start)
            sections.append(Section(s0, widths))
        if not sections or not (_changes(offset) or any(_changes(w) for x in sections for w in x.widths.values())):
            continue
        plan = road.find("planView")
        if plan is None:
            continue
        try:
            ref = ReferenceLine(plan)
        except ValueError:
            continue
        out[road.get("id", "")] = Road(ref, offset, sorted(sections, key=lambda x: x.s))
    return out


def exact_lane_shapes(xodr: bytes, net: Path) -> bool:
    """Put the lanes of ``net`` (converted from ``xodr``) of the roads whose lane offset or
    widths change on their OpenDRIVE centres (module docstring); True when ``net`` was rewritten."""
    roads = changing_roads(xodr)
    if not roads:
        return False
    tree = ET.parse(net)
    root = tree.getroot()
    moved: list[Moved] = []
    inner: list[ET.Element] = []
    for edge in root.iter("edge"):
        if edge.get("function") == "internal":
            inner.extend(edge.iter("lane"))
            continue
        for lane in edge.iter("lane"):
            orig = next((p.get("value", "") for p in lane.iter("param") if p.get("key") == "origId"), "")
            rid, _, lid = orig.rpartition("_")
            road = roads.get(rid)
            if road is None or not lid.lstrip("-").isdigit() or int(lid) == 0:
                continue
            old = _points(lane.get("shape", ""))
            if len(old) < 2:
                continue
            a, b = road.ref.s_of(*old[0]), road.ref.s_of(*old[-1])
            n = max(1, math.ceil(abs(b - a) / STEP))
            own = road.section(0.5 * (a + b))  # its ends may project a hair into the next section
            new = [road.centre(int(lid), a + (b - a) * k / n, own) for k in range(n + 1)]
            moved.append(Moved(rid, int(lid), old[0], old[-1], new[0], new[-1]))
            lane.set("shape", _text(new))
    if not moved:
        return False
    for lane in inner:
        pts = _points(lane.get("shape", ""))
        if len(pts) < 2:
            continue
        before = next((m for m in moved if math.dist(m.old_last, pts[0]) <= SAME), None)
        after = next((m for m in moved if math.dist(m.old_first, pts[-1]) <= SAME), None)
        if before is None and after is None:
            continue
        if before is not None and after is not None and before.road == after.road:
            # between two lane sections of one road: the lanes' own centres, the one before up
            # to where its section ends, the one after from there
            road = roads[before.road]
            a, b = road.ref.s_of(*before.new_last), road.ref.s_of(*after.new_first)
            first = road.section(a)
            n = max(1, math.ceil(abs(b - a) / STEP))
            at = [a + (b - a) * k / n for k in range(n + 1)]
            lane.set(
                "shape", _text([road.centre(before.lane if road.section(s) is first else after.lane, s) for s in at])
            )
            continue
        d0 = _move(before, last=True)
        d1 = _move(after, last=False)
        along = np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(np.asarray(pts), axis=0).T))))
        f = along / (along[-1] or 1.0)
        lane.set(
            "shape",
            _text([(x + d0[0] + (d1[0] - d0[0]) * w, y + d0[1] + (d1[1] - d0[1]) * w) for (x, y), w in zip(pts, f)]),
        )
    tree.write(net, encoding="UTF-8", xml_declaration=True)
    return True


@dataclass(frozen=True)
class Moved:
    """A rewritten lane: its road and OpenDRIVE lane id, its old and new first and last points."""

    road: str
    lane: int
    old_first: tuple[float, float]
    old_last: tuple[float, float]
    new_first: tuple[float, float]
    new_last: tuple[float, float]


def _move(lane: Moved | None, last: bool) -> tuple[float, float]:
    """How far ``lane``'s last (else first) point moved; none without a lane."""
    if lane is None:
        return 0.0, 0.0
    old, new = (lane.old_last, lane.new_last) if last else (lane.old_first, lane.new_first)
    return new[0] - old[0], new[1] - old[1]


def _points(shape: str) -> list[tuple[float, float]]:
    return [(float(p.split(",")[0]), float(p.split(",")[1])) for p in shape.split()]


def _text(points) -> str:
    return " ".join(f"{x:.6f},{y:.6f}" for x, y in points)
