"""Runs-to-first-violation of each optimiser: the jobs behind ``benchmarks/bench_falsify.py``
and ``docs/results/falsify.md``.

* :class:`BenchJob`: one repetition on real ego runs - ``ego falsify`` (in this process, one
  run after another: a docs job already has a worker process of its own) with
  ``--until first`` over the benchmark spec ``benchmarks/falsify/bench.toml`` for one
  requirement, one optimiser and one optimiser seed, within a budget.
* :class:`SurrogateJob`: the same search against an analytic stand-in (no SUMO, clearly
  labelled as such): a violating ball in the unit cube, robustness = distance to it.
* :class:`SweepJob`: one run of the dense sweep that measures how small each violating
  region is (the requirements of ``benchmarks/falsify/dense.toml`` evaluated on it).
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
BENCH_SPEC = ROOT / "benchmarks" / "falsify" / "bench.toml"
DENSE_SPEC = ROOT / "benchmarks" / "falsify" / "dense.toml"
OPTIMIZERS = ("cma", "bo", "random", "lhs")


def bench_spec(requirement: str):
    """The benchmark spec with ``requirement`` as the target."""
    import dataclasses

    from ego.falsify.spec import load

    spec = load(BENCH_SPEC)
    if requirement not in spec.requirements:
        from ego.params import ConfigError

        raise ConfigError(
            f"unknown benchmark requirement {requirement!r} (known: {', '.join(spec.requirements)})"
        )
    return dataclasses.replace(
        spec,
        requirement=requirement,
        requirements={requirement: spec.requirements[requirement]},
    )


@dataclass(frozen=True)
class BenchJob:
    """One repetition on real runs: runs to the first violation (None: none within the budget)
    and the best robustness after each run."""

    requirement: str
    optimizer: str
    seed: int
    budget: int
    batch: int = 2  #: points per proposal (the workers of an ``ego falsify --jobs 2``)

    def __call__(self) -> dict:
        from ego.falsify.search import falsify
        from ego.parallel.executor import InlineExecutor

        class Batched(InlineExecutor):
            workers = self.batch

        with tempfile.TemporaryDirectory(prefix="ego-bench-falsify-") as tmp:
            report = falsify(
                bench_spec(self.requirement),
                Path(tmp),
                optimizer=self.optimizer,
                budget=self.budget,
                until="first",
                optimizer_seed=self.seed,
                verify=False,
                executor=Batched(),
            )
        search = report.searches[0]
        return {
            "runs": search.first_violation,
            "curve": [float(x) for x in search.best_so_far()],
        }


#: the surrogate: a violating ball of this radius in the unit cube of DIMS dimensions
SURROGATE_CENTRE = (0.83, 0.17, 0.71, 0.36)
SURROGATE_RADIUS = 0.08


@dataclass(frozen=True)
class SurrogateJob:
    """One repetition against the analytic stand-in (NOT ego runs): a ball of radius
    :data:`SURROGATE_RADIUS` around :data:`SURROGATE_CENTRE` in [0, 1]^4 violates (0.04 % of
    the cube); the robustness is the distance to it."""

    optimizer: str
    seed: int
    budget: int = 2000
    batch: int = 2

    def __call__(self) -> dict:
        from ego.falsify.optimizers import make, squash

        centre = np.array(SURROGATE_CENTRE)
        opt = make(self.optimizer, len(centre), self.batch, self.seed, self.budget)
        n, best, curve = 0, np.inf, []
        while n < self.budget:
            x = opt.ask()
            rob = np.linalg.norm(x - centre, axis=1) - SURROGATE_RADIUS
            for r in rob:
                n += 1
                best = min(best, float(r))
                curve.append(best)
                if r < 0:
                    return {"runs": n, "curve": curve}
            opt.tell(x, np.array([squash(float(r)) for r in rob]))
        return {"runs": None, "curve": curve}


@dataclass(frozen=True)
class SweepJob:
    """One run of the dense sweep with its requirements: their robustness by name."""

    seed: int
    overrides: tuple[tuple[str, Any], ...]
    controller: str = "pid"

    def __call__(self) -> dict:
        from ego.runner import RunSpec, run
        from ego.sweep.spec import load

        spec = load(DENSE_SPEC)
        result = run(
            RunSpec(
                spec.scenario,
                self.controller,
                self.seed,
                dict(self.overrides),
                requirements=spec.requirements,
            )
        )
        return dict(result.metrics.get("requirements", {}))


def dense_jobs() -> list[SweepJob]:
    from ego.sweep.spec import load

    spec = load(DENSE_SPEC)
    return [
        SweepJob(r.seed, tuple(r.overrides.items()), r.controller) for r in spec.runs()
    ]


def quartiles(runs: list, budget: int) -> tuple[float, float, float, int]:
    """(25th, 50th, 75th percentile, found) of runs-to-first; a repetition that found
    nothing counts as more than ``budget`` (the statistics are then lower bounds: ">")."""
    values = np.array([r if r is not None else np.inf for r in runs], dtype=float)
    q = np.percentile(
        np.where(np.isinf(values), budget + 1, values), [25, 50, 75], method="lower"
    )
    found = int(np.isfinite(values).sum())
    return float(q[0]), float(q[1]), float(q[2]), found


def fmt_runs(x: float, budget: int) -> str:
    return f">{budget}" if x > budget else f"{x:.0f}"


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
        tuple(
            Row(f"{name}: {spec.requirements[name]}", tuple(dense), _share_cells(name))
            for name in REQUIREMENTS
        ),
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
                + tuple(
                    BenchJob(name, "lhs", s, REAL_BUDGET) for s in range(REAL_REPS)
                ),
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
                tuple(
                    SurrogateJob(opt, s, SURROGATE_BUDGET)
                    for s in range(SURROGATE_REPS)
                )
                + tuple(
                    SurrogateJob("lhs", s, SURROGATE_BUDGET)
                    for s in range(SURROGATE_REPS)
                ),
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
