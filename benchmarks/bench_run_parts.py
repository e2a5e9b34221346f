"""Where a sweep's run spends its CPU time: the loop, and what lies outside it.

    python benchmarks/bench_run_parts.py [SPEC.toml] [--every 8] [--rows OUT.json]

Runs every ``--every``-th run of a sweep spec (default ``benchmarks/envelope_200.toml``)
one after another in this process, as a worker does (``ego.sweep.pipeline.execute``: the
run, its default requirements, its row), after one warm-up run per controller (imports,
compiled fuzzy tables). Prints CPU milliseconds per run (``time.process_time``: on a shared
machine the wall clock mostly measures the other jobs), per controller, and split into the
run's parts: start (SUMO start, network load, traffic insertion: ``Scenario.reset``), the
loop (the rest), result packing (the trace as an array, the metrics), the requirements
(ego.stl, every sample), close. ``--rows`` writes the rows (wall time and host aside) to compare two trees:
run it once with ``PYTHONPATH=<other tree>`` and compare the files.

SUMO's own step inside those runs is timed too (libsumo's step function, wrapped for the
benchmark: the same calls the runs make, with the ego driven and the traffic reacting to
it): the floor of a sweep of these runs that no change to ego's own code can go below while
every figure stays, since SUMO's work is the traffic.

Then SUMO's own share as an estimate without the runs (there the ego is not moved by a
controller): for each run, bare ``simulationStep()`` calls on
the same traffic (the run's scenario, seed and values, no control:
``benchmarks/bench_loop.py``'s baseline) for as many SUMO steps as the run took,
and what that makes of a sweep of such runs on ``--jobs`` workers (``--sweep-runs``, default
the 2,500 runs of ``scenarios/sweeps/envelope.toml``).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import tomllib
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import ego.requirements  # noqa: E402
import ego.scenarios.base as base  # noqa: E402
from ego.sweep.pipeline import execute  # noqa: E402
from ego.sweep.runner import row_of, task_of  # noqa: E402
from ego.sweep.spec import parse  # noqa: E402

PARTS = {
    "start": (base.Scenario, "reset"),
    "result": (base.Scenario, "result"),
    "requirements": (ego.requirements, "check_run"),
    "close": (base.Scenario, "close"),
}


def timed_parts(cpu: dict[str, float]) -> None:
    """Wrap each part's function so its CPU seconds add up in ``cpu`` (benchmark only)."""
    for part, (owner, name) in PARTS.items():
        fn = getattr(owner, name)

        def wrapper(*args, _fn=fn, _part=part, **kwargs):
            t0 = time.process_time()
            try:
                return _fn(*args, **kwargs)
            finally:
                cpu[_part] = cpu.get(_part, 0.0) + time.process_time() - t0

        setattr(owner, name, wrapper)


def timed_sumo_step(cpu: dict[str, float]) -> None:
    """Wrap libsumo's step (what ``SumoBridge.start`` binds) so its CPU seconds add up in
    ``cpu["sumo_step"]`` (benchmark only)."""
    import libsumo

    step = libsumo._libsumo_step
    clock = time.process_time

    def wrapper(*args, **kwargs):
        t0 = clock()
        try:
            return step(*args, **kwargs)
        finally:
            cpu["sumo_step"] += clock() - t0

    cpu["sumo_step"] = 0.0
    libsumo._libsumo_step = wrapper


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("spec", nargs="?", default=str(Path(__file__).with_name("envelope_200.toml")))
    ap.add_argument("--every", type=int, default=8, help="take every N-th run of the spec")
    ap.add_argument("--rows", help="write the rows as JSON here")
    ap.add_argument("--sweep-runs", type=int, default=2500, help="runs of the sweep the floor is scaled to")
    ap.add_argument("--jobs", type=int, default=2, help="workers of that sweep")
    ap.add_argument("--no-floor", action="store_true", help="skip the bare-SUMO floor")
    args = ap.parse_args(argv)
    spec = parse(tomllib.loads(Path(args.spec).read_text()))
    tasks = [task_of(r, None, "none", spec.requirements) for r in list(spec.runs())[:: args.every]]
    warm: set[str] = set()
    for t in tasks:
        if t.key.controller not in warm:
            warm.add(t.key.controller)
            execute(t)
    cpu: dict[str, float] = {}
    timed_parts(cpu)
    sumo: dict[str, float] = {}
    timed_sumo_step(sumo)
    per_controller: dict[str, list[float]] = {}
    rows = []
    t_all = time.process_time()
    for t in tasks:
        t0 = time.process_time()
        row = execute(t)
        per_controller.setdefault(t.key.controller, []).append(time.process_time() - t0)
        rows.append({k: v for k, v in row_of(t.key, row).items() if k not in ("wall_time", "host", "node")})
    total = time.process_time() - t_all
    n = len(tasks)
    cpu["loop"] = total - sum(cpu.values())
    figures = {"runs": n, "ms_per_run": 1e3 * total / n}
    print(f"{n} runs of {args.spec}: {1e3 * total / n:.1f} ms CPU a run")
    for c, times in per_controller.items():
        figures[f"ms_{c}"] = 1e3 * sum(times) / len(times)
        print(f"  {c:12s} {figures[f'ms_{c}']:7.1f} ms a run ({len(times)} runs)")
    for part in ("start", "loop", "result", "requirements", "close"):
        figures[f"ms_{part}"] = 1e3 * cpu[part] / n
        print(f"  {part:12s} {figures[f'ms_{part}']:7.1f} ms a run  {100 * cpu[part] / total:5.1f} %")
    figures["ms_sumo_step"] = 1e3 * sumo["sumo_step"] / n
    figures["sweep_sumo_s"] = args.sweep_runs / args.jobs * sumo["sumo_step"] / n
    print(
        f"  of it SUMO's step in the runs {figures['ms_sumo_step']:7.1f} ms a run  {100 * sumo['sumo_step'] / total:5.1f} %: "
        f"{figures['sweep_sumo_s']:.0f} s of CPU a worker in a sweep of {args.sweep_runs} such runs on {args.jobs} workers"
    )
    if not args.no_floor:
        bare = sum(bare_sumo(t, row["steps"]) for t, row in zip(tasks, rows))
        figures["ms_bare_sumo"] = 1e3 * bare / n
        floor = args.sweep_runs / args.jobs * bare / n
        print(
            f"  bare SUMO    {figures['ms_bare_sumo']:7.1f} ms a run  {100 * bare / total:5.1f} % "
            f"(SUMO's own stepping of the same traffic, the same steps)"
        )
        print(
            f"  a sweep of {args.sweep_runs} such runs on {args.jobs} workers: {args.sweep_runs / args.jobs * total / n:.0f} s "
            f"of CPU a worker, of it {floor:.0f} s SUMO's own stepping (its floor)"
        )
        figures["sweep_floor_s"] = floor
    if args.rows:
        Path(args.rows).write_text(json.dumps(rows, sort_keys=True, default=str))
    return figures


def bare_sumo(task, steps: int) -> float:
    """CPU seconds of ``steps`` control periods' worth of bare SUMO steps on ``task``'s traffic."""
    from ego.runner import RunSpec, build

    key = task.key
    scenario = build(RunSpec(key.scenario, "none", key.seed, key.overrides))
    try:
        scenario.reset()
        step = scenario.bridge.libsumo.simulationStep
        n = int(steps) // scenario.config.control_per_sumo
        c0 = time.process_time()
        for _ in range(n):
            step()
        return time.process_time() - c0
    finally:
        scenario.close()


if __name__ == "__main__":
    main()
