"""Metrics of every registered scenario x controller (seeds 0, 1) as JSON, to diff two commits.

    python scripts/metrics_snapshot.py OUT.json [--only SCENARIO ...]

Each run goes through :func:`ego.runner.run` in a fresh process (libsumo runs one simulation
per process). ``wall_time`` is dropped; every other metric is kept as the run reports it, so
two snapshots compare with plain equality. The highway-env backend is run too for
emergency-brake, fast-follower and cut-in with ``pid``.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import os


def _one(job):
    scenario, controller, seed, backend = job
    from ego.runner import RunSpec, run

    try:
        r = run(RunSpec(scenario, controller, seed=seed, backend=backend))
    except Exception as e:  # noqa: BLE001 - a failure is a result to compare too
        return job, {"error": f"{type(e).__name__}: {e}"}
    metrics = {k: v for k, v in r.metrics.items() if k != "wall_time"}
    return job, {"status": r.status, "metrics": metrics, "events": [(e.t, e.kind, e.text) for e in r.events]}


def jobs(only=()):
    from ego.control import CONTROLLERS
    from ego.scenarios import SCENARIOS

    out = []
    for name, cls in SCENARIOS.items():
        if only and name not in only:
            continue
        for controller in CONTROLLERS[cls.task]:
            for seed in (0, 1):
                out.append((name, controller, seed, "sumo"))
    for name in ("emergency-brake", "fast-follower", "cut-in"):
        if only and name not in only:
            continue
        for seed in (0, 1):
            out.append((name, "pid", seed, "highway-env"))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], epilog=__doc__.split("\n\n", 1)[1])
    ap.add_argument(
        "out", metavar="OUT.json", help="where the snapshot is written (compare two with scripts/metrics_diff.py)"
    )
    ap.add_argument("--only", nargs="+", default=(), metavar="SCENARIO", help="only these scenarios (default: all)")
    ap.add_argument("--jobs", type=int, default=2, help="worker processes (default: 2)")
    args = ap.parse_args()
    from ego.scenarios import SCENARIOS

    unknown = [n for n in args.only if n not in SCENARIOS]
    if unknown:
        ap.error(f"unknown scenario {unknown[0]!r} (expected one of: {', '.join(SCENARIOS)})")
    if args.jobs < 1:
        ap.error(f"bad value for --jobs: {args.jobs} (expected >= 1)")
    out_path = args.out
    todo = jobs(tuple(args.only))
    result = {}
    with mp.get_context("spawn").Pool(args.jobs, maxtasksperchild=1) as pool:
        for job, res in pool.imap_unordered(_one, todo):
            result["|".join(map(str, job))] = res
            print(len(result), "/", len(todo), *job, res.get("status", res.get("error")), flush=True)
    tmp = f"{out_path}.part"
    with open(tmp, "w") as f:
        json.dump(dict(sorted(result.items())), f, indent=1, sort_keys=True)
    os.replace(tmp, out_path)


if __name__ == "__main__":
    main()
