"""``ego falsify``: search a spec's ranges for runs that violate a requirement.

For each controller of the spec, an optimiser (:mod:`ego.falsify.optimizers`) proposes a
batch of points (:data:`BATCH`, or ``--batch``: the same search for any number of workers),
the sweep machinery runs them
(:func:`ego.sweep.pipeline.execute` on :func:`ego.parallel.executor.make_executor`, rows into
:class:`ego.sweep.results.ResultStore`), and the optimiser learns the target requirement's
robustness of each. Outputs in ``--out``:

* ``results.parquet``: every run (the sweep's columns, ``requirements.<name>`` for each
  requirement, and ``optimizer``, ``optimizer_seed``, ``evaluation``). The same command
  again resumes: the optimiser is replayed (it is deterministic), and a point whose run is
  already stored takes its stored robustness instead of running again.
* ``falsified.md``: per controller the budget, runs to the first violation, and each
  violation: parameters, robustness, the exact ``ego run`` command that reproduces it (run
  again as a command and checked, unless ``--no-verify``), and its recording.
* ``convergence.png``: the best robustness so far against runs.
"""

from __future__ import annotations

import math
import shlex
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ego.falsify.optimizers import make, squash
from ego.falsify.spec import FalsifySpec
from ego.outputs import FolderLock, write_text
from ego.requirements import PREFIX, defaults
from ego.sweep.results import ResultStore
from ego.sweep.spec import Run

#: violations checked by running their command again (each is a fresh ``ego run`` process)
VERIFY_AT_MOST = 5

#: points an optimiser proposes at a time: the search depends on it, not on the workers
#: (--jobs), so it is the same on any machine
BATCH = 2


@dataclass
class Evaluation:
    """One run of the search: its place in the sequence and its robustness."""

    index: int
    controller: str
    seed: int
    overrides: dict
    run_id: str
    robustness: float
    status: str
    cached: bool = False


@dataclass
class Search:
    controller: str
    evaluations: list[Evaluation] = field(default_factory=list)
    verified: dict = field(default_factory=dict)  #: run_id -> (reproduced?, recording, detail)
    ran: int = 0  #: runs made now (the others were stored already)

    @property
    def violations(self) -> list[Evaluation]:
        return [e for e in self.evaluations if e.robustness < 0.0]

    @property
    def first_violation(self) -> int | None:
        """Runs up to and including the first violation (None: none found)."""
        return next((e.index + 1 for e in self.evaluations if e.robustness < 0.0), None)

    def best_so_far(self) -> np.ndarray:
        rob = np.array([e.robustness if not math.isnan(e.robustness) else np.inf for e in self.evaluations])
        return np.minimum.accumulate(rob) if len(rob) else rob


@dataclass
class FalsifyReport:
    spec: FalsifySpec
    optimizer: str
    searches: list[Search]
    seconds: float
    ran: int
    interrupted: bool = False
    out: Path | None = None

    @property
    def violations(self) -> int:
        return sum(len(s.violations) for s in self.searches)

    def text(self) -> str:
        lines = []
        for s in self.searches:
            first = s.first_violation
            best = s.best_so_far()
            lines.append(
                f"{s.controller}: {len(s.evaluations)} runs ({self.optimizer}), "
                f"{len(s.violations)} violate {self.spec.requirement}"
                + (f", the first at run {first}" if first else "")
                + (f"; best robustness {best[-1]:.4g}" if len(best) else "")
            )
        lines.append(
            f"{self.ran} runs ran now in {self.seconds:.1f} s; wrote {self.out / 'results.parquet'}, "
            f"{self.out / 'falsified.md'}, {self.out / 'convergence.png'}"
        )
        return "\n".join(lines)


def robustness_of(row: dict, name: str) -> float:
    v = row.get(PREFIX + name)
    return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else math.nan


def falsify(
    spec: FalsifySpec,
    out: Path,
    *,
    optimizer: str = "cma",
    budget: int | None = None,
    engine: str = "process",
    jobs: int | None = None,
    address: str | None = None,
    until: str = "budget",
    optimizer_seed: int = 0,
    verify: bool = True,
    progress: bool = False,
    executor=None,
    batch: int = BATCH,
) -> FalsifyReport:
    """Run the search (see the module docstring); ``executor`` overrides ``engine``/``jobs``.
    ``batch``: points per proposal, which the search depends on (not the workers)."""
    from ego.parallel.executor import make_executor
    from ego.sweep.runner import check_results_folder

    out = Path(out)
    budget = budget or spec.budget
    # every name it writes, the results it would add to and the cluster: before --out is touched
    check_results_folder(out, ["falsified.md", "convergence.png"], spec.controllers if verify else ())
    key = resume_key(spec, optimizer, optimizer_seed)
    if (out / "results.parquet").is_file():
        stored = ResultStore(out)
        stored.check_compatible(spec.scenario, _sample_rows(spec, optimizer, optimizer_seed))
        stored.check_spec(key, "search")
    if executor is None and engine == "ray" and address is not None:
        from ego.cluster import check_address

        check_address(address)
    with FolderLock(out, "--out"):
        store = ResultStore(out, spec_key=key)
        table = store.table()
        known: dict[str, dict] = {row["run_id"]: row for row in table.to_pylist()} if table is not None else {}
        own = executor is None
        executor = make_executor(engine, jobs, address) if own else executor
        started = time.perf_counter()
        searches: list[Search] = []
        interrupted = False
        try:
            for controller in spec.controllers:
                search = Search(controller)
                searches.append(search)
                _search(
                    spec,
                    controller,
                    optimizer,
                    optimizer_seed,
                    budget,
                    until,
                    executor,
                    store,
                    known,
                    search,
                    progress,
                    batch,
                )
        except KeyboardInterrupt:
            interrupted = True
        finally:
            ran = sum(s.ran for s in searches)
            store.flush()
            if own:
                executor.close()
        if verify and not interrupted:
            for search in searches:
                _verify(spec, search, out)
        report = FalsifyReport(spec, optimizer, searches, time.perf_counter() - started, ran, interrupted, out)
        _write_outputs(report, budget, out)
    return report


def _write_outputs(report: FalsifyReport, budget: int, out: Path) -> None:
    """falsified.md and convergence.png (the best robustness against runs, per controller)."""
    write_text(out / "falsified.md", markdown(report, budget))
    plot_convergence(
        [(f"{s.controller} ({report.optimizer})", s.best_so_far()) for s in report.searches],
        out / "convergence.png",
        report.spec.requirement,
    )


def resume_key(spec: FalsifySpec, optimizer: str, optimizer_seed: int) -> dict:
    """What a stored search's rows mean beyond their run ids: the ranges, the fixed values,
    the requirements' formulas (every one is checked on every run) and the optimiser.
    Resuming with any of them changed is refused
    (:meth:`ego.sweep.results.ResultStore.check_spec`); the budget, the controllers and the
    target among the same requirements may change (more runs of the same search, another
    search over the same rows: ``ego.falsify.bench`` shares them between targets)."""
    key = {
        "ranges": {d.name: ("false/true" if d.kind == "bool" else [d.lo, d.hi]) for d in spec.dims},
        "fixed values": {**spec.fixed, **({} if spec.seed is None else {"seed": spec.seed})},
        "requirements": dict(spec.requirements),
        "optimizer": f"{optimizer} (seed {optimizer_seed})",
    }
    if spec.seeds_per_point != 1:  # a spec without them keeps its key (and its stored searches)
        key["seeds per point"] = spec.seeds_per_point
    if spec.requirement_period:
        key["requirement period"] = spec.requirement_period
    return key


def _sample_rows(spec: FalsifySpec, optimizer: str, optimizer_seed: int) -> list[dict]:
    """The key columns, overrides and optimiser columns of each controller's runs at the
    corners of the search: what the results file's columns will be asked to hold."""
    rows = []
    for controller in spec.controllers:
        for u in (np.zeros(len(spec.dims)), np.ones(len(spec.dims))):
            seed, overrides = spec.point(u)
            rows.append(
                {
                    "run_id": spec.run_id(controller, seed, overrides),
                    "scenario": spec.scenario,
                    "controller": controller,
                    "seed": seed,
                    **overrides,
                    "optimizer": optimizer,
                    "optimizer_seed": optimizer_seed,
                }
            )
    return rows


def _search(
    spec: FalsifySpec,
    controller: str,
    optimizer: str,
    seed: int,
    budget: int,
    until: str,
    executor,
    store: ResultStore,
    known: dict,
    search: Search,
    progress: bool,
    batch: int = 2,
) -> None:
    opt = make(optimizer, len(spec.dims), batch, seed, budget, spec.kinds)
    k = spec.seeds_per_point

    def keep(row: dict) -> None:
        row.update(optimizer=optimizer, optimizer_seed=seed)
        known[row["run_id"]] = row
        store.add(row)
        search.ran += 1

    try:
        while len(search.evaluations) < budget:
            units = opt.ask()
            full = len(units)
            left = budget - len(search.evaluations)
            units = units[: max(1, left // k)]
            # each point's runs (its seeds), within the budget
            points = [run for u in units for run in spec.runs_of(*spec.point(u))][:left]
            ids = [spec.run_id(controller, s, o) for s, o in points]
            fresh = _run_batch(spec, controller, ids, points, known, executor, keep)
            for rid, (s, o) in zip(ids, points):
                row = known[rid]
                search.evaluations.append(
                    Evaluation(
                        len(search.evaluations),
                        controller,
                        s,
                        o,
                        rid,
                        robustness_of(row, spec.requirement),
                        row.get("status", ""),
                        cached=rid not in fresh,
                    )
                )
            if len(units) == full and len(points) == full * k:
                # a point's score: its worst robustness over its seeds (NaN only when none has one)
                rob = np.array([e.robustness for e in search.evaluations[-full * k :]]).reshape(full, k)
                worst = [float(np.nanmin(r)) if not np.isnan(r).all() else math.nan for r in rob]
                opt.tell(units, np.array([squash(w) for w in worst]))
            if progress:
                best = search.best_so_far()[-1]
                found = len(search.violations)
                sys.stderr.write(
                    f"{controller}: {len(search.evaluations)}/{budget} runs, best robustness "
                    f"{best:.4g}, {found} violation(s)\n"
                )
                sys.stderr.flush()
            if until == "first" and search.violations:
                break
    finally:  # psy-taliro's optimisers end their thread
        close = getattr(opt, "close", None)
        if close is not None:
            close()


def _run_batch(
    spec: FalsifySpec, controller: str, ids: list[str], points: list, known: dict, executor, keep: Callable
) -> set[str]:
    """Run the batch's points not already known (on ``executor``), each row to ``keep`` as
    it finishes; the ids that ran now. A point whose values no run takes is an error row,
    kept too, interrupted or not."""
    from ego.sweep.pipeline import execute
    from ego.sweep.runner import error_row, row_of, task_of

    tasks = {}
    fresh = set()
    done: dict[str, dict] = {}  # the batch's error rows of values no run takes
    for rid, (s, o) in zip(ids, points):
        if rid not in known and rid not in fresh:
            fresh.add(rid)
            r = Run(rid, spec.scenario, controller, s, o)
            try:
                tasks[rid] = task_of(r, None, "none", spec.requirements, spec.requirement_period)
            except Exception as exc:  # noqa: BLE001 - values no run takes: the run's row says so
                done[rid] = error_row(r, f"{type(exc).__name__}: {exc}")
    try:
        for outcome in executor.run(execute, tasks.values()):
            task = outcome.task
            if outcome.value is None:
                row = error_row(task.key, outcome.error or "the worker died")
            else:
                row = row_of(task.key, outcome.value)
            if row["status"] == "interrupted":
                raise KeyboardInterrupt
            keep(row)  # into the store as it finishes: on disk within the store's 2 s
    finally:
        for rid in ids:
            if rid in done and rid not in known:
                keep(done[rid])
    return fresh


def command(spec: FalsifySpec, e: Evaluation, record: str | None = None) -> str:
    """The ``ego run`` command that makes the run ``e`` (the target requirement given with
    ``--require`` unless it is one of the scenario's defaults, unchanged)."""
    from ego.runner import run_command

    require = (
        [] if defaults(spec.scenario).get(spec.requirement) == spec.formula else [(spec.requirement, spec.formula)]
    )
    return run_command(spec.scenario, e.controller, e.seed, e.overrides, require, record)


def _verify(spec: FalsifySpec, search: Search, out: Path) -> None:
    """Run the command of the first few distinct violations (the first found, then the
    worst) as a fresh ``ego run`` with a recording; reproduced when its robustness is the
    search's."""
    import json

    seen: dict[str, Evaluation] = {}
    for e in [
        *search.violations[:1],
        *sorted(search.violations, key=lambda e: e.robustness),
    ]:
        seen.setdefault(e.run_id, e)
    for e in list(seen.values())[:VERIFY_AT_MOST]:
        rrd = out / "runs" / f"{e.controller}-{e.run_id}.rrd"
        rrd.parent.mkdir(parents=True, exist_ok=True)
        args = shlex.split(command(spec, e, str(rrd)))[1:] + ["--json"]
        proc = subprocess.run(
            [sys.executable, "-m", "ego", *args],
            capture_output=True,
            text=True,
            timeout=600,
        )
        try:
            got = json.loads(proc.stdout.strip().splitlines()[-1])["requirements"][spec.requirement]
        except (ValueError, KeyError, IndexError, TypeError):
            search.verified[e.run_id] = (
                False,
                "",
                (proc.stderr.strip().splitlines() or ["no output"])[-1],
            )
            continue
        same = got is not None and math.isclose(float(got), e.robustness, rel_tol=1e-6, abs_tol=1e-9)
        search.verified[e.run_id] = (
            same,
            str(rrd) if rrd.exists() else "",
            f"robustness {got}",
        )


def markdown(report: FalsifyReport, budget: int) -> str:
    spec = report.spec
    lines = [
        f"# Falsification of `{spec.requirement}` on {spec.scenario}",
        "",
        f"Requirement: `{spec.requirement}: {spec.formula}`; spec `{spec.source}`; optimiser "
        f"{report.optimizer}; budget {budget} runs per controller.",
        "",
        "Searched: "
        + ", ".join(f"{d.name} {'false/true' if d.kind == 'bool' else f'{d.lo:g}..{d.hi:g}'}" for d in spec.dims)
        + ("" if spec.seed is None else f"; seed fixed at {spec.seed}")
        + (
            f"; each point run with {spec.seeds_per_point} seeds, its worst robustness kept"
            if spec.seeds_per_point > 1
            else ""
        )
        + ("; fixed: " + ", ".join(f"{k}={v}" for k, v in spec.fixed.items()) if spec.fixed else ""),
        "",
        "| controller | runs | violations | runs to the first violation | best robustness |",
        "|---|---|---|---|---|",
    ]
    for s in report.searches:
        best = s.best_so_far()
        lines.append(
            f"| {s.controller} | {len(s.evaluations)} | {len(s.violations)} | "
            f"{s.first_violation or '-'} | {best[-1]:.4g} |"
            if len(best)
            else f"| {s.controller} | 0 | 0 | - | - |"
        )
    for s in report.searches:
        if not s.violations:
            continue
        distinct = {e.run_id: e for e in sorted(s.violations, key=lambda e: (e.robustness, e.index))}
        lines += [
            "",
            f"## {s.controller}: {len(distinct)} distinct violating run(s)",
            "",
        ]
        for e in list(distinct.values())[:20]:
            ok, rrd, detail = s.verified.get(e.run_id, (None, "", ""))
            verdict = (
                "not verified" if ok is None else "reproduced by the command" if ok else f"NOT reproduced ({detail})"
            )
            params = ", ".join(f"{k}={v}" for k, v in e.overrides.items())
            lines += [
                f"- run {e.index + 1} (`{e.run_id}`), status {e.status}, robustness {e.robustness:.4g}: "
                f"seed {e.seed}, {params}; {verdict}" + (f"; recording `{rrd}`" if rrd else ""),
                f"  `{command(spec, e)}`",
            ]
        if len(distinct) > 20:
            lines.append(f"- ... {len(distinct) - 20} more in results.parquet")
    if report.interrupted:
        lines += ["", "Interrupted: the same command resumes."]
    return "\n".join(lines) + "\n"


def plot_convergence(curves, path: Path, requirement: str, title: str = "") -> Path:
    """Best robustness so far against runs, one line per (label, curve)."""
    from ego.plots import pyplot, save

    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7, 4))
    for label, curve in curves:
        if len(curve):
            ax.plot(np.arange(1, len(curve) + 1), np.clip(curve, -1e6, 1e6), label=label)
    ax.axhline(0.0, color="k", lw=0.8, ls="--")
    ax.set_yscale("symlog", linthresh=0.1)
    ax.set_xlabel("runs")
    ax.set_ylabel(f"best robustness of {requirement}")
    ax.set_title(title or "falsification: best robustness so far (below 0: violated)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return save(fig, path)
