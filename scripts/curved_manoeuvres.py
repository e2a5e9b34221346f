"""The emergency lane change and the cut-in on the curved motorways beside the straight one,
per tracking controller (default parameters, seed 0, real SUMO).

    python scripts/curved_manoeuvres.py
    python scripts/curved_manoeuvres.py --scenarios cut-in --roads straight left-250 --controllers pid

Prints per scenario, road and controller: status, collision, lane change duration (s), max
overshoot (m), min front gap (m, along the lane) and min front TTC (s), max lane departure (m).
"""

from __future__ import annotations

import argparse
import sys

from ego.sumo.net import MOTORWAY_ROADS

CONTROLLERS = ("pid", "fuzzy", "fuzzy-pid", "bp-pid", "rbf-smc")
SCENARIOS = ("emergency-brake", "cut-in")


def _fmt(value, digits: int = 2) -> str:
    return "-" if value is None else (f"{value:.{digits}f}" if isinstance(value, float) else str(value))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], epilog=__doc__.split("\n\n", 1)[1])
    ap.add_argument("--scenarios", nargs="+", default=list(SCENARIOS), choices=SCENARIOS)
    ap.add_argument("--roads", nargs="+", default=list(MOTORWAY_ROADS), choices=list(MOTORWAY_ROADS))
    ap.add_argument("--controllers", nargs="+", default=list(CONTROLLERS))
    args = ap.parse_args(argv)
    from ego.params import ConfigError
    from ego.runner import RunSpec, run

    print(
        "| scenario | road | controller | status | collision | lane change (s) | overshoot (m) | min gap (m) | min TTC (s) | departure (m) |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    for scenario in args.scenarios:
        for road in args.roads:
            for name in args.controllers:
                try:
                    r = run(RunSpec(scenario, name, overrides={"road": road}))
                except ConfigError as exc:
                    print(f"curved_manoeuvres.py: error: {exc}", file=sys.stderr)
                    return 2
                m = r.metrics
                cells = (
                    r.status,
                    m.get("collision"),
                    _fmt(m.get("lane_change_duration")),
                    _fmt(m.get("max_overshoot"), 3),
                    _fmt(m.get("min_gap_front")),
                    _fmt(m.get("min_ttc_front")),
                    _fmt(m.get("max_lane_departure"), 3),
                )
                print(f"| {scenario} | {road} | {name} | " + " | ".join(map(str, cells)) + " |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
