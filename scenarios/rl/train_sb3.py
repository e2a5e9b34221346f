"""Train a stable-baselines3 PPO, SAC or DQN agent on an ego env and score it beside a controller.

    pip install -e ".[rl]"
    python scenarios/rl/train_sb3.py --env ego/CutIn-v0 --algo ppo --seed 0 --steps 5000 [--save model.zip]
    python scenarios/rl/train_sb3.py --env ego/CutIn-v0 --algo sac --seed 1 --steps 10240 --models runs/rl-baselines
    python scenarios/rl/train_sb3.py --env ego/EmergencyBrake-v0 --algo dqn --seed 0 --steps 20000

``--models DIR`` writes the model as ``DIR/<env>-<algo>-seed<seed>-<steps>.zip``, where
``python -m ego.docs results --page rl-baselines`` reads the trained rows' models from
(``runs/rl-baselines/`` of the checkout; a missing model is trained there by the page itself).

The env runs in its benchmark configuration (``ego.gym.baselines.BENCH_CONFIG``: randomised
episodes, 10 Hz policy), and the agent is scored on the evaluation episodes
(``ego.gym.baselines.EVAL_SEEDS``) that docs/results/rl-baselines.md uses, beside the env's
default controller driving the same episodes through ``ControllerPolicy``. DQN trains and is
scored in the discrete setting (``ego.gym.baselines.DISCRETE_CONFIG``), beside each meta
action held all the time.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from ego.gym import ENV_IDS
from ego.gym.baselines import (
    ALGOS,
    BENCH_CONFIG,
    DISCRETE_ALGOS,
    DISCRETE_CONFIG,
    algo_config,
    discrete_actions,
    evaluate,
    model_file,
    save,
    summary,
    train,
)
from ego.params import ConfigError
from ego.paths import check_file_target, check_folder_target


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--env", default="ego/CutIn-v0", help=f"one of {', '.join(ENV_IDS)}")
    ap.add_argument("--algo", default="ppo", help="ppo, sac or dqn")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--steps", type=int, default=5000, help="training budget in env steps")
    ap.add_argument("--save", default=None, help="write the trained model here (.zip)")
    ap.add_argument(
        "--models", default=None, help="write the trained model into this folder, named as the docs read it"
    )
    ap.add_argument("--no-score", action="store_true", help="skip scoring the agent and the controller after training")
    args = ap.parse_args(argv)
    problems = []
    if args.env not in BENCH_CONFIG:
        problems.append(f"bad value for --env: {args.env!r} (expected one of {', '.join(ENV_IDS)})")
    algos = ALGOS + DISCRETE_ALGOS
    if args.algo not in algos:
        problems.append(f"bad value for --algo: {args.algo!r} (expected one of {', '.join(algos)})")
    if not 1 <= args.steps <= 10_000_000:
        problems.append(f"bad value for --steps: {args.steps} (expected 1 to 10000000)")
    if not 0 <= args.seed <= 2**31 - 1:
        problems.append(f"bad value for --seed: {args.seed} (expected 0 to 2147483647)")
    try:  # the places the model goes: refused before the training, not after it
        if args.save:
            check_file_target(args.save, "--save")
        if args.models:
            check_folder_target(args.models, "--models")
    except ConfigError as exc:
        problems.append(str(exc))
    if problems:
        print(f"train_sb3.py: error: {problems[0]}", file=sys.stderr)
        return 2
    t0 = time.perf_counter()
    model = train(args.env, args.algo, args.seed, args.steps, progress=sys.stderr)
    print(f"{args.algo} trained {args.steps} env steps on {args.env} in {time.perf_counter() - t0:.0f} s")
    if args.save:
        save(model, args.save)
    if args.models:
        Path(args.models).mkdir(parents=True, exist_ok=True)
        save(model, Path(args.models) / model_file(args.env, args.algo, args.seed, args.steps))
    if args.no_score:
        return 0
    from ego.scenarios import scenario_class

    if args.algo in DISCRETE_ALGOS:  # no controller drives meta actions: each one held instead
        index = discrete_actions(args.env)
        others = [(f"always {a}", lambda obs, i=i: i) for a, i in index.items()]
        print(f"  in the discrete setting {DISCRETE_CONFIG}")
    else:
        controller = scenario_class(ENV_IDS[args.env]).reference_controller()
        others = [(controller, controller)]
    for name, policy in ((args.algo, model), *others):
        s = summary([evaluate(args.env, policy, algo_config(args.algo))])
        print(
            f"  {name:14} mean return {s['mean']:10.2f}   success {100 * s['success']:5.1f} %   "
            f"collision {100 * s['collision']:5.1f} %"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
