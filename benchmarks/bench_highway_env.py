"""Speed of one scenario on the two traffic simulators: SUMO (libsumo) and highway-env.

    python benchmarks/bench_highway_env.py [--repeat 3] [--scenario emergency-brake]
                                           [--controller pid] [--set key=value ...]

Runs the same scenario, controller, seed and parameters on both backends without a
recording and prints, per backend, the control steps per second of the whole loop and the
cost of one traffic step (``bridge.step()``: the traffic moves, collisions are checked),
then highway-env over SUMO as ratios. Medians of ``--repeat`` runs. highway-env is slower
by design (pure Python, every IDM driver searches every vehicle for its neighbours); the
ratio says by how much, not a target.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from ego.highway_env import BACKENDS  # noqa: E402
from ego.runner import RunSpec, build  # noqa: E402


def timed_run(spec: RunSpec) -> tuple[float, float, int, int]:
    """(loop seconds, seconds inside bridge.step, control steps, traffic steps) after set-up."""
    scenario = build(spec)
    try:
        obs = scenario.reset()
        bridge = scenario.bridge
        inner = bridge.step
        spent = [0.0, 0]

        def step():
            t0 = time.perf_counter()
            try:
                return inner()
            finally:
                spent[0] += time.perf_counter() - t0
                spent[1] += 1

        bridge.step = step
        controller = scenario.controller
        t0 = time.perf_counter()
        while not scenario.done:
            obs = scenario.step(controller.step(obs))
        return time.perf_counter() - t0, spent[0], scenario.k, spent[1]
    finally:
        scenario.close()


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--scenario", default="emergency-brake")
    ap.add_argument("--controller", default="pid")
    ap.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="scenario/controller parameter, as for ego run",
    )
    args = ap.parse_args(argv)
    overrides = dict(item.split("=", 1) for item in args.overrides)
    figures: dict = {"scenario": args.scenario, "controller": args.controller}
    print(f"{args.scenario}, {args.controller}, seed 0, no recording, median of {args.repeat}")
    for backend in BACKENDS:
        runs = [
            timed_run(RunSpec(args.scenario, args.controller, 0, overrides, backend=backend))
            for _ in range(args.repeat)
        ]
        loop = statistics.median(r[0] for r in runs)
        traffic = statistics.median(r[1] for r in runs)
        steps, traffic_steps = runs[0][2], runs[0][3]
        figures[backend] = {
            "control_steps": steps,
            "traffic_steps": traffic_steps,
            "loop_s": loop,
            "steps_per_s": steps / loop,
            "traffic_step_us": 1e6 * traffic / traffic_steps,
            "traffic_share_of_loop": traffic / loop,
        }
        f = figures[backend]
        print(
            f"  {backend:<12} {f['steps_per_s']:9.0f} control steps/s   traffic step "
            f"{f['traffic_step_us']:8.1f} us ({100 * f['traffic_share_of_loop']:.0f} % of the loop; "
            f"{steps} control, {traffic_steps} traffic steps)"
        )
    sumo, he = figures["sumo"], figures["highway-env"]
    figures["sumo_over_highway_env_steps_per_s"] = sumo["steps_per_s"] / he["steps_per_s"]
    figures["highway_env_over_sumo_traffic_step"] = he["traffic_step_us"] / sumo["traffic_step_us"]
    print(
        f"  SUMO runs the loop {figures['sumo_over_highway_env_steps_per_s']:.1f} x faster; "
        f"a highway-env traffic step costs {figures['highway_env_over_sumo_traffic_step']:.1f} x "
        "a SUMO step"
    )
    return figures


if __name__ == "__main__":
    main()
