"""Sweep throughput: runs per second against workers, parallel efficiency and per-run overhead.

    python benchmarks/bench_sweep.py [--runs 240] [--duration 5] [--engines process,ray]

The same runs (emergency-brake, pid, no recording, ``--duration`` seconds simulated each)
are done three ways in one session: one after another in this process (the baseline: the
simulation alone), then through each engine with 1 and with every CPU's worth of workers.
Printed: runs/s, the parallel efficiency (engine runs/s / (workers x in-process runs/s);
target >= 0.85 on 2 cores for >= 200 short runs), the per-run overhead of an engine with one
worker against the simulation itself (spec to result row; target <= 15 %), and Ray's
start-up on its own line.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from ego.parallel.executor import InlineExecutor, make_executor  # noqa: E402
from ego.sweep.pipeline import execute  # noqa: E402
from ego.sweep.runner import task_of  # noqa: E402
from ego.sweep.spec import parse  # noqa: E402


def tasks(n: int, duration: float):
    seeds = max(1, n // 24)
    spec = parse(
        {
            "scenario": "emergency-brake",
            "controllers": ["pid"],
            "seeds": seeds,
            "set": {"duration": duration, "traffic_density": 5.0},
            "grid": {"ego_speed": [16, 20, 24, 28, 32, 36], "lead_gap": [20, 30, 45, 60]},
        }
    )
    return [task_of(r) for r in list(spec.runs())[:n]]


def timed(executor, work) -> float:
    t0 = time.perf_counter()
    for outcome in executor.run(execute, work):
        if outcome.value is None or outcome.value.status == "error":
            raise RuntimeError(f"a run failed: {outcome.error or outcome.value.error}")
    return time.perf_counter() - t0


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=240)
    ap.add_argument("--duration", type=float, default=5.0)
    ap.add_argument("--engines", default="process")
    args = ap.parse_args(argv)
    work = tasks(args.runs, args.duration)
    cpus = os.cpu_count() or 1
    timed(InlineExecutor(), work[:4])  # warm: imports, the fuzzy rule base, SUMO's first start
    inline = timed(InlineExecutor(), work)
    base = len(work) / inline
    print(f"{len(work)} runs of emergency-brake (pid, {args.duration:g} s simulated, no recording)")
    print(f"  in-process, one after another   {base:7.2f} runs/s   ({1e3 * inline / len(work):.1f} ms a run)")
    figures = {"runs": len(work), "inprocess_runs_per_s": base}
    for engine in args.engines.split(","):
        if engine == "ray":
            t0 = time.perf_counter()
            ex = make_executor("ray", cpus)
            timed(ex, work[:1])
            figures["ray_startup_s"] = time.perf_counter() - t0
            print(f"  ray start-up (init + first run)  {figures['ray_startup_s']:6.2f} s")
            ex.close()
        for workers in sorted({1, cpus}):
            ex = make_executor(engine, workers)
            try:
                timed(ex, work[: 2 * workers])  # start the workers
                seconds = timed(ex, work)
            finally:
                ex.close()
            rate = len(work) / seconds
            eff = rate / (workers * base)
            figures[f"{engine}_{workers}_runs_per_s"] = rate
            figures[f"{engine}_{workers}_efficiency"] = eff
            line = f"  {engine}, {workers} worker{'s' if workers > 1 else ' '}            {rate:7.2f} runs/s   efficiency {eff:.2f}"
            if workers == 1:
                overhead = (seconds - inline) / inline
                figures[f"{engine}_overhead"] = overhead
                line += f"   per-run overhead {100 * overhead:+.1f} % of the simulation"
            print(line)
    return figures


if __name__ == "__main__":
    main()
