"""Run every scenario file of a folder (or the files given) with ``ego run`` and tabulate how
each ends: the figures behind docs/openscenario.md's tables of public scenario corpora::

    python scripts/corpus_run.py CORPUS/esmini/resources/xosc -c pid --timeout 120

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
files. ``--json OUT`` also writes the rows.
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

UNSUPPORTED = re.compile(r"<(\w+)> is not supported by ego")
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


def scenario_files(paths: list[str]) -> list[Path]:
    """The scenario files under ``paths`` (catalogs and distribution files left out)."""
    out: list[Path] = []
    for p in map(Path, paths):
        files = sorted(p.glob("*.xosc")) if p.is_dir() else [p]
        for f in files:
            head = f.read_text(errors="replace")[:4000]
            if "<Catalog " in head or "<Catalog>" in head or "ParameterValueDistribution" in head:
                continue
            out.append(f)
    return out


def run_one(path: Path, controller: str, timeout: float) -> dict:
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(
            [sys.executable, "-m", "ego", "run", path.name, "-c", controller],
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
    elif code == 2 and len(errors) == 1 and not traceback:
        verdict, first = "refused", errors[0][len("ego: error:") :].strip()
    else:
        verdict = "crashed"
        first = next((ln for ln in reversed(err.splitlines()) if ln.strip()), f"exit {code}")
    sim = SIM_TIME.search(out)
    return {
        "file": path.name,
        "exit": code,
        "seconds": round(seconds, 1),
        "sim_time": float(sim.group(1)) if sim else None,
        "stop_time": stop_at(path),
        "verdict": verdict,
        "first": first,
    }


def _time(value: float | None) -> str:
    return "-" if value is None else f"{value:.1f}"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("paths", nargs="+", help="folders of .xosc files, or files")
    ap.add_argument("-c", "--controller", default="pid")
    ap.add_argument("--timeout", type=float, default=120.0, help="seconds per file (default 120)")
    ap.add_argument("--json", help="also write the rows to this file")
    args = ap.parse_args(argv)
    files = scenario_files(args.paths)
    if not files:
        print("corpus_run: no scenario files found", file=sys.stderr)
        return 2
    rows = []
    print("| file | exit | s | sim s | stop s | how it ends (the run's end, or the first error) |")
    print("|---|---|---|---|---|---|")
    for f in files:
        r = run_one(f, args.controller, args.timeout)
        rows.append(r)
        first = r["first"].replace("|", "\\|")[:220]
        print(
            f"| {r['file']} | {r['exit']} | {r['seconds']:.1f} | {_time(r['sim_time'])} | "
            f"{_time(r['stop_time'])} | {first} |",
            flush=True,
        )
    verdicts = Counter(r["verdict"] for r in rows)
    passed = sum(r["exit"] == 0 for r in rows)
    print(
        f"\n{len(rows)} files: {verdicts['ran']} ran ({passed} exit 0), "
        f"{verdicts['refused']} refused cleanly, {verdicts['crashed']} crashed"
    )
    refused = Counter(m.group(1) for r in rows if (m := UNSUPPORTED.search(r["first"])))
    if refused:
        print("outermost refused elements: " + ", ".join(f"{k} {n}" for k, n in refused.most_common()))
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
