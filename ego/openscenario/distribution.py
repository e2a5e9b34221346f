"""OpenSCENARIO ParameterValueDistribution files (ASAM OpenSCENARIO 1.2): the one reader.

A distribution file names its ``<ScenarioFile filepath=...>`` (relative to itself) and either
``<Deterministic>`` distributions (the cross product of its single-parameter distributions -
``DistributionSet`` values, ``DistributionRange`` steps - and multi-parameter
``ValueSetDistribution``s, each a list of ``ParameterValueSet`` assignments) or
``<Stochastic numberOfTestRuns randomSeed>`` ones (uniform, normal, log-normal, Poisson,
histogram, probability sets; drawn with one seeded numpy Generator, in file order).

:func:`expand` gives the points as columns (name -> numpy array), then the template's value
constraints are applied vectorised: each constraint is evaluated once per distinct
combination of the values it depends on, not once per point.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ego.openscenario.files import locate, looked
from ego.openscenario.xmltree import Node, ScenarioFileError

#: more combinations than this is a mistake (the sweep's run limit)
MAX_POINTS = 10_000_000
_DETERMINISTIC = ("DeterministicSingleParameterDistribution", "DeterministicMultiParameterDistribution")
_STOCHASTIC = (
    "UniformDistribution",
    "NormalDistribution",
    "LogNormalDistribution",
    "PoissonDistribution",
    "Histogram",
    "ProbabilityDistributionSet",
)


@dataclass
class Distribution:
    path: str  #: the distribution file
    scenario: str  #: the scenario file it names (a path as given to ego run)
    kind: str  #: "deterministic" or "stochastic"
    columns: dict  #: parameter -> numpy array (one value per combination), constraints not applied
    total: int  #: combinations before the constraints


def root_of(path: str | os.PathLike) -> Node | None:
    """The ``<ParameterValueDistribution>`` element of the .xosc file, or None."""
    name = os.fspath(path)
    if not name.lower().endswith(".xosc") or not Path(name).is_file():
        return None
    from ego.openscenario.xmltree import parse_file

    return parse_file(name).child("ParameterValueDistribution")


def scenario_file(path: str, root: Node) -> str:
    """The scenario file a distribution names, checked (exists, is no distribution itself)."""
    node = root.child("ScenarioFile")
    target = node.attrs.get("filepath", "") if node is not None else ""
    if not target:
        raise ScenarioFileError(path, root.line, "<ParameterValueDistribution> needs <ScenarioFile filepath=...>")
    assert node is not None
    # as a scenario's road and catalogs: as written, else in the search folders (ego.openscenario.files)
    found, places = locate(Path(path), target, "ScenarioFile")
    if found is None:
        raise ScenarioFileError(path, node.line, f"ScenarioFile {target!r} not found ({looked(places)})")
    full = os.path.abspath(found)  # absolute: a row's reproducer works from anywhere
    if root_of(full) is not None:
        raise ScenarioFileError(path, node.line, f"{full} is a distribution too (expected a scenario file)")
    return full


def _num(path, node: Node, attr: str, default: float | None = None) -> float:
    raw = node.attrs.get(attr)
    if raw is None:
        if default is not None:
            return default
        raise ScenarioFileError(path, node.line, f"<{node.tag}> needs attribute {attr}")
    try:
        v = float(raw)
    except ValueError:
        raise ScenarioFileError(
            path, node.line, f"bad value for {attr} of <{node.tag}>: {raw!r} (expected a number)"
        ) from None
    if not math.isfinite(v):
        raise ScenarioFileError(
            path, node.line, f"bad value for {attr} of <{node.tag}>: {raw!r} (expected a finite number)"
        )
    return v


def _range(path, node: Node, required: bool = True) -> tuple[float, float] | None:
    r = node.child("Range")
    if r is None:
        if required:
            raise ScenarioFileError(path, node.line, f"<{node.tag}> needs a <Range lowerLimit upperLimit>")
        return None
    lo, hi = _num(path, r, "lowerLimit"), _num(path, r, "upperLimit")
    if lo > hi:
        raise ScenarioFileError(path, r.line, f"<Range> lowerLimit {lo:g} is above upperLimit {hi:g}")
    return lo, hi


def _unsupported(path, node: Node, where: str, allowed: tuple[str, ...]) -> ScenarioFileError:
    return ScenarioFileError(
        path, node.line, f"<{node.tag}> is not supported in <{where}> (supported: {', '.join(allowed)})"
    )


def _column(values: list) -> np.ndarray:
    """Numbers as float64 (a value left out, None: NaN), anything else as an object array of
    strings (None kept): :func:`fill_defaults` gives the left-out values the template's."""
    try:
        return np.asarray([math.nan if v is None else float(v) for v in values], dtype=float)
    except (TypeError, ValueError):
        return np.asarray([None if v is None else str(v) for v in values], dtype=object)


def fill_defaults(dist: Distribution, defaults: Mapping[str, object]) -> None:
    """Give every value a ParameterValueSet left out (NaN or None) the scenario file's
    declared value of that parameter."""
    for name, col in dist.columns.items():
        missing = np.isnan(col) if col.dtype == float else np.asarray([v is None for v in col], dtype=bool)
        if not missing.any():
            continue
        default = defaults[name]
        if col.dtype == float and not isinstance(default, (int, float)):
            col = col.astype(object)
            col[~missing] = [str(v) for v in col[~missing]]
        col[missing] = default if col.dtype == object else float(default)  # type: ignore[arg-type]
        dist.columns[name] = col


def _single(path, node: Node) -> tuple[str, np.ndarray]:
    name = node.attrs.get("parameterName", "")
    if not name:
        raise ScenarioFileError(path, node.line, f"<{node.tag}> needs attribute parameterName")
    inner = [c for c in node.children]
    if len(inner) != 1:
        raise ScenarioFileError(
            path, node.line, f"<{node.tag}> of {name!r} needs one DistributionSet or DistributionRange"
        )
    d = inner[0]
    if d.tag == "DistributionSet":
        elems = d.all("Element")
        if not elems:
            raise ScenarioFileError(
                path, d.line, f"<DistributionSet> of {name!r} is empty (expected <Element value=...>s)"
            )
        for e in elems:
            if "value" not in e.attrs:
                raise ScenarioFileError(path, e.line, "<Element> needs attribute value")
        return name, _column([e.attrs["value"] for e in elems])
    if d.tag == "DistributionRange":
        step = _num(path, d, "stepWidth")
        if step <= 0:
            raise ScenarioFileError(path, d.line, f"bad value for stepWidth of {name!r}: {step:g} (expected > 0)")
        lo, hi = _range(path, d)  # type: ignore[misc]
        n = int(math.floor((hi - lo) / step + 1e-9)) + 1
        if n > MAX_POINTS:
            raise ScenarioFileError(
                path, d.line, f"<DistributionRange> of {name!r} has {n:,} steps; the limit is {MAX_POINTS:,}"
            )
        return name, lo + step * np.arange(n, dtype=float)
    raise _unsupported(path, d, node.tag, ("DistributionSet", "DistributionRange"))


def _multi(path, node: Node) -> dict[str, list]:
    vsd = node.child("ValueSetDistribution")
    if vsd is None:
        other = node.children[0] if node.children else node
        raise _unsupported(path, other, node.tag, ("ValueSetDistribution",))
    sets = vsd.all("ParameterValueSet")
    if not sets:
        raise ScenarioFileError(path, vsd.line, "<ValueSetDistribution> is empty (expected <ParameterValueSet>s)")
    rows = []
    for s in sets:
        row = {}
        for a in s.all("ParameterAssignment"):
            ref, value = a.attrs.get("parameterRef", ""), a.attrs.get("value")
            if not ref or value is None:
                raise ScenarioFileError(path, a.line, "<ParameterAssignment> needs attributes parameterRef and value")
            row[ref] = value
        if not row:
            raise ScenarioFileError(path, s.line, "<ParameterValueSet> is empty (expected <ParameterAssignment>s)")
        rows.append((s.line, row))
    # a set that leaves out a parameter another set assigns keeps the scenario file's value
    # for it (filled in by fill_defaults, once the scenario file is known)
    names = list(dict.fromkeys(n for _, r in rows for n in r))
    return {name: [r.get(name) for _, r in rows] for name in names}


def _deterministic(path, det: Node) -> tuple[dict[str, np.ndarray], int]:
    factors: list[dict[str, np.ndarray]] = []
    for node in det.children:
        if node.tag == "DeterministicSingleParameterDistribution":
            name, col = _single(path, node)
            factors.append({name: col})
        elif node.tag == "DeterministicMultiParameterDistribution":
            factors.append({k: _column(v) for k, v in _multi(path, node).items()})
        else:
            raise _unsupported(path, node, "Deterministic", _DETERMINISTIC)
    if not factors:
        raise ScenarioFileError(path, det.line, "<Deterministic> is empty (expected parameter distributions)")
    seen: set[str] = set()
    for f in factors:
        for name in f:
            if name in seen:
                raise ScenarioFileError(path, det.line, f"parameter {name!r} is distributed twice")
            seen.add(name)
    sizes = [len(next(iter(f.values()))) for f in factors]
    total = math.prod(sizes)
    if total > MAX_POINTS:
        raise ScenarioFileError(path, det.line, f"expands to {total:,} combinations; the limit is {MAX_POINTS:,}")
    # the cross product as index arrays (the first factor varies slowest)
    idx = np.indices(sizes, dtype=np.int64).reshape(len(sizes), -1) if total else np.zeros((len(sizes), 0), int)
    cols = {}
    for i, f in enumerate(factors):
        for name, col in f.items():
            cols[name] = col[idx[i]]
    return cols, total


def _draw(path, node: Node, name: str, rng: np.random.Generator, n: int) -> np.ndarray:
    d = node.children[0] if len(node.children) == 1 else None
    if d is None:
        raise ScenarioFileError(path, node.line, f"<StochasticDistribution> of {name!r} needs one distribution")
    if d.tag == "UniformDistribution":
        lo, hi = _range(path, d)  # type: ignore[misc]
        return rng.uniform(lo, hi, n)
    if d.tag in ("NormalDistribution", "LogNormalDistribution", "PoissonDistribution"):
        mean = _num(path, d, "expectedValue")
        var = 0.0 if d.tag == "PoissonDistribution" else _num(path, d, "variance")
        if var < 0:
            raise ScenarioFileError(path, d.line, f"bad value for variance: {var:g} (expected >= 0)")
        if d.tag == "PoissonDistribution" and mean < 0:
            raise ScenarioFileError(path, d.line, f"bad value for expectedValue: {mean:g} (expected >= 0)")
        bounds = _range(path, d, required=False)

        def one(k: int) -> np.ndarray:
            if d.tag == "NormalDistribution":
                return rng.normal(mean, math.sqrt(var), k)
            if d.tag == "LogNormalDistribution":  # expectedValue and variance of the underlying normal
                return rng.lognormal(mean, math.sqrt(var), k)
            return rng.poisson(mean, k).astype(float)

        if bounds is None:
            return one(n)
        out = np.empty(0)
        for _ in range(1000):  # the range truncates: draws outside it are drawn again
            x = one(max(n, 16))
            out = np.concatenate([out, x[(x >= bounds[0]) & (x <= bounds[1])]])
            if len(out) >= n:
                return out[:n]
        raise ScenarioFileError(path, d.line, f"<{d.tag}> of {name!r} almost never falls in its <Range>")
    if d.tag == "Histogram":
        bins = d.all("HistogramBin")
        if not bins:
            raise ScenarioFileError(path, d.line, "<Histogram> is empty (expected <HistogramBin>s)")
        w = np.asarray([_num(path, b, "weight") for b in bins])
        rs = np.asarray([_range(path, b) for b in bins])
        if (w < 0).any() or w.sum() <= 0:
            raise ScenarioFileError(path, d.line, "<Histogram> weights must be >= 0 with a positive sum")
        k = rng.choice(len(bins), size=n, p=w / w.sum())
        return rng.uniform(rs[k, 0], rs[k, 1])
    if d.tag == "ProbabilityDistributionSet":
        elems = d.all("Element")
        if not elems:
            raise ScenarioFileError(path, d.line, f"<ProbabilityDistributionSet> of {name!r} is empty")
        w = np.asarray([_num(path, e, "weight") for e in elems])
        if (w < 0).any() or w.sum() <= 0:
            raise ScenarioFileError(
                path, d.line, "<ProbabilityDistributionSet> weights must be >= 0 with a positive sum"
            )
        for e in elems:
            if "value" not in e.attrs:
                raise ScenarioFileError(path, e.line, "<Element> needs attribute value")
        values = _column([e.attrs["value"] for e in elems])
        return values[rng.choice(len(elems), size=n, p=w / w.sum())]
    raise _unsupported(path, d, "StochasticDistribution", _STOCHASTIC)


def _stochastic(path, st: Node, seed: int | None) -> tuple[dict[str, np.ndarray], int]:
    if "numberOfTestRuns" not in st.attrs:
        raise ScenarioFileError(path, st.line, "<Stochastic> needs attribute numberOfTestRuns")
    raw = st.attrs["numberOfTestRuns"]
    if not re.fullmatch(r"\d+", raw.strip()) or not 1 <= int(raw) <= MAX_POINTS:
        raise ScenarioFileError(
            path, st.line, f"bad value for numberOfTestRuns: {raw!r} (expected a whole number from 1 to {MAX_POINTS:,})"
        )
    n = int(raw)
    file_seed = st.attrs.get("randomSeed")
    if seed is None:
        try:
            seed = int(float(file_seed)) if file_seed is not None else 0
        except ValueError:
            raise ScenarioFileError(
                path, st.line, f"bad value for randomSeed: {file_seed!r} (expected a whole number)"
            ) from None
    rng = np.random.default_rng(seed)
    cols: dict[str, np.ndarray] = {}
    for node in st.children:
        if node.tag != "StochasticDistribution":
            raise _unsupported(path, node, "Stochastic", ("StochasticDistribution",))
        name = node.attrs.get("parameterName", "")
        if not name:
            raise ScenarioFileError(path, node.line, "<StochasticDistribution> needs attribute parameterName")
        if name in cols:
            raise ScenarioFileError(path, node.line, f"parameter {name!r} is distributed twice")
        cols[name] = _draw(path, node, name, rng, n)
    if not cols:
        raise ScenarioFileError(path, st.line, "<Stochastic> is empty (expected <StochasticDistribution>s)")
    return cols, n


def read(path: str | os.PathLike, seed: int | None = None) -> Distribution:
    """A distribution file's scenario and combinations (``seed`` replaces a Stochastic's
    randomSeed). One-line ScenarioFileError (file:line) on anything wrong."""
    name = os.fspath(path)
    root = root_of(name)
    if root is None:
        raise ScenarioFileError(
            name, 1, "not a ParameterValueDistribution file (expected <ParameterValueDistribution>)"
        )
    target = scenario_file(name, root)
    rest = [c for c in root.children if c.tag != "ScenarioFile"]
    if len(rest) != 1 or rest[0].tag not in ("Deterministic", "Stochastic"):
        bad = next((c for c in rest if c.tag not in ("Deterministic", "Stochastic")), rest[-1] if rest else root)
        raise ScenarioFileError(
            name, bad.line, f"<{bad.tag}> here is not supported (expected one <Deterministic> or <Stochastic>)"
        )
    node = rest[0]
    if node.tag == "Deterministic":
        cols, total = _deterministic(name, node)
        kind = "deterministic"
    else:
        cols, total = _stochastic(name, node, seed)
        kind = "stochastic"
    return Distribution(name, target, kind, cols, total)


def uniform_ranges(path: str, root: Node, target: str, params: set[str]) -> dict[str, list[float]]:
    """For ego's environments (``ego/Scenario-v0``): per parameter of a ``<Stochastic>``'s
    ``<UniformDistribution>``s, ``[lowerLimit, upperLimit]`` (its randomize ranges); any other
    distribution is refused with its line."""
    stochastic = root.child("Stochastic")
    if stochastic is None:
        other = next((c for c in root.children if c.tag != "ScenarioFile"), root)
        raise ScenarioFileError(
            path, other.line, f"<{other.tag}> is not supported by ego's environments (a <Stochastic> one is)"
        )
    ranges: dict[str, list[float]] = {}
    for node in stochastic.all("StochasticDistribution"):
        param_name = node.attrs.get("parameterName", "")
        uniform = node.child("UniformDistribution")
        bounds = uniform.child("Range") if uniform is not None else None
        if bounds is None:
            kind = node.children[0].tag if node.children else "nothing"
            raise ScenarioFileError(
                path,
                node.line,
                f"<{kind}> of {param_name!r} is not supported by ego's environments "
                "(a <UniformDistribution> with a <Range> is)",
            )
        if param_name not in params:
            raise ScenarioFileError(path, node.line, f"parameter {param_name!r} is not one of {target}'s")
        try:
            ranges[param_name] = [float(bounds.attrs["lowerLimit"]), float(bounds.attrs["upperLimit"])]
        except (KeyError, ValueError):
            raise ScenarioFileError(path, bounds.line, "<Range> needs numbers lowerLimit and upperLimit") from None
    return ranges


def _codes(col: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    uniq, inverse = np.unique(col, return_inverse=True)
    return uniq, inverse.reshape(-1)


def constraint_mask(dist: Distribution, params: dict) -> np.ndarray:
    """Which combinations meet the template's value constraints (``params``: its declared
    Parameters with their ConstraintGroups, the defaults for any name the distribution leaves
    alone). Each constraint is evaluated once per distinct combination of the parameter's
    value and the distributed values its rule's expression names."""
    from ego.openscenario.expressions import ExpressionError, resolve
    from ego.openscenario.loader import convert, satisfies

    n = dist.total
    mask = np.ones(n, dtype=bool)
    defaults = {k: p.value for k, p in params.items()}
    for pname, p in params.items():
        if not p.constraints:
            continue
        raws = [c.raw for g in p.constraints for c in g]
        refs = sorted({r for raw in raws for r in re.findall(r"\$\{?([A-Za-z_]\w*)", raw) if r in dist.columns})
        involved = ([pname] if pname in dist.columns else []) + [r for r in refs if r != pname]
        if not involved:
            continue  # the declared value's constraints were checked when the file loaded
        parts = [_codes(dist.columns[k]) for k in involved]
        stacked = np.stack([inv for _, inv in parts], axis=1)
        combos, where = np.unique(stacked, axis=0, return_inverse=True)
        ok = np.empty(len(combos), dtype=bool)
        for i, combo in enumerate(combos):
            values = dict(defaults)
            for k, (uniq, _), c in zip(involved, parts, combo):
                values[k] = convert(params[k].type, uniq[c], f"parameter {k!r}") if k in params else uniq[c]
            good = False
            for g in p.constraints:
                try:
                    if all(satisfies(values[pname], type(c)(c.rule, resolve(c.raw, values), c.line, c.raw)) for c in g):
                        good = True
                        break
                except (ExpressionError, ValueError):
                    pass
            ok[i] = good
        mask &= ok[where.reshape(-1)]
    return mask


def search_ranges(path: str) -> tuple[str, dict[str, list[float]]]:
    """For ``ego falsify FILE.xosc``: the distribution's scenario file and, per distributed
    parameter, the range ``[low, high]`` it spans: a DistributionRange's or a Range's limits,
    a set's (or a histogram's bins') smallest and largest number. A distribution with no
    numeric range (a ValueSetDistribution, a set of names, an unbounded normal) is refused
    with its line: there is nothing to search between."""
    root = root_of(path)
    if root is None:
        raise ScenarioFileError(
            path, 1, "not a ParameterValueDistribution file (expected <ParameterValueDistribution>)"
        )
    target = scenario_file(path, root)
    ranges: dict[str, list[float]] = {}
    for kind in ("Deterministic", "Stochastic"):
        node = root.child(kind)
        for d in node.children if node is not None else ():
            name = d.attrs.get("parameterName", "")
            if d.tag not in ("DeterministicSingleParameterDistribution", "StochasticDistribution") or not name:
                raise ScenarioFileError(
                    path, d.line, f"<{d.tag}> has no numeric range to search (ego falsify searches ranges)"
                )
            bounds = [n for n in _walk(d) if n.tag == "Range"]
            values = [n.attrs.get("value") for n in _walk(d) if n.tag == "Element"]
            try:
                nums = [float(b.attrs[k]) for b in bounds for k in ("lowerLimit", "upperLimit")]
                nums += [float(v) for v in values if v is not None]
            except (KeyError, ValueError):
                nums = []
            if len(nums) < 2 or not min(nums) < max(nums):
                raise ScenarioFileError(
                    path, d.line, f"parameter {name!r} has no numeric range to search (ego falsify searches ranges)"
                )
            ranges[name] = [min(nums), max(nums)]
    if not ranges:
        raise ScenarioFileError(path, root.line, "the distribution names no parameter range to search")
    return target, ranges


def _walk(node: Node):
    yield node
    for c in node.children:
        yield from _walk(c)
