"""Speed of a scenario file against the built-in scenario it mirrors.

    python benchmarks/bench_xosc.py [--repeat 5] [--controller pid]

Runs ``emergency-brake`` and ``scenarios/openscenario/emergency_brake.xosc`` alternately
(the same runs, metric for metric) and prints the ratio of their run times; the file's
parsing and its road's conversion (netconvert, then cached) are timed on their own.
Target (issue 19): the file within 10 % of the built-in.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

FILE = ROOT / "scenarios" / "openscenario" / "emergency_brake.xosc"


def _one(scenario: str, controller: str) -> float:
    """Seconds of one run from the spec to the result (SUMO's start included)."""
    from ego.runner import RunSpec, run

    t0 = time.perf_counter()
    run(RunSpec(scenario, controller))
    return time.perf_counter() - t0


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--controller", default="pid")
    args = ap.parse_args(argv)
    from ego.openscenario.loader import _read, load
    from ego.openscenario.roads import network_file

    with tempfile.TemporaryDirectory() as cache:
        old = os.environ.get("XDG_CACHE_HOME")
        os.environ["XDG_CACHE_HOME"] = cache
        try:
            t0 = time.perf_counter()
            model = load(FILE)
            parse = time.perf_counter() - t0
            _read.cache_clear()
            t0 = time.perf_counter()
            load(FILE)
            parse = min(parse, time.perf_counter() - t0)
            t0 = time.perf_counter()
            network_file(model.road)
            convert = time.perf_counter() - t0
            t0 = time.perf_counter()
            network_file(model.road)
            cached = time.perf_counter() - t0
            _one(str(FILE), args.controller)  # warm both paths (imports, caches)
            _one("emergency-brake", args.controller)
            builtin, from_file = [], []
            for _ in range(args.repeat):
                builtin.append(_one("emergency-brake", args.controller))
                from_file.append(_one(str(FILE), args.controller))
        finally:
            if old is None:
                os.environ.pop("XDG_CACHE_HOME", None)
            else:
                os.environ["XDG_CACHE_HOME"] = old
    figures = {
        "parse_ms": parse * 1e3,
        "convert_ms": convert * 1e3,
        "cached_road_ms": cached * 1e3,
        "builtin_s": statistics.median(builtin),
        "file_s": statistics.median(from_file),
    }
    figures["ratio"] = figures["file_s"] / figures["builtin_s"]
    print(f"emergency-brake with {args.controller}, {args.repeat} runs each, alternating (medians)")
    print(f"  parse emergency_brake.xosc            {figures['parse_ms']:8.2f} ms")
    print(
        f"  convert straight3.xodr (netconvert)   {figures['convert_ms']:8.1f} ms   (cached: "
        f"{figures['cached_road_ms']:.2f} ms)"
    )
    print(f"  built-in run                          {figures['builtin_s']:8.3f} s")
    print(f"  file run                              {figures['file_s']:8.3f} s")
    print(f"  ratio file / built-in                 {figures['ratio']:8.3f}")
    return figures


if __name__ == "__main__":
    main()
