"""SB3 PPO with ``make_vec_env(id, n_envs=2)`` and the env's default config, 200,000 steps.

    python scripts/ppo_vec_200k.py ego/EmergencyBrake-v0 dummy|subproc [STEPS]

Issue 42's check that the standard clients run long trainings without an error: SB3's own
``make_vec_env`` and ``PPO`` with their defaults (one torch thread), DummyVecEnv or
SubprocVecEnv (forkserver). Prints the steps done and the wall and CPU time.
"""

from __future__ import annotations

import argparse
import resource
import time

import ego.gym  # noqa: F401 - registers the ego/ ids, in SubprocVecEnv's workers too (they import this module)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("env_id", help="a registered env id, e.g. ego/EmergencyBrake-v0")
    ap.add_argument("kind", choices=("dummy", "subproc"), help="the vectoriser")
    ap.add_argument("steps", nargs="?", type=int, default=200_000, help="training steps (default: 200000)")
    args = ap.parse_args()
    if args.steps < 1:
        ap.error(f"bad value for STEPS: {args.steps} (expected >= 1)")

    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

    torch.set_num_threads(1)
    t0, c0 = time.perf_counter(), time.process_time()
    if args.kind == "dummy":
        v = make_vec_env(args.env_id, n_envs=2, seed=0, vec_env_cls=DummyVecEnv)
    else:
        v = make_vec_env(
            args.env_id, n_envs=2, seed=0, vec_env_cls=SubprocVecEnv, vec_env_kwargs={"start_method": "forkserver"}
        )
    model = PPO("MlpPolicy", v, seed=0, device="cpu", verbose=0)
    model.learn(args.steps)
    v.close()
    ch = resource.getrusage(resource.RUSAGE_CHILDREN)
    print(
        f"{args.env_id} {args.kind}: {model.num_timesteps} steps OK, wall {time.perf_counter() - t0:.0f} s, "
        f"cpu {time.process_time() - c0:.0f} s (+ {ch.ru_utime + ch.ru_stime:.0f} s in child processes it waited for)"
    )


if __name__ == "__main__":
    main()
