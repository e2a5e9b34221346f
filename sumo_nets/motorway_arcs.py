"""Write the plain XML sources of the curved motorways (``--set road=...`` of emergency-brake,
fast-follower and cut-in) and build them with the wheel's netconvert.

    python sumo_nets/motorway_arcs.py            # sources + networks (sumo_nets/build.py)

Each is the straight motorway's road (``sumo_nets/highway``: one edge ``motorway``, three
3.5 m lanes, 130 km/h, spreadType="center" so the middle lane's centre line IS the edge's
shape) bent into an arc: LEAD_IN m straight along +x from (0, 0), an arc of the middle lane's
radius R to the left or right, then straight to a total length of LENGTH m along the middle
lane. The R 250 m arc turns 180 degrees (785 m), the R 1000 m arc 90 degrees (1571 m): the
ego (its front at ego_start = 300 m by default) is in the arc for the whole of a default run,
and the exit straight never comes near the lead-in. The arc is written as shape points
every ~SEGMENT m, so the chords stay within R (1 - cos(SEGMENT / 2R)) (8 mm at R 250 m) of
the circle; the lane frame measures to the arc each chord stands for. Each road is ONE edge
``motorway`` (PIECE and CLOTHOID_PIECE None). It was cut into edges of ~200 m (the road of
changing curvature: ~100 m; ``motorway.1``, ...) to limit SUMO's moveToXY, which walks every
candidate lane's whole shape each step; the built-in scenarios place the ego on the lanes
instead (ego/sumo/lane_place.py), and SUMO's own step costs more the more edge joints its
drivers look across (docs/performance.md), so the cut is gone. :func:`split_points` still cuts
a road every ~``piece`` m in the middle of a chord when asked (the lanes joined across the
edges are the one-edge road's).

Longer chords were tried and not taken: 10 m chords (5 cm from the R 250 m circle) with ~200
m edges cut the curved run's extra instructions from 91 M to 59 M, but SUMO's traffic then
drives up to 5 cm inside the design arc, and on the R 250 m road that flips bp-pid's emergency
lane change past the lead from a 2.0 m miss into an AEB brake mid-change (overshoot 0.018 ->
0.268 m, beyond the issue's 0.1 m of the straight road's); 6.3 m chords (2 cm) flip it too.

``road=clothoid`` is the road of changing curvature (UN R157's reference roads: straight, arcs
of 250 m and 1000 m, a road whose curvature changes): after the LEAD_IN straight, the middle
lane's curvature changes linearly along clothoids (Euler spirals) between constant arcs -
left R 500 m, through an inflection to right R 250 m, back through one to left R 1000 m and
out to straight (:data:`CLOTHOID`). Its shape points are exact points of that curve, every
~SEGMENT m, from the Fresnel integrals (:func:`clothoid_points`).
"""

from __future__ import annotations

import math
from pathlib import Path

HERE = Path(__file__).resolve().parent
LEAD_IN = 350.0  #: m of straight before the arc
LENGTH = 3000.0  #: m along the middle lane, as the straight motorway
SEGMENT = 4.0  #: m, about, between the arc's shape points
#: m, about, of each edge an arc is split into; None: one edge (the module doc)
PIECE: float | None = None
#: m, about, of each edge of the road of changing curvature; None: one edge
CLOTHOID_PIECE: float | None = None
LANE_WIDTH = 3.5
SPEED = 36.11  #: m/s, 130 km/h
#: road name (``--set road=``) -> (network, radius of the middle lane's centre m, turn deg,
#: +1 left / -1 right)
ARCS = {
    "left-250": ("highway_left_250", 250.0, 180.0, 1),
    "right-250": ("highway_right_250", 250.0, 180.0, -1),
    "left-1000": ("highway_left_1000", 1000.0, 90.0, 1),
    "right-1000": ("highway_right_1000", 1000.0, 90.0, -1),
}


#: the road of changing curvature: (length m, curvature at its start 1/m, at its end 1/m, + left)
#: of each piece after the LEAD_IN straight; a clothoid where the two differ (curvature linear in
#: arc length), an arc where they agree; straight after the last piece to LENGTH.
CLOTHOID = (
    (100.0, 0.0, 1 / 500),  # clothoid into the left R 500 m arc (A = 224 m)
    (150.0, 1 / 500, 1 / 500),  # left arc R 500 m
    (150.0, 1 / 500, -1 / 250),  # clothoid through the inflection (A = 158 m)
    (150.0, -1 / 250, -1 / 250),  # right arc R 250 m
    (150.0, -1 / 250, 1 / 1000),  # clothoid through the second inflection (A = 173 m)
    (300.0, 1 / 1000, 1 / 1000),  # left arc R 1000 m
    (100.0, 1 / 1000, 0.0),  # clothoid out to the straight (A = 316 m)
)
#: the road of changing curvature's network
CLOTHOID_NET = "highway_clothoid"


def clothoid_points(
    x: float, y: float, heading: float, length: float, k0: float, k1: float
) -> list[tuple[float, float, float]]:
    """Points (x, y, heading) every ~SEGMENT m along a piece of ``length`` m starting at (x, y)
    with ``heading`` (rad) whose curvature runs linearly from ``k0`` to ``k1`` (1/m): exact,
    from the Fresnel integrals (scipy.special.fresnel) for a clothoid, from the circle for an
    arc, the line for a straight; the first point is the start."""
    import numpy as np
    from scipy.special import fresnel

    n = max(1, math.ceil(length / SEGMENT))
    s = np.linspace(0.0, length, n + 1)
    c = (k1 - k0) / length  # curvature's rate of change, 1/m^2
    theta = heading + k0 * s + 0.5 * c * s * s
    if abs(c) > 1e-15:
        # theta(s) = theta_m + (c / 2) (s + k0 / c)^2 with theta_m = heading - k0^2 / (2c); with
        # u = sqrt(|c| / pi) (s + k0 / c): cos/sin(theta) = cos/sin(theta_m + sign(c) pi u^2 / 2),
        # and int_0^u cos(pi t^2 / 2) dt = C(u), int_0^u sin(pi t^2 / 2) dt = S(u)
        sign = 1.0 if c > 0 else -1.0
        scale = math.sqrt(math.pi / abs(c))
        theta_m = heading - k0 * k0 / (2.0 * c)
        u = (s + k0 / c) / scale
        fs, fc = fresnel(u)
        fs0, fc0 = fresnel(u[0])
        dc, ds_ = fc - fc0, sign * (fs - fs0)
        px = x + scale * (math.cos(theta_m) * dc - math.sin(theta_m) * ds_)
        py = y + scale * (math.sin(theta_m) * dc + math.cos(theta_m) * ds_)
    elif abs(k0) > 1e-15:  # an arc of radius 1 / k0 (+ left)
        px = x + (np.sin(theta) - math.sin(heading)) / k0
        py = y - (np.cos(theta) - math.cos(heading)) / k0
    else:
        px = x + s * math.cos(heading)
        py = y + s * math.sin(heading)
    return list(zip(px.tolist(), py.tolist(), theta.tolist()))


def clothoid_line(pieces=CLOTHOID) -> list[tuple[float, float]]:
    """The road of changing curvature's middle-lane centre line: lead-in, ``pieces``, exit."""
    pts = [(0.0, 0.0)]
    x, y, heading = LEAD_IN, 0.0, 0.0
    for length, k0, k1 in pieces:
        piece = clothoid_points(x, y, heading, length, k0, k1)
        pts += [(px, py) for px, py, _ in piece]
        x, y, heading = piece[-1]
    exit_ = LENGTH - LEAD_IN - sum(p[0] for p in pieces)
    pts.append((x + exit_ * math.cos(heading), y + exit_ * math.sin(heading)))
    # drop the repeated joins (a piece starts where the last one ended)
    return [p for i, p in enumerate(pts) if i == 0 or math.dist(p, pts[i - 1]) > 1e-9]


def centre_line(radius: float, turn_deg: float, side: int) -> list[tuple[float, float]]:
    """The middle lane's centre line: lead-in, arc, exit, in driving order."""
    turn = math.radians(turn_deg)
    arc = radius * turn
    n = max(2, math.ceil(arc / SEGMENT))
    cx, cy = LEAD_IN, side * radius  # the arc's centre
    pts = [(0.0, 0.0)]
    for k in range(n + 1):
        a = turn * k / n
        pts.append((cx + radius * math.sin(a), cy - side * radius * math.cos(a)))
    exit_ = LENGTH - LEAD_IN - arc
    x, y = pts[-1]
    heading = side * turn
    pts.append((x + exit_ * math.cos(heading), y + exit_ * math.sin(heading)))
    return pts


def edge_id(k: int) -> str:
    """The ``k``-th edge of a curved motorway in driving order: ``motorway`` (the lead-in, where
    every scenario vehicle departs), then ``motorway.1``, ``motorway.2``, ..."""
    return "motorway" if k == 0 else f"motorway.{k}"


def split_points(pts: list[tuple[float, float]], piece: float | None = PIECE) -> list[list[tuple[float, float]]]:
    """``pts`` (lead-in, curved part, exit) split into the shapes of consecutive edges: the
    curved part cut every ~``piece`` m in the middle of a chord, so the two halves of a cut chord
    are collinear and every lane of the one-edge road passes each joint unchanged (each edge's
    lanes are offset from its own shape; the joint is in both); ``piece`` None: one edge."""
    if piece is None:
        return [list(pts)]
    last = len(pts) - 1  # pts[last - 1] -> pts[last] is the exit straight, pts[0] -> pts[1] the lead-in
    step = max(1, round(piece / SEGMENT))
    shapes, shape = [], [pts[0]]
    for i in range(1, last + 1):
        shape.append(pts[i])
        if i % step == 0 and i < last - 1:  # cut the chord pts[i] -> pts[i + 1] in its middle
            (xa, ya), (xb, yb) = pts[i], pts[i + 1]
            mid = (0.5 * (xa + xb), 0.5 * (ya + yb))
            shapes.append([*shape, mid])
            shape = [mid]
    shapes.append(shape)
    return shapes


def _joint_shape(shape: list[tuple[float, float]]) -> str:
    """The junction shape of the joint where the edge of ``shape`` starts: the line across the
    road through it, square to the cut chord. netconvert ends the lanes of the edges on either
    side on that line, where the one-edge road's lanes pass it, instead of cutting a
    junction's length out of them."""
    (x, y), (xb, yb) = shape[0], shape[1]
    h = math.atan2(yb - y, xb - x)
    half = 1.5 * LANE_WIDTH
    nx, ny = -half * math.sin(h), half * math.cos(h)
    return f' shape="{x + nx:.4f},{y + ny:.4f} {x - nx:.4f},{y - ny:.4f}"'


HEADER = '<?xml version="1.0" encoding="UTF-8"?>\n'
CONFIG = """<?xml version="1.0" encoding="UTF-8"?>
<!-- Sources: python sumo_nets/motorway_arcs.py; build with: python sumo_nets/build.py {name} -->
<netconvertConfiguration xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xsi:noNamespaceSchemaLocation="http://sumo.dlr.de/xsd/netconvertConfiguration.xsd">
    <input>
        <node-files value="{name}.nod.xml"/>
        <edge-files value="{name}.edg.xml"/>
    </input>
    <output>
        <output-file value="{name}.net.xml"/>
        <precision value="4"/>
    </output>
    <processing>
        <offset.disable-normalization value="true"/>
        <geometry.min-dist value="0"/>
        <no-internal-links value="true"/>
    </processing>
    <junctions>
        <no-turnarounds value="true"/>
    </junctions>
    <report>
        <verbose value="false"/>
        <no-warnings value="true"/>
    </report>
</netconvertConfiguration>
"""


def _describe(pieces) -> str:
    def radius(k: float) -> str:
        return "straight" if k == 0 else f"{'left' if k > 0 else 'right'} R {1 / abs(k):g} m"

    return ", ".join(
        f"{length:g} m arc {radius(k0)}" if k0 == k1 else f"{length:g} m clothoid {radius(k0)} -> {radius(k1)}"
        for length, k0, k1 in pieces
    )


def write_sources(road: str, out: Path = HERE, piece: float | None = None) -> Path:
    """The sources of ``road`` (a key of ARCS, or ``clothoid``) in ``out/<network>/``, cut into
    edges of ~``piece`` m (None: the module's PIECE / CLOTHOID_PIECE); returns the folder."""
    if road == "clothoid":
        name, pts = CLOTHOID_NET, clothoid_line()
        shape_note = f"then {_describe(CLOTHOID)} (curvature linear along each clothoid; Fresnel integrals)"
    else:
        name, radius, turn, side = ARCS[road]
        pts = centre_line(radius, turn, side)
        shape_note = f"a {'left' if side > 0 else 'right'} {turn:g}-degree arc of the middle lane's radius {radius:g} m"
    folder = out / name
    folder.mkdir(parents=True, exist_ok=True)
    note = (
        f"<!-- Generated by sumo_nets/motorway_arcs.py (road={road}): {LEAD_IN:g} m straight along +x, "
        f"{shape_note}, straight to {LENGTH:g} m; three 3.5 m lanes, lane 0 the right lane. -->\n"
    )
    if piece is None:
        piece = CLOTHOID_PIECE if road == "clothoid" else PIECE
    shapes = split_points(pts, piece)
    joints = [sh[0] for sh in shapes[1:]]
    nodes = [("start", *pts[0], "")]
    nodes += [(f"j{k}", x, y, _joint_shape(sh)) for k, ((x, y), sh) in enumerate(zip(joints, shapes[1:]), 1)]
    nodes.append(("end", *pts[-1], ""))
    (folder / f"{name}.nod.xml").write_text(
        HEADER + note + '<nodes xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" '
        'xsi:noNamespaceSchemaLocation="http://sumo.dlr.de/xsd/nodes_file.xsd">\n'
        + "".join(f'    <node id="{nid}" x="{x:.4f}" y="{y:.4f}" type="priority"{js}/>\n' for nid, x, y, js in nodes)
        + "</nodes>\n",
        encoding="utf-8",
    )
    edges = []
    for k, sh in enumerate(shapes):
        shape = " ".join(f"{x:.4f},{y:.4f}" for x, y in sh)
        edges.append(
            f'    <edge id="{edge_id(k)}" from="{nodes[k][0]}" to="{nodes[k + 1][0]}" priority="10" numLanes="3" '
            f'speed="{SPEED}" width="{LANE_WIDTH}" spreadType="center"\n          shape="{shape}"/>\n'
        )
    (folder / f"{name}.edg.xml").write_text(
        HEADER + note + '<edges xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" '
        'xsi:noNamespaceSchemaLocation="http://sumo.dlr.de/xsd/edges_file.xsd">\n' + "".join(edges) + "</edges>\n",
        encoding="utf-8",
    )
    (folder / f"{name}.netccfg").write_text(CONFIG.format(name=name), encoding="utf-8")
    return folder


def main() -> None:
    import os
    import sys

    sys.path.insert(0, str(HERE.parent))
    os.environ.setdefault("EGO_SUMO_NETS", str(HERE))
    from ego.sumo.net import build_network

    for road, (name, *_) in ARCS.items():
        write_sources(road)
        print(f"{road}: built {build_network(name)}")
    write_sources("clothoid")
    print(f"clothoid: built {build_network(CLOTHOID_NET)}")


if __name__ == "__main__":
    main()
