"""The PNGs of ``ego compare`` (and the file writing ``ego sweep``'s plots share).

What to draw comes from the scenario's declarations (:mod:`ego.results.trace`):

* :class:`~ego.results.trace.Plot` - a trace column over time, every run of every
  controller (one thin line per seed, one colour per controller), its references dashed,
  its tolerance band shaded, the declared events marked on the time axis; with ``lines``,
  one panel per controller and one colour per column (the vehicles of a platoon);
* :class:`~ego.results.trace.Trajectory` - the top-down view of each run: the lanes, the
  ego's path, every vehicle of the traffic log (``RunResult.traffic``), the trigger and the
  closest approach with its gap written there;
* :class:`~ego.results.trace.FrequencyResponse` - a platoon's |H(jw)|: the linear theory
  of each PID-like controller and the gains measured between consecutive vehicles.

The runs come as :class:`ego.results.run.RunRow` (controller, seed, status, traces, events,
traffic, lanes). matplotlib runs with its Agg backend; every file is written atomically.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from ego.outputs import atomic_path
from ego.results.metrics import with_unit
from ego.results.trace import FrequencyResponse, Plot, Trajectory

#: at most this many runs get a panel of their own in a trajectory figure
MAX_PANELS = 12
#: (colour, line style) of the constant references of a plot, in order
CONSTANT_STYLES = [("k", "--"), ("tab:red", "-."), ("tab:purple", ":"), ("0.4", (0, (5, 2, 1, 2)))] * 3
DPI = 110


def pyplot():
    """matplotlib.pyplot on the Agg backend (no display, safe in worker processes)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save(fig, path: Path) -> Path:
    """Write ``fig`` to ``path`` atomically (:func:`ego.outputs.atomic_path`; the format
    from the suffix) and close it."""
    path = Path(path)
    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format=path.suffix[1:])
    finally:
        pyplot().close(fig)
    return path


def write_all(
    scenario: str, plots: Sequence, rows: Sequence, controllers: Sequence[str], out: Path, params: Mapping | None = None
) -> list[Path]:
    """Every declared plot some run has the data for, into ``out``; returns the files."""
    written = []
    for plot in plots:
        fig = figure(scenario, plot, rows, controllers, params or {})
        if fig is not None:
            written.append(save(fig, Path(out) / plot.file))
    return written


def figure(scenario: str, plot, rows: Sequence, controllers: Sequence[str], params: Mapping | None = None):
    """The matplotlib Figure of one declaration, or None when no run has its data."""
    runs = [r for name in controllers for r in rows if r.controller == name and r.traces]
    if isinstance(plot, Trajectory):
        return trajectory_figure(scenario, plot, runs)
    if isinstance(plot, FrequencyResponse):
        return frequency_figure(scenario, plot, runs, params or {})
    return time_figure(scenario, plot, runs, list(dict.fromkeys(r.controller for r in runs)))


def _colours(n: int) -> list:
    plt = pyplot()
    cmap = plt.get_cmap("tab10" if n <= 10 else "tab20")
    return [cmap(i % cmap.N) for i in range(n)]


def _finite(values) -> np.ndarray:
    """Infinite values (no object: TTC, gap) become gaps in the line."""
    a = np.asarray(values, dtype=float).copy()
    a[~np.isfinite(a)] = np.nan
    return a


def _seeds_text(runs: Sequence) -> str:
    seeds = sorted({r.seed for r in runs})
    if len(seeds) == 1:
        return f"seed {seeds[0]}"
    return f"all {len(seeds)} seeds ({seeds[0]}-{seeds[-1]}), one thin line each"


def _status_text(runs: Sequence) -> str:
    counts: dict[str, int] = {}
    for r in runs:
        counts[r.status] = counts.get(r.status, 0) + 1
    return ", ".join(f"{n} {s}" for s, n in counts.items())


def _width(n: int) -> float:
    """Line width: thinner as more seeds overlap."""
    return 1.4 if n <= 1 else max(0.6, 1.2 - 0.1 * n)


def time_figure(scenario: str, plot: Plot, runs: Sequence, controllers: Sequence[str]):
    """A trace column (or ``plot.lines``) over time; see the module docstring."""
    plt = pyplot()
    runs = [r for r in runs if plot.column in r.traces]  # with lines, ``column`` is the first
    if not runs:
        return None
    end = max(
        [float(r.traces["t"][-1]) for r in runs if len(r.traces["t"])]
        + [ev.t for r in runs for ev in r.events if any(ev.kind == m.kind for m in plot.markers)]
    )
    controllers = [c for c in controllers if any(r.controller == c for r in runs)]
    panels = controllers if plot.lines else [None]
    fig, axes = plt.subplots(
        len(panels), 1, figsize=(9.5, 1.2 + 3.0 * len(panels)), dpi=DPI, sharex=True, sharey=True, squeeze=False
    )
    colours = _colours(len(plot.lines) if plot.lines else len(controllers))
    unit = runs[0].units.get(plot.column, "")
    for ax, panel in zip(axes[:, 0], panels):
        mine = [r for r in runs if panel is None or r.controller == panel]
        handles = []
        if plot.band is not None:
            handles.append(ax.axhspan(plot.band.lo, plot.band.hi, color="0.6", alpha=0.18, lw=0, label=plot.band.label))
        constants = [ref for ref in plot.refs if not ref.column]
        for ref, (colour, style) in zip(constants, CONSTANT_STYLES):
            handles.append(ax.axhline(ref.value, color=colour, ls=style, lw=1.0, label=ref.label))
        if plot.lines:
            for (column, legend), colour in zip(plot.lines, colours):
                line = None
                for r in mine:
                    if column in r.traces:
                        (line,) = ax.plot(
                            r.traces["t"], _finite(r.traces[column]), color=colour, lw=_width(len(mine)), alpha=0.85
                        )
                if line is not None:
                    line.set_label(legend)
                    handles.append(line)
            ax.set_title(f"{panel} ({_status_text(mine)})", fontsize=9)
        else:
            for name, colour in zip(controllers, colours):
                own = [r for r in mine if r.controller == name]
                line = None
                for r in own:
                    (line,) = ax.plot(
                        r.traces["t"], _finite(r.traces[plot.column]), color=colour, lw=_width(len(own)), alpha=0.85
                    )
                line.set_label(f"{name} ({_status_text(own)})")
                handles.append(line)
        handles += _column_refs(ax, plot, mine, colours if not plot.lines else None, controllers)
        handles += _markers(ax, plot, mine, controllers, colours if not plot.lines else None)
        if plot.ylim is not None:
            ax.set_ylim(*plot.ylim)
        ax.set_xlim(0.0, 1.01 * end or 1.0)
        ax.grid(True, alpha=0.3)
        ax.set_ylabel(with_unit(plot.label, unit))
        ax.legend(handles=handles, loc="best", fontsize=7)
    axes[-1, 0].set_xlabel(with_unit("time", runs[0].units.get("t", "s")))
    fig.suptitle(f"{scenario}: {plot.label} - {_seeds_text(runs)}", fontsize=10)
    fig.tight_layout()
    return fig


def _column_refs(ax, plot: Plot, runs: Sequence, colours, controllers) -> list:
    """References from trace columns, dashed: in each controller's colour (one panel for
    all), or black (a panel per controller)."""
    handles = []
    for ref in plot.refs:
        if not ref.column:
            continue
        line = None
        for r in runs:
            if ref.column in r.traces:
                colour = colours[controllers.index(r.controller)] if colours else "k"
                (line,) = ax.plot(
                    r.traces["t"], _finite(r.traces[ref.column]), color=colour, ls="--", lw=0.9, alpha=0.8
                )
        if line is not None:
            (proxy,) = ax.plot([], [], color="k", ls="--", lw=0.9, label=ref.label)
            handles.append(proxy)
    return handles


def _markers(ax, plot: Plot, runs: Sequence, controllers, colours) -> list:
    """The declared events of every run: a dotted vertical line and a symbol on the top edge."""
    handles = []
    transform = ax.get_xaxis_transform()  # x in data, y in axes fraction
    for i, marker in enumerate(plot.markers):
        y = 0.97 - 0.05 * i  # one row per kind, so events at the same time stay apart
        seen = False
        for r in runs:
            colour = colours[controllers.index(r.controller)] if colours else "k"
            for ev in r.events:
                if ev.kind != marker.kind:
                    continue
                seen = True
                ax.axvline(ev.t, color=colour, ls=":", lw=0.8, alpha=0.6)
                ax.plot([ev.t], [y], marker=marker.symbol, color=colour, ms=6, transform=transform, ls="")
        if seen:
            (proxy,) = ax.plot([], [], marker=marker.symbol, color="0.3", ls=":", lw=0.8, label=marker.label)
            handles.append(proxy)
    return handles


# --- top-down view --------------------------------------------------------------------------


def _lane_edges(width: float, points) -> tuple[np.ndarray, np.ndarray]:
    """The left and right edges of a lane from its centre line (m)."""
    p = np.asarray(points, dtype=float)
    d = np.gradient(p, axis=0)
    n = np.column_stack([-d[:, 1], d[:, 0]]) / np.linalg.norm(d, axis=1)[:, None]
    return p + 0.5 * width * n, p - 0.5 * width * n


def _box(ax, x, y, heading, length, width, **style) -> None:
    c, s = math.cos(heading), math.sin(heading)
    corners = np.array(
        [
            (0.5 * length, 0.5 * width),
            (-0.5 * length, 0.5 * width),
            (-0.5 * length, -0.5 * width),
            (0.5 * length, -0.5 * width),
            (0.5 * length, 0.5 * width),
        ]
    )
    ax.plot(x + corners[:, 0] * c - corners[:, 1] * s, y + corners[:, 0] * s + corners[:, 1] * c, **style)


def _at(t: np.ndarray, when: float) -> int:
    return int(np.clip(np.searchsorted(t, when), 0, len(t) - 1))


def trajectory_figure(scenario: str, decl: Trajectory, runs: Sequence):
    """One panel per run (up to MAX_PANELS): see :class:`~ego.results.trace.Trajectory`."""
    plt = pyplot()
    runs = [r for r in runs if decl.x in r.traces and decl.y in r.traces and len(r.traces["t"])]
    if not runs:
        return None
    shown = runs[:MAX_PANELS]
    fig, axes = plt.subplots(len(shown), 1, figsize=(12, 0.9 + 2.3 * len(shown)), dpi=DPI, squeeze=False)
    controllers = list(dict.fromkeys(r.controller for r in runs))
    colours = _colours(len(controllers))
    for ax, r in zip(axes[:, 0], shown):
        _trajectory_panel(ax, decl, r, colours[controllers.index(r.controller)])
    axes[-1, 0].set_xlabel("x [m]")
    more = f" (first {len(shown)} of {len(runs)} runs)" if len(shown) < len(runs) else ""
    fig.suptitle(f"{scenario}: top-down paths, the ego and every vehicle within 50 m of it{more}", fontsize=10)
    fig.tight_layout()
    return fig


def _trajectory_panel(ax, decl: Trajectory, r, colour) -> None:
    t, ex, ey = r.traces["t"], r.traces[decl.x], r.traces[decl.y]
    lo_x, hi_x = float(np.min(ex)) - 25.0, float(np.max(ex)) + 25.0
    lo_y, hi_y = float(np.min(ey)), float(np.max(ey))
    for width, points in r.lanes:
        p = np.asarray(points, dtype=float)
        for edge in _lane_edges(width, p):
            ax.plot(edge[:, 0], edge[:, 1], color="0.55", lw=0.8)
        ax.plot(p[:, 0], p[:, 1], color="0.8", lw=0.6, ls=(0, (6, 6)))
    log = r.traffic
    trig = next((ev.t for ev in r.events if ev.kind == decl.trigger), None)
    gaps = [_finite(r.traces[c]) for c in (decl.gap, *decl.other_gaps) if c in r.traces]
    closest = None
    if gaps:
        g = np.fmin.reduce(gaps) if len(gaps) > 1 else gaps[0]
        if np.isfinite(g).any():
            k = int(np.nanargmin(g))
            closest = (float(t[k]), float(g[k]), k)
    # (time, line style of the outlines drawn then, what happened)
    moments = [
        (m, style, what)
        for m, style, what in ((trig, "--", "trigger"), (closest[0] if closest else None, "-", "closest approach"))
        if m is not None
    ]
    if log is not None and len(log):
        lo_y, hi_y = _traffic_outlines(ax, log, moments, lo_y, hi_y)
    ax.plot(ex, ey, color=colour, lw=1.6, label=f"ego ({r.controller})")
    if decl.ego_box is not None:
        _ego_outlines(ax, decl.ego_box, t, ex, ey, moments, colour)
    for _, style, what in moments:
        ax.plot([], [], color="0.3", ls=style, lw=1.0, label=f"outlines at the {what}")
    if trig is not None:
        k = _at(t, trig)
        ax.plot(ex[k], ey[k], marker="^", color="k", ms=8, ls="", label=f"trigger at {trig:.2f} s")
    if closest is not None:
        when, gap, k = closest
        ax.plot(
            ex[k],
            ey[k],
            marker="o",
            mfc="none",
            mec="r",
            ms=10,
            mew=1.5,
            ls="",
            label=f"closest approach at {when:.2f} s",
        )
        ax.annotate(
            f"gap {gap:.2f} m\nat {when:.2f} s",
            (ex[k], ey[k]),
            xytext=(10, 12),
            textcoords="offset points",
            fontsize=8,
            color="r",
            arrowprops={"arrowstyle": "-", "color": "r", "lw": 0.8},
        )
    ax.set_xlim(lo_x, hi_x)
    ax.set_ylim(lo_y - 4.0, hi_y + 4.0)
    ax.set_ylabel("y [m]")
    ax.set_title(f"{r.controller} seed {r.seed}: {r.status}", fontsize=9)
    ax.grid(True, alpha=0.2)
    ax.legend(loc="best", fontsize=7, ncol=3)


def _traffic_outlines(ax, log, moments: list, lo_y: float, hi_y: float) -> tuple[float, float]:
    """Every logged vehicle's path, its name, and its outline at each moment (one SUMO step
    off at most); the y range widened to the paths."""
    steps = np.diff(np.unique(log.t))
    # a vehicle's outline is drawn at its logged pose nearest to the moment, one SUMO step off at most
    reach = 1.0001 * float(steps.min()) if len(steps) else 0.0
    cmap = pyplot().get_cmap("tab20b")  # apart from the controllers' tab10 colours
    for i, vid in enumerate(log.ids):
        rows = np.flatnonzero(log.vehicle == i)
        vx, vy = log.x[rows], log.y[rows]
        col = cmap((4 * i + i // 5) % 20)  # a new hue for each of the first five
        ax.plot(vx, vy, color=col, lw=1.0, alpha=0.8)
        ax.annotate(vid, (vx[0], vy[0]), fontsize=6, color=col, xytext=(0, 3), textcoords="offset points")
        lo_y, hi_y = min(lo_y, float(vy.min())), max(hi_y, float(vy.max()))
        for when, style, _ in moments:  # its outline at the trigger and at the closest approach
            j = rows[np.argmin(np.abs(log.t[rows] - when))]
            if abs(log.t[j] - when) <= reach:
                _box(ax, log.x[j], log.y[j], log.heading[j], log.length[j], log.width[j], color=col, lw=1.0, ls=style)
    return lo_y, hi_y


def _ego_outlines(ax, ego_box: tuple, t, ex, ey, moments: list, colour) -> None:
    """The ego's outline (``ego_box``: length, width, centre ahead of the traced point) at
    each moment, heading along its path."""
    length, width, ahead = ego_box
    for when, style, _ in moments:
        k = _at(t, when)
        k0, k1 = max(k - 1, 0), min(k + 1, len(t) - 1)
        heading = math.atan2(ey[k1] - ey[k0], ex[k1] - ex[k0]) if k1 > k0 else 0.0
        _box(
            ax,
            ex[k] + ahead * math.cos(heading),
            ey[k] + ahead * math.sin(heading),
            heading,
            length,
            width,
            color=colour,
            lw=1.4,
            ls=style,
        )


# --- string stability ------------------------------------------------------------------------


def pid_gains(params, traces: Mapping, decl: FrequencyResponse) -> tuple[float, float, float, float] | None:
    """(kp, ki, kd, delay) of a controller for the linear theory: its parameters ``kp``,
    ``ki``, ``kd``, or the run's mean of its signals of those names (an adaptive PID); the
    delay is half its control period (a held command). None for another law."""
    period = float(getattr(params, "period", 0.0) or 0.0)
    if all(hasattr(params, k) for k in ("kp", "ki", "kd")):
        return float(params.kp), float(params.ki), float(params.kd), 0.5 * period
    means = []
    for k in ("kp", "ki", "kd"):
        cols = [traces[c] for c in decl.gain_columns if c.startswith(k + "_") and c in traces]
        if not cols:
            return None
        means.append(float(np.mean([np.mean(c) for c in cols])))
    return (*means, 0.5 * period)


def measured_gains(
    t: np.ndarray, up: np.ndarray, down: np.ndarray, share: float = 0.1
) -> tuple[np.ndarray, np.ndarray]:
    """(omega rad/s, |V_down / V_up|) at the frequencies where the upstream speed has at
    least ``share`` of its strongest component: the ratio of the two speeds' spectra (an
    empirical transfer function estimate, Hann window, mean removed)."""
    if len(t) < 16:
        return np.zeros(0), np.zeros(0)
    dt = float(t[1] - t[0])
    w = np.hanning(len(t))
    U = np.fft.rfft((up - up.mean()) * w)
    D = np.fft.rfft((down - down.mean()) * w)
    omega = 2.0 * math.pi * np.fft.rfftfreq(len(t), dt)
    mag = np.abs(U)
    mag[0] = 0.0
    keep = mag >= share * mag.max() if mag.max() > 0 else np.zeros(len(mag), bool)
    keep[0] = False
    return omega[keep], np.abs(D[keep]) / mag[keep]


def frequency_figure(scenario: str, decl: FrequencyResponse, runs: Sequence, params: Mapping):
    """|H(jw)| over w: theory lines, measured points; see the module docstring."""
    from ego.scenarios import string_stability as ss

    plt = pyplot()
    runs = [r for r in runs if all(c in r.traces for c in decl.speeds)]
    if not runs:
        return None
    controllers = list(dict.fromkeys(r.controller for r in runs))
    colours = _colours(len(controllers))
    fig, ax = plt.subplots(figsize=(9.5, 5.0), dpi=DPI)
    omegas = np.logspace(-2, 1, 400)
    span = [np.inf, 0.0]
    for name, colour in zip(controllers, colours):
        own = [r for r in runs if r.controller == name]
        for r in own:
            t = r.traces["t"]
            keep = t >= decl.transient
            for k in range(len(decl.speeds) - 1):
                w, g = measured_gains(t[keep], r.traces[decl.speeds[k]][keep], r.traces[decl.speeds[k + 1]][keep])
                ax.plot(w, g, ls="", marker="os^Dv<>p*h"[k % 10], ms=3.5, color=colour, alpha=0.55)
                if len(w):
                    span = [min(span[0], w.min()), max(span[1], w.max())]
                if decl.omega is not None:
                    g1 = ss.sine_gain(
                        t[keep], r.traces[decl.speeds[k]][keep], r.traces[decl.speeds[k + 1]][keep], decl.omega
                    )
                    if g1 is not None:
                        ax.plot([decl.omega], [g1], marker="*", ms=13, color=colour, mec="k", ls="")
        gains = pid_gains(params.get(name), own[0].traces, decl)
        if gains is not None:
            kp, ki, kd, delay = gains
            h = np.abs(ss.pid_transfer(omegas, kp, ki, kd, decl.headway, decl.lag, delay))
            ax.plot(
                omegas,
                h,
                color=colour,
                lw=1.8,
                label=f"{name}: theory (kp {kp:.3g}, ki {ki:.3g}, kd {kd:.3g}), peak {h.max():.3f}",
            )
        ax.plot(
            [],
            [],
            ls="",
            marker="o",
            color=colour,
            label=f"{name}: measured ({len(own)} run{'s' if len(own) > 1 else ''})",
        )
    ax.axhline(1.0, color="k", ls="--", lw=1.0, label="|H| = 1: string stability limit")
    for k in range(len(decl.speeds) - 1):
        ax.plot([], [], ls="", marker="os^Dv<>p*h"[k % 10], color="0.4", label=f"{decl.names[k]}->{decl.names[k + 1]}")
    if decl.omega is not None:
        ax.plot(
            [],
            [],
            ls="",
            marker="*",
            ms=11,
            color="0.4",
            mec="k",
            label=f"gain at the leader's sine ({decl.omega:g} rad/s)",
        )
    ax.set_xscale("log")
    if span[1] > 0:
        ax.set_xlim(max(1e-2, min(0.05, 0.5 * span[0])), min(10.0, max(3.0, 2.0 * span[1])))
    ax.set_ylim(0.0, 2.0)
    ax.set_xlabel("angular frequency w [rad/s]")
    ax.set_ylabel("|H(jw)| = |V_i / V_(i-1)|")
    ax.set_title(
        f"{scenario}: string stability, headway {decl.headway:g} s, lag {decl.lag:g} s - {_seeds_text(runs)}",
        fontsize=9,
    )
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="upper right", fontsize=7)
    fig.tight_layout()
    return fig
