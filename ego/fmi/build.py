"""Build FMI 2.0 / 3.0 co-simulation FMUs from a table of real variables and C sources.

One :class:`ModelSpec` writes both the ``modelDescription.xml`` and the C header the model
compiles against (``model_vars.h``: value references as ``VR_<name>``, start values), so the
two cannot disagree. The frame (``ego/fmi/c/fmi2_frame.c`` or ``fmi3_frame.c``) implements
the FMI functions around the model's ``model_init``/``model_step`` (``ego/fmi/c/model.h``).
The binary is compiled with the system C compiler (``cc``/``gcc``, ``$CC``) against the FMI
headers fmpy ships (``fmpy/c-code``), and the sources go into the FMU's ``sources/`` so it
can be compiled for another platform.

Used by ``ego export-fmu`` and by the tests' FMUs; results are cached by the hash of
everything that goes in.
"""

from __future__ import annotations

import hashlib
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from xml.sax.saxutils import quoteattr

from ego.params import ConfigError

FRAME_DIR = Path(__file__).parent / "c"


@dataclass(frozen=True)
class Var:
    """One real variable: name, causality (input, output, parameter, local), start value,
    unit (a name from :attr:`ModelSpec.units` or an SI name), description."""

    name: str
    causality: str
    start: float = 0.0
    unit: str = ""
    description: str = ""
    variability: str = ""  #: default: tunable for parameters, continuous otherwise


@dataclass(frozen=True)
class ModelSpec:
    """An FMU to build: identifier, variables (value reference = position), C sources."""

    identifier: str
    description: str
    variables: tuple[Var, ...]
    sources: tuple[Path, ...]  #: the model's .c files (headers next to them are shipped too)
    fmi_version: str = "2.0"
    #: unit name -> ({SI base unit: exponent}, factor, offset); the value in SI is
    #: factor * value + offset
    units: tuple[tuple[str, tuple[tuple[str, int], ...], float, float], ...] = ()
    defines: tuple[str, ...] = ()  #: -D macros for the model
    step_size: float | None = None  #: defaultExperiment stepSize
    fixed_step: bool = False  #: only the default step (canHandleVariableCommunicationStepSize false)
    extra_headers: tuple[Path, ...] = field(default=())

    @property
    def guid(self) -> str:
        return "{" + hashlib.sha256(repr(self).encode()).hexdigest()[:32] + "}"


def platform_dir(fmi_version: str) -> str:
    """The binaries/ folder of this platform (FMI 2.0: linux64; 3.0: x86_64-linux)."""
    machine = platform.machine().lower()
    bits64 = sys.maxsize > 2**32
    system = {"linux": "linux", "darwin": "darwin", "win32": "win"}.get(sys.platform, sys.platform)
    if fmi_version.startswith("2"):
        return f"{system}{64 if bits64 else 32}"
    arch = {"amd64": "x86_64", "arm64": "aarch64"}.get(machine, machine)
    return f"{arch}-{system if system != 'win' else 'windows'}"


def shared_suffix() -> str:
    return {"darwin": ".dylib", "win32": ".dll"}.get(sys.platform, ".so")


def fmi_headers() -> Path:
    """fmpy's copy of the FMI headers (fmi2*.h, fmi3*.h)."""
    try:
        import fmpy
    except ImportError as exc:
        raise ConfigError("building an FMU needs fmpy's FMI headers: pip install 'ego[fmi]'") from exc
    return Path(fmpy.__file__).parent / "c-code"


def compiler() -> str:
    cc = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
    if not cc:
        raise ConfigError("building an FMU needs a C compiler (cc or gcc on PATH, or $CC)")
    return cc


def _num(x: float) -> str:
    return repr(float(x))


def model_description(spec: ModelSpec) -> str:
    """The modelDescription.xml of ``spec``."""
    v3 = spec.fmi_version.startswith("3")
    lines = ['<?xml version="1.0" encoding="UTF-8"?>']
    gen = 'generationTool="ego.fmi.build"'
    if v3:
        lines.append(
            f'<fmiModelDescription fmiVersion="3.0" modelName={quoteattr(spec.identifier)} '
            f"instantiationToken={quoteattr(spec.guid)} description={quoteattr(spec.description)} {gen}>"
        )
        caps = f'canHandleVariableCommunicationStepSize="{"false" if spec.fixed_step else "true"}"'
        fixed = f' fixedInternalStepSize="{_num(spec.step_size)}"' if spec.fixed_step and spec.step_size else ""
        lines.append(
            f'  <CoSimulation modelIdentifier="{spec.identifier}" {caps} canGetAndSetFMUState="false"'
            f' canSerializeFMUState="false"{fixed}/>'
        )
    else:
        lines.append(
            f'<fmiModelDescription fmiVersion="2.0" modelName={quoteattr(spec.identifier)} '
            f"guid={quoteattr(spec.guid)} description={quoteattr(spec.description)} {gen} "
            'variableNamingConvention="flat">'
        )
        caps = f'canHandleVariableCommunicationStepSize="{"false" if spec.fixed_step else "true"}"'
        lines.append(f'  <CoSimulation modelIdentifier="{spec.identifier}" {caps}>')
        lines.append("    <SourceFiles>")
        for src in ("fmi2_frame.c", *(p.name for p in spec.sources)):
            lines.append(f'      <File name="{src}"/>')
        lines.append("    </SourceFiles>")
        lines.append("  </CoSimulation>")
    lines.extend(_unit_definitions(spec))
    if spec.step_size:
        lines.append(f'  <DefaultExperiment startTime="0.0" stepSize="{_num(spec.step_size)}"/>')
    lines.append("  <ModelVariables>")
    if v3:  # FMI 3.0 asks for the independent variable (past the model's own references)
        lines.append(
            f'    <Float64 name="time" valueReference="{len(spec.variables)}" causality="independent" '
            'variability="continuous" description="simulation time"/>'
        )
    outputs = _model_variables(spec, v3, lines)
    lines.append("  </ModelVariables>")
    lines.append("  <ModelStructure>")
    if v3:
        lines.extend(f'    <Output valueReference="{vr}"/>' for vr in outputs)
    else:
        lines.append("    <Outputs>")
        lines.extend(f'      <Unknown index="{vr + 1}"/>' for vr in outputs)
        lines.append("    </Outputs>")
    lines.append("  </ModelStructure>")
    lines.append("</fmiModelDescription>")
    return "\n".join(lines) + "\n"


def _unit_definitions(spec: ModelSpec) -> list[str]:
    """``<UnitDefinitions>``: the spec's units and every unit a variable names (fmpy
    validates that each is defined); no lines without units."""
    units = list(spec.units)
    defined = {u[0] for u in units}
    for v in spec.variables:
        if v.unit and v.unit not in defined:
            from ego.fmi.units import parse

            parsed = parse(v.unit)
            if parsed is None:
                raise ValueError(f"unit {v.unit!r} of {v.name!r}: define it in ModelSpec.units")
            units.append((v.unit, tuple(sorted(parsed[0].items())), parsed[1], parsed[2]))
            defined.add(v.unit)
    if not units:
        return []
    lines = ["  <UnitDefinitions>"]
    for name, exps, factor, offset in units:
        attrs = " ".join(f'{k}="{e}"' for k, e in exps)
        lines.append(
            f'    <Unit name={quoteattr(name)}><BaseUnit {attrs} factor="{_num(factor)}" offset="{_num(offset)}"/></Unit>'
        )
    lines.append("  </UnitDefinitions>")
    return lines


def _model_variables(spec: ModelSpec, v3: bool, lines: list[str]) -> list[int]:
    """Each variable's element (FMI 3.0's ``Float64`` or 2.0's ``ScalarVariable``) onto
    ``lines``; the value references of the outputs."""
    outputs = []
    for vr, v in enumerate(spec.variables):
        variability = v.variability or ("tunable" if v.causality == "parameter" else "continuous")
        unit = f" unit={quoteattr(v.unit)}" if v.unit else ""
        desc = f" description={quoteattr(v.description)}" if v.description else ""
        initial = ""
        if v.causality == "output" or v.causality == "local":
            initial = ' initial="exact"'
        if v3:
            lines.append(
                f'    <Float64 name={quoteattr(v.name)} valueReference="{vr}" causality="{v.causality}" '
                f'variability="{variability}"{initial}{unit}{desc} start="{_num(v.start)}"/>'
            )
        else:
            lines.append(
                f'    <ScalarVariable name={quoteattr(v.name)} valueReference="{vr}" causality='
                f'"{v.causality}" variability="{variability}"{initial}{desc}>'
            )
            lines.append(f'      <Real{unit} start="{_num(v.start)}"/>')
            lines.append("    </ScalarVariable>")
        if v.causality == "output":
            outputs.append(vr)
    return outputs


def model_vars_h(spec: ModelSpec) -> str:
    """The header the model compiles against: value references and start values."""
    out = [
        "/* generated by ego.fmi.build from the same table as modelDescription.xml */",
        "#ifndef EGO_MODEL_VARS_H",
        "#define EGO_MODEL_VARS_H",
        f'#define MODEL_IDENTIFIER "{spec.identifier}"',
        f'#define MODEL_GUID "{spec.guid}"',
        f"#define MODEL_N_REALS {len(spec.variables)}",
    ]
    for vr, v in enumerate(spec.variables):
        out.append(f"#define VR_{v.name} {vr}")
    starts = ", ".join(_num(v.start) for v in spec.variables)
    out.append(f"static const double MODEL_START[MODEL_N_REALS] = {{{starts}}};")
    out.append("#endif")
    return "\n".join(out) + "\n"


def _inputs_digest(spec: ModelSpec, frame: Path) -> str:
    h = hashlib.sha256(repr(spec).encode())
    for p in (Path(__file__), frame, FRAME_DIR / "model.h", *spec.sources, *spec.extra_headers):
        h.update(p.read_bytes())
    h.update(compiler().encode())
    return h.hexdigest()[:20]


def build_fmu(spec: ModelSpec, out: str | os.PathLike, *, cache_dir: str | os.PathLike | None = None) -> Path:
    """Compile ``spec`` into the FMU ``out`` (written atomically). With ``cache_dir``, an FMU
    built before from identical inputs is copied from there instead."""
    from ego.outputs import atomic_path

    out = Path(out)
    frame = FRAME_DIR / ("fmi3_frame.c" if spec.fmi_version.startswith("3") else "fmi2_frame.c")
    digest = _inputs_digest(spec, frame)
    cached = Path(cache_dir) / f"{spec.identifier}-{digest}.fmu" if cache_dir is not None else None
    if cached is not None and cached.is_file():
        out.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(out) as tmp:
            shutil.copyfile(cached, tmp)
        return out
    headers = fmi_headers()
    with tempfile.TemporaryDirectory(prefix="ego-fmu-build-") as tmpdir:
        tmp = Path(tmpdir)
        src = tmp / "sources"
        src.mkdir()
        shutil.copy(frame, src / frame.name)
        shutil.copy(FRAME_DIR / "model.h", src / "model.h")
        for p in (*spec.sources, *spec.extra_headers):
            shutil.copy(p, src / p.name)
        # the model's local headers travel with it
        for p in {s.parent for s in spec.sources}:
            for h in p.glob("*.h"):
                if not (src / h.name).exists():
                    shutil.copy(h, src / h.name)
        (src / "model_vars.h").write_text(model_vars_h(spec))
        # headers the sources need when built elsewhere: the FMI ones
        prefix = "fmi3" if spec.fmi_version.startswith("3") else "fmi2"
        for h in headers.glob(f"{prefix}*.h"):
            shutil.copy(h, src / h.name)
        lib = tmp / "binaries" / platform_dir(spec.fmi_version) / (spec.identifier + shared_suffix())
        lib.parent.mkdir(parents=True)
        cmd = [
            compiler(),
            "-shared",
            "-fPIC",
            "-O2",
            "-ffp-contract=off",
            "-fvisibility=default",
            f"-I{src}",
            *(f"-D{d}" for d in spec.defines),
            "-o",
            str(lib),
            str(src / frame.name),
            *(str(src / p.name) for p in spec.sources),
            "-lm",
        ]
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if proc.returncode != 0:
            raise ConfigError(f"compiling the FMU {spec.identifier} failed: {proc.stderr.strip()[:2000]}")
        (tmp / "modelDescription.xml").write_text(model_description(spec))
        out.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(out) as target:
            with zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as z:
                z.write(tmp / "modelDescription.xml", "modelDescription.xml")
                z.write(lib, f"binaries/{platform_dir(spec.fmi_version)}/{lib.name}")
                for p in sorted(src.iterdir()):
                    z.write(p, f"sources/{p.name}")
        if cached is not None:
            cached.parent.mkdir(parents=True, exist_ok=True)
            with atomic_path(cached) as tmpc:
                shutil.copyfile(out, tmpc)
    return out
