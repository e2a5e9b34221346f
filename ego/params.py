"""Typed, unit-annotated parameters for scenarios and controllers.

Every configurable value is a field of a frozen dataclass declared with :func:`param`,
which records its unit, a one-line description and its allowed range. The CLI lists
them (``ego list``), parses ``--set key=value`` against them, and every error names the
parameter and what it accepts.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any


class ConfigError(ValueError):
    """A user-supplied value or name is not allowed; the message is one line for the user."""


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
            rng = f"from {_fmt(lo)} to {_fmt(hi)}" if not self.min_exclusive else \
                f"above {_fmt(lo)} and up to {_fmt(hi)}"
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
    hints = {f.name: f.type for f in dataclasses.fields(cls)}
    out = []
    for f in dataclasses.fields(cls):
        if "unit" not in f.metadata:
            continue
        t = hints[f.name]
        if isinstance(t, str):  # postponed annotations
            t = {"float": float, "int": int, "bool": bool, "str": str}[t]
        m = f.metadata
        out.append(ParamInfo(f.name, t, f.default, m["unit"], m["doc"], m["min"], m["max"],
                             m["choices"], m["min_exclusive"]))
    return out


def parse_value(info: ParamInfo, text: str) -> Any:
    """Convert command-line text to the parameter's type, or raise :class:`ConfigError`."""
    raw = text.strip()
    try:
        if info.type is bool:
            low = raw.lower()
            if low in ("true", "1", "yes", "on"):
                return True
            if low in ("false", "0", "no", "off"):
                return False
            raise ValueError
        if info.type is int:
            value: Any = int(raw)
        elif info.type is float:
            value = float(raw)
        else:
            value = raw
    except ValueError:
        raise ConfigError(f"bad value for {info.name}: {text!r} (expected {info.allowed()})") from None
    return value


def check_value(info: ParamInfo, value: Any) -> None:
    """Raise :class:`ConfigError` unless ``value`` is allowed for ``info``."""
    bad = f"bad value for {info.name}: {_fmt(value)} (expected {info.allowed()})"
    if info.choices is not None:
        if value not in info.choices:
            raise ConfigError(bad)
        return
    if info.type in (int, float):
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(bad)
        if info.type is int and int(value) != value:
            raise ConfigError(bad)
        if not math.isfinite(value):
            raise ConfigError(bad)
        if info.min is not None and (value <= info.min if info.min_exclusive else value < info.min):
            raise ConfigError(bad)
        if info.max is not None and value > info.max:
            raise ConfigError(bad)
    elif info.type is bool and not isinstance(value, bool):
        raise ConfigError(bad)


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
            raise ConfigError(f"bad --set item {item!r} (expected key=value)")
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
        if info.type is float and isinstance(typed, int) and not isinstance(typed, bool):
            typed = float(typed)
        check_value(info, typed)
        changes[key] = typed
    if strict and rest:
        raise unknown_parameter(next(iter(rest)), infos)
    new = dataclasses.replace(obj, **changes) if changes else obj
    validate(new)
    return new, rest


def unknown_parameter(key: str, known: Iterable[str]) -> ConfigError:
    names = sorted(known)
    return ConfigError(f"unknown parameter {key!r} (known: {', '.join(names)})")
