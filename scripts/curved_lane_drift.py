"""How far each tracking controller drifts off its lane centre in a curve, with the curvature
feed-forward off (before) and on (after).

    python scripts/curved_lane_drift.py                      # the R 200 m arc at 20 m/s
    python scripts/curved_lane_drift.py --set EgoSpeed=25 --controllers pid fuzzy

Runs ``scenarios/openscenario/curve200.xosc`` (three lanes, 300 m straight, a left quarter
arc whose middle lane's centre has radius 200 m, the ego alone in the middle lane) with
real SUMO, once per controller with ``feedforward=false`` and once with ``feedforward=true``
(the default), and prints max |lateral error| (m, the trace's ``e_lat``: offset from the
lane centre) over the run and the largest lane departure (m).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "scenarios" / "openscenario" / "curve200.xosc"
CONTROLLERS = ("pid", "fuzzy", "fuzzy-pid", "bp-pid", "rbf-smc")


def drift(scenario: str, controller: str, feedforward: bool, overrides: dict) -> tuple[float, float, str]:
    """(max |e_lat| m, max_lane_departure m, status) of one run."""
    from ego.runner import RunSpec, run

    spec = RunSpec(scenario, controller, overrides={**overrides, "feedforward": feedforward}, requirements=())
    result = run(spec)
    e_lat = result.trace[:, result.columns.index("e_lat")]
    return float(np.max(np.abs(e_lat))), float(result.metrics.get("max_lane_departure") or 0.0), result.status


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], epilog=__doc__.split("\n\n", 1)[1])
    ap.add_argument("--scenario", default=str(SCENARIO), help="the scenario (default: %(default)s)")
    ap.add_argument("--controllers", nargs="+", default=list(CONTROLLERS), help="default: %(default)s")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a scenario parameter")
    args = ap.parse_args(argv)
    overrides = {}
    for item in args.set:
        key, sep, value = item.partition("=")
        if not sep or not key:
            print(f"curved_lane_drift.py: error: bad --set {item!r} (expected KEY=VALUE)", file=sys.stderr)
            return 2
        overrides[key] = value
    from ego.params import ConfigError

    print(f"{Path(args.scenario).name}: max |lateral error| (m), feed-forward off -> on")
    print(f"{'controller':<10} {'off':>7} {'on':>7}  lane departure off / on (m)")
    for name in args.controllers:
        try:
            off = drift(args.scenario, name, False, overrides)
            on = drift(args.scenario, name, True, overrides)
        except ConfigError as exc:
            print(f"curved_lane_drift.py: error: {exc}", file=sys.stderr)
            return 2
        print(f"{name:<10} {off[0]:7.3f} {on[0]:7.3f}  {off[1]:.3f} / {on[1]:.3f}  ({off[2]} / {on[2]})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
