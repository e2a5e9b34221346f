"""A falsification spec (TOML): what to search, for which requirement, with what budget.

```toml
scenario = "emergency-brake"
controllers = ["fuzzy-pid"]          # one search per controller, one after another
requirement = "no_avoidable_collision"   # a name from [requirements] or the scenario's defaults
seed = 0                             # SUMO's seed (or a range [low, high] searched as a whole number)
seeds_per_point = 3                  # optional: each point runs with seeds seed..seed+2, its
                                     # robustness the worst of them (default 1: the seed alone)
budget = 500                         # runs per controller (--budget overrides)
[requirements]                       # optional: name = "formula" (default: the scenario's set)
no_avoidable_collision = "always (not avoidable_collision)"
[set]                                # fixed for every run
lead_speed = -1
[search]                             # the dimensions: [low, high] numbers (a whole-number
ego_speed = [10, 36]                 # parameter is an integer dimension), or [false, true]
block_left = [false, true]           # (a categorical dimension)
```

The optimisers see each dimension's type (:meth:`FalsifySpec.kinds`): a boolean is
categorical, a whole-number parameter with whole-number ends (and a searched seed range) an
integer dimension; the blind baselines sample the cube and the value is rounded. The SUMO
seed is noise, not a smooth dimension (neighbouring seeds are unrelated): fix it, or with
``seeds_per_point = k`` run each point with k seeds and keep the worst robustness (k runs of
the budget per point).

Every name and value is checked as ``ego sweep`` checks its spec (the same helpers), the
formulas as ``--require`` checks them: one line, before anything runs.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ego.params import ConfigError, did_you_mean
from ego.specs import MAX_SEED, SpecReader, check_requirements, is_whole, read_spec, run_id

_TOP = (
    "scenario",
    "controllers",
    "controller",
    "requirement",
    "seed",
    "budget",
    "seeds_per_point",
    "requirements",
    "requirement_period",
    "set",
    "search",
)
#: the float values of a run are rounded to this many decimals: what falsified.md prints
#: is exactly what ran
DIGITS = 4


@dataclass(frozen=True)
class Dim:
    """One searched dimension: a parameter (``float``, ``int``, ``bool``) or the seed."""

    name: str
    kind: str
    lo: float
    hi: float

    def value(self, u: float):
        """The value at ``u`` in [0, 1]."""
        u = min(1.0, max(0.0, float(u)))
        if self.kind == "bool":
            return bool(u >= 0.5)
        x = self.lo + u * (self.hi - self.lo)
        if self.kind in ("int", "seed"):
            return int(min(self.hi, max(self.lo, round(x))))
        return round(x, DIGITS)

    def unit(self, value) -> float:
        """The inverse of :meth:`value` (the point's position in [0, 1])."""
        if self.kind == "bool":
            return 0.75 if value else 0.25
        return 0.0 if self.hi == self.lo else (float(value) - self.lo) / (self.hi - self.lo)


@dataclass(frozen=True)
class FalsifySpec:
    scenario: str
    controllers: tuple[str, ...]
    requirement: str
    requirements: dict  #: name -> formula, every one checked on every run
    dims: tuple[Dim, ...]
    fixed: dict = field(default_factory=dict)
    seed: int | None = 0  #: the fixed seed, None when searched
    budget: int = 200
    source: str = ""
    #: each point runs with this many seeds (its seed, seed + 1, ...), the worst robustness kept
    seeds_per_point: int = 1
    #: requirements on every sample of the trace (0) or on a grid this many seconds apart
    requirement_period: float = 0.0

    @property
    def formula(self) -> str:
        return self.requirements[self.requirement]

    @property
    def kinds(self) -> tuple:
        """Each dimension's type for the optimisers (:class:`ego.falsify.optimizers.Kind`)."""
        from ego.falsify.optimizers import Kind

        out = []
        for d in self.dims:
            if d.kind == "bool":
                out.append(Kind("bool", 2))
            elif d.kind in ("int", "seed") and d.lo.is_integer() and d.hi.is_integer():
                out.append(Kind("int", int(d.hi - d.lo) + 1))
            else:
                out.append(Kind())
        return tuple(out)

    def runs_of(self, seed: int, overrides: dict) -> list[tuple[int, dict]]:
        """The runs of one point: its seed and the next ``seeds_per_point - 1``."""
        return [(seed + j, overrides) for j in range(self.seeds_per_point)]

    def point(self, u: np.ndarray) -> tuple[int, dict]:
        """(seed, overrides) of the run at ``u`` in the unit cube."""
        seed = self.seed
        overrides = dict(self.fixed)
        for dim, x in zip(self.dims, u):
            if dim.kind == "seed":
                seed = dim.value(x)
            else:
                overrides[dim.name] = dim.value(x)
        return int(seed), overrides

    def run_id(self, controller: str, seed: int, overrides: dict) -> str:
        return run_id(self.scenario, controller, seed, overrides)

    def check_optimizer(self, name: str) -> None:
        if name == "cma" and len(self.dims) < 2:
            raise ConfigError(
                f"{self.source}: --optimizer cma needs at least 2 searched dimensions "
                f"(the spec has {len(self.dims)}); use bo, random or lhs"
            )


def load(path: str | Path) -> FalsifySpec:
    """Read and validate a spec file (at most 1 MiB, as ``ego sweep`` reads its spec)."""
    path = Path(path)
    return parse(read_spec(path, "falsification spec"), str(path))


def from_distribution(path: str, controllers: list[str], requirement: str | None, budget: int | None) -> FalsifySpec:
    """The search over a ParameterValueDistribution file's ranges (``ego falsify FILE.xosc
    -c CONTROLLER``): its scenario file, each distributed parameter searched over the range
    its distribution spans, one seed (0), the requirement named (default ``no_collision``)."""
    from ego.openscenario.distribution import search_ranges
    from ego.openscenario.xmltree import ScenarioFileError

    try:
        scenario, ranges = search_ranges(path)
    except ScenarioFileError as exc:
        raise ConfigError(str(exc)) from None
    data: dict = {
        "scenario": scenario,
        "controllers": controllers,
        "requirement": requirement or "no_collision",
        "search": ranges,
        "seed": 0,
    }
    if budget is not None:
        data["budget"] = budget
    return parse(data, path)


def parse(data: dict, source: str = "the spec") -> FalsifySpec:
    """Validate a spec's contents (see the module docstring)."""
    from ego.requirements import defaults

    r = SpecReader(data, source, _TOP)
    if "controller" in data and "controllers" in data:
        raise r.bad("give controller or controllers, not both")
    controllers = r.read_controllers(data.get("controllers", [data["controller"]] if "controller" in data else None))
    requirements = r.requirements()
    if requirements is None:
        requirements = defaults(r.scenario, r.cls)
    target = data.get("requirement")
    if not isinstance(target, str) or target not in requirements:
        raise r.bad(
            f"requirement = {target!r}: name one of the spec's requirements "
            f"({', '.join(requirements) or 'none'}){did_you_mean(str(target), requirements)}"
        )
    budget = data.get("budget", 200)
    if not is_whole(budget, 1, 10_000_000):
        raise r.bad(f"budget must be a whole number of runs from 1 to 10000000, got {budget!r}")
    fixed = r.table("set")
    search = r.table("search")
    r.fixed()
    dims = _dims(r, fixed, search)
    fixed_seed, top_seed = _seed(r, dims)
    if not dims:
        raise r.bad("[search] names nothing to search (and the seed is fixed)")
    per_point = data.get("seeds_per_point", 1)
    if not is_whole(per_point, 1, 100) or top_seed + per_point - 1 > MAX_SEED:
        raise r.bad(
            f"seeds_per_point must be a whole number from 1 to 100 (the seeds up to {MAX_SEED}), got {per_point!r}"
        )
    spec = FalsifySpec(
        r.scenario,
        tuple(controllers),
        target,
        requirements,
        tuple(dims),
        dict(fixed),
        fixed_seed,
        budget,
        source,
        per_point,
        r.period(),
    )
    # the corners as a whole (combinations a value-by-value check cannot see) and the formulas
    for u in (np.zeros(len(dims)), np.ones(len(dims))):
        _, overrides = spec.point(u)
        r.check(overrides, "the search's corner")
    seed0, over0 = spec.point(np.zeros(len(dims)))
    check_requirements(r.scenario, controllers[0], seed0, over0, requirements, r.bad)
    return spec


def _dims(r: SpecReader, fixed: dict, search: dict) -> list[Dim]:
    """``[search]``: a dimension per parameter, true/false as [false, true] (categorical), a
    number over ``[low, high]`` (both ends checked)."""
    dims = []
    for name, rng in search.items():
        info = r.known(name, "search")
        if name in fixed:
            raise r.bad(f"{name} is both fixed in [set] and searched in [search]")
        if info.type is bool:
            if rng != [False, True]:
                raise r.bad(f"[search] {name} is true or false: search it as [false, true], got {rng!r}")
            dims.append(Dim(name, "bool", 0.0, 1.0))
            continue
        lo, hi = r.number_range("search", name, info, rng, "fix it in [set]")
        for end in rng:
            r.check({name: end}, f"[search] {name}")
        dims.append(Dim(name, "int" if info.type is int else "float", lo, hi))
    return dims


def _seed(r: SpecReader, dims: list[Dim]) -> tuple[int | None, int]:
    """``seed``: one fixed seed, or a range ``[low, high]`` searched as a whole number
    (appended to ``dims``; the fixed seed None). Returns the fixed seed and the highest
    seed a point starts from."""
    seed = r.data.get("seed", 0)
    if is_whole(seed, 0, MAX_SEED):
        return int(seed), int(seed)
    if isinstance(seed, list) and len(seed) == 2 and all(is_whole(s, 0, MAX_SEED) for s in seed) and seed[0] < seed[1]:
        dims.append(Dim("seed", "seed", float(seed[0]), float(seed[1])))
        return None, seed[1]
    raise r.bad(f"seed must be one seed or a range [low, high] of seeds within 0..{MAX_SEED}, got {seed!r}")
