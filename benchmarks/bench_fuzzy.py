"""Speed of the fast Mamdani evaluator against scikit-fuzzy on report 000's rule base.

    python benchmarks/bench_fuzzy.py [--points 300]

Both evaluate the same random (e, ec) points; scikit-fuzzy with a fresh
ControlSystemSimulation input each call (``cache=False``, as a controller sees new
inputs every step). Target (issue 2): speed-up >= 1000x.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from ego.control import fuzzy  # noqa: E402


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=300)
    args = ap.parse_args(argv)
    from skfuzzy import control as ctrl

    system = fuzzy.rule_base()
    fast = fuzzy.evaluator()
    sim = ctrl.ControlSystemSimulation(system, cache=False)
    pts = [(float(e), float(c)) for e, c in np.random.default_rng(0).uniform(-10, 10, (args.points, 2))]

    t0 = time.perf_counter()
    ref = []
    for e, c in pts:
        sim.input["e"], sim.input["ec"] = e, c
        sim.compute()
        ref.append(sim.output["u"])
    t_sk = (time.perf_counter() - t0) / len(pts)

    def timed(fn) -> tuple[float, float]:
        reps = 200
        t0 = time.perf_counter()
        for _ in range(reps):
            for e, c in pts:
                fn(e, c)
        per_call = (time.perf_counter() - t0) / (reps * len(pts))
        err = max(abs(a - fn(e, c)) for a, (e, c) in zip(ref, pts))
        return per_call, err

    t_py, err_py = timed(fast.single2_py)
    t_c, err_c = timed(fast.single2)
    figures = {
        "skfuzzy_us": t_sk * 1e6,
        "python_us": t_py * 1e6,
        "native_us": t_c * 1e6,
        "speedup_python": t_sk / t_py,
        "speedup_native": t_sk / t_c,
        "max_abs_difference": max(err_py, err_c),
    }
    print(f"report 000 rule base (7x7, 121/601-sample universes), {len(pts)} random points")
    print(f"  scikit-fuzzy ControlSystemSimulation    {figures['skfuzzy_us']:10.1f} us per evaluation")
    print(
        f"  FastMamdani, Python (single2_py)        {figures['python_us']:10.2f} us   "
        f"speed-up {figures['speedup_python']:8.0f} x   (target >= 1000)"
    )
    print(
        f"  FastMamdani, C twin (single2)           {figures['native_us']:10.2f} us   "
        f"speed-up {figures['speedup_native']:8.0f} x"
    )
    print(f"  largest difference to scikit-fuzzy     {figures['max_abs_difference']:10.2e}   (output range 200)")
    return figures


if __name__ == "__main__":
    main()
