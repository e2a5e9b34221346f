"""The front gap of ego's surround sensor against SUMO's own leader gap, on the curved motorways.

Runs emergency-brake on each road x tracking controller x seed and, after every SUMO step, sets
the sensor's front gap beside SUMO's ``vehicle.getLeader`` distance (measured by SUMO along its
lanes, plus the ego's minGap, which SUMO leaves out) where both name the same car. Prints the
largest overstatement (the sensor's gap above SUMO's) and understatement per run, over gaps
below ``--within`` m::

    python scripts/curved_gap_check.py --roads straight left-250 --seeds 0 1

A gap the sensor overstates is a safety figure on the wrong side; one it understates by up to
one control period's travel is the sensor's look being taken a control step after SUMO's.
"""

from __future__ import annotations

import argparse
import math

from ego.runner import RunSpec, build
from ego.sim.types import EGO

TRACKING = ("pid", "fuzzy", "fuzzy-pid", "bp-pid", "rbf-smc")


def check(road: str, controller: str, seed: int, within: float) -> tuple[int, float, float]:
    """(pairs compared, largest overstatement, largest understatement) in m over one run."""
    import libsumo

    sc = build(RunSpec("emergency-brake", controller, seed, {"road": road}))
    over, under, pairs, steps = -math.inf, -math.inf, 0, 0
    try:
        obs = sc.reset()
        min_gap = libsumo.vehicle.getMinGap(EGO)
        while not sc.done:
            obs = sc.step(sc.controller.step(obs))
            steps += 1
            if steps % round(sc.config.sumo_step / sc.config.dt):
                continue
            front = sc.view.sensor.front
            leader = libsumo.vehicle.getLeader(EGO, within)
            if not leader or leader[0] != front.id or not front.gap < within:
                continue
            diff = front.gap - (leader[1] + min_gap)
            over, under, pairs = max(over, diff), max(under, -diff), pairs + 1
    finally:
        sc.close()
    return pairs, over, under


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--roads", nargs="+", default=["straight", "left-250", "right-250", "left-1000", "right-1000"])
    ap.add_argument("--controllers", nargs="+", default=list(TRACKING))
    ap.add_argument("--seeds", nargs="+", type=int, default=[0])
    ap.add_argument("--within", type=float, default=100.0, help="compare gaps below this (m)")
    args = ap.parse_args(argv)
    print(f"{'road':11} {'controller':10} {'seed':>4} {'pairs':>6} {'overstated':>11} {'understated':>12}")
    for road in args.roads:
        for controller in args.controllers:
            for seed in args.seeds:
                pairs, over, under = check(road, controller, seed, args.within)
                print(f"{road:11} {controller:10} {seed:4d} {pairs:6d} {over:10.3f}m {under:11.3f}m", flush=True)


if __name__ == "__main__":
    main()
