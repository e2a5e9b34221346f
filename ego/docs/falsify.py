"""The tables of ``docs/results/falsify.md``: the jobs of :mod:`ego.falsify.bench` run
by ``python -m ego.docs`` (a checkout's, not the wheel's)."""

from __future__ import annotations

from ego.falsify.bench import (
    BENCH_SPEC,
    OPTIMIZERS,
    SURROGATE_RADIUS,
    BenchJob,
    SurrogateJob,
    dense_jobs,
    fmt_runs,
    quartiles,
)

# -- docs/results/falsify.md ----------------------------------------------------------------------
#: repetitions (optimiser seeds 0..n-1) per optimiser: real runs, and the surrogate
REAL_REPS = 5
SURROGATE_REPS = 20
REAL_BUDGET = 120
SURROGATE_BUDGET = 400
REQUIREMENTS = ("keeps_1m", "no_overbraking")


def _runs_cells(reps: int, budget: int):
    """Cells of a runs-to-first row whose jobs are its own ``reps`` then LHS's ``reps``."""

    def cells(ms: list[dict]) -> list[str]:
        own, lhs = [m["runs"] for m in ms[:reps]], [m["runs"] for m in ms[reps:]]
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


def _share_cells(name: str):
    def cells(ms: list[dict]) -> list[str]:
        values = [m.get(name) for m in ms]
        values = [float(v) for v in values if v is not None]
        bad = sum(v < 0 for v in values)
        return [
            f"{bad}/{len(values)}",
            f"{100.0 * bad / len(values):.2f} %",
            f"{min(values):.3g}",
        ]

    return cells


def docs_tables() -> list:
    """The tables of docs/results/falsify.md (ego.docs builds the page from them)."""
    from ego.docs import Row, Table
    from ego.falsify.spec import load

    dense = dense_jobs()
    spec = load(BENCH_SPEC)
    landscape = Table(
        "falsify-landscape",
        "falsify",
        ("ego sweep benchmarks/falsify/dense.toml --out runs/falsify-dense",),
        ("requirement", "violating runs", "share of the space", "smallest robustness"),
        tuple(Row(f"{name}: {spec.requirements[name]}", tuple(dense), _share_cells(name)) for name in REQUIREMENTS),
    )
    header = (
        "requirement, optimiser",
        "found",
        "median runs to the first violation",
        "quartiles",
        "median / LHS median",
    )
    real = Table(
        "falsify-bench",
        "falsify",
        tuple(
            f"python benchmarks/bench_falsify.py --requirement {name} --reps {REAL_REPS} --budget {REAL_BUDGET}"
            for name in REQUIREMENTS
        ),
        header,
        tuple(
            Row(
                f"{name}, {opt}",
                tuple(BenchJob(name, opt, s, REAL_BUDGET) for s in range(REAL_REPS))
                + tuple(BenchJob(name, "lhs", s, REAL_BUDGET) for s in range(REAL_REPS)),
                _runs_cells(REAL_REPS, REAL_BUDGET),
            )
            for name in REQUIREMENTS
            for opt in OPTIMIZERS
        ),
        (
            f"Real ego runs (emergency-brake braking in lane, pid, {REAL_REPS} optimiser seeds each, "
            f"budget {REAL_BUDGET} runs, batches of 2 as with --jobs 2). '>{REAL_BUDGET}': fewer than half "
            "the repetitions found one within the budget.",
        ),
    )
    surrogate = Table(
        "falsify-surrogate",
        "falsify",
        ("python benchmarks/bench_falsify.py --surrogate",),
        ("optimiser (SURROGATE, not ego runs)",) + header[1:],
        tuple(
            Row(
                opt,
                tuple(SurrogateJob(opt, s, SURROGATE_BUDGET) for s in range(SURROGATE_REPS))
                + tuple(SurrogateJob("lhs", s, SURROGATE_BUDGET) for s in range(SURROGATE_REPS)),
                _runs_cells(SURROGATE_REPS, SURROGATE_BUDGET),
            )
            for opt in OPTIMIZERS
        ),
        (
            f"An analytic stand-in, not ego: a ball of radius {SURROGATE_RADIUS} in [0, 1]^4 (0.04 % of "
            f"the cube), robustness = distance to it; {SURROGATE_REPS} seeds, budget {SURROGATE_BUDGET}.",
        ),
    )
    return [landscape, real, surrogate]
