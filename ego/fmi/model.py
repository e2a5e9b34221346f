"""Reading an FMU and checking it can run here, before anything runs.

:func:`inspect_fmu` opens the zip, reads and validates ``modelDescription.xml`` (fmpy) and
refuses, in one line naming the file and the reason: a file that is not a zip, a missing or
invalid model description, FMI 1.0, model exchange only, no binary for this platform (naming
the platforms it has), non-real inputs or outputs. The result is cached by the file's content
hash, so a worker re-reading the same file does not parse it again.
"""

from __future__ import annotations

import math
import os
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ego.params import ConfigError
from ego.plugins import file_digest

REAL_TYPES = ("Real", "Float64", "Float32")


@dataclass(frozen=True)
class FmuVar:
    """A variable of the FMU, as ego uses it."""

    name: str
    vr: int
    type: str  #: Real (FMI 2.0) / Float64 (3.0) / Integer / Boolean ...
    causality: str
    variability: str
    start: float | None
    unit: str  #: the unit's name ("" when none)
    description: str


@dataclass(frozen=True, eq=False)
class FmuInfo:
    """What ego needs from an FMU's model description (picklable; equal and hashed by the
    file's path and content)."""

    def __eq__(self, other: object) -> bool:
        return isinstance(other, FmuInfo) and (other.path, other.digest) == (self.path, self.digest)

    def __hash__(self) -> int:
        return hash((self.path, self.digest))

    path: str
    digest: str
    fmi_version: str  #: "2.0" or "3.0"
    model_name: str
    model_identifier: str
    guid: str
    description: str
    variables: tuple[FmuVar, ...]
    #: unit name -> ({SI base unit: exponent}, factor, offset)
    units: dict
    variable_step: bool
    fixed_step: float | None  #: FMI 3.0 fixedInternalStepSize
    default_step: float | None
    generation_tool: str

    def var(self, name: str) -> FmuVar | None:
        for v in self.variables:
            if v.name == name:
                return v
        return None

    def of(self, causality: str) -> list[FmuVar]:
        return [v for v in self.variables if v.causality == causality]

    @property
    def tunable(self) -> list[FmuVar]:
        """Parameters ego may set (``--set fmu.<name>=value``): real parameters, fixed or tunable."""
        return [v for v in self.variables if v.causality == "parameter" and v.type in REAL_TYPES]


_cache: dict[tuple[str, str], FmuInfo] = {}

#: limits of an FMU archive, checked before anything is extracted (docs/reliability.md)
MAX_ENTRIES = 10_000
MAX_ENTRY_BYTES = 512 * 1024 * 1024  #: one entry, uncompressed (declared and real)
MAX_TOTAL_BYTES = 1024 * 1024 * 1024  #: all entries, uncompressed (declared and real)
MAX_DESCRIPTION_BYTES = 16 * 1024 * 1024  #: modelDescription.xml


def _mib(n: int) -> str:
    return f"{n / (1024 * 1024):.0f} MiB"


def check_archive(z: zipfile.ZipFile, shown: str) -> None:
    """The archive's entries: how many, their names (inside the archive) and declared sizes;
    ConfigError (one line) before anything is read or extracted."""
    infos = z.infolist()
    if len(infos) > MAX_ENTRIES:
        raise ConfigError(f"bad FMU {shown!r}: {len(infos):,} entries in the archive (the limit is {MAX_ENTRIES:,})")
    total = 0
    for i in infos:
        name = i.filename
        parts = name.replace("\\", "/").split("/")
        if name.startswith(("/", "\\")) or ".." in parts or (len(name) > 1 and name[1] == ":"):
            raise ConfigError(f"bad FMU {shown!r}: the entry {name[:80]!r} points outside the archive's folder")
        if i.file_size > MAX_ENTRY_BYTES:
            raise ConfigError(
                f"bad FMU {shown!r}: {name[:80]!r} is {_mib(i.file_size)} uncompressed "
                f"(the limit is {_mib(MAX_ENTRY_BYTES)} an entry)"
            )
        total += i.file_size
    if total > MAX_TOTAL_BYTES:
        raise ConfigError(
            f"bad FMU {shown!r}: {_mib(total)} uncompressed (the limit is {_mib(MAX_TOTAL_BYTES)} an archive)"
        )


def read_entry(z: zipfile.ZipFile, name: str, limit: int, shown: str) -> bytes:
    """Entry ``name``, decompressed as a stream and refused past ``limit`` bytes (whatever
    its header declares)."""
    out, n = [], 0
    with z.open(name) as f:
        while chunk := f.read(1 << 20):
            n += len(chunk)
            if n > limit:
                raise ConfigError(f"bad FMU {shown!r}: {name!r} inflates past {_mib(limit)} (the limit)")
            out.append(chunk)
    return b"".join(out)


def extract(path: str, folder: str) -> None:
    """The archive at ``path`` into ``folder``, each entry streamed with the limits of
    :func:`check_archive` on the real (not only the declared) sizes."""
    shown = os.path.basename(path)
    total = 0
    with zipfile.ZipFile(path) as z:
        check_archive(z, shown)
        for info in z.infolist():
            target = os.path.join(folder, *info.filename.split("/"))
            if info.is_dir():
                os.makedirs(target, exist_ok=True)
                continue
            os.makedirs(os.path.dirname(target), exist_ok=True)
            n = 0
            with z.open(info) as src, open(target, "wb") as dst:
                while chunk := src.read(1 << 20):
                    n += len(chunk)
                    total += len(chunk)
                    if n > MAX_ENTRY_BYTES or total > MAX_TOTAL_BYTES:
                        raise ConfigError(
                            f"bad FMU {shown!r}: {info.filename[:80]!r} inflates past the limit "
                            f"({_mib(MAX_ENTRY_BYTES)} an entry, {_mib(MAX_TOTAL_BYTES)} an archive)"
                        )
                    dst.write(chunk)


def _platforms(z: zipfile.ZipFile) -> list[str]:
    out = set()
    for n in z.namelist():
        parts = n.split("/")
        if len(parts) >= 3 and parts[0] == "binaries" and parts[2]:
            out.add(parts[1])
    return sorted(out)


def _this_platform(version: str) -> str:
    import fmpy

    return fmpy.platform if version.startswith("2") else fmpy.platform_tuple


def inspect_fmu(path: str | os.PathLike) -> FmuInfo:
    """The model description of the co-simulation FMU at ``path``, checked for this machine;
    ConfigError (one line, the file named) otherwise."""
    from ego.fmi.guard import step_limit

    step_limit()  # EGO_FMU_STEP_LIMIT checked before anything runs
    shown = os.fspath(path)
    p = Path(shown).expanduser()
    if p.is_dir():  # an unpacked FMU, say
        raise ConfigError(f"bad FMU {shown!r}: it is a folder (expected a file ending in .fmu, a zip archive)")
    if not p.is_file():
        raise ConfigError(f"bad FMU {shown!r}: no such file")
    digest = file_digest(p)
    key = (str(p.resolve()), digest)
    info = _cache.get(key)
    if info is not None:
        return info
    try:
        from fmpy import read_model_description
    except ImportError:
        raise ConfigError("FMUs need fmpy: pip install 'ego[fmi]'") from None
    if not zipfile.is_zipfile(p):
        raise ConfigError(f"bad FMU {shown!r}: not a zip file (an FMU is a zip archive with a modelDescription.xml)")
    names, platforms, version = _read_archive(p, shown)
    if version.startswith("1"):
        raise ConfigError(f"bad FMU {shown!r}: FMI {version} is not supported (FMI 2.0 or 3.0 co-simulation)")
    try:
        md = read_model_description(str(p), validate=True)
    except Exception as exc:  # noqa: BLE001 - fmpy's reasons vary: an XML or schema error
        text = " ".join(str(exc).split())
        raise ConfigError(f"bad FMU {shown!r}: invalid modelDescription.xml: {text[:300]}") from None
    version = md.fmiVersion
    if not (version.startswith("2") or version.startswith("3")):
        raise ConfigError(f"bad FMU {shown!r}: FMI {version} is not supported (FMI 2.0 or 3.0 co-simulation)")
    _check_interface(md, shown, version, names, platforms)
    ident = md.coSimulation.modelIdentifier
    units, variables = _units(md), _variables(md)
    de = md.defaultExperiment
    cs = md.coSimulation
    fixed = getattr(cs, "fixedInternalStepSize", None)
    info = FmuInfo(
        path=str(p.resolve()),
        digest=digest,
        fmi_version="3.0" if version.startswith("3") else "2.0",
        model_name=md.modelName or ident,
        model_identifier=ident,
        guid=(md.guid if version.startswith("2") else getattr(md, "instantiationToken", None) or md.guid) or "",
        description=md.description or "",
        variables=tuple(variables),
        units=units,
        variable_step=bool(getattr(cs, "canHandleVariableCommunicationStepSize", False)),
        fixed_step=float(fixed) if fixed not in (None, "") else None,
        default_step=float(de.stepSize) if de is not None and de.stepSize not in (None, "") else None,
        generation_tool=md.generationTool or "",
    )
    _cache[key] = info
    return info


def _read_archive(p: Path, shown: str) -> tuple[set[str], list[str], str]:
    """The FMU's archive checked (sizes, a modelDescription.xml): its entry names, the
    platforms it has binaries for and the fmiVersion its description declares."""
    import re
    import zlib

    try:
        with zipfile.ZipFile(p) as z:
            check_archive(z, shown)
            names = set(z.namelist())
            if "modelDescription.xml" not in names:
                raise ConfigError(f"bad FMU {shown!r}: no modelDescription.xml in the archive")
            if z.getinfo("modelDescription.xml").file_size > MAX_DESCRIPTION_BYTES:
                raise ConfigError(
                    f"bad FMU {shown!r}: modelDescription.xml is larger than {_mib(MAX_DESCRIPTION_BYTES)} (the limit)"
                )
            platforms = _platforms(z)
            head = read_entry(z, "modelDescription.xml", MAX_DESCRIPTION_BYTES, shown)[:4000].decode("utf-8", "replace")
            m = re.search(r'fmiVersion\s*=\s*"([^"]*)"', head)
            return names, platforms, m.group(1) if m else ""
    except (zipfile.BadZipFile, zlib.error, NotImplementedError, RuntimeError, EOFError) as exc:
        raise ConfigError(f"bad FMU {shown!r}: a damaged or unsupported zip archive ({exc})") from None


def _check_interface(md: Any, shown: str, version: str, names: set[str], platforms: list[str]) -> None:
    """A co-simulation interface with a binary for this platform, or one line saying what
    the FMU has instead."""
    if md.coSimulation is None:
        kinds = [
            k
            for k, a in (("model exchange", "modelExchange"), ("scheduled execution", "scheduledExecution"))
            if getattr(md, a, None) is not None
        ]
        raise ConfigError(
            f"bad FMU {shown!r}: {' and '.join(kinds) or 'no'} interface only; ego steps "
            "co-simulation FMUs (export it for co-simulation)"
        )
    here = _this_platform(version)
    ident = md.coSimulation.modelIdentifier
    if here not in platforms:
        has = ", ".join(platforms) or "none (no binaries/ folder)"
        srcs = (
            " (it ships C sources: compile it for this platform, e.g. fmpy's compile_platform_binary)"
            if any(n.startswith("sources/") for n in names)
            else ""
        )
        raise ConfigError(f"bad FMU {shown!r}: no binary for this platform ({here}); it has binaries for {has}{srcs}")
    if not any(n.startswith(f"binaries/{here}/{ident}.") for n in names):
        raise ConfigError(f"bad FMU {shown!r}: binaries/{here}/ has no {ident} library")


def _units(md: Any) -> dict:
    """Unit name -> (SI exponents, factor, offset), None for a unit without a base unit."""
    units: dict = {}
    for u in md.unitDefinitions or ():
        b = u.baseUnit
        if b is None:
            units[u.name] = None
            continue
        exps = {k: int(getattr(b, k, 0) or 0) for k in ("kg", "m", "s", "A", "K", "mol", "cd", "rad")}
        units[u.name] = ({k: e for k, e in exps.items() if e}, float(b.factor or 1.0), float(b.offset or 0.0))
    return units


def _variables(md: Any) -> list[FmuVar]:
    """Every model variable with its unit (its own or its declared type's) and real start."""
    types = {t.name: t for t in md.typeDefinitions or ()}
    variables = []
    for v in md.modelVariables:
        unit = v.unit or ""
        if not unit and v.declaredType is not None:
            unit = getattr(v.declaredType, "unit", "") or ""
        if not unit and isinstance(getattr(v, "declaredType", None), str) and v.declaredType in types:
            unit = getattr(types[v.declaredType], "unit", "") or ""
        start = None
        if v.start is not None and v.type in REAL_TYPES:
            try:
                start = float(v.start)
            except (TypeError, ValueError):
                start = None
        variables.append(
            FmuVar(
                v.name,
                int(v.valueReference),
                v.type,
                v.causality or "local",
                v.variability or "continuous",
                start,
                unit,
                v.description or "",
            )
        )
    return variables


def check_step(info: FmuInfo, dt: float, name: str) -> None:
    """The communication step ``dt`` (the control period) is one the FMU can take: any step
    when it handles variable steps, else its fixed (3.0) or default step, or a whole multiple
    of its fixed internal step."""
    fixed = info.fixed_step or info.default_step
    if info.variable_step:
        if info.fixed_step and not _multiple(dt, info.fixed_step):
            raise ConfigError(
                f"bad FMU {name!r}: its fixed internal step {info.fixed_step:g} s does not divide "
                f"the control period dt = {dt:g} s (set --set dt= a multiple of it)"
            )
        return
    if fixed is None:
        return  # nothing declared: the FMU says at the first doStep
    if not _multiple(dt, fixed) if info.fixed_step else not math.isclose(dt, fixed, rel_tol=1e-9):
        raise ConfigError(
            f"bad FMU {name!r}: it cannot take a communication step of dt = {dt:g} s (it takes "
            f"only {fixed:g} s steps: canHandleVariableCommunicationStepSize is false; "
            f"set {_workable_step(fixed)})"
        )


def _workable_step(step: float) -> str:
    """The ``--set`` options that run an FMU of fixed step ``step``: dt = the step, and SUMO's
    0.1 s step or the nearest whole multiple of it above (SUMO's step is whole control periods)."""
    if _multiple(0.1, step):
        return f"--set dt={step:g}"
    sumo = round(math.ceil(0.1 / step - 1e-9) * step, 9)
    return f"--set dt={step:g} --set sumo_step={sumo:g}"


def _multiple(dt: float, step: float) -> bool:
    n = round(dt / step)
    return n >= 1 and math.isclose(n * step, dt, rel_tol=1e-9)
