"""The cost of ``no_preventable_collision`` (the R157 files' default requirement) on a run of
``scenarios/alks/alks_4_4_cut_in.xosc``: wall time with the default requirements against the
same requirements without it, for a run without a collision (``pid``: no second run) and one
with (``none``, AEB off: the careful driver's run follows). The figures in docs/requirements.md.

    python scripts/preventable_cost.py [--repeats 7]

Interleaved (with, without, with, ...) so that load on a shared machine falls on both alike;
the median of each.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

FILE = "scenarios/alks/alks_4_4_cut_in.xosc"


def main(argv=None) -> None:
    from ego.requirements import defaults
    from ego.runner import RunSpec, run
    from ego.scenarios import scenario_class

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args(argv)
    with_it = defaults(FILE, scenario_class(FILE))
    without = {k: v for k, v in with_it.items() if k != "no_preventable_collision"}
    run(RunSpec(FILE, "pid", 0, {}))  # warm: the file's class, SUMO's libraries
    for label, controller, overrides in (
        ("no collision (pid)", "pid", {}),
        ("collision (none, aeb off)", "none", {"aeb": False}),
    ):
        times: dict[str, list[float]] = {"with": [], "without": []}
        verdict = None
        for _ in range(args.repeats):
            for key, reqs in (("with", None), ("without", without)):
                t = time.perf_counter()
                r = run(RunSpec(FILE, controller, 0, overrides, requirements=reqs))
                times[key].append(time.perf_counter() - t)
                if key == "with":
                    verdict = r.metrics.get("collision_preventable")
        w, wo = statistics.median(times["with"]), statistics.median(times["without"])
        print(
            f"{label:<26} with no_preventable_collision {w:.3f} s, without {wo:.3f} s "
            f"(x{w / wo:.2f}; collision_preventable {verdict})"
        )


if __name__ == "__main__":
    main()
