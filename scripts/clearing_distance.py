"""How far the ego travels from the trigger until a lane change has cleared the car ahead
sideways (the front object changes), in lane changes begun while the AEB brakes at the
friction limit: the measured basis of ``CLEAR_SIDEWAYS_DISTANCE`` (ego/scenarios/manoeuvre.py).

    python scripts/clearing_distance.py RESULTS.parquet [...] [--per-controller N] [--jobs N]

Each RESULTS.parquet is an emergency-brake ``ego falsify`` (or sweep) output; its runs are run
again with every lane change allowed to begin (the clearing check itself switched off): the N
of each controller closest to the requirement's boundary (smallest ``--column``), each with every
controller. Prints, per controller, the clearing distance's median and 5-95 % range.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp

PARAMS = ("ego_speed", "lead_decel", "lead_gap", "traffic_density", "block_left", "block_right")
CONTROLLERS = ("pid", "fuzzy", "fuzzy-pid", "bp-pid", "rbf-smc")


def _one(job):
    import numpy as np

    from ego.runner import RunSpec, run
    from ego.scenarios import manoeuvre

    manoeuvre.EvasiveManoeuvre._cannot_clear_first = lambda self: None  # every lane change begins
    controller, seed, params = job
    r = run(RunSpec("emergency-brake", controller, seed, params))
    m = r.metrics
    if m["target_side"] is None or m["trigger_time"] is None or m["aeb_time"] != m["trigger_time"]:
        return None  # no lane change begun under the AEB
    df = r.to_pandas()
    after = df[df.t >= m["trigger_time"]]
    gap = after.gap_front.to_numpy()
    with np.errstate(invalid="ignore"):
        changed = np.flatnonzero(~np.isfinite(gap[1:]) | (gap[1:] - gap[:-1] > 5.0))
    if not changed.size:
        return controller, None
    s = after.s.to_numpy()
    return controller, float(s[changed[0] + 1] - s[0])


def main(argv=None) -> None:
    import numpy as np
    import pyarrow.parquet as pq

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("results", nargs="+")
    ap.add_argument("--per-controller", type=int, default=40)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--column", default="requirements.no_avoidable_collision_q")
    a = ap.parse_args(argv)
    cases = []
    for path in a.results:
        t = pq.read_table(path).to_pandas()
        for controller in CONTROLLERS:
            rows = t[t.controller == controller].nsmallest(a.per_controller, a.column)
            cases += [
                (int(r.seed), {k: (bool(r[k]) if k.startswith("block") else float(r[k])) for k in PARAMS})
                for _, r in rows.iterrows()
            ]
    jobs = [(c, seed, params) for seed, params in cases for c in CONTROLLERS]
    found: dict[str, list] = {c: [] for c in CONTROLLERS}
    with mp.get_context("forkserver").Pool(a.jobs, maxtasksperchild=20) as pool:
        for out in pool.imap_unordered(_one, jobs):
            if out is not None:
                found[out[0]].append(out[1])
    print(f"{len(jobs)} runs; lane changes begun under the AEB, distance from the trigger to clearing the car ahead:")
    for c, d in found.items():
        cleared = np.array([x for x in d if x is not None])
        if cleared.size:
            lo, med, hi = np.percentile(cleared, [5, 50, 95])
            print(
                f"  {c:10} {len(d):4} begun, {cleared.size:4} cleared: median {med:.0f} m (5-95 %: {lo:.0f}-{hi:.0f} m)"
            )
        else:
            print(f"  {c:10} {len(d):4} begun, none cleared")


if __name__ == "__main__":
    main()
