"""A sweep's specification (TOML, read with ``tomllib``) and its lazily expanded runs.

```toml
scenario = "emergency-brake"
controllers = ["pid", "fuzzy"]      # names as `ego run` takes them
seeds = 2                           # seeds 0..1, or a list [0, 7, 9]
[set]                               # fixed overrides for every run
traffic_density = 5
[grid]                              # full factorial over these values
ego_speed = [20, 25, 30]
lead_decel = [4, 6, 8]
[sample]                            # or/and: n points over ranges
method = "sobol"                    # random | lhs | sobol (scipy.stats.qmc)
n = 256
seed = 0                            # of the sampler (default 0)
lead_gap = [20, 60]
```

Every name and value is checked before anything runs, with the same checks as ``--set``
(a grid's every value, a range's both ends), and the number of runs is computed, not
listed: a spec of billions of runs fails at once. The runs are then generated one by one:
points (grid x sample) in order, and for each point every controller and seed. A run's id
is a hash of scenario, controller, seed and overrides, stable across machines and sessions.
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Iterator
from dataclasses import dataclass, field
from itertools import product
from pathlib import Path
from typing import Any

from ego.params import ConfigError, did_you_mean
from ego.specs import (
    MAX_SEED,
    check_controllers,
    check_keys,
    check_values,
    param_types,
    read_spec,
    run_id,
    scenario_of,
)

#: more runs than this is a mistake, not a sweep
MAX_RUNS = 10_000_000
METHODS = ("random", "lhs", "sobol")
_TOP = ("scenario", "controllers", "seeds", "set", "grid", "sample", "requirements", "requirement_period")
#: grids with at most this many points are checked point by point (combinations of values)
MAX_CHECKED_POINTS = 10_000


@dataclass(frozen=True)
class Run:
    """One run of a sweep: what ``ego run`` would take, and its stable id."""

    run_id: str
    scenario: str
    controller: str
    seed: int
    overrides: dict


@dataclass(frozen=True)
class Sample:
    method: str
    n: int
    ranges: dict  #: name -> (low, high)
    seed: int = 0


@dataclass(frozen=True)
class SweepSpec:
    scenario: str
    controllers: tuple[str, ...]
    seeds: tuple[int, ...]
    fixed: dict = field(default_factory=dict)
    grid: dict = field(default_factory=dict)  #: name -> list of values
    sample: Sample | None = None
    source: str = ""
    #: [requirements] name -> formula, checked on every run (None: the scenario's defaults)
    requirements: dict | None = None
    #: the points as a list (a ParameterValueDistribution file's combinations), instead of grid x sample
    listed: tuple | None = None
    #: requirements on every sample of the trace (0) or on a grid this many seconds apart
    requirement_period: float = 0.0
    #: after each collision, run UN R157's careful driver on the same run too and report
    #: ``collision_preventable`` (``ego sweep --preventable``; a second run per collision)
    preventable: bool = False

    @property
    def swept(self) -> tuple[str, ...]:
        """The parameters that vary between runs (grid, then sample)."""
        if self.listed is not None:
            return tuple(self.listed[0]) if self.listed else ()
        return tuple(self.grid) + (tuple(self.sample.ranges) if self.sample else ())

    def points(self) -> int:
        """How many parameter points: grid combinations x distinct sample points."""
        if self.listed is not None:
            return len(self.listed)
        n = math.prod(len(v) for v in self.grid.values()) if self.grid else 1
        return n * (self._sample_points_count if self.sample else 1)

    @functools.cached_property
    def _sample_points_count(self) -> int:
        """The sample's distinct points: ``n``, or fewer when whole-number parameters alone
        are sampled and two draws fall on the same numbers (counted by drawing them)."""
        assert self.sample is not None
        types = self._types
        if not _whole_numbers(self.sample, types):
            return self.sample.n
        return sum(1 for _ in _sample_points(self.sample, types))

    def count(self) -> int:
        """How many runs: points x controllers x seeds."""
        return self.points() * len(self.controllers) * len(self.seeds)

    def runs(self) -> Iterator[Run]:
        """Every run, generated lazily: for each point, every controller and seed."""
        for point in self._points():
            overrides = {**self.fixed, **point}
            for controller in self.controllers:
                for seed in self.seeds:
                    yield Run(
                        run_id(self.scenario, controller, seed, overrides), self.scenario, controller, seed, overrides
                    )

    def _points(self) -> Iterator[dict]:
        if self.listed is not None:
            yield from self.listed
            return
        names = list(self.grid)
        combos = product(*(self.grid[n] for n in names)) if names else [()]
        for combo in combos:
            base = dict(zip(names, combo))
            if self.sample is None:
                yield base
                continue
            for drawn in _sample_points(self.sample, self._types):
                yield {**base, **drawn}

    @property
    def _types(self) -> dict:
        return param_types(self.scenario, self.controllers)


def _whole_numbers(sample: Sample, infos: dict) -> bool:
    """True when every sampled parameter is a whole number: then two draws can be one point."""
    return all(infos[name].type is int for name in sample.ranges)


def _sample_points(sample: Sample, infos: dict, chunk: int = 4096) -> Iterator[dict]:
    """``sample.n`` points over the ranges (scipy.stats.qmc), in the order drawn.

    A whole-number parameter takes each whole number of its range ``[low, high]`` with the
    same chance (the unit interval cut into ``high - low + 1`` equal parts; an LHS then
    spreads its points over them evenly). When whole-number parameters alone are sampled,
    a point drawn again is left out: the same run twice would count twice in the summary. A
    real-valued parameter (rounded to 6 decimals) makes a repeat as good as impossible, so
    points are not remembered then and a sample of millions costs no memory."""
    import numpy as np
    from scipy.stats import qmc

    names = list(sample.ranges)
    lo = np.array([sample.ranges[k][0] for k in names], dtype=float)
    hi = np.array([sample.ranges[k][1] for k in names], dtype=float)
    d = len(names)
    if sample.method == "lhs":  # stratified over all n at once
        blocks = iter([qmc.LatinHypercube(d=d, seed=sample.seed).random(sample.n)])
    elif sample.method == "sobol":
        engine = qmc.Sobol(d=d, scramble=True, seed=sample.seed)
        blocks = (engine.random(min(chunk, sample.n - i)) for i in range(0, sample.n, chunk))
    else:
        rng = np.random.default_rng(sample.seed)
        blocks = (rng.random((min(chunk, sample.n - i), d)) for i in range(0, sample.n, chunk))
    whole = [infos[name].type is int for name in names]
    # a whole number's share of the unit interval: high - low + 1 parts
    parts = np.array([hi[i] - lo[i] + 1.0 if w else 0.0 for i, w in enumerate(whole)])
    seen: set[tuple] | None = set() if all(whole) else None
    # every whole-number point there is: once all are drawn, the rest of n can only repeat them
    every = math.prod(int(k) for k in parts) if seen is not None else 0
    for block in blocks:
        scaled = lo + block * (hi - lo)
        wholes = lo + np.minimum(np.floor(block * parts), parts - 1.0)
        for row, whole_row in zip(scaled, wholes):
            point = {}
            for name, w, value, k in zip(names, whole, row, whole_row):
                point[name] = int(k) if w else round(float(value), 6)
            if seen is not None:
                key = tuple(point.values())
                if key in seen:
                    continue
                seen.add(key)
                yield point
                if len(seen) == every:
                    return
                continue
            yield point


def load(path: str | Path) -> SweepSpec:
    """Read and validate a spec file; ConfigError (one line, naming the file) on anything wrong."""
    if not isinstance(path, (str, Path)) and not hasattr(path, "__fspath__"):
        raise ConfigError(f"bad sweep spec path {path!r:.60} (expected a path to a .toml file)")
    path = Path(path)
    return parse(read_spec(path, "sweep spec"), str(path))


def parse(data: dict, source: str = "the spec") -> SweepSpec:
    """Validate a spec's contents (see the module docstring)."""

    def bad(msg: str) -> ConfigError:
        return ConfigError(f"{source}: {msg}")

    if not isinstance(data, dict):
        raise bad(f"expected a table of scenario, controllers, ... (got {type(data).__name__})")
    check_keys(data, _TOP, bad)
    scenario, cls = scenario_of(data, bad)
    controllers = data.get("controllers")
    if not isinstance(controllers, list) or not controllers or not all(isinstance(c, str) for c in controllers):
        raise bad('controllers must be a non-empty list of names, e.g. controllers = ["pid"]')
    if len(set(controllers)) != len(controllers):
        dup = next(c for c in controllers if controllers.count(c) > 1)
        raise bad(f"controller {dup!r} is listed twice")
    check_controllers(controllers, cls, bad)
    seeds = _seeds(data.get("seeds", 1), bad)
    infos = param_types(scenario, controllers)

    def known(name: str, where: str):
        info = infos.get(name)
        if info is None:
            raise bad(
                f"[{where}] unknown parameter {name!r} for {scenario} with "
                f"{', '.join(controllers)} (see ego list){did_you_mean(name, infos)}"
            )
        return info

    fixed = data.get("set", {})
    grid = data.get("grid", {})
    sample_data = data.get("sample")
    for section, value in (("set", fixed), ("grid", grid)):
        if not isinstance(value, dict):
            raise bad(f"[{section}] must be a table of parameter = value")
    # the grid's size before any value is checked (each check builds a scenario: 20 million
    # of them would take hours); a [sample] multiplies it by n, checked below
    if all(isinstance(v, list) for v in grid.values()):
        early = math.prod(len(v) for v in grid.values()) * len(controllers) * len(seeds)
        if early > MAX_RUNS:
            raise bad(f"expands to {early:,} runs; the limit is {MAX_RUNS:,}")
    for name, value in fixed.items():
        known(name, "set")
        check_values(scenario, controllers, {name: value}, f"[set] {name}", bad)
    for name, values in grid.items():
        known(name, "grid")
        if not isinstance(values, list) or not values:
            raise bad(f"[grid] {name} must be a non-empty list of values")
        if name in fixed:
            raise bad(f"{name} is both fixed in [set] and swept in [grid]")
        for v in values:
            check_values(scenario, controllers, {**fixed, name: v}, f"[grid] {name}", bad)
        _one_kind(name, values, bad)
    sample = None
    if sample_data is not None:
        if not isinstance(sample_data, dict):
            raise bad("[sample] must be a table")
        method = sample_data.get("method", "lhs")
        if method not in METHODS:
            raise bad(f"[sample] method {method!r} (allowed: {', '.join(METHODS)}){did_you_mean(method, METHODS)}")
        n = sample_data.get("n")
        if not isinstance(n, int) or isinstance(n, bool) or n < 1:
            raise bad(f"[sample] n must be a whole number of at least 1, got {n!r}")
        sseed = sample_data.get("seed", 0)
        if not isinstance(sseed, int) or isinstance(sseed, bool) or not 0 <= sseed <= MAX_SEED:
            raise bad(f"[sample] seed must be a whole number from 0 to {MAX_SEED}, got {sseed!r}")
        ranges = {}
        # a range's ends with the grid's points too (a duration in [grid] bounds a sampled
        # brake time): the first 64 of them, each check a few milliseconds
        points = [dict(zip(grid, combo)) for combo in itertools.islice(itertools.product(*grid.values()), 64)]
        for name, rng in sample_data.items():
            if name in ("method", "n", "seed"):
                continue
            info = known(name, "sample")
            if info.type not in (int, float) or info.choices is not None:
                raise bad(f"[sample] {name} is not a number to sample (put it in [grid])")
            if (
                not isinstance(rng, list)
                or len(rng) != 2
                or not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in rng)
                or not rng[0] < rng[1]
            ):
                raise bad(f"[sample] {name} must be a range [low, high] with low < high, got {rng!r}")
            if name in fixed or name in grid:
                raise bad(f"{name} is sampled in [sample] and also in [set] or [grid]")
            for end in rng:
                for point in points or [{}]:
                    with_grid = "".join(f" with [grid] {k} = {v!r}" for k, v in point.items())
                    check_values(
                        scenario, controllers, {**fixed, **point, name: end}, f"[sample] {name}{with_grid}", bad
                    )
            ranges[name] = (float(rng[0]), float(rng[1]))
        if not ranges:
            raise bad("[sample] names no parameter range")
        if method == "sobol" and n & (n - 1):
            raise bad(f"[sample] sobol needs n a power of 2 for its balance properties, got {n}")
        sample = Sample(method, n, ranges, sseed)
    requirements = None
    if "requirements" in data:
        from ego.requirements import from_table

        requirements = from_table(data["requirements"], source)
    period = spec_period(data, bad)
    spec = SweepSpec(
        scenario,
        tuple(controllers),
        seeds,
        dict(fixed),
        {k: list(v) for k, v in grid.items()},
        sample,
        source,
        requirements,
        requirement_period=period,
    )
    total = spec.count()
    if total > MAX_RUNS:
        raise bad(f"expands to {total:,} runs; the limit is {MAX_RUNS:,}")
    # whole points (combinations a value-by-value check cannot see): every grid point when
    # there are not too many, else the first
    points = math.prod(len(v) for v in spec.grid.values()) if spec.grid else 1
    names = list(spec.grid)
    combos = (
        product(*(spec.grid[n] for n in names))
        if points <= MAX_CHECKED_POINTS
        else [tuple(spec.grid[n][0] for n in names)]
    )
    for combo in combos:
        point = dict(zip(names, combo))
        where = "the run with " + ", ".join(f"{k} = {v!r}" for k, v in point.items()) if point else "the first run"
        check_values(scenario, controllers, {**spec.fixed, **point}, where, bad)
    first = next(spec.runs())
    if sample is not None:
        check_values(scenario, controllers, first.overrides, "the first run", bad)
    if requirements:
        check_requirements(first, requirements, bad)
    return spec


def spec_period(data: dict, bad) -> float:
    """A spec's ``requirement_period`` (s; default 0: every sample of the trace)."""
    from ego.requirements import RequirementError, check_period

    try:
        return check_period(data.get("requirement_period", 0.0), "requirement_period")
    except RequirementError as exc:
        raise bad(str(exc).removeprefix("bad ")) from None


def check_requirements(first: Run, requirements: dict, bad) -> None:
    """Every formula against the signals of the spec's first run (one line on a problem)."""
    from ego.runner import RunSpec, requirements_of, resolve

    spec = RunSpec(first.scenario, first.controller, first.seed, first.overrides, requirements=requirements)
    try:
        requirements_of(resolve(spec))
    except ConfigError as exc:
        raise bad(str(exc)) from None


def _kind(value: Any) -> str:
    if isinstance(value, bool):
        return "true/false"
    if isinstance(value, (int, float)):
        return "numbers"
    if isinstance(value, str):
        return "text"
    return type(value).__name__


def _one_kind(name: str, values: list, bad) -> None:
    """A grid axis holds values of one kind (numbers, text or true/false), each once: a
    column of the results holds one type, and one run id is one run."""
    kinds = {_kind(v) for v in values}
    if len(kinds) > 1:
        raise bad(f"[grid] {name} mixes {' and '.join(sorted(kinds))} ({values!r:.80}); write every value the same way")
    seen = []
    for v in values:
        if any(v == s for s in seen):
            raise bad(f"[grid] {name} lists {v!r} twice")
        seen.append(v)


def _seeds(value: Any, bad) -> tuple[int, ...]:
    if isinstance(value, int) and not isinstance(value, bool):
        if not 1 <= value <= 100_000:
            raise bad(f"seeds = {value}: give a count from 1 to 100000 or a list of seeds")
        return tuple(range(value))
    if isinstance(value, list) and value:
        for s in value:
            if not isinstance(s, int) or isinstance(s, bool) or not 0 <= s <= MAX_SEED:
                raise bad(f"seed {s!r} is not a whole number from 0 to {MAX_SEED}")
        if len(set(value)) != len(value):
            raise bad("a seed is listed twice")
        return tuple(value)
    raise bad(f"seeds must be a count or a list of seeds, got {value!r}")
