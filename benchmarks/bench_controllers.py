"""Cost of one controller step, with and without ego's C twins, and the start-up of the fuzzy ones.

    python benchmarks/bench_controllers.py [--steps 20000] [--repeat 5]

Each tracking controller steps through the same recorded observations (an emergency-brake
run's, fuzzy controller, seed 0: the errors a controller meets in a run), its ``signals()``
read after each step as the loop's trace row does; report 004's ``bp-pid-acc`` through a
platoon's first follower's (pid, seed 0), with ``period=0.01`` so that every step is an
update. Where a controller has a C twin (``bp-pid``: ``ego._native.bp_pid``, ``rbf-smc``:
``ego._native.rbf_smc``, ``bp-pid-acc``: ``ego._native.bp_pid_acc``) the same steps
are also timed with the twin switched off (``controller.native = False``, the Python
reference) and the outputs of both compared to the bit. The variants take turns, best of
``--repeat``, so a busy machine slows both alike: the ratio is the figure.

Then the start-up of the fuzzy rule bases as a fresh process pays it once: compiling the
scikit-fuzzy rules (``FastMamdani.from_rules``, what the controllers do) against first
building scikit-fuzzy's ``ControlSystem`` of them and compiling that (``from_system``).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from ego.control import CONTROLLERS  # noqa: E402
from ego.runner import RunSpec, build  # noqa: E402

TRACKING = ("pid", "fuzzy", "fuzzy-pid", "bp-pid", "rbf-smc")
#: report 004's car-following controllers, one follower's, updating every control period here
FOLLOWING = ("bp-pid-acc",)


def observations(scenario: str, controller: str, n: int) -> list:
    """``n`` observations of a run (copies; repeated if the run is shorter): the ego's, or the
    first follower's in a platoon."""
    import copy

    sc = build(RunSpec(scenario, controller, 0, {}))
    try:
        obs = sc.reset()
        seen = []
        while not sc.done:
            seen.append(copy.copy(obs[0] if isinstance(obs, list) else obs))
            obs = sc.step(sc.controller.step(obs))
    finally:
        sc.close()
    return [seen[i % len(seen)] for i in range(n)]


def make(name: str, native: bool):
    task = "car-following" if name in FOLLOWING else "tracking"
    spec = CONTROLLERS[task][name]
    params = spec.params(period=0.01) if task == "car-following" else spec.params()
    controller = spec.build(params, 0.01)
    if hasattr(controller, "native"):
        controller.native = controller.native and native
    controller.reset(seed=0)
    return controller


def timed(name: str, native: bool, obs: list) -> tuple[float, list]:
    """(seconds per step, the outputs) of a fresh controller over ``obs``."""
    c = make(name, native)
    step, signals = c.step, c.signals
    out = []
    add = out.append
    t0 = time.perf_counter()
    for o in obs:
        add(step(o))
        signals()
    return (time.perf_counter() - t0) / len(obs), out


FRESH = """
import time
import skfuzzy.control
from ego.control import fuzzy
from ego.control.fuzzy_engine import FastMamdani, table_rules
t1 = time.perf_counter()
if {system}:
    FastMamdani.from_system(fuzzy.rule_base(), ["e", "ec"], ["u"])
else:
    FastMamdani.from_rules(table_rules(**fuzzy.TABLE), ["e", "ec"], ["u"])
print(time.perf_counter() - t1)
"""


def compile_seconds(system: bool) -> float:
    """Seconds a fresh process spends compiling the fuzzy controller's rule base (imports apart)."""
    out = subprocess.run(
        [sys.executable, "-c", FRESH.format(system=system)],
        capture_output=True,
        text=True,
        check=True,
        cwd=Path(__file__).resolve().parents[1],
    )
    return float(out.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--steps", type=int, default=20000, help="controller steps per timing")
    ap.add_argument("--repeat", type=int, default=5, help="turns of every variant (the best is printed)")
    args = ap.parse_args(argv)
    if args.steps < 1 or args.repeat < 1:
        ap.error(f"bad value for --steps/--repeat: {args.steps}/{args.repeat} (expected 1 or more)")
    obs = {
        "tracking": observations("emergency-brake", "fuzzy", args.steps),
        "car-following": observations("platoon", "pid", args.steps),
    }
    names = TRACKING + FOLLOWING
    twins = [name for name in names if getattr(make(name, True), "native", False)]
    variants = [(name, True) for name in names] + [(name, False) for name in twins]
    best: dict = {}
    outputs: dict = {}
    for _ in range(args.repeat):
        for v in variants:
            seconds, out = timed(*v, obs["car-following" if v[0] in FOLLOWING else "tracking"])
            best[v] = min(best.get(v, seconds), seconds)
            outputs[v] = out
    print(
        f"one controller step and its signals, {args.steps} steps of an emergency-brake run (bp-pid-acc: of a "
        f"platoon's first follower, updating every 0.01 s), best of {args.repeat}"
    )
    print(f"  {'controller':12} {'us a step':>10} {'Python reference':>17} {'speed-up':>9}  outputs")
    figures: dict = {}
    for name in names:
        us = best[(name, True)] * 1e6
        row = {"us": us}
        if (name, False) in best:
            ref = best[(name, False)] * 1e6
            same = np.array_equal(np.array(outputs[(name, True)]), np.array(outputs[(name, False)]), equal_nan=True)
            row.update(python_us=ref, speedup=ref / us, identical=bool(same))
            print(f"  {name:12} {us:10.2f} {ref:17.2f} {ref / us:8.1f}x  {'identical' if same else 'DIFFER'}")
        else:
            print(f"  {name:12} {us:10.2f} {'-':>17} {'-':>9}")
        figures[name] = row
    rules, system = compile_seconds(False), compile_seconds(True)
    print("compiling the fuzzy controller's rule base in a fresh process (scikit-fuzzy imported before)")
    print(f"  from its scikit-fuzzy rules   {rules:6.3f} s")
    print(f"  through a ControlSystem       {system:6.3f} s")
    figures["compile_s"] = {"rules": rules, "system": system}
    return figures


if __name__ == "__main__":
    main()
