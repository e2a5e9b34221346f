"""Speed of report 003's tuning: one vectorised generation against the per-member loop,
and the full report-setting differential evolution.

    python benchmarks/bench_tune.py [--members 180] [--loop-members 180] [--no-full] [--workers 1]

One generation = every member driven over the whole road on each of the tuner's drives
(8 m/s from rest, 25 m/s from 1 m off). The per-member loop runs the plain single-run
simulation (the scenario's controller, one member at a time); the batch simulates the whole
generation in one time loop. Both give the same errors (tests/control/test_cascade.py).
Targets (issue 5): the full tuning <= 120 s on this 2-core machine.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from ego.train.lane_centering import (  # noqa: E402
    BOUNDS,
    TuneSpec,
    drives,
    simulate_drives,
    simulate_single,
    tune,
)


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--members", type=int, default=180, help="members of the generation")
    ap.add_argument(
        "--loop-members",
        type=int,
        default=None,
        help="time the per-member loop on this many members and scale up (default: all)",
    )
    ap.add_argument("--no-full", action="store_true", help="skip the full tuning")
    ap.add_argument("--workers", type=int, default=1)
    args = ap.parse_args(argv)
    spec = TuneSpec(workers=args.workers)
    setups, kappas = drives(spec.drives)
    lo, hi = np.array(BOUNDS).T
    gens = lo + (hi - lo) * np.random.default_rng(0).random((args.members, 12))

    batch = float("inf")
    for _ in range(2):  # the first call also warms up numpy's allocations: best of two
        t0 = time.perf_counter()
        simulate_drives(gens, setups, kappas)
        batch = min(batch, time.perf_counter() - t0)
    n_loop = min(args.loop_members or args.members, args.members)
    t0 = time.perf_counter()
    for g in gens[:n_loop]:
        for st, k in zip(setups, kappas):
            simulate_single(g, st, k)
    loop = (time.perf_counter() - t0) * args.members / n_loop
    steps = sum(len(k) for k in kappas)
    figures = {
        "members": args.members,
        "batch_generation_s": batch,
        "loop_generation_s": loop,
        "speedup": loop / batch,
        "drive_steps": steps,
    }
    print(f"one generation of {args.members} members, {len(setups)} drives ({steps} steps each member):")
    print(f"  per-member loop: {loop:7.2f} s" + (f" (timed on {n_loop}, scaled)" if n_loop < args.members else ""))
    print(f"  vectorised batch: {batch:6.2f} s  -> {loop / batch:.0f}x faster")
    if not args.no_full:
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            preset = tune(spec, Path(tmp) / "preset.json", log=lambda *_: None)
            full = time.perf_counter() - t0
        figures.update(full_tuning_s=full, generations=preset["generations"], cost=preset["cost"])
        print(
            f"full tuning (population {spec.popsize} x 12, {preset['generations']} generations, "
            f"workers {spec.workers}): {full:.1f} s (target <= 120 s); best cost {preset['cost']:.6f}"
        )
    return figures


if __name__ == "__main__":
    main()
