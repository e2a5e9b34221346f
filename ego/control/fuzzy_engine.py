"""Mamdani rule bases: defined with scikit-fuzzy, evaluated fast.

scikit-fuzzy's ``ControlSystemSimulation.compute`` re-walks its rule graph on every call
(tens of milliseconds), far too slow for a controller stepping at 100 Hz inside a
traffic simulation. :class:`FastMamdani` compiles a scikit-fuzzy ``ControlSystem`` once
and evaluates the same inference in closed form:

* AND = min, implication = min (clipping), aggregation = max, centroid defuzzification,
  inputs clipped to their universes - scikit-fuzzy's defaults;
* every variable's terms must form a triangular Ruspini partition (neighbouring
  triangles cross at 0.5 and the memberships sum to one) whose peaks lie on samples of
  the universe, the first and last peaks at the universe's ends;
* every rule ANDs one term of each input; the rule table must be complete.

scikit-fuzzy computes the centroid of the aggregated membership sampled on the output
universe plus the points where each term meets its cut level, joined by straight lines.
The clipped triangles are piecewise linear with corners at exactly those points, except
where two neighbouring clipped terms cross between samples; there scikit-fuzzy's chord
differs from the true kink by a small triangle. The evaluator integrates the exact
shape and subtracts that triangle, so it reproduces scikit-fuzzy's number (to rounding)
at any universe resolution, not just approximately on a fine one.
"""

from __future__ import annotations

import bisect
import functools
import itertools
import struct
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np


class UnsupportedRuleBase(ValueError):
    """The scikit-fuzzy system uses a feature the fast evaluator does not implement."""


@dataclass(frozen=True)
class Partition:
    """A triangular Ruspini partition of one fuzzy variable.

    Term ``k`` is the triangle rising from ``peaks[k-1]`` to 1 at ``peaks[k]`` and falling
    to 0 at ``peaks[k+1]``; the first and last terms are half triangles at the ends of the
    universe. ``grid`` is the variable's sampled universe (scikit-fuzzy's array).
    """

    label: str
    term_labels: tuple[str, ...]
    peaks: tuple[float, ...]
    grid: tuple[float, ...]

    @property
    def lower(self) -> float:
        return self.peaks[0]

    @property
    def upper(self) -> float:
        return self.peaks[-1]


def partition_of(variable: Any) -> Partition:
    """Read and validate a scikit-fuzzy Antecedent/Consequent as a :class:`Partition`."""
    universe = np.asarray(variable.universe, dtype=float)
    if universe.ndim != 1 or universe.size < 2 or np.any(np.diff(universe) <= 0):
        raise UnsupportedRuleBase(f"{variable.label}: universe must be a strictly increasing 1-D array")
    terms = list(variable.terms.values())
    if len(terms) < 2:
        raise UnsupportedRuleBase(f"{variable.label}: needs at least two terms")
    peaks_idx = []
    for term in terms:
        mf = np.asarray(term.mf, dtype=float)
        at_one = np.flatnonzero(mf == 1.0)
        if at_one.size != 1:
            raise UnsupportedRuleBase(
                f"{variable.label}[{term.label}]: a triangular term must reach 1 at exactly one "
                "universe sample (put the peaks on the grid)"
            )
        peaks_idx.append(int(at_one[0]))
    order = np.argsort(peaks_idx)
    peaks = universe[np.asarray(peaks_idx)[order]]
    if peaks[0] != universe[0] or peaks[-1] != universe[-1]:
        raise UnsupportedRuleBase(
            f"{variable.label}: the outer terms must peak at the ends of the universe [{universe[0]}, {universe[-1]}]"
        )
    for rank, k in enumerate(order):
        expected = np.interp(universe, peaks, np.eye(len(peaks))[rank])
        if not np.allclose(terms[k].mf, expected, rtol=0.0, atol=1e-9):
            raise UnsupportedRuleBase(
                f"{variable.label}[{terms[k].label}]: not a triangle between its neighbours' peaks "
                "(the terms must form a triangular Ruspini partition)"
            )
    return Partition(
        label=variable.label,
        term_labels=tuple(terms[k].label for k in order),
        peaks=tuple(float(p) for p in peaks),
        grid=tuple(float(x) for x in universe),
    )


def _envelope(a: float, b: float, s: float) -> float:
    """max(min(a, 1 - s), min(b, s)): two neighbours clipped at a and b, at s in [0, 1]."""
    left = a if a < 1.0 - s else 1.0 - s
    right = b if b < s else s
    return left if left > right else right


class _Output:
    """Closed-form centroid of max-aggregated clipped triangles on one output partition."""

    __slots__ = ("partition", "peaks", "grid", "_coef")

    def __init__(self, partition: Partition) -> None:
        self.partition = partition
        self.peaks = p = partition.peaks
        self.grid = partition.grid
        n = len(p)
        coef = []
        for j in range(n):
            # Term j clipped at c: a rising side of width L from p[j-1] and a falling side
            # of width R to p[j+1]. Area = (L + R)(c - c^2/2); the first moment is a cubic
            # in c (integrate the trapezoids; checked against the full triangle at c = 1).
            L = p[j] - p[j - 1] if j > 0 else 0.0
            R = p[j + 1] - p[j] if j < n - 1 else 0.0
            lo = p[j - 1] if j > 0 else p[j]
            hi = p[j + 1] if j < n - 1 else p[j]
            coef.append(
                (
                    L + R,
                    0.5 * L * (lo + p[j]) + 0.5 * R * (p[j] + hi),
                    -0.5 * L * lo - 0.5 * R * hi,
                    (R * R - L * L) / 6.0,
                )
            )
        self._coef = tuple(coef)

    def _pair(self, j: int, a: float, b: float) -> tuple[float, float]:
        """Correction for the overlap of neighbours j (cut a) and j+1 (cut b).

        Removes the double-counted min(c_j, c_j+1) and, where the two clipped shapes cross
        between samples, the triangle between scikit-fuzzy's chord and the true kink.
        """
        p = self.peaks[j]
        q = self.peaks[j + 1]
        w = q - p
        m = a if a < b else b
        area = -w * (0.25 if m >= 0.5 else m - m * m)
        moment = area * 0.5 * (p + q)
        if a >= 0.5 and b >= 0.5:
            s_star = 0.5
        elif a > b:
            s_star = 1.0 - b
        elif a < b:
            s_star = a
        else:
            return area, moment  # equal plateaus: no kink between the cut points
        x_star = p + s_star * w
        grid = self.grid
        i = bisect.bisect_right(grid, x_star) - 1
        left = grid[i]
        if left == x_star:
            return area, moment
        right = grid[i + 1]
        # the points scikit-fuzzy inserts where each term meets its cut
        for c in (q - a * w, p + b * w):
            if left < c < x_star:
                left = c
            elif x_star < c < right:
                right = c
        fl = _envelope(a, b, (left - p) / w)
        fr = _envelope(a, b, (right - p) / w)
        f_star = s_star if s_star <= 0.5 else 1.0 - s_star
        tri = 0.5 * ((x_star - left) * (fr - fl) - (right - left) * (f_star - fl))
        return area + tri, moment + tri * (left + x_star + right) / 3.0

    def centroid(self, cuts: Mapping[int, float]) -> float:
        area = moment = 0.0
        coef = self._coef
        for j, c in cuts.items():
            A, M1, M2, M3 = coef[j]
            area += A * c * (1.0 - 0.5 * c)
            moment += c * (M1 + c * (M2 + c * M3))
            nxt = cuts.get(j + 1)
            if nxt is not None:
                da, dm = self._pair(j, c, nxt)
                area += da
                moment += dm
        if area <= 0.0:
            raise ArithmeticError("no rule fired: the aggregated membership is empty")
        return moment / area


class FastMamdani:
    """Closed-form evaluator of a compiled scikit-fuzzy Mamdani system.

    ``evaluate(*inputs)`` takes the crisp inputs in ``input_labels`` order and returns a
    tuple of crisp outputs in ``output_labels`` order.
    """

    def __init__(
        self,
        inputs: Sequence[Partition],
        outputs: Sequence[Partition],
        table: Mapping[tuple[int, ...], Sequence[tuple[int, int]]],
    ) -> None:
        self.inputs = tuple(inputs)
        self.outputs = tuple(outputs)
        self.input_labels = tuple(p.label for p in self.inputs)
        self.output_labels = tuple(p.label for p in self.outputs)
        self._out = tuple(_Output(p) for p in self.outputs)
        sizes = [len(p.peaks) for p in self.inputs]
        missing = [k for k in itertools.product(*map(range, sizes)) if not table.get(k)]
        if missing:
            names = [
                " AND ".join(f"{p.label}[{p.term_labels[i]}]" for p, i in zip(self.inputs, k)) for k in missing[:3]
            ]
            raise UnsupportedRuleBase(
                f"the rule table is incomplete: {len(missing)} input combinations have no rule "
                f"(e.g. {'; '.join(names)})"
            )
        for k, cons in table.items():
            covered = {o for o, _ in cons}
            if covered != set(range(len(self.outputs))):
                raise UnsupportedRuleBase(f"rule {k} does not give every output a term")
        # flat lookup: combination -> ((output, term), ...)
        self._table = {tuple(k): tuple(v) for k, v in table.items()}
        self._peaks = tuple(p.peaks for p in self.inputs)
        if len(self.inputs) == 2:
            # rows[i][j] -> per output, the terms the rule (i, j) fires
            self._table2 = [
                [
                    tuple(tuple(t for o2, t in self._table[(i, j)] if o2 == o) for o in range(len(self.outputs)))
                    for j in range(sizes[1])
                ]
                for i in range(sizes[0])
            ]
            self._fuzzify2 = (_fuzzifier(self._peaks[0]), _fuzzifier(self._peaks[1]))
            if len(self.outputs) == 1 and all(len(t[0]) == 1 for row in self._table2 for t in row):
                #: ``single2(x0, x1) -> float``: the fastest path, for one output (the C twin
                #: when built, else :attr:`single2_py`; the same numbers either way)
                self.single2_py = _single_output_two_inputs(self, 0)
                self.single2 = _native_single2(self, 0) or self.single2_py

    def single2_output(self, o: int, native: bool = True) -> Callable[[float, float], float]:
        """``f(x0, x1) -> float`` computing output ``o`` alone (two inputs, one term per
        rule for that output): the C twin when built and ``native``, else Python."""
        if len(self.inputs) != 2 or not all(len(t[o]) == 1 for row in self._table2 for t in row):
            raise UnsupportedRuleBase(f"output {o}: needs two inputs and one term per rule")
        fast = _native_single2(self, o) if native else None
        return fast or _single_output_two_inputs(self, o)

    @classmethod
    def from_system(
        cls,
        system: Any,
        input_labels: Sequence[str] | None = None,
        output_labels: Sequence[str] | None = None,
    ) -> FastMamdani:
        """Compile a ``skfuzzy.control.ControlSystem``."""
        return cls._compile(system.antecedents, system.consequents, system.rules, input_labels, output_labels)

    @classmethod
    def from_rules(
        cls,
        rules: Sequence[Any],
        input_labels: Sequence[str] | None = None,
        output_labels: Sequence[str] | None = None,
    ) -> FastMamdani:
        """Compile scikit-fuzzy ``Rule`` objects as :meth:`from_system` compiles a
        ``ControlSystem`` of them, without building that system (scikit-fuzzy composes a
        networkx graph per rule added: about 0.6 s for a 7 x 7 table). The variables are
        the ones the rules' terms belong to."""
        from skfuzzy.control.term import TermAggregate

        ants: dict[str, Any] = {}
        cons: dict[str, Any] = {}
        for rule in rules:
            stack = [rule.antecedent]
            while stack:  # every variable the antecedent names (_compile checks its form)
                node = stack.pop()
                if isinstance(node, TermAggregate):
                    stack += [t for t in (node.term1, node.term2) if t is not None]
                elif hasattr(node, "parent"):
                    ants.setdefault(node.parent.label, node.parent)
            for wt in rule.consequent:
                cons.setdefault(wt.term.parent.label, wt.term.parent)
        return cls._compile(ants.values(), cons.values(), rules, input_labels, output_labels)

    @classmethod
    def _compile(
        cls,
        antecedents: Any,
        consequents: Any,
        rules: Any,
        input_labels: Sequence[str] | None,
        output_labels: Sequence[str] | None,
    ) -> FastMamdani:
        from skfuzzy.control.term import Term, TermAggregate

        ants = {a.label: a for a in antecedents}
        cons = {c.label: c for c in consequents}
        input_labels = tuple(input_labels) if input_labels else tuple(sorted(ants))
        output_labels = tuple(output_labels) if output_labels else tuple(sorted(cons))
        if set(input_labels) != set(ants) or set(output_labels) != set(cons):
            raise UnsupportedRuleBase(
                f"labels {input_labels}->{output_labels} do not match the system's {sorted(ants)}->{sorted(cons)}"
            )
        inputs = [partition_of(ants[k]) for k in input_labels]
        outputs = [partition_of(cons[k]) for k in output_labels]
        for c in (cons[k] for k in output_labels):
            if getattr(c, "defuzzify_method", "centroid") != "centroid":
                raise UnsupportedRuleBase(f"{c.label}: only centroid defuzzification is supported")

        def and_terms(node: Any) -> list[Any]:
            if isinstance(node, Term):
                return [node]
            if isinstance(node, TermAggregate) and node.kind == "and":
                return and_terms(node.term1) + and_terms(node.term2)
            raise UnsupportedRuleBase(f"rule antecedent {node!r}: only AND of terms is supported")

        table: dict[tuple[int, ...], list[tuple[int, int]]] = {}
        for rule in rules:
            if rule.and_func is not np.fmin:
                raise UnsupportedRuleBase(f"rule {rule}: AND must be min (np.fmin)")
            picked: dict[str, str] = {}
            for t in and_terms(rule.antecedent):
                if t.parent.label in picked:
                    raise UnsupportedRuleBase(f"rule {rule}: {t.parent.label} appears twice")
                picked[t.parent.label] = t.label
            if set(picked) != set(input_labels):
                raise UnsupportedRuleBase(f"rule {rule}: must AND one term of every input")
            key = tuple(p.term_labels.index(picked[p.label]) for p in inputs)
            entry = table.setdefault(key, [])
            for wt in rule.consequent:
                if wt.weight != 1.0:
                    raise UnsupportedRuleBase(f"rule {rule}: consequent weights must be 1")
                o = output_labels.index(wt.term.parent.label)
                entry.append((o, outputs[o].term_labels.index(wt.term.label)))
        return cls(inputs, outputs, table)

    def memberships(self, i: int, x: float) -> tuple[tuple[int, float], ...]:
        """Non-zero memberships (term index, degree) of input ``i`` at ``x`` (clipped)."""
        peaks = self._peaks[i]
        if x <= peaks[0]:
            return ((0, 1.0),)
        if x >= peaks[-1]:
            return ((len(peaks) - 1, 1.0),)
        k = bisect.bisect_right(peaks, x) - 1
        t = (x - peaks[k]) / (peaks[k + 1] - peaks[k])
        if t == 0.0:
            return ((k, 1.0),)
        return ((k, 1.0 - t), (k + 1, t))

    def evaluate(self, *values: float) -> tuple[float, ...]:
        """Crisp outputs for the crisp inputs ``values`` (in ``input_labels`` order)."""
        table = self._table
        cuts: list[dict[int, float]] = [{} for _ in self._out]
        for combo in itertools.product(*(self.memberships(i, v) for i, v in enumerate(values))):
            strength = min(m for _, m in combo)
            for o, term in table[tuple(k for k, _ in combo)]:
                c = cuts[o]
                if strength > c.get(term, 0.0):
                    c[term] = strength
        return tuple(out.centroid(c) for out, c in zip(self._out, cuts))

    def evaluate2(self, x0: float, x1: float) -> tuple[float, ...]:
        """:meth:`evaluate` for exactly two inputs, written out for speed (same result)."""
        k0, a0, b0 = self._fuzzify2[0](x0)
        k1, a1, b1 = self._fuzzify2[1](x1)
        rows = self._table2
        combos = [(rows[k0][k1], a0 if a0 < a1 else a1)]
        if b1 > 0.0:
            combos.append((rows[k0][k1 + 1], a0 if a0 < b1 else b1))
        if b0 > 0.0:
            combos.append((rows[k0 + 1][k1], b0 if b0 < a1 else a1))
            if b1 > 0.0:
                combos.append((rows[k0 + 1][k1 + 1], b0 if b0 < b1 else b1))
        out = []
        for o, output in enumerate(self._out):
            cuts: dict[int, float] = {}
            for terms, strength in combos:
                for term in terms[o]:
                    if strength > cuts.get(term, 0.0):
                        cuts[term] = strength
            out.append(output.centroid(cuts))
        return tuple(out)


def _single_output_two_inputs(engine: FastMamdani, o: int) -> Callable[[float, float], float]:
    """A closure computing engine.evaluate2(x0, x1)[o] for one output, without the
    generic bookkeeping: the Python twin of ego._native.mamdani2 (tests compare them)."""
    fuzzify0, fuzzify1 = engine._fuzzify2
    rows = [[terms[o][0] for terms in row] for row in engine._table2]
    centroid = engine._out[o].centroid

    def evaluate(x0: float, x1: float) -> float:
        k0, a0, b0 = fuzzify0(x0)
        k1, a1, b1 = fuzzify1(x1)
        row = rows[k0]
        cuts = {row[k1]: a0 if a0 < a1 else a1}
        if b1 > 0.0:
            term = row[k1 + 1]
            w = a0 if a0 < b1 else b1
            if w > cuts.get(term, 0.0):
                cuts[term] = w
        if b0 > 0.0:
            row = rows[k0 + 1]
            term = row[k1]
            w = b0 if b0 < a1 else a1
            if w > cuts.get(term, 0.0):
                cuts[term] = w
            if b1 > 0.0:
                term = row[k1 + 1]
                w = b0 if b0 < b1 else b1
                if w > cuts.get(term, 0.0):
                    cuts[term] = w
        return centroid(cuts)

    return evaluate


def _native_single2(engine: FastMamdani, o: int) -> Callable[[float, float], float] | None:
    """Output ``o`` bound to ego._native.mamdani2 and this rule base's packed tables."""
    from ego.native import NATIVE

    if NATIVE is None:
        return None
    out = engine._out[o]
    table = [row[j][o][0] for row in engine._table2 for j in range(len(row))]
    return functools.partial(
        NATIVE.mamdani2,
        struct.pack(f"{len(engine._peaks[0])}d", *engine._peaks[0]),
        struct.pack(f"{len(engine._peaks[1])}d", *engine._peaks[1]),
        struct.pack(f"{len(table)}i", *table),
        struct.pack(f"{4 * len(out._coef)}d", *(v for c in out._coef for v in c)),
        struct.pack(f"{len(out.peaks)}d", *out.peaks),
        struct.pack(f"{len(out.grid)}d", *out.grid),
    )


def _fuzzifier(peaks: Sequence[float]) -> Callable[[float], Any]:
    """x -> (k, mu_k, mu_k+1) for a Ruspini partition: at most two neighbours are non-zero."""
    last = len(peaks) - 1
    lo, hi = peaks[0], peaks[-1]
    inv = [1.0 / (peaks[k + 1] - peaks[k]) for k in range(last)]
    bisect_right = bisect.bisect_right

    def fuzzify(x: float) -> tuple[int, float, float]:
        if x <= lo:
            return 0, 1.0, 0.0
        if x >= hi:
            return last, 1.0, 0.0
        k = bisect_right(peaks, x) - 1
        t = (x - peaks[k]) * inv[k]
        return k, 1.0 - t, t

    return fuzzify


def uniform_partition(
    label: str, lower: float, upper: float, term_labels: Sequence[str], samples: int
) -> tuple[np.ndarray, dict[str, tuple[float, float, float]]]:
    """Universe and triangle vertices for a uniform Ruspini partition over [lower, upper].

    ``samples`` must put every peak on the grid, i.e. (samples - 1) divisible by
    (number of terms - 1).
    """
    n = len(term_labels)
    if (samples - 1) % (n - 1):
        raise ValueError(f"{label}: samples-1={samples - 1} must be a multiple of {n - 1} terms-1")
    universe = np.linspace(lower, upper, samples)
    peaks = universe[:: (samples - 1) // (n - 1)]
    vertices = {}
    for k, name in enumerate(term_labels):
        a = peaks[k - 1] if k > 0 else peaks[0]
        c = peaks[k + 1] if k < n - 1 else peaks[-1]
        vertices[name] = (a, peaks[k], c)
    return universe, vertices


def table_rules(
    inputs: Sequence[tuple[str, float, float]],
    outputs: Sequence[tuple[str, float, float]],
    term_labels: Sequence[str],
    tables: Mapping[str, Sequence[Sequence[str]]],
    samples: int,
    output_samples: int | None = None,
) -> list[Any]:
    """A two-input rule table as scikit-fuzzy ``Rule`` objects (one per cell, row-major),
    whose terms belong to ``Antecedent``/``Consequent`` variables: what
    :func:`table_system` makes a ``ControlSystem`` of.

    ``inputs``/``outputs`` are (label, lower, upper); every variable gets the same uniform
    triangular terms ``term_labels``. ``tables[output][row][col]`` is the output term for
    (first input = row term, second input = column term).
    """
    import skfuzzy as fuzz
    from skfuzzy import control as ctrl

    if len(inputs) != 2:
        raise ValueError(f"a rule table has two inputs, got {len(inputs)}")

    def make(kind: Any, spec: tuple[str, float, float], n_samples: int) -> Any:
        label, lo, hi = spec
        universe, vertices = uniform_partition(label, lo, hi, term_labels, n_samples)
        var = kind(universe, label)
        for name, abc in vertices.items():
            var[name] = fuzz.trimf(universe, list(abc))
        return var

    ins = [make(ctrl.Antecedent, s, samples) for s in inputs]
    outs = {s[0]: make(ctrl.Consequent, s, output_samples or samples) for s in outputs}
    rules = []
    for i, row_term in enumerate(term_labels):
        for j, col_term in enumerate(term_labels):
            consequents = [outs[name][tables[name][i][j]] for name in outs]
            rules.append(ctrl.Rule(ins[0][row_term] & ins[1][col_term], consequents))
    return rules


def table_system(*args: Any, **kwargs: Any) -> Any:
    """The rules of :func:`table_rules` (same arguments) as a scikit-fuzzy
    ``ControlSystem``. scikit-fuzzy composes a networkx graph per rule added: about 0.6 s for a
    7 x 7 table, which :meth:`FastMamdani.from_rules` does not need."""
    from skfuzzy import control as ctrl

    return ctrl.ControlSystem(table_rules(*args, **kwargs))
