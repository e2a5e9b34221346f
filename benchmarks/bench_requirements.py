"""What checking the requirements costs a run, at the trace's full rate and on the 0.1 s grid.

    python benchmarks/bench_requirements.py [--scenarios emergency-brake,cut-in,fast-follower]
                                            [--controller pid] [--seeds 3] [--rounds 2]

Each run is a real ``ego run`` (in this process, no recording) with the scenario's default
requirements plus the issue's cut-in formula ``always ((ttc_front <= 3 s) implies
eventually[0:1.5] (accel <= -1 m/s^2))``; the requirement check (``ego.requirements.check_run``)
is timed inside the run (CPU, ``time.process_time``). The runs alternate between full rate
(``requirement_period`` 0, the default) and the 0.1 s grid, run by run and in turn, so the
machine's load falls on both alike. Printed per mode: the runs' CPU, the checks' CPU and
their ratio (the target: under 5 % at full rate).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import ego.requirements  # noqa: E402

EXTRA = ("ttc_brakes", "always ((ttc_front <= 3 s) implies eventually[0:1.5] (accel <= -1 m/s^2))")


def main(argv=None) -> dict:
    from ego.requirements import defaults
    from ego.runner import RunSpec, run

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenarios", default="emergency-brake,cut-in,fast-follower")
    ap.add_argument("--controller", default="pid")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--rounds", type=int, default=2)
    args = ap.parse_args(argv)
    spent = [0.0]
    check = ego.requirements.check_run

    def timed(*a, **k):
        t0 = time.process_time()
        try:
            return check(*a, **k)
        finally:
            spent[0] += time.process_time() - t0

    ego.requirements.check_run = timed
    totals = {0.0: [0.0, 0.0, 0], 0.1: [0.0, 0.0, 0]}
    scenarios = [s.strip() for s in args.scenarios.split(",") if s.strip()]
    for s in scenarios:  # warm-up: imports, compiled tables
        run(RunSpec(s, args.controller, 0, requirement_period=0.1))
    turn = 0
    cut_in: dict[float, float] = {}
    for _ in range(args.rounds):
        for s in scenarios:
            reqs = {**defaults(s), EXTRA[0]: EXTRA[1]} if s == "cut-in" else None
            for seed in range(args.seeds):
                periods = (0.0, 0.1) if turn % 2 == 0 else (0.1, 0.0)
                turn += 1
                for period in periods:
                    spent[0] = 0.0
                    t0 = time.process_time()
                    result = run(RunSpec(s, args.controller, seed, requirements=reqs, requirement_period=period))
                    total = time.process_time() - t0
                    row = totals[period]
                    row[0] += total
                    row[1] += spent[0]
                    row[2] += 1
                    if s == "cut-in" and seed == 0:
                        rob = result.metrics["requirements"][EXTRA[0]]
                        cut_in[period] = rob
                        print(f"cut-in seed 0, period {period:g} s: {EXTRA[0]} robustness {rob}")
    out = {}
    for period, (total, checks, n) in totals.items():
        ratio = checks / total
        out[period] = {
            "runs": n,
            "run_ms": 1e3 * total / n,
            "check_ms": 1e3 * checks / n,
            "ratio": ratio,
            "robustness": cut_in.get(period),
        }
        label = "full rate" if period == 0 else f"{period:g} s grid"
        print(
            f"{label:<11} {n} runs: {1e3 * total / n:7.1f} ms CPU a run, requirements {1e3 * checks / n:6.2f} ms "
            f"({100 * ratio:.2f} % of the run)"
        )
    return out


if __name__ == "__main__":
    main()
