"""Check ``collision_preventable`` of a sweep against the careful driver run independently.

``ego sweep ... --preventable`` reports, for every collision, whether UN R157's careful
driver avoids it on the same concrete scenario (``ego.runner.collision_preventable``, which
builds that run with ``reference_run``). This script asks the same question the other way:
for every row of the sweep it runs ``careful-driver`` itself through the public API
(``RunSpec`` with the row's scenario, seed and values, and the ego's own evasion and AEB off,
as Annex 4 Appendix 3's driver has neither), then checks that every collision the sweep
calls not preventable is one the careful driver also has, and every one it calls
preventable is one the careful driver avoids.

    ego sweep ALKS_Scenario_4.4_1_CutInNoCollision_VARIATION_ego.xosc -c none,pid \\
        --sample 100 --seed 7 --preventable --out runs/r157-cutin
    python scripts/preventable_check.py runs/r157-cutin

Exit status 0 when every verdict agrees, 1 otherwise.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def _plain(v):
    return int(v) if isinstance(v, float) and v.is_integer() else v


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("folder", help="an ego sweep --preventable folder")
    args = ap.parse_args(argv)
    from ego.report import load
    from ego.runner import REFERENCE_DRIVER, REFERENCE_OFF, RunSpec, run

    campaign = load(args.folder)
    careful: dict[tuple, bool] = {}  # (seed, values) -> the careful driver collides
    agree = disagree = unknown = 0
    rows = campaign.rows
    for i, row in enumerate(rows):
        values = {
            p: _plain(row[p])
            for p in campaign.params
            if row.get(p) is not None and not (isinstance(row[p], float) and math.isnan(row[p]))
        }
        key = (int(row["seed"]), tuple(sorted(values.items())))
        if key not in careful:
            spec = RunSpec(campaign.scenario, REFERENCE_DRIVER, key[0], {**values, **REFERENCE_OFF})
            careful[key] = bool(run(spec).metrics.get("collision"))
        if not row.get("collision"):
            continue
        verdict = row.get("collision_preventable")
        if verdict is None:
            unknown += 1
            print(f"  {row['controller']} {row['run_id']}: collision without a verdict")
        elif bool(verdict) == (not careful[key]):
            agree += 1
        else:
            disagree += 1
            print(
                f"  {row['controller']} {row['run_id']}: preventable={verdict}, careful driver collides={careful[key]}"
            )
        print(f"{i + 1}/{len(rows)} rows", file=sys.stderr, end="\r")
    collisions = agree + disagree + unknown
    preventable = sum(1 for r in rows if r.get("collision") and r.get("collision_preventable") is True)
    print(
        f"{len(rows)} rows ({len(careful)} concrete scenarios); the careful driver collides in "
        f"{sum(careful.values())} of them; {collisions} collisions of the systems under test: "
        f"{preventable} preventable, {collisions - preventable - unknown} not; "
        f"{agree} agree with the careful driver's own run, {disagree} disagree, {unknown} without a verdict"
    )
    return 0 if disagree == 0 and unknown == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
