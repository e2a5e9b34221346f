"""How far from road s an OpenDRIVE lane position puts a car, lane by lane.

    python scripts/road_s_error.py ROAD.xodr|NET.net.xml ... [--step 1]

For every lane and every road s (each ``--step`` m, 1 m from the lane's ends and from the
joints of the road's geometries aside) the point a car is put at for (road, lane, s) is
compared with where the lane's centre is at road s. Two rules: ``sumo-pos`` takes s as SUMO's
lane position (ego's rule before issue 39f), ``road-s`` is ego's rule
(:meth:`ego.openscenario.roads.RoadMap.lane_s`). Where the lane's centre is: on an ``.xodr``
of lines and arcs with constant lane widths, OpenDRIVE's closed form (the reference line's
point at s moved t along its normal); on a SUMO network (no OpenDRIVE geometry), the point
of the lane whose projection onto the edge's shape, resampled every 0.25 m along a spline
(:func:`refine_shape`), is at s (that projection errs by up to t * 0.25 m / 2R along the
road: 1.8 mm for t = 3.5 m on R = 250 m). Printed per lane: the largest distance (m) of each
rule's point from the lane's centre at s, and the lane's SUMO length over its shape's length
(SUMO scales its positions and speeds on that lane by it).
"""

from __future__ import annotations

import argparse
import math
import xml.etree.ElementTree as ET
from pathlib import Path

from ego.lane_frame import LanePolyline
from ego.openscenario.roads import RoadMap, network_file, refine_shape


def _planview(road_file: Path) -> dict[str, tuple[list, dict[int, float], float]] | None:
    """road id -> (geometries (s, x, y, hdg, length, curvature), lane id -> centre offset t,
    length) of an OpenDRIVE file of lines and arcs with one lane section of constant widths;
    None for anything else."""
    if str(road_file).endswith(".net.xml"):
        return None
    out = {}
    for r in ET.parse(road_file).getroot().iter("road"):
        geos = []
        for g in r.iter("geometry"):
            kind = list(g)[0]
            if kind.tag not in ("line", "arc"):
                return None
            k = float(kind.get("curvature", "0")) if kind.tag == "arc" else 0.0
            geos.append(tuple(float(g.get(a, "0")) for a in ("s", "x", "y", "hdg", "length")) + (k,))
        sections = list(r.iter("laneSection"))
        if len(sections) != 1 or list(r.iter("laneOffset")):
            return None
        t: dict[int, float] = {}
        for side, sign in (("left", 1), ("right", -1)):
            acc = 0.0
            lanes = sorted(
                (ln for el in sections[0].iter(side) for ln in el.iter("lane")), key=lambda ln: abs(int(ln.get("id")))
            )
            for ln in lanes:
                widths = list(ln.iter("width"))
                if len(widths) != 1 or any(float(widths[0].get(c, "0")) for c in "bcd"):
                    return None
                w = float(widths[0].get("a"))
                t[int(ln.get("id"))] = sign * (acc + 0.5 * w)
                acc += w
        out[r.get("id")] = (geos, t, float(r.get("length")))
    return out


def _closed_form(geos: list, s: float, t: float) -> tuple[float, float]:
    s0, x, y, hdg, _, k = next(g for g in reversed(geos) if g[0] <= s + 1e-9)
    u = s - s0
    if k == 0.0:
        px, py, h = x + u * math.cos(hdg), y + u * math.sin(hdg), hdg
    else:
        h = hdg + k * u
        px, py = x + (math.sin(h) - math.sin(hdg)) / k, y - (math.cos(h) - math.cos(hdg)) / k
    return px - t * math.sin(h), py + t * math.cos(h)


def errors(road_file: Path, step: float = 1.0) -> list[tuple[str, int, str, float, float, float]]:
    """(road, OpenDRIVE lane, SUMO lane, max error of sumo-pos, of road-s, SUMO factor) per lane."""
    converted = not str(road_file).endswith(".net.xml")
    roads = RoadMap(network_file(road_file), converted)
    plan = _planview(road_file)
    names = sorted({roads._section(e)[0] for e in roads.edges if not e.startswith(":")})
    out = []
    for name in names:
        secs = roads.sections(name)
        if not secs:
            continue
        end = secs[-1][0] + roads.reference(secs[-1][1].id).length
        joints = [x[0] for x in secs] + [end]
        if plan is not None:
            joints += [g[0] for g in plan[name][0]]
        smooth = {e.id: LanePolyline(refine_shape(e.shape)) for _, e, _ in secs}
        for lane_id in sorted({roads.lane_id_of(ln) for _, e, _ in secs for ln in e.lanes}):
            worst = {"old": 0.0, "new": 0.0}
            factor, sumo_id, s = 1.0, "", 0.0
            while s <= end:
                near = min(abs(s - j) for j in joints) < 1.0
                try:
                    lane, g = roads.lane_s(name, lane_id, s)
                except ValueError:
                    lane = None
                if lane is None or near:
                    s += step
                    continue
                start, _, right = next(x for x in reversed(secs) if x[0] <= s + 1e-9 and x[2] == (lane_id < 0))
                geom = roads.shape_length(lane)
                factor, sumo_id = lane.length / geom, lane.id
                poly = LanePolyline(lane.shape, lane.width, lane.id)
                if plan is not None:
                    want = _closed_form(plan[name][0], s, plan[name][1][lane_id])
                else:
                    ref = smooth[lane.edge]
                    u = s - start if right else ref.length - (s - start)
                    want = poly.offset_point(0.0, 0.0)  # found below: the lane's point projecting to u
                    lo, hi = 0.0, geom
                    for _ in range(60):
                        mid = 0.5 * (lo + hi)
                        if ref.project(*poly.offset_point(mid, 0.0))[0] < u:
                            lo = mid
                        else:
                            hi = mid
                    want = poly.offset_point(0.5 * (lo + hi), 0.0)
                old = s - start if right else lane.length - (s - start)  # SUMO's position = s
                for rule, along in (("old", old * geom / lane.length), ("new", g)):
                    if 1.0 < along < geom - 1.0:
                        x, y = poly.offset_point(along, 0.0)
                        worst[rule] = max(worst[rule], math.hypot(x - want[0], y - want[1]))
                s += step
            out.append((name, lane_id, sumo_id, worst["old"], worst["new"], factor))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("roads", nargs="+", type=Path)
    ap.add_argument("--step", type=float, default=1.0, help="m between the road s checked (default 1)")
    a = ap.parse_args()
    print(
        f"{'road file':28} {'road':>9} {'lane':>4} {'SUMO lane':>12} {'sumo-pos m':>10} {'road-s m':>9} {'SUMO/shape':>10}"
    )
    for f in a.roads:
        for name, lane, sumo, old, new, factor in errors(f, a.step):
            print(f"{f.name:28} {name:>9} {lane:>4} {sumo:>12} {old:10.4f} {new:9.5f} {factor:10.6f}")


if __name__ == "__main__":
    main()
