"""``ego sweep FILE.xosc``: a ParameterValueDistribution file as a sweep's list of points.

The file's combinations (:mod:`ego.openscenario.distribution`) are filtered by the scenario
file's value constraints before anything runs; ``sample`` keeps a seeded subsample of the
rest. The result is a :class:`~ego.sweep.spec.SweepSpec` whose ``listed`` points carry the
file's parameter values, so results.parquet, resume and the engines are the TOML specs'.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ego.params import ConfigError, did_you_mean
from ego.specs import check_controllers, check_values, scenario_of
from ego.sweep.spec import MAX_RUNS, SweepSpec

_WHOLE = ("integer", "int", "unsignedInt", "unsignedShort")


@dataclass(frozen=True)
class Variation:
    spec: SweepSpec
    total: int  #: combinations in the file
    discarded: int  #: of them outside the template's value constraints
    remaining: int  #: total - discarded (the sample is drawn from these)


def load(path: str, controllers: list[str], sample: int | None = None, seed: int = 0) -> Variation:
    """The sweep of distribution file ``path`` with ``controllers`` (one seed, 0)."""
    from ego.openscenario import distribution
    from ego.openscenario.loader import convert, declared_parameters

    def bad(msg: str) -> ConfigError:
        return ConfigError(f"{path}: {msg}")

    dist = distribution.read(path, seed=None)
    params = declared_parameters(dist.scenario)
    for name in dist.columns:
        if name not in params:
            raise bad(f"unknown parameter {name!r} (not declared in {dist.scenario}){did_you_mean(name, params)}")
    distribution.fill_defaults(dist, {k: p.value for k, p in params.items()})
    scenario, cls = scenario_of({"scenario": dist.scenario}, bad)
    check_controllers(controllers, cls, bad)
    if dist.total * len(controllers) > MAX_RUNS:
        raise bad(f"expands to {dist.total * len(controllers):,} runs; the limit is {MAX_RUNS:,}")
    for name, col in dist.columns.items():  # a drawn number for a whole-number parameter: the nearest one
        if dist.kind == "stochastic" and params[name].type in _WHOLE and col.dtype == float:
            dist.columns[name] = np.rint(col)
    mask = distribution.constraint_mask(dist, params)
    keep = np.flatnonzero(mask)
    remaining = len(keep)
    if sample is not None:
        if not 1 <= sample:
            raise ConfigError(f"bad value for --sample: {sample} (expected a whole number >= 1)")
        if sample < remaining:
            keep = np.sort(np.random.default_rng(seed).choice(keep, size=sample, replace=False))
    names = list(dist.columns)
    points = []
    for i in keep.tolist():
        point = {}
        for n in names:
            try:
                point[n] = convert(params[n].type, dist.columns[n][i], f"parameter {n!r}")
            except ValueError as exc:
                raise bad(str(exc)) from None
        points.append(point)
    if not points:
        raise bad(f"all {dist.total:,} combinations break the value constraints of {dist.scenario}: nothing to run")
    check_values(scenario, controllers, points[0], "the first run", bad)
    spec = SweepSpec(scenario, tuple(controllers), (0,), {}, {}, None, path, None, tuple(points))
    return Variation(spec, dist.total, dist.total - remaining, remaining)
