"""The tables of ``docs/results/falsify.md``: the jobs of :mod:`ego.falsify.bench` run
by ``python -m ego.docs`` (a checkout's, not the wheel's), and its convergence figure."""

from __future__ import annotations

from ego.falsify.bench import (
    COARSE_CELLS,
    OPTIMIZERS,
    RATE_SPEC,
    REGION_BOX,
    REGION_CELLS,
    ROOT,
    SURROGATE_RADIUS,
    BenchJob,
    SurrogateJob,
    available,
    convergence_figure,
    dense_jobs,
    fmt_runs,
    grid_jobs,
    quartiles,
    region_share,
    requirements,
    wilson,
)

# -- docs/results/falsify.md ----------------------------------------------------------------------
#: repetitions (optimiser seeds 0..n-1) per optimiser, and the budget of each: real runs, and the surrogate
REAL_REPS = 20
REAL_BUDGET = 300
SURROGATE_REPS = 20
SURROGATE_BUDGET = 400
#: the fixed-budget table (ARCH-COMP's falsification rate): repetitions and their budget
RATE_REPS = 10
RATE_BUDGET = 150
FIGURE = ROOT / "docs" / "img" / "falsify_convergence.png"


def _runs_cells(name: str | None, reps: int, budget: int):
    """Cells of a runs-to-first row whose jobs are its own ``reps`` then LHS's ``reps``
    (``name``: the requirement whose figures a real repetition's result holds)."""

    def runs(m: dict):
        return (m if name is None else m[name])["runs"]

    def cells(ms: list[dict]) -> list[str]:
        own, lhs = [runs(m) for m in ms[:reps]], [runs(m) for m in ms[reps:]]
        q1, med, q3, found = quartiles(own, budget)
        _, lhs_med, _, _ = quartiles(lhs, budget)
        ratio = med / lhs_med
        bound = "<=" if lhs_med > budget and med <= budget else ""
        return [
            f"{found}/{reps}",
            fmt_runs(med, budget),
            f"{fmt_runs(q1, budget)} - {fmt_runs(q3, budget)}",
            f"{bound}{ratio:.2f}" if not (med > budget) else "-",
        ]

    return cells


def _rate_cells(name: str, reps: int, budget: int):
    """Cells of a fixed-budget row: falsified within the budget (its share and 95 % Wilson
    interval), the median and quartiles of runs to the first violation."""

    def cells(ms: list[dict]) -> list[str]:
        runs = [m[name]["runs"] for m in ms]
        q1, med, q3, found = quartiles(runs, budget)
        lo, hi = wilson(found, reps)
        return [
            f"{found}/{reps}",
            f"{100 * found / reps:.0f} % ({100 * lo:.0f}-{100 * hi:.0f} %)",
            fmt_runs(med, budget),
            f"{fmt_runs(q1, budget)} - {fmt_runs(q3, budget)}",
        ]

    return cells


def _share_cells(name: str):
    def cells(ms: list[dict]) -> list[str]:
        values = [(float(m[name]), m["point"]) for m in ms if m.get(name) is not None]
        bad = [p for v, p in values if v < 0]
        lo, hi = wilson(len(bad), len(values))
        where = (
            ", ".join(f"{k} {min(p[k] for p in bad):.3g}-{max(p[k] for p in bad):.3g}" for k in bad[0]) if bad else "-"
        )
        return [
            f"{len(bad)}/{len(values)}",
            f"{100.0 * len(bad) / len(values):.2f} % ({100 * lo:.2f}-{100 * hi:.2f} %)",
            f"{min(v for v, _ in values):.3g}",
            where,
        ]

    return cells


def _figure(jobs: dict):
    """The convergence figure of the real repetitions (``jobs``: optimiser -> its jobs)."""

    def write(results: dict) -> None:
        curves = {
            (name, opt): [results[j][name]["curve"] for j in js] for name in requirements() for opt, js in jobs.items()
        }
        convergence_figure(curves, REAL_BUDGET, FIGURE)

    return write


def docs_tables() -> list:
    """The tables of docs/results/falsify.md (ego.docs builds the page from them)."""
    return [_landscape_table(), _bench_table(), _rate_table(), region_table(), _surrogate_table()]


#: the header of the runs-to-the-first-violation tables (the real runs' and the surrogate's)
RUNS_HEADER = (
    "requirement, optimiser",
    "found",
    "median runs to the first violation",
    "quartiles",
    "median / LHS median",
)


def _landscape_table():
    """Each requirement's violating share of the dense Sobol sweep."""
    from ego.docs.common import Row, Table
    from ego.falsify.bench import DENSE_SPEC
    from ego.sweep.spec import load

    dense = dense_jobs()
    formulas = load(DENSE_SPEC).requirements
    return Table(
        "falsify-landscape",
        "falsify",
        ("ego sweep benchmarks/falsify/dense.toml --out runs/falsify-dense",),
        (
            "requirement",
            "violating runs",
            "share of the space (95 % interval)",
            "smallest robustness",
            "where the violating runs lie",
        ),
        tuple(Row(f"{name}: {formulas[name]}", tuple(dense), _share_cells(name)) for name in requirements()),
        (
            f"A Sobol sequence of {len(dense)} points over the box, one run each; the interval is the Wilson "
            "score interval of the share.",
        ),
    )


def _bench_table():
    """Runs to the first violation per requirement and optimiser, real ego runs."""
    from ego.docs.common import Row, Table

    jobs = {opt: tuple(BenchJob(opt, s, REAL_BUDGET) for s in range(REAL_REPS)) for opt in OPTIMIZERS}
    return Table(
        "falsify-bench",
        "falsify",
        (f"python benchmarks/bench_falsify.py --reps {REAL_REPS} --budget {REAL_BUDGET}",),
        RUNS_HEADER,
        tuple(
            Row(f"{name}, {opt}", jobs[opt] + jobs["lhs"], _runs_cells(name, REAL_REPS, REAL_BUDGET))
            for name in requirements()
            for opt in OPTIMIZERS
        ),
        (
            f"Real ego runs (emergency-brake braking in lane, pid, optimiser seeds 0-{REAL_REPS - 1} each, "
            f"budget {REAL_BUDGET} runs, batches of 2 as with --jobs 2). A repetition that found no violation "
            f"within the budget counts as more than {REAL_BUDGET} runs ('>{REAL_BUDGET}'; the quartiles are "
            "then lower bounds, and a ratio against a censored LHS median an upper bound, '<=').",
        ),
        figures=_figure(jobs),
    )


def _surrogate_table():
    """The optimisers on an analytic stand-in (a check of their wiring)."""
    from ego.docs.common import Row, Table

    return Table(
        "falsify-surrogate",
        "falsify",
        ("python benchmarks/bench_falsify.py --surrogate",),
        ("optimiser (SURROGATE, not ego runs)",) + RUNS_HEADER[1:],
        tuple(
            Row(
                opt,
                tuple(SurrogateJob(opt, s, SURROGATE_BUDGET) for s in range(SURROGATE_REPS))
                + tuple(SurrogateJob("lhs", s, SURROGATE_BUDGET) for s in range(SURROGATE_REPS)),
                _runs_cells(None, SURROGATE_REPS, SURROGATE_BUDGET),
            )
            for opt in OPTIMIZERS
        ),
        (
            f"An analytic stand-in, not ego: a ball of radius {SURROGATE_RADIUS} in [0, 1]^4 (0.04 % of "
            f"the cube), robustness = distance to it; {SURROGATE_REPS} seeds, budget {SURROGATE_BUDGET}. "
            "A check of the optimisers' wiring, not the result.",
        ),
    )


def _rate_table():
    """The falsification rate at a fixed budget, per requirement and optimiser."""
    from ego.docs.common import Row, Table

    rate_opts = available()
    rate_jobs = {
        opt: tuple(BenchJob(opt, s, RATE_BUDGET, spec=str(RATE_SPEC)) for s in range(RATE_REPS)) for opt in rate_opts
    }
    return Table(
        "falsify-rate",
        "falsify",
        (f"python benchmarks/bench_falsify.py --rate --repetitions {RATE_REPS} --budget {RATE_BUDGET}",),
        (
            "requirement, optimiser",
            "falsified",
            "falsification rate (95 % interval)",
            "median runs to the first violation",
            "quartiles",
        ),
        tuple(
            Row(f"{name}, {opt}", rate_jobs[opt], _rate_cells(name, RATE_REPS, RATE_BUDGET))
            for name in requirements(RATE_SPEC)
            for opt in rate_opts
        ),
        (
            f"Real ego runs as above (benchmarks/falsify/rate.toml: bench.toml with min_speed_low), a fixed "
            f"budget of {RATE_BUDGET} runs, optimiser seeds 0-{RATE_REPS - 1}; the rate is the share of "
            "repetitions that found a violation within the budget, with its Wilson score interval; a "
            f"repetition that found none counts as more than {RATE_BUDGET} runs. psy-taliro's rows: its "
            "UniformRandom and DualAnnealing driving ego's runs through ego.falsify (psy-taliro 3.2.0).",
        ),
    )


def _region_cells(name: str, coarse_n: int):
    def cells(ms: list[list[dict]]) -> list[str]:
        coarse = [p for m in ms[:coarse_n] for p in m]
        fine = [p for m in ms[coarse_n:] for p in m]
        r = region_share(coarse, fine, name)
        return [
            f"{r['coarse_bad']}/{r['coarse_n']}",
            f"{r['outside_bad']} ({r['outside_min']:.3g})",
            f"{r['fine_bad']}/{r['fine_n']}",
            f"{100 * r['volume']:.2f} %",
            f"{100 * r['share']:.3f} %",
        ]

    return cells


def region_table():
    """How much of the box each requirement of the rate spec violates, on grids of runs."""
    from ego.docs.common import Row, Table

    coarse = grid_jobs(((0.0, 1.0),) * 3, COARSE_CELLS)
    fine = grid_jobs(REGION_BOX, REGION_CELLS)
    jobs = tuple(coarse) + tuple(fine)
    return Table(
        "falsify-region",
        "falsify",
        ("python benchmarks/bench_falsify.py --region",),
        (
            "requirement",
            "violating cells, coarse grid",
            "of them outside the sub-box (smallest robustness there)",
            "violating cells, fine grid of the sub-box",
            "sub-box's share of the box",
            "violating share of the box",
        ),
        tuple(Row(name, jobs, _region_cells(name, len(coarse))) for name in requirements(RATE_SPEC)),
        (
            f"Runs at the centres of a {'x'.join(map(str, COARSE_CELLS))} grid of cells over the whole box, "
            f"and of a {'x'.join(map(str, REGION_CELLS))} grid over the sub-box ego_speed 16.5-25 m/s, lead_gap "
            "10-32 m, lead_decel 5.8-9 m/s^2; the violating share is the fine grid's share times the sub-box's "
            "volume, which holds where no coarse cell outside the sub-box violates.",
        ),
    )
