"""Cost of an FMU controller against the built-in pid, measured in one run.

    python benchmarks/bench_fmu.py [--repeat 5] [--steps 20000]

Builds ego's pid as a C FMU (FMI 2.0, tests/fmi/c/pid_tracking.c, with the system C compiler
against fmpy's headers) and prints:

* the cost of one control step (observation in, doStep, action out) of the FMU controller
  and of the built-in pid on the same recorded observations, and the difference - target:
  the FMU adds <= 5 us per control step;
* emergency-brake's real-time factor with the pid FMU and with the built-in pid (no
  recording, alternating runs, best of ``--repeat``), and their ratio - target >= 0.8.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "fmi"))

import fmu_zoo  # noqa: E402

from ego.control import controller_spec  # noqa: E402
from ego.runner import RunSpec, build  # noqa: E402


def observations(n: int):
    """``n`` observations of an emergency-brake run with the built-in pid (copies)."""
    from copy import copy

    scenario = build(RunSpec("emergency-brake", "pid"))
    out = []
    try:
        obs = scenario.reset()
        while not scenario.done and len(out) < n:
            out.append(copy(obs))
            obs = scenario.step(scenario.controller.step(obs))
    finally:
        scenario.close()
    return out


def per_step(name: str, obs, repeat: int) -> float:
    """Best seconds per control step of controller ``name`` over the observations."""
    spec = controller_spec(name, "tracking")
    ctrl = spec.build(spec.params(), 0.01)
    best = float("inf")
    try:
        for _ in range(repeat):
            ctrl.reset()
            step = ctrl.step
            t0 = time.perf_counter()
            for o in obs:
                step(o)
            best = min(best, (time.perf_counter() - t0) / len(obs))
    finally:
        close = getattr(ctrl, "close", None)
        if close:
            close()
    return best


def real_time_factor(controller: str) -> float:
    scenario = build(RunSpec("emergency-brake", controller))
    try:
        obs = scenario.reset()
        ctrl = scenario.controller
        t0 = time.perf_counter()
        while not scenario.done:
            obs = scenario.step(ctrl.step(obs))
        return scenario.t / (time.perf_counter() - t0)
    finally:
        scenario.close()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--steps", type=int, default=2500, help="observations replayed per measurement")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        fmu = str(fmu_zoo.build(fmu_zoo.pid_tracking(), tmp))
        obs = observations(args.steps)
        builtin = per_step("pid", obs, args.repeat)
        mine = per_step(fmu, obs, args.repeat)
        print(f"control step over {len(obs)} observations (best of {args.repeat}):")
        print(f"  built-in pid   {builtin * 1e6:7.2f} us")
        print(f"  pid C FMU      {mine * 1e6:7.2f} us")
        print(
            f"  FMU overhead   {(mine - builtin) * 1e6:7.2f} us per control step (target <= 5 us); "
            f"ratio {mine / builtin:.2f}x"
        )
        rtf = {"pid": 0.0, fmu: 0.0}
        for _ in range(args.repeat):  # alternating, best of each
            for name in rtf:
                rtf[name] = max(rtf[name], real_time_factor(name))
        print(f"emergency-brake real-time factor (best of {args.repeat}, alternating, no recording):")
        print(f"  built-in pid   {rtf['pid']:7.1f}x")
        print(f"  pid C FMU      {rtf[fmu]:7.1f}x")
        print(f"  ratio FMU / built-in: {rtf[fmu] / rtf['pid']:.3f} (target >= 0.8)")


if __name__ == "__main__":
    main()
