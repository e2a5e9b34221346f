"""The Euro NCAP CCR matrices (aeb-ccr-s/m/b.toml beside this file) as tables: for every
controller and case, collision or not and the impact speed in km/h.

    PYTHONPATH=. python scenarios/sweeps/ccr_table.py [--workers 4] [--set key=value ...] [aeb-ccr-s.toml ...]

``--set`` overrides the files' values for every run (e.g. ``--set ttc_threshold=1.5``: an AEB
that reacts later).

``ego sweep`` runs the same files into results.parquet; this script only formats the CCR
matrices as tables: it reads ``scenario``, ``controllers``, ``seeds``, ``[set]`` and
``[grid]`` (the CCR files have no ``[sample]``), one run a case, in a pool of processes
(libsumo runs one simulation per process).
"""

from __future__ import annotations

import argparse
import itertools
import tomllib
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

HERE = Path(__file__).parent
FILES = ("aeb-ccr-s.toml", "aeb-ccr-m.toml", "aeb-ccr-b.toml")


def cases(spec: dict) -> list[dict]:
    """Every [grid] point with the [set] values."""
    grid = spec.get("grid", {})
    names = list(grid)
    fixed = spec.get("set", {})
    return [{**fixed, **dict(zip(names, values))} for values in itertools.product(*grid.values())]


def seeds(spec: dict) -> list[int]:
    s = spec.get("seeds", 1)
    return list(range(s)) if isinstance(s, int) else list(s)


def _text(v) -> str:
    return str(v).lower() if isinstance(v, bool) else str(v)


def run_case(job: tuple[str, str, int, dict]) -> dict:
    from ego.runner import RunSpec, run

    scenario, controller, seed, case = job
    m = run(RunSpec(scenario, controller, seed, {k: _text(v) for k, v in case.items()})).metrics
    return {k: m[k] for k in ("status", "status_detail", "collision", "collision_with", "impact_speed",
                              "impact_relative_speed", "trigger_time", "aeb_time", "min_gap_front")}


def cell(m: dict) -> str:
    if m["status"] not in ("completed", "collision"):
        return m["status"]
    if not m["collision"]:
        return f"no ({m['min_gap_front']:.1f} m)"
    rel = m["impact_relative_speed"]
    return f"HIT {m['impact_speed'] * 3.6:.1f} ({rel * 3.6:.1f})"


def table(path: Path, workers: int, extra: dict | None = None) -> str:
    spec = tomllib.loads(path.read_text())
    if extra:
        spec["set"] = {**spec.get("set", {}), **extra}
    grid = spec.get("grid", {})
    runs = [(spec["scenario"], c, s, case) for c in spec["controllers"] for s in seeds(spec)
            for case in cases(spec)]
    with ProcessPoolExecutor(workers) as pool:
        results = list(pool.map(run_case, runs))

    def label(case):
        parts = []
        for k in grid:
            v = case[k]
            parts.append(f"{v * 3.6:.0f} km/h" if k == "ego_speed" else f"{k} {v:g}")
        return ", ".join(parts)

    columns = [label(case) for case in cases(spec)]
    n = len(columns)
    title = path.name + "".join(f", {k}={v}" for k, v in (extra or {}).items())
    lines = [f"{title}: collision? HIT impact speed km/h (relative km/h); no = avoided (smallest gap)", "",
             "| controller | " + " | ".join(columns) + " |", "|---" * (n + 1) + "|"]
    per_row = n * len(seeds(spec))
    for i, controller in enumerate(spec["controllers"]):
        row = results[i * per_row:(i + 1) * per_row]
        lines.append(f"| {controller} | " + " | ".join(cell(m) for m in row) + " |")
    odd = [(r[1], r[3], m["status_detail"]) for r, m in zip(runs, results)
           if m["collision"] and m["collision_with"] != "lead" or m["status"] not in ("completed", "collision")]
    lines += [f"  ! {c} {case}: {why}" for c, case, why in odd]
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="*", default=[str(HERE / f) for f in FILES])
    ap.add_argument("--workers", type=int, default=4)
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    args = ap.parse_args()
    extra = dict(item.split("=", 1) for item in args.set)
    for f in args.files:
        print(table(Path(f), args.workers, extra))
        print()


if __name__ == "__main__":
    main()
