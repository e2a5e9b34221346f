"""Requirements in signal temporal logic over a run's named, unit-carrying trace signals.

A requirement is ``name: formula``. The formula is STL over the trace's columns and a few
derived signals (:data:`DERIVED`), evaluated after the run on every sample of the trace
(or on a grid, ``period``) with rtamt's offline discrete-time semantics in numpy
(:mod:`ego.stl`; rtamt itself is the tests' reference); its **robustness** (how far the run
is from violating it, in the unit of its comparisons; negative: violated) becomes the metric
``requirements.<name>``, and a violation's first time the metric ``first_violation.<name>``
and a ``requirement`` event of the run and its recording.

Grammar (``docs/requirements.md`` has the full story)::

    formula  := until ('implies' formula)?          (also ->)
    until    := or ('until' [a:b]? or)?
    or       := and ('or' and)*
    and      := unary ('and' unary)*
    unary    := 'not' unary | ('always' | 'eventually' | 'historically' | 'once') [a:b]? unary
              | '(' formula ')' | arith CMP arith | BOOLEAN_SIGNAL
    arith    := term (('+' | '-') term)* ;  term := factor (('*' | '/') factor)*
    factor   := '-' factor | NUMBER UNIT? | SIGNAL | 'abs' '(' arith ')' | '(' arith ')'
    CMP      := >= | <= | > | < | == | !=

Intervals ``[a:b]`` are in seconds (``[0:3]``, or ``[0 s:3 s]``). A number may carry a unit
written after it (``2 m``, ``1.0 s``, ``0.5 m/s``, ``3 m/s^2``); a number without one takes
the unit of the other side. Both sides of a comparison, and both terms of ``+``/``-``, must
have the same unit, so ``gap_front >= 2 s`` and ``gap_front >= ttc_front`` are refused. A
boolean signal (unit ``bool``) stands alone as a proposition: internally it is +1 (true) or
-1 (false) and its robustness is that value.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from ego.params import ConfigError, did_you_mean
from ego.results.summary import REQUIREMENTS_PREFIX, requirement_lines
from ego.stl import render, robustness

BOOL = "bool"
#: units a number may carry (besides the units of the trace's own columns)
KNOWN_UNITS = ("m/s^2", "rad/s", "m/s", "m", "s", "N", "rad", "-")
_TEMPORAL = ("always", "eventually", "historically", "once")
_KEYWORDS = {"not", "and", "or", "implies", "until", "abs", "true", "false", *_TEMPORAL}
_CMP = (">=", "<=", "==", "!=", ">", "<")
_TOKEN = re.compile(
    r"\s*(?:(?P<num>\d+(?:\.\d*)?(?:[eE][-+]?\d+)?|\.\d+(?:[eE][-+]?\d+)?)"
    r"|(?P<name>[A-Za-z_][A-Za-z_0-9]*)|(?P<op>->|>=|<=|==|!=|[<>()\[\]:+\-*/^&|~]))"
)
_REQ_NAME = re.compile(r"^[A-Za-z_][A-Za-z_0-9]*$")


class RequirementError(ConfigError):
    """A formula that cannot be evaluated (syntax, unknown signal, unit mismatch)."""


# -- derived signals ----------------------------------------------------------------------------
def _status_time(result, kind: str) -> float | None:
    return next((e.t for e in result.events if e.kind == kind), None)


def _collision(result, t: np.ndarray, scenario=None) -> np.ndarray:
    when = _status_time(result, "collision") if result.status == "collision" else None
    if when is None or not len(t):
        return np.zeros(len(t), bool)
    return t >= min(when, t[-1]) - 1e-9  # the run ends at the collision: its last sample at least


def _avoidable_collision(result, t: np.ndarray, scenario=None) -> np.ndarray:
    return _collision(result, t) & bool(result.metrics.get("collision_avoidable"))


def _preventable_collision(result, t: np.ndarray, scenario=None) -> np.ndarray:
    return _collision(result, t) & bool(result.metrics.get("collision_preventable"))


#: the signal whose requirement makes a run compute ``collision_preventable`` after a collision
#: (UN R157's careful driver on the same concrete scenario: a second run, ego.runner)
PREVENTABLE_SIGNAL = "preventable_collision"


def _collision_avoidable(result, t: np.ndarray, scenario=None) -> np.ndarray:
    return np.full(len(t), bool(result.metrics.get("collision_avoidable")))


def _aeb_active(result, t: np.ndarray, scenario=None) -> np.ndarray:
    """From the run's ``aeb`` events: engaged from "AEB engages" until "AEB releases"."""
    out = np.zeros(len(t), bool)
    start = None
    for e in result.events:
        if e.kind != "aeb":
            continue
        if "engages" in e.text and start is None:
            start = e.t
        elif "releases" in e.text and start is not None:
            out |= (t >= start) & (t < e.t)
            start = None
    if start is not None:
        out |= t >= start
    return out


def _lateral_clear(result, t: np.ndarray, scenario=None) -> np.ndarray:
    """The ego's outline has left the lane it started in (|lane_offset| at least half a
    lane plus half the ego's width): a car ahead in that lane is no longer in its way."""
    from ego.models.geometry import VehicleGeometry

    width = result.lanes[0][0] if result.lanes else 3.2
    offset = np.abs(result.column("lane_offset"))
    return offset >= 0.5 * width + 0.5 * VehicleGeometry().width


def _lane_departure(result, t: np.ndarray, scenario=None) -> np.ndarray:
    """How far the ego's side reaches beyond its lane's marking outside a commanded lane
    change (m; inside the lane minus the margin left, -inf during a commanded lane change;
    :func:`ego.lane_frame.lane_departure`)."""
    from ego.lane_frame import lane_departure
    from ego.models.geometry import VehicleGeometry

    if not result.lanes:
        return np.zeros(len(t))
    geometry = getattr(scenario, "geometry", None) or VehicleGeometry()
    return lane_departure(
        result.column("d"), result.column("d_ref"), result.column("phase"), result.lanes[0][0], geometry.width, True
    )


def _gap_min(result, t: np.ndarray, scenario=None) -> np.ndarray:
    return np.minimum(result.column("gap_front"), result.column("gap_rear"))


def _clearance(result, t: np.ndarray, scenario=None) -> np.ndarray:
    """The smaller bumper gap, front or rear, at least 0 m until the ego's collision (the
    outlines may touch by millimetres without a collision), from then on at most -1 m (a
    collision is a violation by a clear margin even when the outlines only touch)."""
    gap = np.minimum(result.column("gap_front"), result.column("gap_rear"))
    hit = _collision(result, t)
    return np.where(hit, np.minimum(gap, 0.0) - 1.0, np.maximum(gap, 0.0))


def _braking_margin(result, t: np.ndarray, scenario=None) -> np.ndarray:
    """The scenario's braking margin (constant over the run); 1e9 without a trigger."""
    margin = scenario.braking_margin() if scenario is not None else None
    return np.full(len(t), 1e9 if margin is None else float(margin))


def _accel(result, t: np.ndarray, scenario=None) -> np.ndarray:
    """The ego's longitudinal acceleration: the change of its speed to the next sample over
    the time between them (the last sample keeps the one before)."""
    v = result.column("speed")
    if len(v) < 2:
        return np.zeros(len(t))
    a = np.empty(len(v))
    a[:-1] = np.diff(v) / np.diff(result.column("t"))
    a[-1] = a[-2]
    return a


@dataclass(frozen=True)
class Derived:
    """A signal computed from a finished run (its trace, events and metrics)."""

    name: str
    unit: str
    description: str
    needs: tuple[str, ...]  #: trace columns (or metrics, prefixed ``metric:``) it needs
    fn: object


DERIVED = {
    d.name: d
    for d in (
        Derived(
            "collision",
            BOOL,
            "true from the ego's collision on (status collision)",
            (),
            _collision,
        ),
        Derived(
            "collision_avoidable",
            BOOL,
            "the run's collision_avoidable metric, constant over the "
            "run (true: braking at the friction limit from the trigger would have avoided the "
            "collision)",
            ("metric:collision_avoidable",),
            _collision_avoidable,
        ),
        Derived(
            "avoidable_collision",
            BOOL,
            "true from the ego's collision on when that collision was avoidable (collision_avoidable)",
            ("metric:collision_avoidable",),
            _avoidable_collision,
        ),
        Derived(
            PREVENTABLE_SIGNAL,
            BOOL,
            "true from the ego's collision on when UN R157's careful driver, on the same concrete "
            "scenario, avoids it (collision_preventable; a requirement naming it makes a colliding "
            "run compute that with a second run)",
            (),
            _preventable_collision,
        ),
        Derived(
            "aeb_active",
            BOOL,
            "the AEB brakes (between its engage and release events)",
            (),
            _aeb_active,
        ),
        Derived(
            "lateral_clear",
            BOOL,
            "the ego's outline has left its start lane (|lane_offset| >= half a lane + half the ego's width)",
            ("lane_offset",),
            _lateral_clear,
        ),
        Derived(
            "lane_departure",
            "m",
            "how far the ego's side reaches beyond the outer edge of its lane's marking outside a "
            "commanded lane change (negative: the margin left inside; -1e9 during a lane change; "
            "metric max_lane_departure)",
            ("d", "d_ref", "phase"),
            _lane_departure,
        ),
        Derived(
            "braking_margin",
            "m",
            "the smallest gap to the lead had the ego braked at its friction "
            "limit from the trigger, constant over the run (positive: braking avoids the lead; 1e9: no "
            "trigger)",
            ("scenario:braking_margin",),
            _braking_margin,
        ),
        Derived(
            "clearance",
            "m",
            "gap_min floored at 0 m, and from the ego's collision on "
            "min(gap_min, 0) - 1 m (negative exactly when the ego collided)",
            ("gap_front", "gap_rear"),
            _clearance,
        ),
        Derived(
            "accel",
            "m/s^2",
            "the ego's longitudinal acceleration (the change of speed to the next control step)",
            ("speed",),
            _accel,
        ),
        Derived(
            "gap_min",
            "m",
            "the smaller of gap_front and gap_rear",
            ("gap_front", "gap_rear"),
            _gap_min,
        ),
    )
}


# -- parsing ----------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Requirement:
    """One parsed requirement: its name, the formula as written, the formula as rtamt reads
    it, the signals it uses and the unit of its robustness (``"mixed"`` when its comparisons
    have different units)."""

    name: str
    formula: str
    rtamt: str
    signals: tuple[str, ...]
    unit: str
    #: the interval bounds it uses (s), as written
    bounds: tuple[float, ...] = ()
    #: the parsed formula (:mod:`ego.stl`'s tree; ``rtamt`` is its text)
    tree: tuple = field(default=(), compare=False, repr=False)

    @property
    def text(self) -> str:
        return f"{self.name}: {self.formula}"


#: limits of a requirement formula (docs/reliability.md): tokens, nesting of not, temporal
#: operators, parentheses, signs and abs(), and interval bounds (s; also at most the run)
MAX_TOKENS = 2000
MAX_NESTING = 100
MAX_BOUND = 86400.0


class _Parser:
    def __init__(self, formula: str, units: Mapping[str, str]) -> None:
        self.formula = formula
        self.units = units
        self.toks = self._lex(formula)
        if len(self.toks) > MAX_TOKENS:
            raise self.error(f"{len(self.toks):,} tokens (the limit is {MAX_TOKENS:,})")
        self.i = 0
        self.depth = 0
        self.used: dict[str, None] = {}
        self.cmp_units: set[str] = set()
        self.bounds: list[float] = []

    def _lex(self, text: str) -> list[str]:
        toks, pos = [], 0
        text = text.rstrip()
        while pos < len(text):
            m = _TOKEN.match(text, pos)
            if m is None or m.end() == pos:
                raise self.error(f"unexpected character {text[pos:].lstrip()[:1]!r}")
            toks.append(m.group(m.lastgroup))
            pos = m.end()
        return toks

    def error(self, msg: str) -> RequirementError:
        shown = self.formula if len(self.formula) <= 120 else self.formula[:117] + "..."
        return RequirementError(f"bad requirement formula {shown!r}: {msg}")

    def deeper(self) -> None:
        self.depth += 1
        if self.depth > MAX_NESTING:
            raise self.error(f"nested deeper than {MAX_NESTING} levels (the limit)")

    def peek(self, k: int = 0) -> str | None:
        j = self.i + k
        return self.toks[j] if j < len(self.toks) else None

    def take(self, expected: str | None = None) -> str:
        tok = self.peek()
        if tok is None:
            raise self.error(f"ends early (expected {expected!r})" if expected else "ends early")
        if expected is not None and tok != expected:
            raise self.error(f"expected {expected!r}, found {tok!r}")
        self.i += 1
        return tok

    def next(self, what: str) -> str:
        """The next token, whatever it is (``what`` names it when the formula ends)."""
        tok = self.peek()
        if tok is None:
            raise self.error(f"ends early (expected {what})")
        self.i += 1
        return tok

    def parse(self) -> tuple:
        if not self.toks:
            raise self.error("empty")
        out = self.formula_()
        if self.peek() is not None:
            raise self.error(f"unexpected {self.peek()!r}")
        return out

    # formulas (return ego.stl trees; ego.stl.render gives rtamt's text)
    def formula_(self) -> tuple:
        left = self.until()
        if self.peek() in ("implies", "->"):
            self.take()
            return ("implies", left, self.formula_())
        return left

    def until(self) -> tuple:
        left = self.or_()
        if self.peek() == "until":
            self.take()
            bounds = self.interval()
            return ("until", bounds, left, self.or_())
        return left

    def or_(self) -> tuple:
        parts = [self.and_()]
        while self.peek() in ("or", "|"):
            self.take()
            parts.append(self.and_())
        return parts[0] if len(parts) == 1 else ("or", tuple(parts))

    def and_(self) -> tuple:
        parts = [self.unary()]
        while self.peek() in ("and", "&"):
            self.take()
            parts.append(self.unary())
        return parts[0] if len(parts) == 1 else ("and", tuple(parts))

    def unary(self) -> tuple:
        tok = self.peek()
        if tok in ("not", "~"):
            self.take()
            self.deeper()
            inner = self.unary()
            self.depth -= 1
            return ("not", inner)
        if tok in _TEMPORAL:
            self.take()
            bounds = self.interval()
            self.deeper()
            inner = self.unary()
            self.depth -= 1
            return ("temporal", tok, bounds, inner)
        if tok in ("true", "false"):
            self.take()
            return ("const", tok == "true")
        if tok == "(":
            start = self.i
            try:  # a parenthesised comparison's left side, e.g. (a - b) >= 2 m
                return self.comparison()
            except RequirementError:
                self.i = start
            self.take("(")
            self.deeper()
            inner = self.formula_()
            self.depth -= 1
            self.take(")")
            return ("group", inner)
        if tok is not None and tok not in _KEYWORDS and _is_name(tok) and self.units.get(tok) == BOOL:
            nxt = self.peek(1)
            if nxt not in _CMP:
                self.take()
                self.used[tok] = None
                self.cmp_units.add(BOOL)
                return ("bool", tok)
        return self.comparison()

    def interval(self) -> tuple[float, float] | None:
        if self.peek() != "[":
            return None
        self.take("[")
        lo = self.seconds()
        self.take(":")
        hi = self.seconds()
        self.take("]")
        if hi < lo:
            raise self.error(f"interval [{lo:g}:{hi:g}] ends before it starts")
        return (lo, hi)

    def seconds(self) -> float:
        tok = self.next("a time in s")
        if not _is_number(tok):
            raise self.error(f"interval bound {tok!r} is not a number of seconds")
        if self.peek() == "s":
            self.take()
        value = self.finite(tok)
        if value > MAX_BOUND:
            raise self.error(f"interval bound {tok} s is longer than a day ({MAX_BOUND:g} s, the limit)")
        self.bounds.append(value)
        return value

    def finite(self, tok: str) -> float:
        value = float(tok)
        if not math.isfinite(value):
            raise self.error(f"{tok} is not a finite number")
        return value

    def comparison(self) -> tuple:
        left, lu = self.arith()
        op = self.peek()
        if op not in _CMP:
            raise self.error(
                f"expected a comparison ({' '.join(_CMP)}) after {render(left)!r}, found "
                f"{op if op is not None else 'the end'!r}"
            )
        self.take()
        right, ru = self.arith()
        unit = _join(lu, ru)
        if unit is False:
            raise self.error(f"compares {render(left)!r} in {lu} with {render(right)!r} in {ru} (units differ)")
        if unit == BOOL:
            raise self.error(f"compares booleans ({render(left)} {op} {render(right)}): use the signal alone, or not")
        self.cmp_units.add(unit or "-")
        return ("cmp", op, left, right)

    def arith(self) -> tuple[tuple, str | None]:
        node, unit = self.term()
        while self.peek() in ("+", "-"):
            op = self.take()
            rt, ru = self.term()
            joined = _join(unit, ru)
            if joined is False:
                raise self.error(f"{render(node)!r} in {unit} {op} {render(rt)!r} in {ru} (units differ)")
            node, unit = ("bin", op, node, rt), joined
        return node, unit

    def term(self) -> tuple[tuple, str | None]:
        node, unit = self.factor()
        while self.peek() in ("*", "/"):
            op = self.take()
            rt, ru = self.factor()
            if op == "/" and rt[0] == "num" and float(rt[1]) == 0.0:
                raise self.error(f"divides by zero ({render(node)} / {render(rt)})")
            if unit is None or unit == "-":
                unit = ru if op == "*" else (None if ru in (None, "-") else f"1/({ru})")
            elif ru not in (None, "-"):
                unit = f"({unit}){op}({ru})"
            node = ("bin", op, node, rt)
        return node, unit

    def factor(self) -> tuple[tuple, str | None]:
        tok = self.next("a signal or a number")
        if tok in ("-", "(", "abs"):
            self.deeper()
            if tok == "-":
                node, unit = self.factor()
                # rtamt's grammar takes a sign before a number only: -speed is 0 - speed
                if node[0] == "num" and not node[1].startswith("-"):
                    node = ("num", f"-{node[1]}")
                else:
                    node = ("paren", ("bin", "-", ("num", "0.0"), node))
            else:
                if tok == "abs":
                    self.take("(")
                node, unit = self.arith()
                self.take(")")
                node = ("abs", node) if tok == "abs" else ("paren", node)
            self.depth -= 1
            return node, unit
        if _is_number(tok):
            value, unit = repr(self.finite(tok)), self.unit_suffix()
            after = self.peek()
            if unit is None and after is not None and _is_name(after) and after not in _KEYWORDS:
                units = sorted((set(KNOWN_UNITS) | {u for u in self.units.values() if u and u != BOOL}) - {"-"})
                raise self.error(f"unknown unit {after!r} after {tok} (units: {', '.join(units)}; SI only)")
            return ("num", value), unit
        if tok in _KEYWORDS or not _is_name(tok):
            raise self.error(f"expected a signal or a number, found {tok!r}")
        if tok not in self.units:
            known = sorted(self.units)
            raise self.error(f"unknown signal {tok!r} (known: {', '.join(known)}){did_you_mean(tok, known)}")
        if self.units[tok] == BOOL:
            raise self.error(f"{tok} is a boolean signal: use it alone as a proposition (e.g. not {tok})")
        self.used[tok] = None
        return ("sig", tok), self.units[tok] or "-"

    def unit_suffix(self) -> str | None:
        """The unit written after a number (tokens up to the longest known unit), or None. A
        dimensionless number is written bare: ``-`` after a number is a minus (``100 - speed``)."""
        for unit in sorted(
            (set(KNOWN_UNITS) | {u for u in self.units.values() if u and u != BOOL}) - {"-"},
            key=len,
            reverse=True,
        ):
            toks = [t for t in self._lex_unit(unit)]
            if toks and self.toks[self.i : self.i + len(toks)] == toks:
                # "s" after a number inside an interval is handled by seconds(); here a name
                # that is also a signal is a unit only when a comparison or an operator follows
                self.i += len(toks)
                return unit
        return None

    @staticmethod
    def _lex_unit(unit: str) -> list[str]:
        return [m.group(m.lastgroup) for m in _TOKEN.finditer(unit)]


def _is_number(tok: str) -> bool:
    return bool(tok) and (tok[0].isdigit() or (tok[0] == "." and len(tok) > 1))


def _is_name(tok: str) -> bool:
    return tok[0].isalpha() or tok[0] == "_"


def _join(a: str | None, b: str | None):
    """The unit of ``a`` op ``b`` for + - and comparisons: None (a bare number), the common
    unit, or False when they differ."""
    if a is None:
        return b
    if b is None or a == b:
        return a
    return False


def parse(formula: str, units: Mapping[str, str], name: str = "requirement") -> Requirement:
    """Check ``formula`` against the signals ``units`` (name -> unit; ``bool`` for booleans)
    and translate it for rtamt. RequirementError (one line) on anything wrong."""
    if not isinstance(formula, str):
        raise RequirementError(f"bad requirement {name!r}: the formula must be text, got {formula!r}")
    p = _Parser(formula.strip(), units)
    tree = p.parse()
    unit = next(iter(p.cmp_units)) if len(p.cmp_units) == 1 else "mixed"
    return Requirement(name, formula.strip(), render(tree), tuple(p.used), unit, tuple(p.bounds), tree)


def sample_stride(bounds: Sequence[float], dt: float, period: float = 0.1) -> int:
    """The most samples of ``dt`` s, at most ``period`` s, that every interval bound of
    ``bounds`` is a whole number of (to 1e-6 of a sample); 1 when there is none: the bounds
    are then taken at the nearest control step."""
    for stride in range(max(1, round(period / dt)), 1, -1):
        step = stride * dt
        if all(abs(b / step - round(b / step)) < 1e-6 for b in bounds):
            return stride
    return 1


_INTERVAL = re.compile(r"\[([^:\]]+):([^\]]+)\]")


def in_samples(rtamt_text: str, step: float) -> str:
    """The formula with its interval bounds (s) as whole numbers of samples ``step`` s apart
    (the nearest), which rtamt reads exactly against a sampling period of 1."""
    return _INTERVAL.sub(lambda m: f"[{round(float(m.group(1)) / step)}:{round(float(m.group(2)) / step)}]", rtamt_text)


def split(text: str) -> tuple[str, str]:
    """``"name: formula"`` -> (name, formula); RequirementError naming the text otherwise."""
    name, sep, formula = text.partition(":")
    name = name.strip()
    if not sep or not _REQ_NAME.match(name) or not formula.strip():
        raise RequirementError(
            f"bad --require {text!r} (expected NAME: FORMULA, e.g. "
            '"keep_gap: always (gap_front >= 2 m)"; NAME a Python identifier)'
        )
    return name, formula.strip()


def from_options(texts: Sequence[str]) -> dict[str, str]:
    """``--require`` options as name -> formula; a name given twice is refused (the later
    one would silently win, as a ``--set`` key given twice would)."""
    out: dict[str, str] = {}
    for text in texts:
        name, formula = split(text)
        if name in out:
            raise RequirementError(f"--require {name} is given twice ({out[name]!r} and {formula!r})")
        out[name] = formula
    return out


def from_table(table, source: str) -> dict[str, str]:
    """A TOML ``[requirements]`` table (name = "formula") checked for shape."""
    if not isinstance(table, dict):
        raise RequirementError(f'{source}: [requirements] must be a table of name = "formula"')
    for k, v in table.items():
        if not _REQ_NAME.match(k) or not isinstance(v, str) or not v.strip():
            raise RequirementError(
                f'{source}: [requirements] {k} = {v!r}: expected name = "formula" (name a Python identifier)'
            )
    return {k: v.strip() for k, v in table.items()}


# -- defaults ---------------------------------------------------------------------------------------
def defaults(scenario: str, cls: type | None = None) -> dict[str, str]:
    """The scenario's default requirements (name -> formula), as its class declares them
    (``Scenario.requirements``): ``cls``, else the registered scenario ``scenario``; a class
    that names a ``base_scenario`` (a scenario file: emergency-brake) has that one's and its
    own ``extra_requirements`` (an UN R157 file: ``no_preventable_collision``). None for a
    name no scenario has (a reference resolves its class first)."""
    from ego.scenarios import SCENARIOS

    if cls is None:
        cls = SCENARIOS.get(scenario)
        if cls is None:
            return {}
    base = getattr(cls, "base_scenario", None)
    own = dict(getattr(cls, "extra_requirements", ()))  # a file's own (an R157 file's)
    if base in SCENARIOS:
        cls = SCENARIOS[base]
    return {**dict(getattr(cls, "requirements", ())), **own}


# -- resolving and evaluating -----------------------------------------------------------------------
def signal_units(columns: Mapping[str, str], metrics: Sequence[str] = (), cls=None) -> dict[str, str]:
    """Every signal a formula may name for a run with trace ``columns`` (name -> unit),
    metric names ``metrics`` and scenario class ``cls``: the columns and the derived signals
    they allow."""
    out = dict(columns)

    def have(need: str) -> bool:
        kind, _, name = need.rpartition(":")
        if kind == "metric":
            return name in metrics
        if kind == "scenario":
            return hasattr(cls, name)
        return name in columns

    for d in DERIVED.values():
        ok = all(have(n) for n in d.needs)
        if ok and d.name not in out:
            out[d.name] = d.unit
    return out


def resolve(texts: Mapping[str, str], units: Mapping[str, str]) -> tuple[Requirement, ...]:
    """Parse every (name -> formula) against ``units``; the first problem is the error."""
    out = []
    for name, formula in texts.items():
        try:
            out.append(parse(formula, units, name))
        except RequirementError as exc:
            raise RequirementError(f"requirement {name}: {exc}") from None
    return tuple(out)


def signal(result, name: str, scenario=None) -> np.ndarray:
    """Signal ``name`` of a finished run as floats (booleans +1/-1; infinities clipped to
    +-1e9, so the min/max stay finite)."""
    t = result.column("t")
    if name in result.columns:
        x = result.column(name).astype(float)
    else:
        x = np.asarray(DERIVED[name].fn(result, t, scenario))
        if x.dtype == bool:
            return np.where(x, 1.0, -1.0)
    x = np.nan_to_num(x, nan=0.0, posinf=1e9, neginf=-1e9)
    return x


@dataclass(frozen=True)
class Verdict:
    """A requirement's result on one run: robustness at t = 0 (``unit``) and the first time
    its body fails (``always`` formulas: the first sample where the body's robustness is
    negative; others: where the formula's own robustness is), None when satisfied."""

    name: str
    robustness: float
    violated_at: float | None
    unit: str

    @property
    def passed(self) -> bool:
        return self.robustness >= 0.0


#: an infinite robustness (a formula's arithmetic past the float range) is reported as this
#: bound with its sign, the one signals are clamped to (:func:`signal`): the verdict stays,
#: the number is one JSON and Parquet take (docs/reliability.md, "Limits")
MAX_ROBUSTNESS = 1e9

#: requirements are evaluated on every sample of the trace by default (0: the control step,
#: 0.01 s); a period > 0 (``--requirement-period 0.1``, a spec's ``requirement_period``)
#: evaluates them on a grid of samples that far apart instead (the SUMO step, at which the
#: traffic's signals change; a violation shorter than it can be missed)
PERIOD = 0.0
#: the metrics :func:`check_run` adds to a run (absent where requirements are not evaluated: a Gym env)
METRIC_KEYS = ("requirements", "first_violation")
#: the largest grid period accepted (s)
MAX_PERIOD = 10.0


def check_period(value, what: str = "--requirement-period") -> float:
    """``value`` as a requirement period (s): 0 (every sample) up to MAX_PERIOD; ConfigError
    naming it otherwise."""
    try:
        period = float(value)
    except (TypeError, ValueError):
        period = math.nan
    if isinstance(value, bool) or not (0.0 <= period <= MAX_PERIOD):
        raise RequirementError(
            f"bad {what} {value!r} (expected seconds from 0, every sample of the trace, to {MAX_PERIOD:g})"
        )
    return period


def evaluate(req: Requirement, result, period: float = PERIOD, scenario=None) -> Verdict:
    """Evaluate ``req`` on a finished run (rtamt's offline discrete-time semantics, in numpy:
    :mod:`ego.stl`) on every sample of the trace (``period`` 0, the default) or on samples
    every ``period`` s, counted back from the last one so the run's end (a collision) is
    always a sample. An ``always`` formula is evaluated as its body's robustness signal,
    whose minimum is the formula's robustness (the same number, and its first negative
    sample is the first violation)."""
    t_all = result.column("t")
    if len(t_all) < 2:
        return Verdict(req.name, math.nan, None, req.unit)
    dt = float(t_all[1] - t_all[0])
    # samples every interval bound falls on (else every control step, the bounds at the
    # nearest one)
    stride = sample_stride(req.bounds, dt, period) if period > 0 else 1
    idx = np.arange(len(t_all) - 1, -1, -stride)[::-1]
    if len(idx) < 2:
        idx = np.arange(len(t_all))
        stride = 1
    t = t_all[idx] if stride > 1 else t_all
    tree = req.tree or parse(req.formula, {n: DERIVED[n].unit if n in DERIVED else "-" for n in req.signals}).tree
    always = tree[0] == "temporal" and tree[1] == "always" and tree[2] is None
    body = tree[3] if always else tree
    data = {n: (signal(result, n, scenario)[idx] if stride > 1 else signal(result, n, scenario)) for n in req.signals}
    try:
        rob = robustness(body, data, len(idx), stride * dt)
    except (ArithmeticError, ValueError, MemoryError, RecursionError):  # no number
        return Verdict(req.name, math.nan, None, req.unit)
    if not len(rob):
        return Verdict(req.name, math.nan, None, req.unit)
    value = float(rob.min()) if always else float(rob[0])
    if math.isnan(value):
        return Verdict(req.name, math.nan, None, req.unit)
    if math.isinf(value):  # arithmetic past the float range (speed * 1e300 * 1e300): the
        value = math.copysign(MAX_ROBUSTNESS, value)  # verdict kept, the bound signals have
    at = None
    if value < 0.0:
        bad = np.flatnonzero(rob < 0.0)
        at = float(t[bad[0]]) if len(bad) else float(t[0])
    return Verdict(req.name, value, at, req.unit)


def check_run(scenario, result, requirements: Sequence[Requirement], period: float = PERIOD) -> list[Verdict]:
    """Evaluate ``requirements`` on ``result`` (a run of ``scenario`` that has not closed its
    recording yet; every sample of its trace, or a grid ``period`` s apart): the robustness
    of each into ``result.metrics["requirements"]``, the first violation's time of each into
    ``result.metrics["first_violation"]`` (None: not violated), each violation as a
    ``requirement`` event of the run (in time order, before the run's own events of that
    moment) and of its recording."""
    from ego.scenarios.base import Event

    verdicts = []
    rob, first = {}, {}
    for req in requirements:
        v = evaluate(req, result, period, scenario=scenario)
        verdicts.append(v)
        rob[req.name] = None if math.isnan(v.robustness) else round(v.robustness, 6)
        first[req.name] = None if v.violated_at is None else round(v.violated_at, 6)
        if v.violated_at is not None:
            text = (
                f"requirement {req.name} violated (robustness {v.robustness:.3g}"
                f"{'' if v.unit in ('-', 'mixed', BOOL) else ' ' + v.unit}): {req.formula}"
            )
            # in time order, before the run's own events of that moment (its end stays last)
            at = next((i for i, e in enumerate(result.events) if e.t >= v.violated_at), len(result.events))
            result.events.insert(at, Event(v.violated_at, "requirement", text, "WARN"))
            scenario.recorder.event(v.violated_at, f"[requirement] {text}", "WARN")
    if requirements:
        result.metrics.update(zip(METRIC_KEYS, (rob, first), strict=True))
    return verdicts


# -- summaries ----------------------------------------------------------------------------------------
PREFIX = REQUIREMENTS_PREFIX


#: every run's requirements' robustness in its metrics, flattened: ``requirements.<name>``
#: (the pass/fail table of many runs is :func:`ego.results.summary.requirement_lines`)
summary_lines = requirement_lines


def with_defaults(scenario: str, texts: Sequence[str]) -> tuple[tuple[str, str], ...] | None:
    """``--require NAME: FORMULA`` options on top of the scenario's defaults (a name given
    again replaces the default); None (the defaults) without options."""
    if not texts:
        return None
    options = from_options(texts)
    from ego.params import ConfigError
    from ego.scenarios import scenario_class

    try:
        cls = scenario_class(scenario)  # a scenario file or a user's class: its base's defaults
    except ConfigError:
        cls = None  # named wrongly: resolving the run says so
    return tuple({**defaults(scenario, cls), **options}.items())
