"""The emergency lane change and the cut-in on the curved motorways beside the straight one,
per tracking controller (default parameters, seed 0, real SUMO).

    python scripts/curved_manoeuvres.py
    python scripts/curved_manoeuvres.py --scenarios cut-in --roads straight left-250 --controllers pid

Prints per scenario a markdown table, a row per road and controller, with the cells of
docs/results/curved-roads.md (``ego.docs.curved.manoeuvre_cells``): status, collision, the
lane change's duration (s) and overshoot (m) or the cut-in's response and largest
deceleration (m/s^2), min front gap (m, along the lane), min front TTC (s), max lane
departure (m).
"""

from __future__ import annotations

import argparse
import sys

from ego.sumo.net import MOTORWAY_ROADS

CONTROLLERS = ("pid", "fuzzy", "fuzzy-pid", "bp-pid", "rbf-smc")
SCENARIOS = ("emergency-brake", "cut-in")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], epilog=__doc__.split("\n\n", 1)[1])
    ap.add_argument("--scenarios", nargs="+", default=list(SCENARIOS), choices=SCENARIOS)
    ap.add_argument("--roads", nargs="+", default=list(MOTORWAY_ROADS), choices=list(MOTORWAY_ROADS))
    ap.add_argument("--controllers", nargs="+", default=list(CONTROLLERS))
    args = ap.parse_args(argv)
    from ego.docs.curved import ALONG_THE_LANE, MANOEUVRE_HEADER, manoeuvre_cells
    from ego.params import ConfigError
    from ego.runner import RunSpec, run

    for scenario in args.scenarios:
        header = ("road", "controller", *MANOEUVRE_HEADER[scenario], *ALONG_THE_LANE)
        print(f"\n{scenario}\n\n| " + " | ".join(header) + " |\n|" + "---|" * len(header))
        for road in args.roads:
            for name in args.controllers:
                try:
                    r = run(RunSpec(scenario, name, overrides={"road": road}))
                except ConfigError as exc:
                    print(f"curved_manoeuvres.py: error: {exc}", file=sys.stderr)
                    return 2
                cells = manoeuvre_cells(scenario, {"status": r.status, **r.metrics})
                print(f"| {road} | {name} | " + " | ".join(cells) + " |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
