"""Two env processes stepping freely against one: what the machine's two cores give, and how
unequal they are.

    python benchmarks/bench_free_pair.py [--ids ego/CutIn-v0 ...] [--steps 30000] [--rounds 2]

For each id, ``rounds`` times: one env alone in a process of its own for ``steps`` zero-action
steps (episodes reset as they end, one fixed scenario), then two such processes at once,
each stepping on its own with nothing between them. Printed: the one env's steps/s, each of
the pair's, their sum over the one env's (the throughput two cores give: about 2 where the
cores are equal and free) and the slower over the faster (1 where they are equal).

A vector env (``gym.make_vec``, ``AsyncVectorEnv``) steps its envs in lock step: each step
waits for the slower env, so its speed-up is about twice the slower's share, not the sum.
``benchmarks/bench_gym.py``'s "2 processes" column measures that lock-stepped ceiling.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

IDS = ("ego/EmergencyBrake-v0", "ego/CutIn-v0", "ego/Platoon-v0")


def _steps_per_second(env_id: str, steps: int, start, conn) -> None:
    import gymnasium as gym
    import numpy as np

    import ego.gym  # noqa: F401 - registers the ids

    env = gym.make(env_id, config={"randomize": {}})
    try:
        env.reset(seed=0)
        zero = np.zeros(env.action_space.shape, env.action_space.dtype)
        env.step(zero)
        start.wait()
        t0 = time.perf_counter()
        for _ in range(steps):
            *_, terminated, truncated, _ = env.step(zero)
            if terminated or truncated:
                env.reset()
        conn.send(steps / (time.perf_counter() - t0))
    finally:
        env.close()


def measure(env_id: str, steps: int, n: int) -> list[float]:
    """Steps/s of each of ``n`` env processes started together (a process each: libsumo)."""
    ctx = mp.get_context("forkserver")
    start = ctx.Event()
    pipes = [ctx.Pipe(duplex=False) for _ in range(n)]
    procs = [ctx.Process(target=_steps_per_second, args=(env_id, steps, start, w), daemon=True) for _, w in pipes]
    for p in procs:
        p.start()
    start.set()
    rates = [r.recv() for r, _ in pipes]
    for p in procs:
        p.join(30)
    return rates


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ids", nargs="+", default=list(IDS))
    ap.add_argument("--steps", type=int, default=30000)
    ap.add_argument("--rounds", type=int, default=2)
    args = ap.parse_args(argv)
    print(f"one env alone, then two at once stepping freely, {args.steps} steps each, zero actions, 2 cores")
    print(f"  {'env id':24s} {'1 env steps/s':>14} {'pair steps/s':>16} {'sum / 1 env':>12} {'slower / faster':>16}")
    figures: dict = {}
    for env_id in args.ids:
        for _ in range(args.rounds):
            (one,) = measure(env_id, args.steps, 1)
            pair = measure(env_id, args.steps, 2)
            total, balance = sum(pair) / one, min(pair) / max(pair)
            figures.setdefault(env_id, []).append({"one": one, "pair": pair, "sum": total, "balance": balance})
            print(
                f"  {env_id:24s} {one:14.0f} {pair[0]:7.0f} {pair[1]:8.0f} {total:11.2f}x {balance:16.2f}",
                flush=True,
            )
    return figures


if __name__ == "__main__":
    main()
