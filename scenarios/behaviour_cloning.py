"""Behaviour cloning through the Gymnasium interface: a small torch policy learns to steer from
a controller's runs, then drives the env itself.

    python scenarios/behaviour_cloning.py [--episodes 4] [--duration 40] [--epochs 300]

1. Demonstrations: report 003's cascade PID drives ``ego/LaneCentering-v0`` (at 25 m/s, from
   800 m, into the easement and the 500 m-radius arc) as a policy on the ``EgoState``
   observation (:class:`ego.gym.ControllerPolicy`), from a different lateral offset each
   episode; every step's observation and steer angle are kept.
2. Training: a 6-32-32-1 MLP maps six named fields of the observation (lateral offset and its
   rate, heading error, yaw rate, lateral speed, curvature) to the steer angle, by mean
   squared error on standardised inputs and outputs (Adam, full batch, CPU).
3. Evaluation: the MLP drives the env from an offset it never saw; its metrics (what ``ego
   run`` reports) beside the controller's.

The action type is ``EgoAction`` with the steering channel only (the lateral-error model
runs at constant speed; its longitudinal channel stays with the env's controller). A few
seconds on a CPU.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import gymnasium as gym  # noqa: E402
import torch  # noqa: E402

import ego.gym  # noqa: E402, F401 - registers the env ids

ENV_ID = "ego/LaneCentering-v0"
FEATURES = ("d", "dd", "heading_error", "yaw_rate", "vy", "curvature")
HEADLINE = ("status", "rms_lateral_error", "max_abs_lateral_error", "max_abs_steer")


def episode(env, policy, offset: float, seed: int) -> tuple[list, list, dict]:
    """One run from ``offset`` (m): observations, actions, the run's metrics."""
    obs, _ = env.reset(seed=seed, options={"config": {"offset": offset}})
    observations, actions = [], []
    while True:
        action = policy(obs)
        observations.append(obs)
        actions.append(action)
        obs, _, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            return observations, actions, info["metrics"]


class Clone(torch.nn.Module):
    """An MLP on standardised features; it returns the steer angle (rad)."""

    def __init__(self, x: np.ndarray, y: np.ndarray, hidden: int = 32) -> None:
        super().__init__()
        self.net = torch.nn.Sequential(
            torch.nn.Linear(x.shape[1], hidden),
            torch.nn.Tanh(),
            torch.nn.Linear(hidden, hidden),
            torch.nn.Tanh(),
            torch.nn.Linear(hidden, 1),
        )
        self.x_mean, self.x_std = x.mean(0), x.std(0) + 1e-9
        self.y_mean, self.y_std = y.mean(0), y.std(0) + 1e-9

    def fit(self, x: np.ndarray, y: np.ndarray, epochs: int) -> float:
        xs = torch.as_tensor((x - self.x_mean) / self.x_std, dtype=torch.float32)
        ys = torch.as_tensor((y - self.y_mean) / self.y_std, dtype=torch.float32)
        opt = torch.optim.Adam(self.parameters(), lr=3e-3)
        loss = torch.zeros(())
        for _ in range(epochs):
            opt.zero_grad()
            loss = torch.nn.functional.mse_loss(self.net(xs), ys)
            loss.backward()
            opt.step()
        return loss.item()

    def policy(self, columns: list[int]):
        def act(obs: np.ndarray) -> np.ndarray:
            x = (obs[columns] - self.x_mean) / self.x_std
            with torch.no_grad():
                z = self.net(torch.as_tensor(x, dtype=torch.float32)[None])[0].numpy()
            return (z * self.y_std + self.y_mean).astype(np.float64)

        return act


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--episodes", type=int, default=4, help="demonstration runs")
    ap.add_argument("--duration", type=float, default=40.0, help="simulated seconds per run")
    ap.add_argument("--epochs", type=int, default=300, help="full-batch training steps")
    args = ap.parse_args(argv)
    torch.manual_seed(0)
    torch.set_num_threads(1)  # a small net: threads cost more than they give
    config = {
        "speed": 25.0,
        "start": 800.0,
        "duration": args.duration,
        "action": {"type": "EgoAction", "longitudinal": False},
        # the script chooses the speed and each run's offset: no episode randomisation (the
        # env's default draws both, and its draw would win over the values set here)
        "randomize": {},
        # the clone learns and drives at the controller's own 100 Hz (the id's default is the
        # benchmark's 10 Hz), so the TimeLimit is the whole run's control periods
        "policy_frequency": 0,
    }
    env = gym.make(ENV_ID, config=config, max_episode_steps=math.ceil(args.duration / 0.01))
    try:
        names = env.unwrapped.observation_type.names
        columns = [names.index(f) for f in FEATURES]
        teacher = ego.gym.ControllerPolicy("cascade-pid", env)
        t0 = time.perf_counter()
        xs, ys = [], []
        for k, offset in enumerate(np.linspace(-0.6, 0.6, args.episodes) if args.episodes > 1 else [0.5]):
            observations, actions, _ = episode(env, teacher, float(offset), seed=k)
            xs += observations
            ys += actions
        x, y = np.array(xs)[:, columns], np.array(ys)
        t1 = time.perf_counter()
        clone = Clone(x, y)
        loss = clone.fit(x, y, args.epochs)
        t2 = time.perf_counter()
        test_offset = 0.3
        _, _, cloned = episode(env, clone.policy(columns), test_offset, seed=99)
        _, _, reference = episode(env, teacher, test_offset, seed=99)
        t3 = time.perf_counter()
    finally:
        env.close()
    print(
        f"{len(x)} demonstration steps from {args.episodes} cascade-pid runs in {t1 - t0:.1f} s; "
        f"training {args.epochs} epochs in {t2 - t1:.1f} s (loss {loss:.4f} on standardised steer); "
        f"evaluation in {t3 - t2:.1f} s"
    )
    print(f"from offset {test_offset} m:   {'clone':>12} {'cascade-pid':>12}")
    for key in HEADLINE:
        print(f"  {key:24} {cloned[key]!s:>12} {reference[key]!s:>12}")
    return {"steps": len(x), "loss": loss, "clone": cloned, "controller": reference}


if __name__ == "__main__":
    main()
