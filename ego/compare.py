"""``ego compare``: every controller x seed of one scenario, in parallel processes.

Each run is a :class:`~ego.runner.RunSpec` executed in a worker process (libsumo allows one
simulation per process), writing its own ``.rrd``. A run that fails or diverges becomes a
row with its status; it never stops the comparison. Outputs in ``--out``:

* ``metrics.csv`` - one row per run, every metric (nested ones as dotted columns,
  ``followers.f1.min_gap``);
* ``metrics.md`` - one row per controller: runs by status, then mean +- standard deviation
  over seeds of the scenario's headline metrics;
* ``lateral_error.png``, ``speed.png``, ``steering.png``, ``fx.png`` (and the plots the
  scenario adds: the curve's e_d, e_a, a_x; the platoon's spacing error and acceleration of
  its first and last follower) - the first seed of every controller, one line each;
* ``runs/<controller>-seed<N>.rrd`` - every run's recording.
"""

from __future__ import annotations

import csv
import math
import multiprocessing
import os
import sys
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ego.control import controller_spec
from ego.params import ConfigError, describe
from ego.processes import main_module_hidden
from ego.runner import RunSpec, configure, run, split_overrides
from ego.scenarios import scenario_class
from ego.scenarios.metrics import flatten

#: trace columns kept for the plots: (column, file, y label)
PLOTS = (
    ("e_lat", "lateral_error.png", "lateral error (actual - reference) [m]"),
    ("e_d", "e_d.png", "e_d = distance to the arc centre - R [m]"),
    ("e_a", "e_a.png", "e_a = heading - tangent [rad]"),
    ("speed", "speed.png", "speed [m/s]"),
    ("delta", "steering.png", "front steer angle [rad]"),
    ("Fx", "fx.png", "Fx per driven wheel [N]"),
    ("a_x", "a_x.png", "axial acceleration [m/s^2]"),
)
#: headline metrics for metrics.md, in order, when the scenario reports them
HEADLINE = (
    "max_abs_ed", "final_ed", "max_abs_ea", "final_ea", "time_in_arc", "entry_speed", "exit_speed",
    "lane_change_duration", "max_overshoot", "min_ttc_front", "min_ttc_rear", "min_gap_front",
    "rms_lateral_error", "max_abs_lateral_error_after_10s", "rms_speed_error", "x_settling_time",
    "max_abs_lateral_accel",
    # the platoon (a key ending in "." stands for every flattened metric under it)
    "rms_spacing_error", "max_abs_spacing_error", "min_gap", "min_ttc", "max_abs_accel", "max_abs_jerk",
    "settle_times.", "string_stable", "frequency_gain.",
)


@dataclass
class RunRow:
    controller: str
    seed: int
    status: str
    metrics: dict
    traces: dict = field(default_factory=dict)  # column -> (t, values)
    error: str = ""


def plots_of(spec: RunSpec) -> tuple[tuple[str, str, str], ...]:
    """The standard plots and the scenario's own: (column, file, y label)."""
    cls, config, _, _ = configure(spec)
    return PLOTS + cls.compare_plots(config)


def _one(spec: RunSpec) -> RunRow:
    """Worker: run and keep the metrics (flattened) and the plotted columns (never raises)."""
    try:
        plots = plots_of(spec)
        result = run(spec)
    except Exception as exc:  # noqa: BLE001 - a broken run is a row, not a crash
        return RunRow(spec.controller, spec.seed, "error", {}, error=f"{type(exc).__name__}: {exc}")
    t = result.column("t")
    traces = {c: result.column(c) for c, _, _ in plots if c in result.columns}
    return RunRow(spec.controller, spec.seed, result.status, flatten(result.metrics), {"t": t, **traces})


def plan(scenario: str, controllers: Sequence[str], seeds: int, overrides: dict, out: Path) -> list[RunSpec]:
    """Validate names and overrides, and list the runs (before any process starts)."""
    cls = scenario_class(scenario)
    if not controllers:
        raise ConfigError("--controllers needs at least one name")
    for name in controllers:
        controller_spec(name, cls.task)
    known = {i.name for i in describe(cls.config_cls)}
    for name in controllers:
        known |= {i.name for i in describe(controller_spec(name, cls.task).params)}
    unknown = sorted(set(overrides) - known)
    if unknown:
        raise ConfigError(f"unknown parameter {unknown[0]!r} for {scenario} with "
                          f"{', '.join(controllers)} (see ego list)")
    specs = []
    for name in controllers:
        mine = split_overrides(scenario, name, overrides)
        for seed in range(seeds):
            rrd = out / "runs" / f"{name}-seed{seed}.rrd"
            specs.append(RunSpec(scenario, name, seed, mine, str(rrd), background_recording=False))
    return specs


def _progress(done: int, total: int, row: RunRow, started: float) -> None:
    width = 24
    filled = int(width * done / total)
    bar = "#" * filled + "." * (width - filled)
    what = f"{row.controller} seed {row.seed}: {row.status}"
    line = f"[{bar}] {done}/{total} runs, {time.perf_counter() - started:5.1f} s  {what}"
    if sys.stderr.isatty():
        sys.stderr.write("\r" + line.ljust(100) + ("\n" if done == total else ""))
    else:
        sys.stderr.write(line + "\n")
    sys.stderr.flush()


def compare(scenario: str, controllers: Sequence[str], seeds: int, overrides: dict, out: Path,
            jobs: int | None = None, progress: Callable | None = _progress) -> list[RunRow]:
    """Run everything, write the outputs, return the rows (in controller, seed order)."""
    out = Path(out)
    specs = plan(scenario, controllers, seeds, overrides, out)
    for spec in specs:  # every value too (a bad --set value) before any process starts
        cls, config, ctrl, params = configure(spec)
        cls.build_controller(ctrl, params, config)
    (out / "runs").mkdir(parents=True, exist_ok=True)
    jobs = max(1, min(jobs or os.cpu_count() or 1, len(specs)))
    rows: list[RunRow] = []
    started = time.perf_counter()
    ctx = multiprocessing.get_context("forkserver")
    with ProcessPoolExecutor(max_workers=jobs, mp_context=ctx) as pool:
        with main_module_hidden():  # workers start on the first submissions
            futures = [pool.submit(_one, spec) for spec in specs]
        for future in as_completed(futures):
            rows.append(future.result())
            if progress:
                progress(len(rows), len(specs), rows[-1], started)
    order = {(s.controller, s.seed): i for i, s in enumerate(specs)}
    rows.sort(key=lambda r: order[(r.controller, r.seed)])
    write_csv(rows, out / "metrics.csv")
    write_markdown(scenario, rows, list(controllers), out / "metrics.md")
    write_plots(scenario, rows, list(controllers), out, plots_of(specs[0]))
    return rows


def write_csv(rows: Sequence[RunRow], path: Path) -> None:
    """One row per run, one column per (flattened) metric."""
    keys: list[str] = []
    for r in rows:
        keys += [k for k in r.metrics if k not in keys]
    head = ["controller", "seed", "status", "error"]
    keys = [k for k in keys if k not in head]
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(head + keys)
        for r in rows:
            w.writerow([r.controller, r.seed, r.status, r.error] + ["" if r.metrics.get(k) is None
                                                                  else r.metrics.get(k) for k in keys])


def _mean_spread(values: list) -> str:
    if values and all(isinstance(v, bool) for v in values):
        return f"{sum(values)}/{len(values)}"  # how many runs say yes
    nums = [float(v) for v in values if isinstance(v, (int, float)) and not isinstance(v, bool)
            and v is not None and math.isfinite(v)]
    if not nums:
        return "-"
    mean = float(np.mean(nums))
    text = f"{mean:.3g}"
    if len(nums) > 1:
        spread = float(np.std(nums, ddof=1))
        text += f" +- {0.0 if spread < 1e-9 * max(1.0, abs(mean)) else spread:.2g}"
    if len(nums) < len(values):
        text += f" ({len(nums)}/{len(values)})"
    return text


def headline_keys(rows: Sequence[RunRow]) -> list[str]:
    """The HEADLINE metrics the rows have, prefixes ("settle_times.") expanded in order."""
    keys: list[str] = []
    for k in HEADLINE:
        if k.endswith("."):
            keys += [name for name in dict.fromkeys(n for r in rows for n in r.metrics)
                     if name.startswith(k) and name not in keys]
        elif any(k in r.metrics for r in rows):
            keys.append(k)
    return keys


def write_markdown(scenario: str, rows: Sequence[RunRow], controllers: list[str], path: Path) -> None:
    present = headline_keys(rows)
    lines = [f"# {scenario}: {len(rows)} runs",
             "",
             "Mean +- standard deviation over seeds; (k/n) when only k of n runs have the value; "
             "k/n for a yes/no metric: k of n runs say yes.",
             "",
             "| controller | runs | " + " | ".join(present) + " |",
             "|---|---|" + "---|" * len(present)]
    for name in controllers:
        mine = [r for r in rows if r.controller == name]
        counts: dict[str, int] = {}
        for r in mine:
            counts[r.status] = counts.get(r.status, 0) + 1
        status = ", ".join(f"{n} {s}" for s, n in counts.items())
        cells = [_mean_spread([r.metrics.get(k) for r in mine]) for k in present]
        lines.append(f"| {name} | {status} | " + " | ".join(cells) + " |")
    errors = [r for r in rows if r.error]
    if errors:
        lines += ["", "Errors:", ""] + [f"- {r.controller} seed {r.seed}: {r.error}" for r in errors]
    path.write_text("\n".join(lines) + "\n")


def write_plots(scenario: str, rows: Sequence[RunRow], controllers: list[str], out: Path,
                plots: Sequence[tuple[str, str, str]] = PLOTS) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    first = {}
    for r in rows:
        if r.controller not in first and r.traces:
            first[r.controller] = r
    for column, filename, label in plots:
        if not any(column in r.traces for r in first.values()):
            continue  # not a column of this scenario
        fig, ax = plt.subplots(figsize=(9, 4.5), dpi=110)
        for name in controllers:
            r = first.get(name)
            if r is None or column not in r.traces:
                continue
            ax.plot(r.traces["t"], r.traces[column], label=f"{name} ({r.status})", linewidth=1.3)
        ax.set_xlabel("time [s]")
        ax.set_ylabel(label)
        ax.set_title(f"{scenario}: {label.split(' [')[0]} (seed {min(r.seed for r in rows)})")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best", fontsize=8)
        fig.tight_layout()
        fig.savefig(out / filename)
        plt.close(fig)
