"""Typed, unit-annotated parameters for scenarios and controllers.

Every configurable value is a field of a frozen dataclass declared with :func:`param`,
which records its unit, a one-line description and its allowed range. The CLI lists
them (``ego list``), parses ``--set key=value`` against them, and every error names the
parameter and what it accepts.
"""

from __future__ import annotations

import dataclasses
import difflib
import functools
import math
import numbers
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

#: a quarter turn (rad): the bound of every steer limit and angle
HALF_PI = math.pi / 2


class ConfigError(ValueError):
    """A user-supplied value or name is not allowed; the message is one line for the user."""


def did_you_mean(name: Any, known: Iterable[Any]) -> str:
    """``"; did you mean 'x'?"`` for the known name closest to a misspelt ``name``, or ``""``."""
    if not isinstance(name, str):
        return ""
    names = [str(k) for k in known]
    close = difflib.get_close_matches(name, names, n=1, cutoff=0.6)
    if not close:  # a case slip (LEFT for left) is a near miss too
        lower = {n.lower(): n for n in names}
        close = [lower[n] for n in difflib.get_close_matches(name.lower(), list(lower), n=1, cutoff=0.8)]
    return f"; did you mean {close[0]!r}?" if close else ""


class Params:
    """Base of every parameter dataclass: its values are checked when it is made, so a
    controller's or scenario's parameters built in Python are held to the same ranges and
    types as ``--set`` (subclasses with a ``__post_init__`` of their own call this one)."""

    def __post_init__(self) -> None:
        validate(self)


def param(
    default: Any,
    unit: str,
    doc: str,
    *,
    min: float | None = None,
    max: float | None = None,
    choices: Iterable[Any] | None = None,
    min_exclusive: bool = False,
) -> Any:
    """A dataclass field carrying unit, description and allowed values."""
    meta = {
        "unit": unit,
        "doc": doc,
        "min": min,
        "max": max,
        "choices": tuple(choices) if choices is not None else None,
        "min_exclusive": min_exclusive,
    }
    return dataclasses.field(default=default, metadata=meta)


@dataclass(frozen=True)
class ParamInfo:
    name: str
    type: type
    default: Any
    unit: str
    doc: str
    min: float | None
    max: float | None
    choices: tuple | None
    min_exclusive: bool

    def allowed(self) -> str:
        """What the parameter accepts, for error messages and listings."""
        if self.choices is not None:
            return "one of " + ", ".join(_fmt(c) for c in self.choices)
        if self.type is bool:
            return "true or false"
        if self.type is str:
            return "text"
        kind = "a whole number" if self.type is int else "a number"
        lo, hi = self.min, self.max
        if lo is not None and hi is not None:
            rng = (
                f"from {_fmt(lo)} to {_fmt(hi)}" if not self.min_exclusive else f"above {_fmt(lo)} and up to {_fmt(hi)}"
            )
        elif lo is not None:
            rng = f"above {_fmt(lo)}" if self.min_exclusive else f"of at least {_fmt(lo)}"
        elif hi is not None:
            rng = f"up to {_fmt(hi)}"
        else:
            rng = ""
        unit = f" ({self.unit})" if self.unit not in ("", "-") else ""
        return " ".join(x for x in (kind, rng) if x) + unit


def _fmt(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float) and v.is_integer() and abs(v) < 1e15:
        return str(int(v))
    if isinstance(v, float):
        return f"{v:g}"
    return str(v)


def describe(cls_or_obj: Any) -> list[ParamInfo]:
    """The parameters of a config dataclass (class or instance), in declaration order."""
    cls = cls_or_obj if isinstance(cls_or_obj, type) else type(cls_or_obj)
    return list(_described(cls))


@functools.cache
def _described(cls: type) -> tuple[ParamInfo, ...]:
    """:func:`describe` once per class (a class's fields do not change; every value check
    and every resolved run asks)."""
    hints = {f.name: f.type for f in dataclasses.fields(cls)}
    out = []
    for f in dataclasses.fields(cls):
        if "unit" not in f.metadata:
            continue
        t = hints[f.name]
        if isinstance(t, str):  # postponed annotations
            t = {"float": float, "int": int, "bool": bool, "str": str}[t]
        m = f.metadata
        out.append(
            ParamInfo(f.name, t, f.default, m["unit"], m["doc"], m["min"], m["max"], m["choices"], m["min_exclusive"])
        )
    return tuple(out)


#: a number as the command line takes it: ASCII digits, an optional fraction and exponent
#: (inf and nan are read, then refused by the range check with the value named)
_NUMBER = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)(e[+-]?\d+)?|[+-]?(inf|infinity|nan)", re.ASCII | re.IGNORECASE)


def parse_value(info: ParamInfo, text: str) -> Any:
    """Convert command-line text to the parameter's type, or raise :class:`ConfigError`."""
    raw = text.strip()
    bad = f"bad value for {info.name}: {shown(text)} (expected {info.allowed()})"
    if info.type is bool:
        low = raw.lower()
        if low in ("true", "1", "yes", "on"):
            return True
        if low in ("false", "0", "no", "off"):
            return False
        raise ConfigError(bad)
    if info.type not in (int, float):
        return raw
    if not _NUMBER.fullmatch(raw):  # Python also reads "1_0" and other scripts' digits: not here
        raise ConfigError(bad)
    try:
        return info.type(raw)
    except (ValueError, OverflowError):
        pass
    whole = float(raw)  # the pattern is a float's
    if info.type is int and whole.is_integer():  # "2.0" or "1e2": a whole number written as a float
        raise ConfigError(f"{bad[:-1]}: write {int(whole)})")
    raise ConfigError(bad)


def shown(value: Any, exact: bool = False) -> str:
    """A value as a message quotes it, on one line and cut short: numbers plainly (``exact``:
    as Python writes them, so ``2.0`` shows it is a float), anything else as its repr."""
    plain = isinstance(value, (int, float)) and not exact
    text = _fmt(value) if plain else repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _kind(value: Any) -> str:
    """What a value of the wrong type is, for the message."""
    if isinstance(value, bool):
        return "true/false"
    if isinstance(value, numbers.Integral):
        return "a whole number"
    if isinstance(value, numbers.Real):
        return "a float"
    if isinstance(value, str):
        return "text"
    return "None" if value is None else f"a {type(value).__name__}"


def _type_ok(info: ParamInfo, value: Any) -> bool:
    """Booleans are not numbers, and a float is not a whole number even when integral
    (``2.0`` for ``substeps`` is refused, not silently truncated)."""
    if info.type is bool:
        return isinstance(value, bool)
    if isinstance(value, bool):
        return False
    if info.type is int:
        return isinstance(value, numbers.Integral)
    if info.type is float:
        return isinstance(value, numbers.Real)
    return isinstance(value, info.type)


def check_value(info: ParamInfo, value: Any) -> None:
    """Raise :class:`ConfigError` unless ``value`` is allowed for ``info`` (type, then range)."""
    if not _type_ok(info, value):
        raise ConfigError(
            f"bad value for {info.name}: {shown(value, exact=True)} (expected {info.allowed()}, not {_kind(value)})"
        )
    if info.choices is not None:
        if value not in info.choices:
            raise ConfigError(_bad_value(info, value) + did_you_mean(value, info.choices))
        return
    if info.type in (int, float):
        try:
            finite = math.isfinite(value)
        except OverflowError:  # a whole number too big for a float
            finite = False
        if not finite:
            raise ConfigError(_bad_value(info, value))
        if info.min is not None and (value <= info.min if info.min_exclusive else value < info.min):
            raise ConfigError(_bad_value(info, value))
        if info.max is not None and value > info.max:
            raise ConfigError(_bad_value(info, value))


def _bad_value(info: ParamInfo, value: Any) -> str:
    """The message of a value out of range (written only when one is)."""
    return f"bad value for {info.name}: {shown(value)} (expected {info.allowed()})"


def validate(obj: Any) -> None:
    """Check every annotated field of a config instance."""
    for info in describe(obj):
        check_value(info, getattr(obj, info.name))


def parse_overrides(pairs: Iterable[str]) -> dict[str, str]:
    """``["a=1", "b=x"]`` -> ``{"a": "1", "b": "x"}``; malformed items raise ConfigError."""
    out: dict[str, str] = {}
    for item in pairs:
        key, sep, value = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise ConfigError(f"bad --set item {shown(item)} (expected key=value)")
        if key in out:  # the later one would silently win
            raise ConfigError(f"--set {key} is given twice ({shown(out[key])} and {shown(value)})")
        out[key] = value
    return out


def apply_overrides(obj: Any, overrides: Mapping[str, Any], *, strict: bool = True) -> tuple[Any, dict]:
    """Return (copy of ``obj`` with the overrides it knows applied and validated, leftovers).

    Values may be strings (parsed) or already typed. With ``strict`` an unknown key raises.
    """
    infos = {i.name: i for i in describe(obj)}
    changes = {}
    rest = {}
    for key, value in overrides.items():
        info = infos.get(key)
        if info is None:
            rest[key] = value
            continue
        typed = parse_value(info, value) if isinstance(value, str) else value
        check_value(info, typed)
        # plain Python values (an int for a float, numpy scalars): hashes and JSON stay stable
        changes[key] = info.type(typed)
    if strict and rest:
        raise unknown_parameter(next(iter(rest)), infos)
    new = dataclasses.replace(obj, **changes) if changes else obj
    if not isinstance(new, Params):  # a Params checked itself when it was made
        validate(new)
    return new, rest


def unknown_parameter(key: str, known: Iterable[str]) -> ConfigError:
    names = sorted(set(known))
    # the suggestion before the (long) list, where it is read
    return ConfigError(f"unknown parameter {key!r}{did_you_mean(key, names)} (known: {', '.join(names)})")
