"""ego's own UN R157 ALKS scenarios (scenarios/alks/*.xosc, Annex 5 4.1-4.5) x the tracking
controllers: a markdown table of status, collision, min front gap, min front TTC, max |lateral
error| and max lane departure (the table in docs/openscenario.md).

    python scripts/alks_own.py                          # every concrete file x 5 controllers
    python scripts/alks_own.py --controllers pid --files alks_4_4_cut_in

Each run is ``ego run scenarios/alks/FILE.xosc -c CONTROLLER`` (seed 0, the file's defaults,
real SUMO); min front TTC is over the run (inf when never closing or above 100 s); the lateral error is the
trace's ``e_lat`` (offset from the lane centre); lane departure is how far a front tyre's outer
edge went over the lane's marking (R157 5.2.1), 0 when it never did.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
ALKS = ROOT / "scenarios" / "alks"
CONTROLLERS = ("pid", "fuzzy", "fuzzy-pid", "bp-pid", "rbf-smc")


def concrete_files() -> list[Path]:
    """The concrete scenario files (not the variations), in name order."""
    return sorted(p for p in ALKS.glob("alks_*.xosc") if not p.stem.endswith("_variation"))


def measure(path: Path, controller: str) -> dict:
    """One run's figures for the table."""
    from ego.runner import RunSpec, run

    result = run(RunSpec(str(path), controller, requirements=()))
    m = result.metrics
    e_lat = result.trace[:, result.columns.index("e_lat")]
    ttc = m.get("min_ttc_front")
    return {
        "status": result.status,
        "collision": bool(m.get("collision")),
        "gap": m.get("min_gap_front"),
        "ttc": math.inf if ttc is None or ttc > 100 else float(ttc),
        "e_lat": float(np.max(np.abs(e_lat))),
        "departure": float(m.get("max_lane_departure") or 0.0),
    }


def fmt(value: float | None, digits: int = 2) -> str:
    if value is None:
        return "-"
    return "inf" if math.isinf(value) else f"{value:.{digits}f}"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], epilog=__doc__.split("\n\n", 1)[1])
    ap.add_argument("--controllers", nargs="+", default=list(CONTROLLERS), help="default: %(default)s")
    ap.add_argument("--files", nargs="+", default=None, help="file stems (default: every concrete file)")
    args = ap.parse_args(argv)
    files = concrete_files()
    if args.files:
        known = {p.stem: p for p in files}
        for stem in args.files:
            if stem not in known:
                print(
                    f"alks_own.py: error: unknown file {stem!r} (expected one of {', '.join(known)})", file=sys.stderr
                )
                return 2
        files = [known[s] for s in args.files]
    print(
        "| file | controller | status | collision | min front gap (m) | min front TTC (s) | max \\|e_lat\\| (m) | max lane departure (m) |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for path in files:
        for controller in args.controllers:
            r = measure(path, controller)
            print(
                f"| {path.stem} | {controller} | {r['status']} | {'yes' if r['collision'] else 'no'} | {fmt(r['gap'])} "
                f"| {fmt(r['ttc'])} | {fmt(r['e_lat'], 3)} | {fmt(r['departure'], 3)} |",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
