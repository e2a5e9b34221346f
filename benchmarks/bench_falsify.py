"""Falsification: runs to the first violation per optimiser (issue 21, point 3).

    python benchmarks/bench_falsify.py [--repetitions 20] [--budget 300] [--optimizers cma,bo,random,lhs]
                                       [--jobs 2] [--surrogate] [--docs] [--plot PNG]

    python benchmarks/bench_falsify.py --rate [--repetitions 10 --budget 150]   # the fixed-budget table
    python benchmarks/bench_falsify.py --region    # how small each of its requirements' region is

For each optimiser, ``--reps`` repetitions (optimiser seeds 0..reps-1) of ``ego falsify
--until first`` over ``benchmarks/falsify/bench.toml`` on real ego runs, within ``--budget``
runs, once per requirement of the spec (batches of two points, as ``--jobs 2`` proposes
them). The repetitions keep their runs under ``runs/bench-falsify/`` and resume from them.
Printed per requirement and optimiser: how many repetitions found a violation, the median
and quartiles of runs to the first violation (a repetition that found none counts as more
than the budget), the ratio of the median to LHS's (target: CMA-ES or BO <= 0.2) and the
falsification rate at the budget (the share of repetitions that found a violation within
it, with its 95 % Wilson interval: how ARCH-COMP's falsification category compares tools).
``--reps`` is ``--repetitions``. ``--rate``: the fixed-budget table's spec
(``benchmarks/falsify/rate.toml``: a third requirement with a violating region under 0.2 %
of the box), 10 repetitions of 150 runs, and psy-taliro's uniform random and dual annealing
as two more optimisers where psy-taliro is installed (``import staliro``; ego's ``test``
extra, not a dependency of ego). ``--region``: runs on a coarse grid over the box and a fine
grid over the corner that holds the violations, and each requirement's violating share.
``--surrogate`` runs the analytic stand-in instead (no SUMO; clearly not ego). ``--docs``
(with the defaults) writes docs/results/falsify.md and its figure from the same runs, as
``python -m ego.docs results --page falsify`` does.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from ego.docs import falsify as docs_falsify  # noqa: E402
from ego.falsify import bench  # noqa: E402


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repetitions", "--reps", dest="reps", type=int, default=None)
    ap.add_argument("--budget", type=int, default=None)
    ap.add_argument("--optimizers", default=None, help="default cma,bo,random,lhs (--rate: and psy-taliro's two)")
    ap.add_argument("--rate", action="store_true", help="the fixed-budget table's spec, budget and optimisers")
    ap.add_argument("--region", action="store_true", help="the rate spec's requirements' violating shares (grids)")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--surrogate", action="store_true")
    ap.add_argument("--docs", action="store_true")
    ap.add_argument("--plot", default=None, help="convergence plot path (real runs)")
    ap.add_argument("--spec", default=str(bench.BENCH_SPEC), help=argparse.SUPPRESS)
    ap.add_argument("--cache", default="", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.region:
        return region(args.jobs, args.docs)
    if args.rate:
        args.spec = str(bench.RATE_SPEC)
        args.reps = args.reps or docs_falsify.RATE_REPS
        args.budget = args.budget or docs_falsify.RATE_BUDGET
    default = bench.available() if args.rate else bench.OPTIMIZERS
    optimizers = [o.strip() for o in (args.optimizers or ",".join(default)).split(",")]
    if "lhs" not in optimizers:
        optimizers.append("lhs")
    reps = args.reps or (docs_falsify.SURROGATE_REPS if args.surrogate else docs_falsify.REAL_REPS)
    budget = args.budget or (docs_falsify.SURROGATE_BUDGET if args.surrogate else docs_falsify.REAL_BUDGET)
    from ego.docs import regenerate, run_jobs

    if args.surrogate:
        jobs = {o: [bench.SurrogateJob(o, s, budget) for s in range(reps)] for o in optimizers}
        names: tuple = (None,)
    else:
        jobs = {
            o: [bench.BenchJob(o, s, budget, spec=args.spec, cache=args.cache) for s in range(reps)] for o in optimizers
        }
        names = bench.requirements(Path(args.spec))
    started = time.perf_counter()
    # seeds outer, optimisers inner: an interrupted run leaves every optimiser as far along
    results = run_jobs([js[s] for s in range(reps) for js in jobs.values()], workers=args.jobs)
    figures: dict = {}
    print(f"{'requirement':<12} {'optimiser':<8} found  median  [q1, q3]   median/LHS  rate (95 %)")
    for name in names:

        def runs(js, name=name):
            return [(results[j] if name is None else results[j][name])["runs"] for j in js]

        _, lhs, _, _ = bench.quartiles(runs(jobs["lhs"]), budget)
        for opt, js in jobs.items():
            q1, med, q3, found = bench.quartiles(runs(js), budget)
            figures[(name or "surrogate", opt)] = {"runs": runs(js), "median": med, "ratio_to_lhs": med / lhs}
            fmt = bench.fmt_runs
            lo, hi = bench.wilson(found, len(js))
            figures[(name or "surrogate", opt)]["rate"] = found / len(js)
            print(
                f"{name or 'surrogate':<12} {opt:<8} {found:>2}/{len(js):<3} {fmt(med, budget):>6}  "
                f"[{fmt(q1, budget)}, {fmt(q3, budget)}]  {med / lhs:.2f}        "
                f"{100 * found / len(js):.0f} % ({100 * lo:.0f}-{100 * hi:.0f} %)"
            )
    print(f"{time.perf_counter() - started:.0f} s")
    if args.plot and not args.surrogate:
        curves = {(n, o): [results[j][n]["curve"] for j in js] for n in names for o, js in jobs.items()}
        bench.convergence_figure(curves, budget, Path(args.plot))
        print(f"wrote {args.plot}")
    if args.docs:
        regenerate(
            [t for t in __import__("ego.docs", fromlist=["tables"]).tables() if t.page == "falsify"], False, args.jobs
        )
        print("wrote docs/results/falsify.md and docs/img/falsify_convergence.png")
    return figures


def region(jobs: int, docs: bool) -> dict:
    """The rate spec's requirements' violating shares of the box (the grids of
    :func:`ego.docs.falsify.region_table`); ``docs``: its table into docs/results/falsify.md."""
    from ego.docs import block, page_path, render, run_jobs
    from ego.outputs import write_text

    table = docs_falsify.region_table()
    results = run_jobs([j for r in table.rows for j in r.jobs], workers=jobs)
    text = render(table, results)
    print(text)
    if docs:
        path = page_path(table.page)
        page = path.read_text()
        write_text(path, page.replace(block(page, table.name), text))
        print(f"wrote the {table.name} table of {path}")
    return results


if __name__ == "__main__":
    main()
