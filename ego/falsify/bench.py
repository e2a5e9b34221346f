"""Runs-to-first-violation of each optimiser: the jobs behind ``benchmarks/bench_falsify.py``
and ``docs/results/falsify.md`` (its tables: :mod:`ego.falsify.bench` and :mod:`ego.docs.falsify`).

* :class:`BenchJob`: one repetition on real ego runs for one optimiser and one optimiser
  seed: ``ego falsify --until first`` over the benchmark spec ``benchmarks/falsify/bench.toml``
  (in this process, one run after another, in batches of two as ``--jobs 2`` proposes them:
  a docs job already has a worker process of its own), once per requirement of the spec.
  Every run evaluates every requirement, and the searches of one repetition share an output
  folder under ``runs/bench-falsify/`` (kept: the repetition resumes from it, and a blind
  baseline's points, the same whatever the target, run once for all requirements).
* :class:`SurrogateJob`: the same search against an analytic stand-in (no SUMO, clearly
  labelled as such): a violating ball in the unit cube, robustness = distance to it.
* :class:`SweepJob`: one run of the dense sweep that measures how small each violating
  region is (the requirements of ``benchmarks/falsify/dense.toml`` evaluated on it).
"""

from __future__ import annotations

import functools
import hashlib
import itertools
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
BENCH_SPEC = ROOT / "benchmarks" / "falsify" / "bench.toml"
#: the fixed-budget table's spec: bench.toml's space and requirements and one whose violating
#: region is under 0.2 % of the box
RATE_SPEC = ROOT / "benchmarks" / "falsify" / "rate.toml"
DENSE_SPEC = ROOT / "benchmarks" / "falsify" / "dense.toml"
#: where the repetitions keep their runs (resumable; a changed spec gets a folder of its own)
CACHE = ROOT / "runs" / "bench-falsify"
OPTIMIZERS = ("cma", "bo", "random", "lhs")
#: psy-taliro's uniform random and dual annealing (rows where psy-taliro is installed)
PSYTALIRO = ("psytaliro-uniform", "psytaliro-annealing")


def available(optimizers=OPTIMIZERS + PSYTALIRO) -> tuple[str, ...]:
    """``optimizers`` without psy-taliro's where it is not installed (not a dependency of ego)."""
    import importlib.util

    have = importlib.util.find_spec("staliro") is not None
    return tuple(o for o in optimizers if have or o not in PSYTALIRO)


#: a finished repetition's figures, beside its runs (delete the folder to search again)
RESULT = "result.json"


def bench_spec(requirement: str, path: Path = BENCH_SPEC):
    """The benchmark spec with ``requirement`` as the target (every requirement still
    evaluated on every run)."""
    import dataclasses

    from ego.falsify.spec import load

    spec = load(path)
    if requirement not in spec.requirements:
        from ego.params import ConfigError

        raise ConfigError(f"unknown benchmark requirement {requirement!r} (known: {', '.join(spec.requirements)})")
    return dataclasses.replace(spec, requirement=requirement)


def requirements(path: Path = BENCH_SPEC) -> tuple[str, ...]:
    from ego.falsify.spec import load

    return tuple(load(path).requirements)


@dataclass(frozen=True)
class BenchJob:
    """One repetition on real runs, for each requirement of the spec: runs to the first
    violation (None: none within the budget) and the best robustness after each run."""

    optimizer: str
    seed: int
    budget: int
    batch: int = 2  #: points per proposal (the workers of an ``ego falsify --jobs 2``)
    spec: str = str(BENCH_SPEC)
    cache: str = ""  #: the folder of the repetitions (default :data:`CACHE`)

    def folder(self) -> Path:
        text = Path(self.spec).read_bytes()
        key = hashlib.sha256(text).hexdigest()[:10]
        return (
            Path(self.cache or CACHE) / key / f"{self.optimizer}-seed{self.seed}-budget{self.budget}-batch{self.batch}"
        )

    def __call__(self) -> dict:
        import json

        from ego.falsify.search import falsify
        from ego.outputs import write_text
        from ego.parallel.executor import InlineExecutor

        class Batched(InlineExecutor):
            workers = self.batch

        done = self.folder() / RESULT
        if done.exists():  # a finished repetition: its figures, without replaying the optimiser
            return json.loads(done.read_text())
        out = {}
        for name in requirements(Path(self.spec)):
            report = falsify(
                bench_spec(name, Path(self.spec)),
                self.folder(),
                optimizer=self.optimizer,
                budget=self.budget,
                until="first",
                optimizer_seed=self.seed,
                verify=False,
                executor=Batched(),
            )
            search = report.searches[0]
            out[name] = {
                "runs": search.first_violation,
                "curve": [float(x) for x in search.best_so_far()],
            }
        write_text(done, json.dumps(out))
        return out


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
        try:
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
        finally:
            getattr(opt, "close", lambda: None)()


#: the grids that measure the small requirement's region (:class:`GridJob`): cells per
#: dimension over the whole box, and over the sub-box (in the unit cube) that holds every
#: violation the coarse grid and the dense Sobol sweep found, with a margin
COARSE_CELLS = (12, 12, 12)
REGION_BOX = ((6.5 / 15, 1.0), (0.0, 22 / 90), (3.8 / 7, 1.0))  # ego_speed 16.5-25, lead_gap 10-32, lead_decel 5.8-9
REGION_CELLS = (24, 24, 16)


@dataclass(frozen=True)
class GridJob:
    """One slice of a grid of cells over a box of the unit cube (``box``: (lo, hi) per
    dimension): a run at the centre of every cell whose first coordinate is cell ``index``;
    each point's unit coordinates and the robustness of every requirement of ``spec``."""

    box: tuple[tuple[float, float], ...]
    cells: tuple[int, ...]
    index: int
    spec: str = str(RATE_SPEC)

    def points(self) -> list[np.ndarray]:
        axes = [lo + (hi - lo) * (np.arange(n) + 0.5) / n for (lo, hi), n in zip(self.box, self.cells)]
        axes[0] = axes[0][self.index : self.index + 1]
        return [np.array(p) for p in itertools.product(*axes)]

    def __call__(self) -> list[dict]:
        from ego.falsify.spec import load
        from ego.runner import RunSpec, run

        spec = load(Path(self.spec))
        out = []
        for u in self.points():
            seed, overrides = spec.point(u)
            result = run(RunSpec(spec.scenario, spec.controllers[0], seed, overrides, requirements=spec.requirements))
            out.append({"u": [float(x) for x in u], **result.metrics["requirements"]})
        return out


def grid_jobs(box: tuple[tuple[float, float], ...], cells: tuple[int, ...], spec: Path = RATE_SPEC) -> list[GridJob]:
    return [GridJob(box, cells, i, str(spec)) for i in range(cells[0])]


def region_share(coarse: list[dict], fine: list[dict], name: str, box=REGION_BOX) -> dict:
    """The share of the unit cube where ``name`` is violated: the share of the fine grid's
    cells (over ``box``) that violate times the box's volume, valid when no coarse cell
    outside ``box`` violates (``outside``: the count that do, and their smallest robustness)."""
    inside = np.array([[lo <= x <= hi for x, (lo, hi) in zip(p["u"], box)] for p in coarse]).all(axis=1)
    rob = np.array([p[name] for p in coarse], dtype=float)
    fine_rob = np.array([p[name] for p in fine], dtype=float)
    volume = float(np.prod([hi - lo for lo, hi in box]))
    bad = int((fine_rob < 0).sum())
    return {
        "share": volume * bad / len(fine_rob),
        "fine_bad": bad,
        "fine_n": len(fine_rob),
        "volume": volume,
        "coarse_bad": int((rob < 0).sum()),
        "coarse_n": len(rob),
        "outside_bad": int((rob[~inside] < 0).sum()),
        "outside_min": float(rob[~inside].min()) if (~inside).any() else math.inf,
    }


#: where ``ego sweep benchmarks/falsify/dense.toml --out runs/falsify-dense`` keeps its runs
DENSE_OUT = ROOT / "runs" / "falsify-dense"


@functools.lru_cache(maxsize=1)
def _dense_stored(path: str) -> dict:
    """The dense sweep's stored rows by run id (empty without that sweep's results)."""
    from ego.sweep.results import ResultStore

    table = ResultStore(Path(path)).table() if (Path(path) / "results.parquet").exists() else None
    return {row["run_id"]: row for row in table.to_pylist()} if table is not None else {}


@functools.lru_cache(maxsize=1)
def _dense_spec():
    from ego.sweep.spec import load

    return load(DENSE_SPEC)


@dataclass(frozen=True)
class SweepJob:
    """One run of the dense sweep with its requirements: their robustness by name, and the
    searched values under ``"point"``. A run the dense sweep's own command has stored (in
    :data:`DENSE_OUT`; the same run, deterministic) is read from there instead of run again."""

    seed: int
    overrides: tuple[tuple[str, Any], ...]
    controller: str = "pid"

    def __call__(self) -> dict:
        from ego.requirements import PREFIX
        from ego.runner import RunSpec, run
        from ego.sweep.spec import run_id

        spec = _dense_spec()
        overrides = dict(self.overrides)
        row = _dense_stored(str(DENSE_OUT)).get(run_id(spec.scenario, self.controller, self.seed, overrides))
        if row is not None and row.get("status") not in (None, "error", "interrupted"):
            out = {name: row.get(PREFIX + name) for name in spec.requirements}
        else:
            result = run(RunSpec(spec.scenario, self.controller, self.seed, overrides, requirements=spec.requirements))
            out = dict(result.metrics.get("requirements", {}))
        ranges = spec.sample.ranges if spec.sample else {}
        out["point"] = {k: v for k, v in self.overrides if k in ranges}
        return out


def dense_jobs() -> list[SweepJob]:
    spec = _dense_spec()
    return [SweepJob(r.seed, tuple(r.overrides.items()), r.controller) for r in spec.runs()]


def quartiles(runs: list, budget: int) -> tuple[float, float, float, int]:
    """(25th, 50th, 75th percentile, found) of runs-to-first; a repetition that found
    nothing counts as more than ``budget`` (the statistics are then lower bounds: ">")."""
    values = np.array([r if r is not None else np.inf for r in runs], dtype=float)
    q = np.percentile(np.where(np.isinf(values), budget + 1, values), [25, 50, 75], method="lower")
    found = int(np.isfinite(values).sum())
    return float(q[0]), float(q[1]), float(q[2]), found


def fmt_runs(x: float, budget: int) -> str:
    return f">{budget}" if x > budget else f"{x:.0f}"


def wilson(k: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """The 95 % Wilson score interval of a share k/n (sound at k = 0 and for small k)."""
    if n == 0:
        return 0.0, 1.0
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(0.0, centre - half), min(1.0, centre + half)


def convergence_figure(curves: dict, budget: int, path: Path) -> Path:
    """Best robustness so far against runs: per requirement a panel, per optimiser the median
    over the repetitions and the band between their quartiles. ``curves`` maps (requirement,
    optimiser) to the repetitions' curves; a repetition that stopped at its first violation
    keeps its last value."""
    from ego.plots import pyplot, save

    plt = pyplot()
    reqs = list(dict.fromkeys(r for r, _ in curves))
    fig, axes = plt.subplots(1, len(reqs), figsize=(6 * len(reqs), 4.2), squeeze=False)
    x = np.arange(1, budget + 1)
    for ax, req in zip(axes[0], reqs):
        for (r, opt), reps in curves.items():
            if r != req:
                continue
            grid = np.full((len(reps), budget), np.nan)
            for i, c in enumerate(reps):
                c = np.clip(np.asarray(c, dtype=float)[:budget], -1e6, 1e6)
                if len(c):
                    grid[i, : len(c)] = c
                    grid[i, len(c) :] = c[-1]
            q1, med, q3 = np.nanpercentile(grid, [25, 50, 75], axis=0)
            (line,) = ax.plot(x, med, label=f"{opt} (median)")
            ax.fill_between(x, q1, q3, color=line.get_color(), alpha=0.15, lw=0)
        ax.axhline(0.0, color="k", lw=0.8, ls="--")
        ax.set_yscale("symlog", linthresh=0.1)
        ax.set_xscale("log")
        ax.set_xlabel("runs")
        ax.set_ylabel(f"best robustness of {req} so far")
        ax.set_title(f"{req}: median and quartiles over {len(reps)} repetitions", fontsize=9)
        ax.legend(fontsize=8)
    fig.tight_layout()
    return save(fig, path)
