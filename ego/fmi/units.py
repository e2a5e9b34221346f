"""Units: an FMU variable's unit against the task signal's, and the conversion between them.

A unit is (SI base exponents, factor, offset) with ``value_SI = factor * value + offset``,
as FMI's ``UnitDefinitions`` give it (base units kg, m, s, A, K, mol, cd and rad). ego's
task signals are in SI (``m``, ``m/s``, ``m/s^2``, ``rad``, ``N``, ``1/m``...). An FMU unit
comes from its ``UnitDefinitions``; a unit listed there by name only (no ``BaseUnit``) is
read as one of the common names below (``km/h``, ``deg``, ``kN``...); one not listed at all
fmpy's validation refuses first. Two units convert when their
exponents agree; otherwise it is a ConfigError naming both.
"""

from __future__ import annotations

import math
import re

from ego.params import ConfigError

Unit = tuple[dict, float, float]

_BASE: dict[str, Unit] = {
    "m": ({"m": 1}, 1.0, 0.0),
    "s": ({"s": 1}, 1.0, 0.0),
    "kg": ({"kg": 1}, 1.0, 0.0),
    "rad": ({"rad": 1}, 1.0, 0.0),
    "N": ({"kg": 1, "m": 1, "s": -2}, 1.0, 0.0),
    "kN": ({"kg": 1, "m": 1, "s": -2}, 1000.0, 0.0),
    "km": ({"m": 1}, 1000.0, 0.0),
    "cm": ({"m": 1}, 0.01, 0.0),
    "mm": ({"m": 1}, 0.001, 0.0),
    "ms": ({"s": 1}, 0.001, 0.0),
    "h": ({"s": 1}, 3600.0, 0.0),
    "min": ({"s": 1}, 60.0, 0.0),
    "deg": ({"rad": 1}, math.pi / 180.0, 0.0),
    "g": ({"kg": 1}, 0.001, 0.0),
    "t": ({"kg": 1}, 1000.0, 0.0),
    "Nm": ({"kg": 1, "m": 2, "s": -2}, 1.0, 0.0),
    "K": ({"K": 1}, 1.0, 0.0),
    "degC": ({"K": 1}, 1.0, 273.15),
    "1": ({}, 1.0, 0.0),
    "-": ({}, 1.0, 0.0),
}
_ALIASES = {
    "kph": "km/h",
    "km/hr": "km/h",
    "mps": "m/s",
    "degree": "deg",
    "degrees": "deg",
    "rpm": "rev/min",
    "rev": "rev",
}
_BASE["rev"] = ({"rad": 1}, 2.0 * math.pi, 0.0)


def parse(text: str) -> Unit | None:
    """``m/s^2``, ``km/h``, ``rad/s``, ``1/m``, ``N s/m``... as (exponents, factor, offset); None
    when a part is not known. Products by space, ``.`` or ``*``; one ``/`` divides all after it."""
    text = _ALIASES.get(text.strip(), text.strip())
    if text in ("", "1", "-"):
        return {}, 1.0, 0.0
    if text in _BASE:
        return _BASE[text]
    num, _, den = text.partition("/")
    exps: dict[str, int] = {}
    factor = 1.0
    for part, sign in ((num, 1), (den, -1)):
        for tok in re.split(r"[ .*]+", part.strip("() ")):
            if not tok or tok == "1":
                continue
            m = re.fullmatch(r"([A-Za-z]+)(?:\^?(-?\d+))?", tok)
            if not m or m.group(1) not in _BASE or _BASE[m.group(1)][2] != 0.0:
                return None
            e = int(m.group(2) or 1) * sign
            base, f, _ = _BASE[m.group(1)]
            factor *= f**e
            for k, x in base.items():
                exps[k] = exps.get(k, 0) + x * e
    return {k: e for k, e in exps.items() if e}, factor, 0.0


def fmu_unit(name: str, definitions: dict) -> Unit | None:
    """The FMU's unit ``name``: its definition if it has one with a ``BaseUnit``, else (listed by
    name only) the common name; None when neither says what it is."""
    d = definitions.get(name)
    if d is not None:
        return d
    return parse(name)


def _same(a: dict, b: dict) -> bool:
    """Exponents agree; a radian counts as dimensionless only against itself (deg vs rad ok,
    rad vs 1 not: an angle where a pure number is expected is a mapping error)."""
    return {k: v for k, v in a.items() if v} == {k: v for k, v in b.items() if v}


def conversion(fmu_unit_name: str, definitions: dict, task_unit: str, what: str) -> tuple[float, float]:
    """(factor, offset) with ``value_in_task_unit = factor * value_in_fmu_unit + offset``.
    An FMU variable without a unit is taken as in the task's unit."""
    if not fmu_unit_name:
        return 1.0, 0.0
    fu = fmu_unit(fmu_unit_name, definitions)
    tu = parse(task_unit)
    if fu is None:
        raise ConfigError(
            f"{what}: unit {fmu_unit_name!r} is not defined in the FMU's UnitDefinitions and "
            f"is not a unit ego knows (expected something convertible to {task_unit})"
        )
    if tu is None:  # a task unit ego does not parse (should not happen): only the same name passes
        if fmu_unit_name == task_unit:
            return 1.0, 0.0
        raise ConfigError(f"{what}: cannot convert {fmu_unit_name!r} to {task_unit!r}")
    if not _same(fu[0], tu[0]):
        raise ConfigError(f"{what}: unit {fmu_unit_name!r} cannot be converted to {task_unit!r} (different dimensions)")
    # SI = f_f * x + o_f ; task = (SI - o_t) / f_t
    factor = fu[1] / tu[1]
    offset = (fu[2] - tu[2]) / tu[1]
    return factor, offset
