"""Falsification: runs to the first violation per optimiser (issue 21, point 3).

    python benchmarks/bench_falsify.py [--requirement NAME] [--reps 10] [--budget 200]
                                       [--optimizers cma,bo,random,lhs] [--jobs 2] [--surrogate]
                                       [--docs]

For each requirement of ``benchmarks/falsify/bench.toml`` (or the one named), each optimiser
runs ``--reps`` repetitions of ``ego falsify --until first`` (optimiser seeds 0..reps-1,
batches of two) on real ego runs, within ``--budget`` runs. Printed per optimiser: how many
repetitions found a violation, the median and quartiles of runs to the first violation, and
the ratio of the median to LHS's median in the same session (target: CMA-ES or BO <= 0.2).
``--surrogate`` runs the analytic stand-in instead (no SUMO; clearly not ego). ``--docs``
(with the defaults) also writes docs/results/falsify.md's tables and
docs/img/falsify_convergence.png from the same runs.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from ego.docs import falsify as docs_falsify  # noqa: E402
from ego.falsify import bench  # noqa: E402


def _jobs(args):
    if args.surrogate:
        return {
            ("surrogate", o): [bench.SurrogateJob(o, s, args.budget) for s in range(args.reps)] for o in args.optimizers
        }
    return {
        (r, o): [bench.BenchJob(r, o, s, args.budget) for s in range(args.reps)]
        for r in args.requirements
        for o in args.optimizers
    }


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--requirement", action="append", dest="requirements", default=[])
    ap.add_argument("--reps", type=int, default=None)
    ap.add_argument("--budget", type=int, default=None)
    ap.add_argument("--optimizers", default=",".join(bench.OPTIMIZERS))
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--surrogate", action="store_true")
    ap.add_argument("--docs", action="store_true")
    ap.add_argument(
        "--plot",
        default=None,
        help="convergence plot path (default with --docs: docs/img/)",
    )
    args = ap.parse_args(argv)
    args.requirements = args.requirements or list(docs_falsify.REQUIREMENTS)
    args.optimizers = [o.strip() for o in args.optimizers.split(",")]
    if "lhs" not in args.optimizers:
        args.optimizers.append("lhs")
    if args.reps is None:
        args.reps = docs_falsify.SURROGATE_REPS if args.surrogate else docs_falsify.REAL_REPS
    if args.budget is None:
        args.budget = docs_falsify.SURROGATE_BUDGET if args.surrogate else docs_falsify.REAL_BUDGET
    from ego.docs import run_jobs

    groups = _jobs(args)
    jobs = [j for js in groups.values() for j in js]
    tables = docs_falsify.docs_tables() if args.docs else []
    jobs += [j for t in tables for r in t.rows for j in r.jobs]
    results = run_jobs(jobs, workers=args.jobs)
    figures: dict = {}
    print(f"{'requirement':<16} {'optimiser':<8} found  median  [q1, q3]   median/LHS")
    for (req, opt), js in groups.items():
        runs = [results[j]["runs"] for j in js]
        q1, med, q3, found = bench.quartiles(runs, args.budget)
        _, lhs, _, _ = bench.quartiles([results[j]["runs"] for j in groups[(req, "lhs")]], args.budget)
        figures[(req, opt)] = {"runs": runs, "median": med, "ratio_to_lhs": med / lhs}
        fmt = bench.fmt_runs
        print(
            f"{req:<16} {opt:<8} {found:>2}/{len(js):<3} {fmt(med, args.budget):>6}  "
            f"[{fmt(q1, args.budget)}, {fmt(q3, args.budget)}]  {med / lhs:.2f}"
        )
    plot = args.plot or (str(ROOT / "docs" / "img" / "falsify_convergence.png") if args.docs else None)
    if plot:
        write_plot(groups, results, Path(plot), args.budget)
        print(f"wrote {plot}")
    if args.docs:
        write_docs(tables, results)
    return figures


def write_plot(groups, results, path: Path, budget: int) -> None:
    """Median best robustness so far (over the repetitions) against runs, per optimiser."""
    from ego.plots import pyplot, save

    plt = pyplot()
    reqs = list(dict.fromkeys(r for r, _ in groups))
    fig, axes = plt.subplots(1, len(reqs), figsize=(6 * len(reqs), 4), squeeze=False)
    for ax, req in zip(axes[0], reqs):
        for (r, opt), js in groups.items():
            if r != req:
                continue
            curves = np.full((len(js), budget), np.nan)
            for i, j in enumerate(js):
                c = np.array(results[j]["curve"], dtype=float)
                curves[i, : len(c)] = c
                curves[i, len(c) :] = c[-1] if len(c) else np.nan
            ax.plot(np.arange(1, budget + 1), np.nanmedian(curves, axis=0), label=opt)
        ax.axhline(0.0, color="k", lw=0.8, ls="--")
        ax.set_yscale("symlog", linthresh=0.1)
        ax.set_xscale("log")
        ax.set_xlabel("runs")
        ax.set_ylabel(f"best robustness of {req} (median)")
        ax.legend(fontsize=8)
    fig.tight_layout()
    save(fig, path)


def write_docs(tables, results) -> None:
    """docs/results/falsify.md's tables from the runs made above (as ``python -m ego.docs
    results --page falsify`` writes them)."""
    from ego.docs import block, page_path, render
    from ego.outputs import write_text

    path = page_path("falsify")
    text = path.read_text()
    for t in tables:
        text = text.replace(block(text, t.name), render(t, results))
    write_text(path, text)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
