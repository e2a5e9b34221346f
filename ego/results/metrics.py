"""Metrics computed from a run's trace (pure numpy), and how flattened metric names map to
their declarations (:class:`~ego.results.trace.Metric`: unit, headline)."""

from __future__ import annotations

import math
import sys
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ego.plugins import METRIC_GROUP, entry_points
from ego.results.trace import Metric


def settling_time(t: np.ndarray, error: np.ndarray, band: float, start: float) -> float | None:
    """Time from ``start`` until |error| stays below ``band`` to the end of the trace (s).

    None when the last sample is still outside the band (not settled).
    """
    t = np.asarray(t)
    error = np.asarray(error)
    after = t >= start
    if not after.any():
        return None
    outside = np.abs(error[after]) >= band
    if outside[-1]:
        return None
    idx = np.flatnonzero(outside)
    t_after = t[after]
    settled_at = t_after[idx[-1] + 1] if idx.size else t_after[0]
    return float(settled_at - start)


def overshoot(offset: np.ndarray, direction: float) -> float:
    """Largest excursion past the target (m); ``offset`` = position - target, ``direction``
    the sign of the motion towards the target (+1 moving up/left, -1 down/right)."""
    if offset.size == 0:
        return 0.0
    return float(max(0.0, np.max(direction * offset)))


def finite_min(values: np.ndarray) -> float | None:
    """Smallest finite value, or None when there is none (e.g. a TTC that stayed infinite)."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    return float(v.min()) if v.size else None


def max_abs(values: np.ndarray) -> float:
    v = np.asarray(values, dtype=float)
    return float(np.max(np.abs(v))) if v.size else 0.0


def json_number(x: float | None, digits: int = 6) -> float | None:
    """Round for JSON; non-finite -> None (JSON has no infinity)."""
    if x is None or not math.isfinite(x):
        return None
    return round(float(x), digits)


def flatten(metrics: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """Nested metrics on one level, keys joined by dots (``followers.f1.min_gap``): for CSV
    columns and text listings."""
    out = {}
    for key, value in metrics.items():
        name = f"{prefix}{key}"
        if isinstance(value, Mapping):
            out.update(flatten(value, name + "."))
        else:
            out[name] = value
    return out


# -- declarations: which Metric a flattened name belongs to ---------------------------------
def declaration(declared: Sequence[Metric], name: str) -> Metric | None:
    """The :class:`~ego.results.trace.Metric` that declares the flattened metric ``name``.

    An exact name wins; otherwise the longest prefix declaration (a name ending in ``"."``)
    that ``name`` starts with, so ``followers.`` can give a default and
    ``followers.f1.min_gap`` a more specific one. None when nothing declares it.
    """
    best: Metric | None = None
    for m in declared:
        if m.name == name:
            return m
        if m.name.endswith(".") and name.startswith(m.name) and (best is None or len(m.name) > len(best.name)):
            best = m
    return best


def metric_units(declared: Sequence[Metric], names: Iterable[str]) -> dict[str, str]:
    """Flattened metric name -> its declared unit (``""`` where nothing declares it)."""
    out = {}
    for name in names:
        m = declaration(declared, name)
        out[name] = m.unit if m is not None else ""
    return out


def headline_names(declared: Sequence[Metric], names: Iterable[str]) -> list[str]:
    """The headline metrics among the flattened ``names``: in declaration order, a prefix
    declaration expanded over the names under it in the order they come."""
    names = list(dict.fromkeys(names))
    owner = {n: declaration(declared, n) for n in names}
    return [n for m in declared if m.headline for n in names if owner[n] is m]


def with_unit(name: str, unit: str) -> str:
    """``"min_gap [m]"``; the bare name for a pure number (``"-"``) or an unknown unit (``""``)."""
    return name if unit in ("", "-") else f"{name} [{unit}]"


@dataclass(frozen=True)
class TraceMetric:
    """A metric every run reports whose scenario's trace has the ``needs`` columns: ``fn``
    maps the trace (column name -> array, SI units) to a number, a bool or None, declared
    by ``metric`` (name, unit, description). A pure function of the trace: no scenario state."""

    metric: Metric
    needs: tuple[str, ...]
    fn: Callable[[Mapping[str, np.ndarray]], Any]


#: the registered trace metrics by name (:func:`register_metric`)
TRACE_METRICS: dict[str, TraceMetric] = {}


def register_metric(metric: TraceMetric) -> TraceMetric:
    """Make ``metric`` part of every run whose trace has its columns (a later one of the same
    name replaces it)."""
    TRACE_METRICS[metric.metric.name] = metric
    return metric


def load_metric_plugins() -> None:
    """Register the ``ego.metrics`` entry points (a :class:`TraceMetric` each), once per
    process; a plugin that fails to load is a warning, not an error."""
    for ep in entry_points(METRIC_GROUP):
        try:
            obj = ep.load()
            if not isinstance(obj, TraceMetric):
                raise TypeError("not an ego.results.metrics.TraceMetric")
            TRACE_METRICS.setdefault(obj.metric.name, obj)
        except Exception as exc:  # noqa: BLE001
            print(
                f"ego: warning: metric plugin {ep.name!r} ({ep.value}) not loaded: {type(exc).__name__}: {exc}",
                file=sys.stderr,
            )


def trace_metrics_declared(columns: Iterable[str]) -> tuple[Metric, ...]:
    """The declarations of the registered trace metrics a trace with ``columns`` reports."""
    load_metric_plugins()
    have = set(columns)
    return tuple(m.metric for m in TRACE_METRICS.values() if have.issuperset(m.needs))


def trace_metrics(trace: np.ndarray, names: Sequence[str], columns: Iterable[str]) -> dict[str, Any]:
    """The registered trace metrics of a run: ``trace`` (rows x ``names``) of a scenario whose
    declared trace ``columns`` the metrics are chosen by (:func:`trace_metrics_declared`)."""
    load_metric_plugins()
    if not TRACE_METRICS:
        return {}
    have = set(columns)
    named = {n: trace[:, i] for i, n in enumerate(names)}
    return {m.metric.name: m.fn(named) for m in TRACE_METRICS.values() if have.issuperset(m.needs)}
