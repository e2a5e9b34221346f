"""CPU taken by threads other than the env's own: numerical libraries' thread pools spinning.

    python benchmarks/bench_pool_threads.py [--ids ego/LaneCentering-v0 ...] [--rounds 6] [--steps 300]

For each env id: ``rounds`` times a reset (a new seed each) and ``steps`` env steps of zero
actions; per round the CPU time of this process, of its threads other than the main one
(read from ``/proc/self/task``: an OpenBLAS or OpenMP pool woken by a call spins on another
core for a while after it) and the wall time. With no pool spinning, the other threads take
0 s and the process's CPU equals its wall time. Before ``LateralError.discrete`` held the BLAS
pools to one thread (this script on 09cdbda's tree), every lane-centring round had 0.040-0.050
s of CPU on another thread (docs/gym.md#speed).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import gymnasium as gym  # noqa: E402
import numpy as np  # noqa: E402

import ego.gym  # noqa: E402

TICK = 1.0 / os.sysconf("SC_CLK_TCK")


def other_threads_cpu() -> float:
    """Seconds of CPU (user + system) of this process's threads other than the main one."""
    me = os.getpid()
    total = 0
    for tid in os.listdir(f"/proc/{me}/task"):
        if int(tid) == me:
            continue
        try:
            fields = Path(f"/proc/{me}/task/{tid}/stat").read_text().rsplit(")", 1)[1].split()
        except FileNotFoundError:  # the thread ended meanwhile
            continue
        total += int(fields[11]) + int(fields[12])
    return total * TICK


def rounds_of(env_id: str, rounds: int, steps: int) -> list[tuple[float, float, float]]:
    """(process CPU s, other threads' CPU s, wall s) of each round."""
    env = gym.make(env_id, config={"randomize": {}})
    try:
        zero = np.zeros(env.action_space.shape, env.action_space.dtype)
        env.reset(seed=0)
        out = []
        for k in range(rounds):
            others0, cpu0, wall0 = other_threads_cpu(), time.process_time(), time.perf_counter()
            env.reset(seed=k)
            for _ in range(steps):
                *_, terminated, truncated, _ = env.step(zero)
                if terminated or truncated:
                    env.reset(seed=k)
            out.append((time.process_time() - cpu0, other_threads_cpu() - others0, time.perf_counter() - wall0))
        return out
    finally:
        env.close()


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ids", nargs="+", default=["ego/LaneCentering-v0"], help="env ids (default: LaneCentering)")
    ap.add_argument("--rounds", type=int, default=6)
    ap.add_argument("--steps", type=int, default=300, help="env steps after each reset")
    args = ap.parse_args(argv)
    bad = [i for i in args.ids if i not in ego.gym.ENV_IDS]
    if bad or args.rounds < 1 or args.steps < 1:
        what = f"--ids {bad[0]!r} (expected {', '.join(ego.gym.ENV_IDS)})" if bad else "--rounds/--steps (>= 1)"
        print(f"bench_pool_threads.py: error: bad value for {what}", file=sys.stderr)
        raise SystemExit(2)
    figures = {}
    print(f"a reset and {args.steps} env steps of zero actions, {args.rounds} rounds")
    print(f"  {'env id':24s} {'process CPU s':>16s} {'other threads s':>16s} {'wall s':>16s}")
    for env_id in args.ids:
        rows = rounds_of(env_id, args.rounds, args.steps)
        cpu, others, wall = (sorted(r[i] for r in rows) for i in range(3))
        print(
            f"  {env_id:24s} {cpu[0]:7.3f}-{cpu[-1]:<8.3f} {others[0]:7.3f}-{others[-1]:<8.3f} "
            f"{wall[0]:7.3f}-{wall[-1]:<8.3f}"
        )
        figures[env_id] = {"cpu_s": cpu, "other_threads_s": others, "wall_s": wall}
    return figures


if __name__ == "__main__":
    main()
