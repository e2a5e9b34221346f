"""The catalogue of hostile inputs (docs/reliability.md, "Limits"): files that would exhaust
memory, disk or time, or nest deeper than the parsers go, and the command lines that use
them. One place for tests/test_input_limits.py (each case: exit 2, one line, nothing
written) and scripts/input_memory.py (each case's peak memory in a process of its own).
"""

from __future__ import annotations

import os
import shutil
import sys
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
XOSC_DIR = ROOT / "scenarios" / "openscenario"
EB_XOSC = (XOSC_DIR / "emergency_brake.xosc").read_text()
sys.path.insert(0, str(ROOT / "tests" / "fmi"))

import fmu_zoo  # noqa: E402


def _decl(name: str, kind: str, value: str) -> str:
    return f'<ParameterDeclaration name="{name}" parameterType="{kind}" value="{value}"/>'


def _with_decls(*decls: str) -> str:
    return EB_XOSC.replace("<ParameterDeclarations>", "<ParameterDeclarations>" + "".join(decls), 1)


def _fmu_with(path: Path, base: Path, extra: dict[str, bytes] | None = None, md: bytes | None = None) -> None:
    """A copy of FMU ``base`` with entries added or modelDescription.xml replaced."""
    with zipfile.ZipFile(base) as src, zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as dst:
        for info in src.infolist():
            data = src.read(info)
            if info.filename == "modelDescription.xml" and md is not None:
                data = md
            dst.writestr(info.filename, data)
        for name, data in (extra or {}).items():
            dst.writestr(name, data)


def build(d: Path) -> Path:
    """Every hostile file of the catalogue, made in folder ``d``."""
    for f in ("straight3.xodr",):
        shutil.copy(XOSC_DIR / f, d / f)
    (d / "zero.xosc").symlink_to("/dev/zero")
    os.mkfifo(d / "fifo.xosc")
    os.mkfifo(d / "fifo.toml")
    with open(d / "huge.xosc", "wb") as f:  # sparse: 17 MiB that take no disk
        f.truncate(17 * 1024 * 1024)
    (d / "loop.xosc").symlink_to(d / "loop.xosc")
    deep = "<Properties>" + "<Property>" * 250 + "</Property>" * 250 + "</Properties>"
    (d / "deep.xosc").write_text(EB_XOSC.replace("<CatalogLocations/>", "<CatalogLocations/>" + deep, 1))
    (d / "encoding.xosc").write_text(EB_XOSC.replace('encoding="UTF-8"', 'encoding="x-no-such"', 1))
    many = "".join(_decl(f"p{i}", "double", "1") for i in range(100_000))
    (d / "many.xosc").write_text(_with_decls(many))
    (d / "parens.xosc").write_text(_with_decls(_decl("X", "double", "${" + "(" * 1000 + "1" + ")" * 1000 + "}")))
    (d / "minus.xosc").write_text(_with_decls(_decl("X", "double", "${" + "-" * 5000 + "1}")))
    (d / "ushort.xosc").write_text(_with_decls(_decl("N", "unsignedShort", "70000")))
    (d / "digits.xosc").write_text(_with_decls(_decl("N", "int", "9" * 4500)))
    road = d / "zero_road.xosc"
    road.write_text(EB_XOSC.replace('filepath="straight3.xodr"', 'filepath="zero.xodr"'))
    (d / "zero.xodr").symlink_to("/dev/zero")
    (d / "big.toml").write_text("# padding\n" * 120_000)
    grid = ", ".join(str(20 + i * 0.001) for i in range(5000))
    (d / "grid.toml").write_text(
        f'scenario = "{d / "ok.xosc"}"\ncontrollers = ["pid"]\n[grid]\nEgoSpeed = [{grid}]\n'
        f"LeadGap = [{', '.join(str(30 + i * 0.01) for i in range(4000))}]\n"
    )
    (d / "ok.xosc").write_text(EB_XOSC)
    (d / "decel.xosc").write_text(
        EB_XOSC.replace(
            'name="LeadDecel" parameterType="double" value="6"',
            'name="LeadDecel" parameterType="double" value="1e308"',
            1,
        ).replace('<ValueConstraint rule="lessOrEqual" value="12"/>', "", 1)  # the file's own 12 m/s^2 bound off
    )
    (d / "delay.xosc").write_text(EB_XOSC.replace('name="BrakeTime" delay="0"', 'name="BrakeTime" delay="1e308"', 1))
    xodr = (XOSC_DIR / "straight3.xodr").read_text()
    (d / "negative.xodr").write_text(xodr.replace('a="3.5"', 'a="-3.5"', 1))
    (d / "negative_road.xosc").write_text(EB_XOSC.replace('filepath="straight3.xodr"', 'filepath="negative.xodr"'))
    # the shipped file declares LeadGap's range with OpenSCENARIO 1.2 constraints (the built-in
    # scenario's 5..300 m): a grid value outside is refused before the sweep starts
    (d / "ranged.xosc").write_text(EB_XOSC)
    (d / "behind.toml").write_text(
        f'scenario = "{d / "ranged.xosc"}"\ncontrollers = ["pid"]\n[grid]\nLeadGap = [-40, 30]\n'
    )
    base = fmu_zoo.build(fmu_zoo.pid_tracking(), d)
    (d / "zero.toml").symlink_to("/dev/zero")
    _fmu_with(d / "entries.fmu", base, {f"resources/r{i}": b"" for i in range(10_001)})
    _fmu_with(d / "bigmd.fmu", base, md=b"<?xml version='1.0'?>" + b" " * (17 * 1024 * 1024))
    _fmu_with(d / "absolute.fmu", base, {"/etc/evil": b"x"})
    notlib = d / "notlib.fmu"
    with zipfile.ZipFile(base) as src, zipfile.ZipFile(notlib, "w") as dst:
        for info in src.infolist():
            data = src.read(info)
            if info.filename.startswith("binaries/") and not info.is_dir():
                data = b"this is not a shared library"
            dst.writestr(info.filename, data)
    with (
        zipfile.ZipFile(base) as src,
        zipfile.ZipFile(d / "bomb.fmu", "w", zipfile.ZIP_DEFLATED, compresslevel=1) as dst,
    ):
        for info in src.infolist():
            dst.writestr(info.filename, src.read(info))
        with dst.open("resources/zeros.bin", "w", force_zip64=True) as f:
            block = b"\0" * (1 << 24)
            for _ in range(33):  # 528 MiB: past the 512 MiB an entry
                f.write(block)
    return d


RUN = ["run", "emergency-brake", "-c", "pid"]
REQ = [*RUN, "--require"]

CASES = [
    ("list-dev-zero", ["list", "{zero.xosc}"], "not a regular file (a device"),
    ("run-dev-zero", ["run", "{zero.xosc}", "-c", "pid"], "zero.xosc' is not a file"),
    ("list-fifo", ["list", "{fifo.xosc}"], "not a regular file (a FIFO"),
    ("huge-xosc", ["list", "{huge.xosc}"], "larger than the limit of 16 MiB"),
    ("symlink-loop", ["list", "{loop.xosc}"], "symbolic link loop"),
    ("deep-xml", ["list", "{deep.xosc}"], "nested deeper than 200 levels"),
    ("unknown-encoding", ["list", "{encoding.xosc}"], "unknown XML encoding"),
    ("100k-declarations", ["list", "{many.xosc}"], "more than 10,000 parameter declarations"),
    ("1000-parens", ["run", "{parens.xosc}", "-c", "pid"], "nested deeper than 100 levels"),
    ("5000-minus", ["run", "{minus.xosc}", "-c", "pid"], "nested deeper than 100 levels"),
    ("unsigned-short", ["run", "{ushort.xosc}", "-c", "pid"], "from 0 to 65535"),
    ("4500-digits", ["run", "{digits.xosc}", "-c", "pid"], "(4500 characters)"),
    ("road-dev-zero", ["run", "{zero_road.xosc}", "-c", "pid"], "road file 'zero.xodr' not found (looked for "),
    ("sweep-spec-fifo", ["sweep", "{fifo.toml}", "--out", "{out}"], "not a regular file (a FIFO"),
    ("falsify-spec-big", ["falsify", "{big.toml}", "--out", "{out}"], "larger than the limit of 1 MiB"),
    ("sweep-20-million", ["sweep", "{grid.toml}", "--out", "{out}"], "the limit is 10,000,000"),
    ("map-dev-zero", ["run", "emergency-brake", "-c", "{pid_tracking.fmu}", "--set", "fmu_map={zero.toml}"], "device"),
    ("fmu-entries", ["list", "{entries.fmu}"], "entries in the archive (the limit is 10,000)"),
    ("fmu-big-description", ["list", "{bigmd.fmu}"], "modelDescription.xml is larger than 16 MiB"),
    ("fmu-absolute-entry", ["list", "{absolute.fmu}"], "points outside the archive's folder"),
    ("fmu-bomb", ["list", "{bomb.fmu}"], "528 MiB uncompressed (the limit is 512 MiB an entry)"),
    ("fmu-not-a-library", ["run", "emergency-brake", "-c", "{notlib.fmu}"], "its binary cannot be loaded"),
    ("xosc-decel-1e308", ["run", "{decel.xosc}", "-c", "pid"], "1e+308 (expected at most 100 m/s^2"),
    ("xosc-delay-1e308", ["run", "{delay.xosc}", "-c", "pid"], "1e+308 (expected at most 86400 s"),
    ("xodr-negative-width", ["run", "{negative_road.xosc}", "-c", "pid"], "bad lane width a=-3.5 m (allowed: 0"),
    ("ego-empty", ["run", "{ok.xosc}", "-c", "pid", "--ego", ""], "bad value for --ego: ''"),
    ("list-ego-empty", ["list", "{ok.xosc}", "--ego", ""], "bad value for --ego: ''"),
    ("sweep-lead-behind", ["sweep", "{behind.toml}", "--out", "{out}"], "'LeadGap' = -40 breaks its value constraint"),
    ("stl-1000-not", [*REQ, "r: " + "not " * 1000 + "speed > 0"], "nested deeper than 100 levels"),
    ("stl-1000-always", [*REQ, "r: " + "always " * 1000 + "speed > 0"], "nested deeper than 100 levels"),
    ("stl-400-abs", [*REQ, "r: " + "abs(" * 400 + "speed" + ")" * 400 + " > 0"], "nested deeper than 100"),
    ("stl-5500-or", [*REQ, "r: " + " or ".join(["speed > 0"] * 5500)], "tokens (the limit is 2,000)"),
    ("stl-1e9", [*REQ, "r: eventually[0:1e9] speed > 0"], "longer than a day"),
    ("stl-1e300", [*REQ, "r: eventually[0:1e300] speed > 0"], "longer than a day"),
    ("stl-past-the-run", [*REQ, "r: eventually[0:100] speed > 0"], "longer than the run (duration 25 s)"),
    ("stl-divide-by-zero", [*REQ, "r: always speed / 0 > 1"], "divides by zero"),
]


def fill(args: list[str], files: Path, out: Path) -> list[str]:
    res = []
    for a in args:
        for name in [p.name for p in files.iterdir()]:
            a = a.replace("{" + name + "}", str(files / name))
        res.append(a.replace("{out}", str(out / "out")))
    return res
