"""Connecting an FMU's inputs and outputs to a task's observation and action.

Default: an FMU input named like one of the task's observation signals gets that signal, an
FMU output named like one of its actions gives that action (``ego list`` lists both with
units). A TOML mapping file (``--set fmu_map=map.toml``) names other connections, FMU
variable = task signal::

    [inputs]                 # FMU input = observation signal
    lateral_error = "e_lat"
    v_kmh = "speed"
    [outputs]                # FMU output = action (or plant output, for a plant FMU)
    steer_deg = "delta"

Names the file does not mention are still connected by name. Every FMU input must be
connected (an FMU cannot run on a dangling input), every action must come from an output;
the other outputs are recorded as the controller's signals. Units are checked and
converted (:mod:`ego.fmi.units`).
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path

from ego.fmi.model import REAL_TYPES, FmuInfo
from ego.fmi.units import conversion
from ego.params import ConfigError, did_you_mean


@dataclass(frozen=True)
class Link:
    """One connection: FMU variable (value reference) <-> task signal, with the conversion
    ``task = factor * fmu + offset``."""

    fmu_name: str
    vr: int
    signal: str
    factor: float
    offset: float

    @property
    def identity(self) -> bool:
        return self.factor == 1.0 and self.offset == 0.0


@dataclass(frozen=True)
class Mapping:
    inputs: tuple[Link, ...]  #: FMU inputs, from observation signals
    outputs: tuple[Link, ...]  #: in the order of the task's actions
    extras: tuple[Link, ...]  #: other real outputs: recorded as signals (their unit kept)
    extra_units: tuple[str, ...]


def read_map_file(path: str, key: str = "fmu_map") -> dict:
    """The [inputs]/[outputs] tables of a mapping file, the value of parameter ``key``
    (ConfigError naming it and what is wrong)."""
    from ego.checks import MAX_MAP_BYTES, read_limited

    p = Path(path).expanduser()
    if not p.exists() and not p.is_symlink():
        raise ConfigError(f"bad value for {key}: no file {path!r} (expected a TOML mapping file)")
    raw = read_limited(p, f"{key} file", MAX_MAP_BYTES)
    try:
        data = tomllib.loads(raw.decode("utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ConfigError(f"bad {key} {path!r}: not TOML ({exc})") from None
    bad = set(data) - {"inputs", "outputs"}
    if bad:
        raise ConfigError(f"bad {key} {path!r}: unknown table {sorted(bad)[0]!r} (expected [inputs] and [outputs])")
    out = {}
    for table in ("inputs", "outputs"):
        items = data.get(table, {})
        if not isinstance(items, dict) or not all(isinstance(v, str) for v in items.values()):
            raise ConfigError(f'bad {key} {path!r}: [{table}] must hold FMU_VARIABLE = "signal" lines')
        out[table] = dict(items)
    return out


def build_mapping(
    info: FmuInfo,
    observes: dict[str, str],
    actions: dict[str, str],
    name: str,
    map_file: str = "",
    *,
    outputs_word: str = "action",
    key: str = "fmu_map",
) -> Mapping:
    """Connect ``info``'s variables to ``observes`` (signal -> unit) and ``actions``
    (action -> unit, in order); ``map_file`` is the value of parameter ``key``. ConfigError
    names the FMU and the offending variable."""
    explicit = read_map_file(map_file, key) if map_file else {"inputs": {}, "outputs": {}}
    by_name = {v.name: v for v in info.variables}
    for table, causality in (("inputs", "input"), ("outputs", "output")):
        for var, signal in explicit[table].items():
            v = by_name.get(var)
            if v is None:
                raise ConfigError(
                    f"bad {key} for {name!r}: the FMU has no variable {var!r}{did_you_mean(var, by_name)}"
                )
            if v.causality != causality:
                raise ConfigError(
                    f"bad {key} for {name!r}: FMU variable {var!r} is {_a(v.causality)}, not an {causality}"
                )
            known = observes if table == "inputs" else actions
            if signal not in known:
                what = "observation signal" if table == "inputs" else outputs_word
                raise ConfigError(
                    f"bad {key} for {name!r}: unknown {what} {signal!r} for {var!r} (known: "
                    f"{', '.join(known)}){did_you_mean(signal, known)}"
                )
    inputs = []
    for v in info.of("input"):
        signal = explicit["inputs"].get(v.name, v.name)
        if signal not in observes:
            raise ConfigError(
                f"FMU {name!r}: input {v.name!r} is connected to no observation signal (known: "
                f"{', '.join(observes)}); name it in a mapping file (--set {key}=map.toml)"
            )
        _real(v, name)
        f, o = conversion(v.unit, info.units, observes[signal], f"FMU {name!r} input {v.name!r}")
        # the FMU gets fmu = (task - o) / f
        inputs.append(Link(v.name, v.vr, signal, f, o))
    given = {sig: var for var, sig in explicit["outputs"].items()}
    outputs = []
    for action, unit in actions.items():
        var = given.get(action, action)
        v = by_name.get(var)
        if v is None:
            outs = ", ".join(o.name for o in info.of("output")) or "none"
            raise ConfigError(
                f"FMU {name!r}: no output for the {outputs_word} {action!r} ({unit}); its outputs: "
                f"{outs}; name it in a mapping file (--set {key}=map.toml)"
            )
        if v.causality != "output":
            raise ConfigError(
                f"FMU {name!r}: variable {var!r} for the {outputs_word} {action!r} is {_a(v.causality)}, not an output"
            )
        _real(v, name)
        f, o = conversion(v.unit, info.units, unit, f"FMU {name!r} output {var!r}")
        outputs.append(Link(v.name, v.vr, action, f, o))
    used = {link.fmu_name for link in outputs}
    extras = tuple(
        Link(v.name, v.vr, v.name, 1.0, 0.0) for v in info.of("output") if v.name not in used and v.type in REAL_TYPES
    )
    units = tuple(next((x.unit for x in info.variables if x.name == e.fmu_name), "") for e in extras)
    return Mapping(tuple(inputs), tuple(outputs), extras, units)


def _a(causality: str) -> str:
    return {
        "input": "an input",
        "output": "an output",
        "parameter": "a parameter",
        "calculatedParameter": "a calculated parameter",
        "independent": "the independent variable",
    }.get(causality, f"a {causality} variable")


def _real(v, name: str) -> None:
    if v.type not in REAL_TYPES:
        raise ConfigError(f"FMU {name!r}: variable {v.name!r} is {v.type}; ego connects real (Float64) variables only")
