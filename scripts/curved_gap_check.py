"""The surround sensor's front gap and TTC against the truth, on the straight and curved motorways.

Runs emergency-brake on each road x tracking controller x seed and, after every SUMO step where
the sensor has a front car within ``--within`` m, sets its front gap and TTC beside the truth:

* **gap**: the arc length along the ego's lane (the lane SUMO has it in) between the outlines
  SUMO has for the two cars (front bumper position, angle, length and width): each corner
  projected through the arc's centre onto the lane's design arc (``sumo_nets/motorway_arcs.py``:
  lead-in straight, arc of radius R, exit straight), the front car's rearmost corner less the
  ego's foremost. On the straight road, the difference of x.
* **TTC**: that gap over the rate it closes at, from the cars' velocities (the ego's plant state,
  the front car's SUMO speed along its heading) turned into arc length per second along the
  ego's lane; where it closes faster than 0.1 m/s and the TTC is below 20 s.

It prints per run the largest overstatement (sensor above truth) and understatement of the
gap (m) and the largest TTC overstatement (s), and SUMO's own ``vehicle.getLeader`` gap (plus
the ego's minGap, which SUMO leaves out) against the truth where both name the same car (SUMO
measures in lane positions scaled by one factor over the whole lane, so on the inner lane of
an arc its gap is longer than the arc)::

    python scripts/curved_gap_check.py --seeds 0 1 2 3 4 5

``--summary`` prints one line per road x controller over the seeds instead.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "sumo_nets"))
sys.path.insert(0, str(HERE.parent))

from motorway_arcs import ARCS, LEAD_IN  # noqa: E402

from ego.runner import RunSpec, build  # noqa: E402
from ego.sim.types import EGO  # noqa: E402

TRACKING = ("pid", "fuzzy", "fuzzy-pid", "bp-pid", "rbf-smc")
ROADS = ("straight", "left-250", "right-250", "left-1000", "right-1000")
LANE_WIDTH = 3.5  #: the motorway's; lane 1 (the middle) is the design line


class Arc:
    """Arc length along a lane of a road of ``sumo_nets/motorway_arcs.py`` (or the straight
    motorway along +x), of points projected through the arc's centre."""

    def __init__(self, road: str, lane: int) -> None:
        self.straight = road == "straight"
        if self.straight:
            return
        _, radius, turn, side = ARCS[road]
        self.side, self.turn = side, math.radians(turn)
        self.cx, self.cy = LEAD_IN, side * radius
        self.radius = radius - side * (lane - 1) * LANE_WIDTH  #: the lane's
        self.end = (self.cx + radius * math.sin(self.turn), self.cy - side * radius * math.cos(self.turn))
        self.exit = (math.cos(side * self.turn), math.sin(side * self.turn))

    def _angle(self, x: float, y: float) -> float:
        return math.atan2(x - self.cx, -self.side * (y - self.cy))  # 0 at the arc's start

    def station(self, x: float, y: float) -> float:
        if self.straight:
            return x
        phi = self._angle(x, y)
        if phi < 0.0 and x <= self.cx:
            return x - LEAD_IN
        if 0.0 <= phi <= self.turn:
            return self.radius * phi
        (ex, ey), (hx, hy) = self.end, self.exit
        return self.radius * self.turn + (x - ex) * hx + (y - ey) * hy

    def rate(self, x: float, y: float, vx: float, vy: float) -> float:
        """d station / dt of a point at (x, y) moving at (vx, vy) (m/s)."""
        if self.straight:
            return vx
        phi = self._angle(x, y)
        if phi < 0.0 and x <= self.cx:
            return vx
        if 0.0 <= phi <= self.turn:
            rx, ry = x - self.cx, y - self.cy
            return self.radius * self.side * (rx * vy - ry * vx) / (rx * rx + ry * ry)
        return vx * self.exit[0] + vy * self.exit[1]


def outline(bridge, vid: str) -> list[tuple[float, float]]:
    """The four corners of SUMO's box of ``vid`` (world m; the ego's as pushed into SUMO:
    ``SumoBridge.pose``, on a curved road SUMO's own angle of it is its lane's)."""
    veh = bridge.libsumo.vehicle
    x, y, angle = bridge.pose(vid)
    a = math.radians(90.0 - angle)
    length, half = veh.getLength(vid), 0.5 * veh.getWidth(vid)
    ux, uy = math.cos(a), math.sin(a)
    return [(x - k * length * ux - s * half * uy, y - k * length * uy + s * half * ux) for k in (0, 1) for s in (-1, 1)]


def check(road: str, controller: str, seed: int, within: float = 100.0) -> dict:
    """One run's figures: pairs compared, the gap's largest over- and understatement (m), the
    TTC's largest overstatement (s), SUMO's getLeader gap's largest over/understatement (m)."""
    import libsumo

    sc = build(RunSpec("emergency-brake", controller, seed, {"road": road}))
    out = {"pairs": 0, "over": -math.inf, "under": -math.inf, "ttc_over": -math.inf, "ttc_pairs": 0}
    out |= {"sumo_over": -math.inf, "sumo_under": -math.inf}
    arcs: dict[int, Arc] = {}
    try:
        obs = sc.reset()
        veh = libsumo.vehicle
        min_gap = veh.getMinGap(EGO)
        per_sumo = round(sc.config.sumo_step / sc.config.dt)
        steps = 0
        while not sc.done:
            obs = sc.step(sc.controller.step(obs))
            steps += 1
            if steps % per_sumo:
                continue
            view = sc.view
            front = view.sensor.front
            if not front.id or not front.gap < within:
                continue
            lane = veh.getLaneIndex(EGO)
            arc = arcs.get(lane) or arcs.setdefault(lane, Arc(road, lane))
            ego_front = max(arc.station(*p) for p in outline(sc.bridge, EGO))
            true = min(arc.station(*p) for p in outline(sc.bridge, front.id)) - ego_front
            diff = front.gap - true
            out["pairs"] += 1
            out["over"], out["under"] = max(out["over"], diff), max(out["under"], -diff)
            leader = veh.getLeader(EGO, within)
            if leader and leader[0] == front.id:
                sumo = leader[1] + min_gap - true
                out["sumo_over"], out["sumo_under"] = max(out["sumo_over"], sumo), max(out["sumo_under"], -sumo)
            # the TTC: closing rate of the two centres along the ego's lane
            X, u, Y, v, psi, _ = view._plant.state
            ego_rate = arc.rate(X, Y, u * math.cos(psi) - v * math.sin(psi), u * math.sin(psi) + v * math.cos(psi))
            x, y = veh.getPosition(front.id)
            a = math.radians(90.0 - veh.getAngle(front.id))
            half = 0.5 * veh.getLength(front.id)
            speed = veh.getSpeed(front.id)
            closing = ego_rate - arc.rate(
                x - half * math.cos(a), y - half * math.sin(a), speed * math.cos(a), speed * math.sin(a)
            )
            if closing > 0.1 and 0.0 < true / closing < 20.0:
                out["ttc_pairs"] += 1
                out["ttc_over"] = max(out["ttc_over"], view.ttc_front - true / closing)
    finally:
        sc.close()
    return out


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--roads", nargs="+", default=list(ROADS), choices=ROADS)
    ap.add_argument("--controllers", nargs="+", default=list(TRACKING), choices=TRACKING)
    ap.add_argument("--seeds", nargs="+", type=int, default=[0])
    ap.add_argument("--within", type=float, default=100.0, help="compare gaps below this (m)")
    ap.add_argument("--summary", action="store_true", help="one row per road x controller over the seeds")
    args = ap.parse_args(argv)
    head = ("gap over (m)", "gap under (m)", "TTC over (s)", "SUMO's gap over (m)")
    if args.summary:
        print("| road | controller | seeds | pairs | " + " | ".join(head) + " |")
        print("|---|---|---|---|---|---|---|---|")
    else:
        print(f"{'road':11} {'controller':10} {'seed':>4} {'pairs':>6} " + " ".join(f"{h:>20}" for h in head))
    for road in args.roads:
        for controller in args.controllers:
            rows = []
            for seed in args.seeds:
                r = check(road, controller, seed, args.within)
                rows.append(r)
                if not args.summary:
                    print(
                        f"{road:11} {controller:10} {seed:4d} {r['pairs']:6d} {r['over']:20.4f} {r['under']:20.4f} "
                        f"{r['ttc_over']:20.4f} {r['sumo_over']:20.3f}",
                        flush=True,
                    )
            if args.summary:
                worst = [max(r[k] for r in rows) for k in ("over", "under", "ttc_over", "sumo_over")]
                print(
                    f"| {road} | {controller} | {len(rows)} | {sum(r['pairs'] for r in rows)} | "
                    + " | ".join(f"{w:.3f}" for w in worst)
                    + " |",
                    flush=True,
                )


if __name__ == "__main__":
    main()
