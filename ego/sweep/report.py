"""A sweep's summary (markdown) and envelope plots, from its results table.

**Reading an envelope plot** (``envelope_<X>_<Y>[_<METRIC>].png``): one column per
controller. The top row is the outcome of every run at its (X, Y) point: green completed,
light green ended (the duration ran out first), red collision, black diverged, orange
timeout, grey error; where a point has several runs (seeds) the worst outcome is drawn. The boundary between green and red is the controller's
operating envelope over those two parameters (the others vary or stay fixed as the spec
says). The bottom row, when a metric is asked for, colours each point by that metric (the
mean over its runs), on one colour scale shared by all controllers, so the columns compare.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ego.outputs import write_text
from ego.results import summary
from ego.results.metrics import metric_units, with_unit

#: outcome -> (colour, rank: a point with several runs shows its worst)
OUTCOMES = {
    "completed": ("#2ca02c", 0),
    "ended": ("#98df8a", 1),
    "timeout": ("#ff7f0e", 2),
    "collision": ("#d62728", 4),
    "diverged": ("#000000", 5),
    "error": ("#9e9e9e", 3),
}


def _unit(scenario: str, metric: str) -> str:
    """The declared unit of a (flattened) metric: ``settle_times.brake@10s`` is in the unit
    its prefix ``settle_times.`` declares."""
    from ego.scenarios import scenario_class

    return metric_units(scenario_class(scenario).metrics_declared(), [metric])[metric]


def write_summary(spec, table, path: Path) -> None:
    """Per controller: runs by status, then each headline metric's median, 5th and 95th
    percentiles, minimum and maximum over the runs that have it
    (:func:`ego.results.summary.sweep`)."""
    from ego.scenarios import scenario_class

    text = summary.sweep(
        spec.scenario,
        spec.source,
        spec.swept,
        len(spec.seeds),
        table.to_pylist(),
        spec.controllers,
        scenario_class(spec.scenario).metrics_declared(),
    )
    write_text(path, text)


def write_plots(spec, table, out: Path, x: str, y: str, metric: str | None) -> Path:
    """The envelope plot for (x, y[, metric]); see the module docstring. Returns its path."""
    from ego.plots import pyplot, save

    plt = pyplot()
    data = table.to_pydict()
    rows = 2 if metric else 1
    ncol = len(spec.controllers)
    fig, axes = plt.subplots(
        rows, ncol, figsize=(3.6 * ncol + 1.2, 3.3 * rows + 0.6), dpi=110, squeeze=False, sharex=True, sharey=True
    )
    values_all = []
    points: dict[str, dict] = {}
    for c in spec.controllers:
        pts: dict[tuple, list] = {}
        for i in range(table.num_rows):
            if data["controller"][i] != c or data.get(x, [None])[i] is None or data.get(y, [None])[i] is None:
                continue
            key = (float(data[x][i]), float(data[y][i]))
            pts.setdefault(key, []).append(i)
        points[c] = pts
        if metric and metric in data:
            values_all += [
                v for v in data[metric] if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            ]
    vmin, vmax = (min(values_all), max(values_all)) if values_all else (0.0, 1.0)
    scatter = None
    seen: dict[str, str] = {}
    for j, c in enumerate(spec.controllers):
        ax = axes[0][j]
        pts = points[c]
        counts = []
        for status, (colour, _) in OUTCOMES.items():
            xy = [
                k
                for k, idx in pts.items()
                if max((data["status"][i] for i in idx), key=lambda s: OUTCOMES.get(s, ("", 5))[1]) == status
            ]
            if xy:
                a = np.array(xy)
                ax.scatter(a[:, 0], a[:, 1], s=18, c=colour, edgecolors="none")
                seen[status] = colour
                counts.append(f"{len(xy)} {status}")
        ax.set_title(f"{c}\n{', '.join(counts)}", fontsize=8)
        ax.grid(True, alpha=0.25)
        if metric:
            ax2 = axes[1][j]
            xs, ys, vs = [], [], []
            for (px, py), idx in pts.items():
                vals = [
                    data[metric][i]
                    for i in idx
                    if metric in data
                    and isinstance(data[metric][i], (int, float))
                    and not isinstance(data[metric][i], bool)
                    and math.isfinite(data[metric][i])
                ]
                if vals:
                    xs.append(px)
                    ys.append(py)
                    vs.append(float(np.mean(vals)))
            if vs:
                scatter = ax2.scatter(xs, ys, c=vs, s=18, cmap="viridis", vmin=vmin, vmax=vmax)
            ax2.grid(True, alpha=0.25)
    for ax in axes[-1]:
        ax.set_xlabel(with_unit(x, _param_unit(spec, x)))
    for row in axes:
        row[0].set_ylabel(with_unit(y, _param_unit(spec, y)))
    # one legend for the outcomes and one colour bar for the metric, beside the plots
    fig.subplots_adjust(right=0.82, top=0.84, hspace=0.4)
    handles = [plt.Line2D([], [], marker="o", linestyle="", color=col, label=st) for st, col in seen.items()]
    fig.legend(handles=handles, loc="upper right", fontsize=7, title="outcome\n(worst of a point)", title_fontsize=7)
    if metric and scatter is not None:
        cax = fig.add_axes([0.85, 0.1, 0.02, 0.3])
        bar = fig.colorbar(scatter, cax=cax)
        bar.set_label(with_unit(metric, _unit(spec.scenario, metric)) + "\n(mean of a point's runs)", fontsize=7)
    title = f"{spec.scenario}: outcome over {x} and {y}" + (f"; {metric}" if metric else "")
    fig.suptitle(title, fontsize=10)
    name = f"envelope_{x}_{y}" + (f"_{metric}" if metric else "") + ".png"
    return save(fig, out / name)


def _param_unit(spec, name: str) -> str:
    from ego.runner import parameter_namespace

    info = parameter_namespace(spec.scenario, spec.controllers).get(name)
    return info.unit if info is not None else ""
