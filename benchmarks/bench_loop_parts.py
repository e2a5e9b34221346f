"""Where the loop's time goes inside a run: the control period, the SUMO step's own parts, the plan.

    python benchmarks/bench_loop_parts.py [--runs 5] [--scenario emergency-brake] [--controller fuzzy]

Runs the scenario (no recording, seed 0) ``--runs`` times with a clock (``perf_counter_ns``)
around the parts it names, and prints medians (the clock's own ~0.1 us included):

* a control period without a SUMO step (``Scenario.step``), right after a SUMO step and
  between two, and the controller's step;
* per SUMO step: ``simulationStep()`` itself, ego's own work around it (the rest of
  ``_sumo_step``), and the three libsumo calls of that work (the context subscription's
  results, ``moveToXY``, ``setPreviousSpeed``);
* the manoeuvre's plan per state (``EvasiveManoeuvre.plan``, Python: its C twin
  ``plan_steady`` went back to Python with issue 37, docs/performance.md).

Figures of one machine at one time: compare two trees by running each in the same session.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections import defaultdict
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import ego.scenarios.manoeuvre as manoeuvre  # noqa: E402
from ego.runner import RunSpec, build  # noqa: E402

clock = time.perf_counter_ns


def _timed(samples: list, fn):
    def timed(*args):
        t0 = clock()
        out = fn(*args)
        samples.append(clock() - t0)
        return out

    return timed


class _Timed:
    """``obj``'s attributes, some of them timed (libsumo's vehicle domain is a module-level
    class whose static methods cannot be patched per run)."""

    def __init__(self, obj, samples: dict, names) -> None:
        self._obj = obj
        for name in names:
            setattr(self, name, _timed(samples[name], getattr(obj, name)))

    def __getattr__(self, name):
        return getattr(self._obj, name)


def one_run(spec: RunSpec, samples: dict, plan_label: str | None = None) -> None:
    """One run: the periods and the SUMO step's parts timed, or (``plan_label``) the plan alone."""
    sc = build(spec)
    try:
        obs = sc.reset()
        step, control = sc.step, sc.controller.step
        if plan_label is not None:
            plan, man = sc.loop._plan, sc.manoeuvre

            def timed_plan(o, t):
                t0 = clock()
                plan(o, t)
                samples[f"plan {plan_label}, {manoeuvre.PHASE_NAMES[man.phase]}"].append(clock() - t0)

            sc.loop._plan = timed_plan
            while not sc.done:
                obs = step(control(obs))
            return
        bridge = sc.bridge
        if bridge._raw_step is not None:
            bridge._raw_step = _timed(samples["simulationStep"], bridge._raw_step)
        ls = bridge._ls
        libsumo = _Timed(ls, samples, ())
        libsumo.vehicle = _Timed(ls.vehicle, samples, ("getContextSubscriptionResults", "moveToXY", "setPreviousSpeed"))
        bridge._ls = libsumo
        sc._sumo_step = _timed(samples["_sumo_step"], sc._sumo_step)
        per_sumo = sc.config.control_per_sumo
        while not sc.done:
            k = sc.k
            t0 = clock()
            action = control(obs)
            t1 = clock()
            obs = step(action)
            t2 = clock()
            samples["controller"].append(t1 - t0)
            if (k + 1) % per_sumo:  # no SUMO step in this period
                samples["period, first after a SUMO step" if k % per_sumo == 0 else "period, between"].append(t2 - t1)
    finally:
        sc.close()


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--scenario", default="emergency-brake")
    ap.add_argument("--controller", default="fuzzy")
    args = ap.parse_args(argv)
    spec = RunSpec(args.scenario, args.controller, seed=0, record=None)
    samples: dict[str, list] = defaultdict(list)
    for _ in range(args.runs):
        one_run(spec, samples)
    probe = build(spec)
    try:
        evasive = isinstance(getattr(probe, "manoeuvre", None), manoeuvre.EvasiveManoeuvre)
    finally:
        probe.close()
    if evasive:
        for _ in range(args.runs):
            one_run(spec, samples, "(Python)")
    us = {k: statistics.median(v) / 1000 for k, v in samples.items()}
    sumo = us.get("simulationStep")
    if sumo is not None:
        own = [t - s for t, s in zip(samples["_sumo_step"], samples["simulationStep"], strict=True)]
        us["ego's own work around a SUMO step"] = statistics.median(own) / 1000
    print(f"{args.scenario}, {args.controller}, no recording, {args.runs} runs: medians in us")
    for key in sorted(us):
        if key != "_sumo_step":
            print(f"  {key:48} {us[key]:8.1f}   (n {len(samples.get(key, ())) or '-'})")
    return us


if __name__ == "__main__":
    main()
