"""Where the Gymnasium wrapper's cost per step goes, measured inside the loop by ablation.

    python benchmarks/bench_gym_parts.py [--rounds 9] [--duration 20] [--ids ego/CutIn-v0 ego/Platoon-v0]

``benchmarks/bench_gym.py`` measures the wrapper's whole cost over the raw scenario step.
Timing each piece alone (``timeit`` in a warm loop) undercounts it: inside a run its code and
data come cold, between SUMO's and the scenario's. So this replays the default controller's
actions (as bench_gym does: ``EgoState`` observation, ``EgoAction``) through ``env.step``
as the env steps by default (an env step that ends nothing in one call into C,
``ego._native.env_step``), through the Python step (``EgoEnv._step``, its pieces still bound
to C), and through the Python step with one piece at a time replaced by a stand-in that returns
a constant of the same shape:

* ``reward``: the reward and its terms (``EgoEnv._step_reward``, bound at the reset);
* ``observation``: the observation vector (``EgoEnv._observe``, bound at the reset);
* ``action``: the agent's action to the scenario's command (``EgoEnv._native``);

and the raw loop (the scenario stepping the same commands, in a platoon its controllers for
the other followers, as bench_gym's raw step counts them, and the run's result at the end). The variants take turns, the
episodes alike (seed 0, no randomisation), so a busy machine's load falls on each alike.
Printed: the median time per env step, what the step in C saves over the Python step, and
per piece what leaving it out of the Python step saves (its cost in the loop). Only a
measurement: the stand-ins change what the env returns.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import gymnasium as gym  # noqa: E402
import numpy as np  # noqa: E402
from bench_gym import demonstration  # noqa: E402

import ego.gym  # noqa: E402, F401  (registers the ids)
from ego.scenarios import scenario_class  # noqa: E402

IDS = ("ego/CutIn-v0", "ego/Platoon-v0")  # the two envs above bench_gym's 15 % target
PIECES = ("reward", "observation", "action")


def measure(env_id: str, scenario: str, rounds: int, duration: float) -> dict[str, float]:
    """Median seconds per env step of the whole env, of it without each piece, and of the raw loop."""
    actions = np.array(demonstration(scenario, scenario_class(scenario).reference_controller(), {"duration": duration}))
    env = gym.make(
        env_id,
        config={
            "duration": duration,
            "policy_frequency": 0,  # one env step per control period, as the raw loop's
            "randomize": {},
            "observation": {"type": "EgoState"},
            "action": {"type": "EgoAction"},
        },
        max_episode_steps=len(actions),
    )
    u = env.unwrapped
    platoon = u.task == "car-following"
    if platoon:
        actions = actions[:, :1]
    actions = list(actions)  # the same row objects every round (the action stand-in looks them up)
    try:
        env.reset(seed=0)
        commands = [u._native(a) for a in actions]
        zero = np.zeros(u.observation_space.shape)
        _, terms = u.reward(u._view, False)
        terms = dict.fromkeys(terms, 0.0)
        command_of = dict(zip(map(id, actions), commands))
        stand_ins = {
            "reward": ("_step_reward", lambda crashed: (0.0, terms)),
            "observation": ("_observe", lambda: zero),
            "action": ("_native", lambda action: command_of[id(action)]),
        }
        times: dict[str, list[float]] = {name: [] for name in ("env", "python", *PIECES, "raw")}
        clock = time.perf_counter
        for _ in range(rounds):
            for name in times:
                env.reset(seed=0)
                if name == "raw":
                    sc = u.scenario
                    step = sc.step
                    t0 = clock()
                    if platoon:
                        controller, agent = sc.controller, u._agent
                        for lon, lat in commands:
                            step(sc.joint_action(controller.step(sc.obs), agent, lon, lat))
                    else:
                        for command in commands:
                            step(command)
                    sc.result()  # the run's metrics, which the env computes at the episode's end
                    times[name].append(clock() - t0)
                    continue
                if name != "env":  # the Python step, which the stand-ins replace pieces of
                    u._fast_step = None
                if name in stand_ins:
                    attr, fn = stand_ins[name]
                    setattr(u, attr, fn)
                env_step = env.step
                t0 = clock()
                for a in actions:
                    env_step(a)
                times[name].append(clock() - t0)  # the next reset binds the env's own pieces again
        return {name: statistics.median(v) / len(actions) for name, v in times.items()}
    finally:
        env.close()


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rounds", type=int, default=9, help="turns of every variant (the median is printed)")
    ap.add_argument("--duration", type=float, default=20.0, help="simulated seconds per run")
    ap.add_argument("--ids", nargs="*", default=list(IDS), help=f"env ids (default: {' '.join(IDS)})")
    args = ap.parse_args(argv)
    known = {
        spec.id: spec.kwargs["scenario"]
        for spec in gym.registry.values()
        if spec.id.startswith("ego/") and "scenario" in spec.kwargs
    }
    for env_id in args.ids:
        if env_id not in known:
            ap.error(f"unknown env id {env_id!r} (known: {', '.join(sorted(known))})")
    if args.rounds < 1:
        ap.error(f"bad value for --rounds: {args.rounds} (expected 1 or more)")
    os.environ.setdefault("MPLCONFIGDIR", tempfile.mkdtemp(prefix="ego-mpl-"))
    print(f"the wrapper's pieces inside the loop, dt = 0.01 s, {args.duration:g} s runs, median of {args.rounds}")
    print(
        f"  {'env id':22s} {'env step':>9s} {'raw step':>9s} {'wrapper':>8s} {'step in C saves':>16s}"
        "   without, from the Python step (saves):"
    )
    figures = {}
    for env_id in args.ids:
        t = measure(env_id, known[env_id], args.rounds, args.duration)
        us = {k: v * 1e6 for k, v in t.items()}
        saves = {p: us["python"] - us[p] for p in PIECES}
        parts = "  ".join(f"{p} {saves[p]:.2f} us" for p in PIECES)
        wrapper, in_c = us["env"] - us["raw"], us["python"] - us["env"]
        print(f"  {env_id:22s} {us['env']:7.2f}us {us['raw']:7.2f}us {wrapper:6.2f}us {in_c:14.2f}us   {parts}")
        figures[env_id] = {
            "env_us": us["env"],
            "python_step_us": us["python"],
            "raw_us": us["raw"],
            "wrapper_us": wrapper,
            "step_in_c_saves_us": in_c,
            "saves_us": saves,
        }
    return figures


if __name__ == "__main__":
    main()
