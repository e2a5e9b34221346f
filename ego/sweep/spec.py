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
from ego.specs import MAX_SEED, SpecReader, is_whole, param_types, read_spec, run_id
from ego.specs import check_requirements as check_run_requirements

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
    r = SpecReader(data, source, _TOP)
    controllers = r.read_controllers(data.get("controllers"))
    seeds = _seeds(data.get("seeds", 1), r.bad)
    fixed = r.table("set")
    grid = r.table("grid")
    # the grid's size before any value is checked (each check builds a scenario: 20 million
    # of them would take hours); a [sample] multiplies it by n, checked below
    if all(isinstance(v, list) for v in grid.values()):
        early = math.prod(len(v) for v in grid.values()) * len(controllers) * len(seeds)
        if early > MAX_RUNS:
            raise r.bad(f"expands to {early:,} runs; the limit is {MAX_RUNS:,}")
    r.fixed()
    _check_grid(r, fixed, grid)
    sample = _sample(r, fixed, grid) if data.get("sample") is not None else None
    requirements = r.requirements()
    spec = SweepSpec(
        r.scenario,
        tuple(controllers),
        seeds,
        dict(fixed),
        {k: list(v) for k, v in grid.items()},
        sample,
        source,
        requirements,
        requirement_period=r.period(),
    )
    total = spec.count()
    if total > MAX_RUNS:
        raise r.bad(f"expands to {total:,} runs; the limit is {MAX_RUNS:,}")
    _check_points(r, spec)
    return spec


def _check_grid(r: SpecReader, fixed: dict, grid: dict) -> None:
    """``[grid]``: each axis a known parameter (not also in [set]), a non-empty list of
    values of one kind, each checked with the fixed values."""
    for name, values in grid.items():
        r.known(name, "grid")
        if not isinstance(values, list) or not values:
            raise r.bad(f"[grid] {name} must be a non-empty list of values")
        if name in fixed:
            raise r.bad(f"{name} is both fixed in [set] and swept in [grid]")
        for v in values:
            r.check({**fixed, name: v}, f"[grid] {name}")
        _one_kind(name, values, r.bad)


def _sample(r: SpecReader, fixed: dict, grid: dict) -> Sample:
    """``[sample]``: the method, ``n``, the sampler's seed and each parameter's range, both
    ends checked with the fixed values and the grid's first points."""
    sample_data = r.data["sample"]
    if not isinstance(sample_data, dict):
        raise r.bad("[sample] must be a table")
    method = sample_data.get("method", "lhs")
    if method not in METHODS:
        raise r.bad(f"[sample] method {method!r} (allowed: {', '.join(METHODS)}){did_you_mean(method, METHODS)}")
    n = sample_data.get("n")
    if not is_whole(n, 1, math.inf):
        raise r.bad(f"[sample] n must be a whole number of at least 1, got {n!r}")
    sseed = sample_data.get("seed", 0)
    if not is_whole(sseed, 0, MAX_SEED):
        raise r.bad(f"[sample] seed must be a whole number from 0 to {MAX_SEED}, got {sseed!r}")
    ranges = {}
    # a range's ends with the grid's points too (a duration in [grid] bounds a sampled
    # brake time): the first 64 of them, each check a few milliseconds
    points = [dict(zip(grid, combo)) for combo in itertools.islice(itertools.product(*grid.values()), 64)]
    for name, rng in sample_data.items():
        if name in ("method", "n", "seed"):
            continue
        info = r.known(name, "sample")
        ranges[name] = r.number_range("sample", name, info, rng, "put it in [grid]")
        if name in fixed or name in grid:
            raise r.bad(f"{name} is sampled in [sample] and also in [set] or [grid]")
        for end in rng:
            for point in points or [{}]:
                with_grid = "".join(f" with [grid] {k} = {v!r}" for k, v in point.items())
                r.check({**fixed, **point, name: end}, f"[sample] {name}{with_grid}")
    if not ranges:
        raise r.bad("[sample] names no parameter range")
    if method == "sobol" and n & (n - 1):
        raise r.bad(f"[sample] sobol needs n a power of 2 for its balance properties, got {n}")
    return Sample(method, n, ranges, sseed)


def _check_points(r: SpecReader, spec: SweepSpec) -> None:
    """Whole points (combinations a value-by-value check cannot see): every grid point when
    there are not too many, else the first; the first run (with its sample) and the
    requirements against it."""
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
        r.check({**spec.fixed, **point}, where)
    first = next(spec.runs())
    if spec.sample is not None:
        r.check(first.overrides, "the first run")
    if spec.requirements:
        check_requirements(first, spec.requirements, r.bad)


def check_requirements(first: Run, requirements: dict, bad) -> None:
    """Every formula against the signals of the spec's first run (one line on a problem)."""
    check_run_requirements(first.scenario, first.controller, first.seed, first.overrides, requirements, bad)


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
        if not is_whole(value, 1, 100_000):
            raise bad(f"seeds = {value}: give a count from 1 to 100000 or a list of seeds")
        return tuple(range(value))
    if isinstance(value, list) and value:
        for s in value:
            if not is_whole(s, 0, MAX_SEED):
                raise bad(f"seed {s!r} is not a whole number from 0 to {MAX_SEED}")
        if len(set(value)) != len(value):
            raise bad("a seed is listed twice")
        return tuple(value)
    raise bad(f"seeds must be a count or a list of seeds, got {value!r}")
