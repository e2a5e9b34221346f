"""Three checks behind docs/gym.md's reading of the vector env figures, in one run.

    python benchmarks/bench_vector_checks.py [--steps 4000]

1. scaling: pure Python arithmetic in one process, then in two at once: what this machine's
   two cores give to work that touches little memory (bench_gym.py's "2 processes" column
   gives the same for env steps).
2. busy: ``gym.make_vec("ego/EmergencyBrake-v0", 2)`` hosted (the default) and with
   ``host=False`` (pipes), env steps/s, with one busy process (``while True: pass``) beside
   them and without: whether the counters' watching holds up when a core is taken.
3. from a reset: ``--steps`` vector steps of ego/LaneCentering-v0 from a reset (seed 0 in both
   envs) against one env alone for as many steps.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import gymnasium as gym  # noqa: E402
import numpy as np  # noqa: E402

import ego.gym  # noqa: E402, F401 - registers the ids


def _arithmetic(n: int, out=None) -> float:
    t0 = time.perf_counter()
    x = 0
    for i in range(n):
        x += i * i % 7
    spent = time.perf_counter() - t0
    if out is not None:
        out.put(spent)
    return spent


def scaling(n: int = 3_000_000) -> float:
    """Speed-up of two processes doing the same arithmetic over one."""
    one = _arithmetic(n)
    ctx = mp.get_context("fork")
    queue = ctx.Queue()
    procs = [ctx.Process(target=_arithmetic, args=(n, queue)) for _ in range(2)]
    for p in procs:
        p.start()
    spent = max(queue.get(), queue.get())
    for p in procs:
        p.join()
    return 2 * one / spent


def _vector_rate(env_id: str, config: dict, host, steps: int, seeds) -> float:
    envs = gym.make_vec(env_id, num_envs=2, config=config, host=host)
    try:
        envs.reset(seed=seeds)
        zeros = np.zeros((2, *envs.single_action_space.shape), envs.single_action_space.dtype)
        t0 = time.perf_counter()
        for _ in range(steps):
            envs.step(zeros)
        return 2 * steps / (time.perf_counter() - t0)
    finally:
        envs.close()


def _one_rate(env_id: str, config: dict, steps: int) -> float:
    env = gym.make(env_id, config=config)
    try:
        env.reset(seed=0)
        zero = np.zeros(env.action_space.shape, env.action_space.dtype)
        t0 = time.perf_counter()
        for _ in range(steps):
            *_, terminated, truncated, _ = env.step(zero)
            if terminated or truncated:
                env.reset()
        return steps / (time.perf_counter() - t0)
    finally:
        env.close()


def _busy() -> None:
    while True:
        pass


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=4000, help="vector steps per measurement (>= 100)")
    args = ap.parse_args(argv)
    if args.steps < 100:
        ap.error(f"bad value for --steps: {args.steps} (expected a whole number >= 100)")
    os.environ.setdefault("MPLCONFIGDIR", tempfile.mkdtemp())
    figures: dict = {"arithmetic_two_process_scaling": scaling()}
    print(f"pure Python arithmetic, two processes over one: {figures['arithmetic_two_process_scaling']:.2f}x")
    for pf in (0, 10):
        config = {"duration": 20.0, "policy_frequency": pf, "randomize": {}}
        steps = args.steps if pf == 0 else args.steps // 10
        for busy in (False, True):
            hog = mp.get_context("fork").Process(target=_busy, daemon=True) if busy else None
            if hog is not None:
                hog.start()
            try:
                rates = {h: _vector_rate("ego/EmergencyBrake-v0", config, h, steps, 0) for h in (None, False)}
            finally:
                if hog is not None:
                    hog.kill()
                    hog.join()
            figures[f"busy_{busy}_pf{pf}"] = rates
            print(
                f"make_vec(EmergencyBrake, 2), pf {pf}, {'one busy process beside' if busy else 'nothing beside'}: "
                f"hosted {rates[None]:.0f}, host=False {rates[False]:.0f} env steps/s"
            )
    config = {"duration": 20.0, "policy_frequency": 0, "randomize": {}}
    two = _vector_rate("ego/LaneCentering-v0", config, None, args.steps, [0, 0])
    one = _one_rate("ego/LaneCentering-v0", config, args.steps)
    figures["lane_centering_from_reset"] = two / one
    print(
        f"LaneCentering, {args.steps} vector steps from a reset: make_vec {two:.0f} env steps/s, "
        f"one env {one:.0f}: {two / one:.2f}x"
    )
    return figures


if __name__ == "__main__":
    main()
