"""Run every scenario file of a folder (or the files given) with ``ego run`` and tabulate how
each ends: the figures behind docs/openscenario.md's tables of public scenario corpora::

    python scripts/corpus_run.py CORPUS/esmini/resources/xosc -c pid --timeout 120 \
        --path CORPUS/esmini/resources --path CORPUS/esmini/resources/xodr

Each ``.xosc`` (catalogs and ParameterValueDistribution files left out: they are not scenarios
to run) is run as its own process from its own folder (its relative paths resolve there), with
a timeout. A file

- **ran** when it exits 0 (the run passed) or 1 (the run ended and failed: a collision, a
  requirement broken);
- is **refused** when it exits 2 with one ``ego: error:`` line and no traceback;
- **crashed** otherwise (a traceback, another exit code, the timeout).

Prints a markdown table (file, exit, wall seconds, the simulated time the run reached and the
time the file's StopTrigger stops it at when that is a simulation time, the run's end or the
first error line: a run that ended at 1.3 s of a 30 s scenario shows it), the
counts, and the outermost refused elements (``<X> is not supported``) with their number of
files. Each scenario file is also read by ``ego list FILE --json`` (same folder and ``--path``):
it **agrees** with the run when it says supported for a file that ran, and gives the run's
error line for a file the run refused; the disagreements are printed by name. ``--json OUT`` also writes the rows. Each variation file (a ParameterValueDistribution)
is then run with ``ego sweep FILE -c C --out TMP --jobs 1`` (``--no-sweeps`` leaves them out):
it **ran** when the sweep exits 0 or 1; it counts in the target set as its scenario file does.

It also prints how many of the **target set** ran: the corpus issue's "examples on roads
without city junction networks and without trailers". Each file left out is listed with its
reason, decided from the file (and its road and catalogs), not from a list of names:

- **city junction network**: its road (``LogicFile``, or OpenSCENARIO 0.9's ``Logics``) has a
  junction of the common kind (not ``type="direct"``) joining 3 or more roads: an
  intersection, not a motorway merge. A road the copy lacks counts by name when it is one of
  the reference player's known city maps (``fabriksgatan.xodr``, ``multi_intersections.xodr``);
- **trailer**: an entity's vehicle really tows one (its ``<Trailer>`` holds a vehicle, a
  non-empty ``EntityRef`` or a non-empty catalog reference, parameters resolved: the
  reference player's ``car_white`` with its empty ``TrailerRef`` tows none), it is a trailer
  itself (``vehicleCategory="trailer"``), or the storyboard connects one;
- **no road**: the file names no road file (a scene graph only);
- **road unavailable**: the road file is neither where the file says nor anywhere under the
  corpus folder's parent by its name (an author's disk path, a file the repository lacks).
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
from collections import Counter
from pathlib import Path

UNSUPPORTED = re.compile(r"<(\w+)> is not supported by ego")
#: the reference player's city maps, known by name where a copy lacks the road file
CITY_ROADS = ("fabriksgatan.xodr", "multi_intersections.xodr")
PARAM = re.compile(r"^\$\{?(\w+)\}?$")
#: a variation sweep's count: combinations, discarded by the value constraints, remaining
COMBINATIONS = re.compile(r"([\d,]+) combinations, ([\d,]+) discarded .*?, ([\d,]+) remain")
SIM_TIME = re.compile(r"^\s*sim_time\s+([-\d.]+) s\s*$", re.M)


def stop_at(path: Path) -> float | None:
    """The simulation time (s) the file's StopTrigger ends it at (a SimulationTimeCondition),
    or None (no such trigger, or a file ego refuses)."""
    from ego.openscenario.loader import load
    from ego.openscenario.scenario import stop_time

    try:
        return stop_time(load(path))
    except Exception:  # a refused file: its error is the run's
        return None


def scenario_files(paths: list[str], variations: bool = False) -> list[Path]:
    """The scenario files under ``paths`` (catalogs and distribution files left out), or with
    ``variations`` the ParameterValueDistribution files."""
    out: list[Path] = []
    for p in map(Path, paths):
        files = sorted(p.glob("*.xosc")) if p.is_dir() else [p]
        for f in files:
            head = f.read_text(errors="replace")[:4000]
            if "<Catalog " in head or "<Catalog>" in head:
                continue
            if ("ParameterValueDistribution" in head) == variations:
                out.append(f)
    return out


def _params(elem: ET.Element | None, outer: dict[str, str]) -> dict[str, str]:
    """The parameter values an element declares (its ``ParameterDeclarations``), ``outer`` first."""
    values = dict(outer)
    for d in elem.iterfind("ParameterDeclarations/ParameterDeclaration") if elem is not None else ():
        values[d.get("name", "")] = _value(d.get("value", ""), outer)
    return values


def _value(text: str, params: dict[str, str]) -> str:
    """``text`` with a plain ``$name`` reference resolved (expressions are left as written)."""
    m = PARAM.match(text.strip())
    return params.get(m.group(1), text) if m else text


def _road(scenario: Path, root: ET.Element, params: dict[str, str]) -> tuple[str | None, Path | None]:
    """The road file a scenario names, and where it is (None: nowhere in reach)."""
    node = root.find("RoadNetwork/LogicFile")
    if node is None:
        node = root.find("RoadNetwork/Logics")  # OpenSCENARIO 0.9
    if node is None or not node.get("filepath"):
        return None, None
    name = _value(node.get("filepath", ""), params)
    here = scenario.parent / name
    if here.is_file():
        return name, here
    base = name.replace("\\", "/").rsplit("/", 1)[-1]
    found = sorted(scenario.parent.parent.rglob(base)) if base else []
    return name, (found[0] if found else None)


def _city_junction(road: Path) -> str | None:
    """The first intersection of a road file (a common junction joining 3 or more roads)."""
    for j in ET.parse(road).getroot().iterfind("junction"):
        incoming = {c.get("incomingRoad") for c in j.iterfind("connection")}
        if j.get("type", "default") != "direct" and len(incoming) >= 3:
            return f"junction {j.get('id')} joins {len(incoming)} roads"
    return None


def _catalog_vehicle(scenario: Path, root: ET.Element, ref: ET.Element, params: dict[str, str]):
    """The catalog ``Vehicle`` a ``CatalogReference`` names, with its parameter values."""
    name, entry = ref.get("catalogName", ""), _value(ref.get("entryName", ""), params)
    for d in root.iterfind("CatalogLocations/*/Directory"):
        folder = scenario.parent / d.get("path", "")
        files = sorted(folder.glob("*.xosc")) if folder.is_dir() else [folder] if folder.is_file() else []
        for f in files:
            try:
                cat = ET.parse(f).getroot().find("Catalog")
            except ET.ParseError:
                continue
            if cat is None or cat.get("name") != name:
                continue
            for v in cat.iterfind("Vehicle"):
                if v.get("name") == entry:
                    values = _params(v, {})
                    for a in ref.iterfind("ParameterAssignments/ParameterAssignment"):
                        values[a.get("parameterRef", "")] = _value(a.get("value", ""), params)
                    return v, values
    return None, {}


def _tows(vehicle: ET.Element, values: dict[str, str]) -> str | None:
    """How a vehicle is or tows a trailer (None: it does not)."""
    if (vehicle.get("vehicleCategory") or vehicle.get("category")) == "trailer":
        return f"'{vehicle.get('name')}' is a trailer"
    for t in vehicle.iterfind("Trailer"):
        if t.find("Vehicle") is not None:
            return f"'{vehicle.get('name')}' tows '{t.find('Vehicle').get('name')}'"
        for ref, attr in (("EntityRef", "entityRef"), ("CatalogReference", "entryName")):
            node = t.find(ref)
            if node is not None and _value(node.get(attr, ""), values).strip():
                return f"'{vehicle.get('name')}' tows '{_value(node.get(attr, ''), values)}'"
    return None


def _trailer(scenario: Path, root: ET.Element, params: dict[str, str]) -> str | None:
    """The first entity that really has a trailer (see the module text), or None."""
    if root.find(".//ConnectTrailerAction") is not None:
        return "the storyboard connects a trailer (ConnectTrailerAction)"
    for obj in root.iterfind("Entities/ScenarioObject"):
        vehicle, values = obj.find("Vehicle"), _params(obj.find("Vehicle"), params)
        ref = obj.find("CatalogReference")
        if vehicle is None and ref is not None:
            vehicle, values = _catalog_vehicle(scenario, root, ref, params)
        how = _tows(vehicle, values) if vehicle is not None else None
        if how:
            return f"entity '{obj.get('name')}': {how}"
    return None


def exclusion(scenario: Path) -> str | None:
    """Why a file is outside the target set (see the module text), or None when it is in it.
    A variation file is where the scenario file it varies is."""
    try:
        root = ET.parse(scenario).getroot()
    except ET.ParseError:
        return None  # ego refuses it: a target file that does not run
    varied = root.find("ParameterValueDistribution/ScenarioFile")
    if varied is not None:
        target = scenario.parent / varied.get("filepath", "")
        why = exclusion(target) if target.is_file() else f"its scenario file {varied.get('filepath')!r} is missing"
        return why and f"varies {varied.get('filepath')}: {why}"
    params = _params(root, {})
    name, road = _road(scenario, root, params)
    base = (name or "").replace("\\", "/").rsplit("/", 1)[-1]
    city = _city_junction(road) if road is not None else ("by name" if base in CITY_ROADS else None)
    if city:
        return f"city junction network: {base} ({city})"
    trailer = _trailer(scenario, root, params)
    if trailer:
        return f"trailer: {trailer}"
    if name is None:
        return "no road: the file names no road file"
    if road is None:
        return f"road unavailable: {name} is nowhere under {scenario.parent.parent}"
    return None


def run_one(
    path: Path,
    controller: str,
    timeout: float,
    search: tuple[str, ...] = (),
    sweep_out: str | None = None,
    sweep_args: tuple[str, ...] = ("--jobs", "1"),
) -> dict:
    """``ego run`` of a scenario file, or with ``sweep_out`` ``ego sweep`` of a variation file
    (its results in that folder, ``sweep_args`` added: the jobs, a ``--sample``), as a row:
    file, exit, seconds, verdict, first line; each folder of ``search`` is passed on as
    ``--path``."""
    t0 = time.perf_counter()
    extra = [a for d in search for a in ("--path", str(Path(d).resolve()))]
    cmd = ["run", path.name, "-c", controller, *extra]
    if sweep_out is not None:
        cmd = ["sweep", path.name, "-c", controller, "--out", sweep_out, *sweep_args, "--record", "none", *extra]
    try:
        proc = subprocess.run(
            [sys.executable, "-m", "ego", *cmd],
            cwd=path.parent,
            capture_output=True,
            text=True,
            timeout=timeout,
        )
        code, out, err = proc.returncode, proc.stdout, proc.stderr
    except subprocess.TimeoutExpired:
        code, out, err = 124, "", f"timeout after {timeout:g} s"
    seconds = time.perf_counter() - t0
    lines = [ln.strip() for ln in (err + "\n" + out).splitlines() if ln.strip()]
    errors = [ln for ln in lines if ln.startswith("ego: error:")]
    traceback = "Traceback" in err
    if code in (0, 1) and not traceback:
        verdict = "ran"
        ends = [ln for ln in out.splitlines() if "run ends:" in ln]
        first = ends[-1].split("run ends:", 1)[1].strip() if ends else (lines[0] if lines else "")
        if sweep_out is not None:  # the sweep's count: how many runs, how they ended
            counts = [ln.strip() for ln in out.splitlines() if " runs in the spec" in ln]
            first = counts[-1] if counts else next((ln.strip() for ln in reversed(out.splitlines()) if ln.strip()), "")
    elif code == 2 and len(errors) == 1 and not traceback:
        verdict, first = "refused", errors[0][len("ego: error:") :].strip()
    else:
        verdict = "crashed"
        first = next((ln for ln in reversed(err.splitlines()) if ln.strip()), f"exit {code}")
    sim = SIM_TIME.search(out)
    combos = COMBINATIONS.search(err + "\n" + out) if sweep_out is not None else None
    return {
        "combinations": [int(g.replace(",", "")) for g in combos.groups()] if combos else None,
        "file": path.name,
        "exit": code,
        "seconds": round(seconds, 1),
        "sim_time": float(sim.group(1)) if sim else None,
        "stop_time": stop_at(path),
        "verdict": verdict,
        "first": first,
    }


def list_agrees(path: Path, row: dict, search: tuple[str, ...] = (), timeout: float = 120.0) -> bool:
    """Whether ``ego list FILE --json`` says what ``ego run`` did (``row``, from :func:`run_one`):
    supported for a file that ran, the same error for one it refused (a crashed run agrees with
    nothing)."""
    extra = [a for d in search for a in ("--path", str(Path(d).resolve()))]
    try:
        proc = subprocess.run(
            [sys.executable, "-m", "ego", "list", path.name, "--json", *extra],
            cwd=path.parent,
            capture_output=True,
            text=True,
            timeout=timeout,
        )
        said = json.loads(proc.stdout)
    except (subprocess.TimeoutExpired, json.JSONDecodeError):
        return False
    if row["verdict"] == "ran":
        return said.get("supported") is True
    if row["verdict"] == "refused":
        return said.get("supported") is False and str(said.get("error", "")).strip() == row["first"]
    return False


def _time(value: float | None) -> str:
    return "-" if value is None else f"{value:.1f}"


def target_summary(files: list[Path], rows: list[dict]) -> str:
    """The target set's line (run of target files, percent) after the list of files left out."""
    lines, target = [], []
    for f, r in zip(files, rows, strict=True):
        r["excluded"] = exclusion(f)
        if r["excluded"]:
            lines.append(f"- {f.name}: {r['excluded']}")
        else:
            target.append(r)
    ran = sum(r["verdict"] == "ran" for r in target)
    share = 100.0 * ran / len(target) if target else 0.0
    head = f"\nleft out of the target set ({len(lines)} files):"
    return "\n".join([head, *lines, f"{ran} of {len(target)} target files run ({share:.0f} %)"])


def _print_row(r: dict, times: bool = False) -> None:
    """One row of the table; with ``times`` the simulated time the run reached and the file's
    StopTrigger time beside it."""
    first = r["first"].replace("|", "\\|")[:220]
    reached = f" {_time(r['sim_time'])} | {_time(r['stop_time'])} |" if times else ""
    print(f"| {r['file']} | {r['exit']} | {r['seconds']:.1f} |{reached} {first} |", flush=True)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("paths", nargs="+", help="folders of .xosc files, or files")
    ap.add_argument("-c", "--controller", default="pid")
    ap.add_argument("--timeout", type=float, default=120.0, help="seconds per file (default 120)")
    ap.add_argument("--json", help="also write the rows to this file")
    ap.add_argument(
        "--path",
        action="append",
        default=[],
        metavar="DIR",
        help="passed on to every ego run: a folder to look in for roads and catalogs (repeatable)",
    )
    ap.add_argument(
        "--no-sweeps", action="store_true", help="leave out the variation files (run with ego sweep by default)"
    )
    ap.add_argument("--sweep-timeout", type=float, default=1200.0, help="seconds per variation file (default 1200)")
    args = ap.parse_args(argv)
    files = scenario_files(args.paths)
    variations = [] if args.no_sweeps else scenario_files(args.paths, variations=True)
    if not files and not variations:
        print("corpus_run: no scenario files found", file=sys.stderr)
        return 2
    rows = []
    print("| file | exit | s | sim s | stop s | how it ends (the run's end, or the first error) |")
    print("|---|---|---|---|---|---|")
    for f in files:
        r = run_one(f, args.controller, args.timeout, tuple(args.path))
        r["list_agrees"] = list_agrees(f, r, tuple(args.path), args.timeout)
        rows.append(r)
        _print_row(r, times=True)
    verdicts = Counter(r["verdict"] for r in rows)
    passed = sum(r["exit"] == 0 for r in rows)
    print(
        f"\n{len(rows)} files: {verdicts['ran']} ran ({passed} exit 0), "
        f"{verdicts['refused']} refused cleanly, {verdicts['crashed']} crashed"
    )
    differ = [r["file"] for r in rows if not r["list_agrees"]]
    print(
        f"ego list agrees with ego run on {len(rows) - len(differ)} of {len(rows)} files"
        + (f"; not on: {', '.join(differ)}" if differ else "")
    )
    refused = Counter(m.group(1) for r in rows if (m := UNSUPPORTED.search(r["first"])))
    if refused:
        print("outermost refused elements: " + ", ".join(f"{k} {n}" for k, n in refused.most_common()))
    swept = []
    if variations:
        print("\n| variation file (ego sweep) | exit | s | the sweep's runs, or the first error |")
        print("|---|---|---|---|")
    for f in variations:
        with tempfile.TemporaryDirectory() as out:
            r = run_one(f, args.controller, args.sweep_timeout, tuple(args.path), sweep_out=out)
        swept.append(r)
        _print_row(r)
    if variations:
        ok = sum(r["verdict"] == "ran" for r in swept)
        print(f"\n{len(swept)} variation files: {ok} swept")
    print(target_summary([*files, *variations], [*rows, *swept]))
    rows += swept
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
