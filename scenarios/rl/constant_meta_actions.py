"""One meta action all the time on an env with DiscreteMetaAction: what IDLE, SLOWER and
FASTER do on their own (the floor a discrete agent must beat), with the outcome rates.

    python scenarios/rl/constant_meta_actions.py [--env ego/EmergencyBrake-v0] [--episodes 20]

The env in highway-env's setting for meta actions (``{"action": {"type":
"DiscreteMetaAction"}, "policy_frequency": 1}``, the env's default episode distribution),
seeds 0 .. episodes - 1, through :func:`ego.gym.evaluate` (Wilson's 95 % intervals).
"""

from __future__ import annotations

import argparse

import ego.gym

CONFIG = {"action": {"type": "DiscreteMetaAction"}, "policy_frequency": 1}


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    motorway = ["ego/EmergencyBrake-v0", "ego/FastFollower-v0", "ego/CutIn-v0"]
    ap.add_argument("--env", default=motorway[0], choices=motorway)
    ap.add_argument("--episodes", type=int, default=20)
    ap.add_argument("--actions", nargs="*", default=["IDLE", "SLOWER", "FASTER"])
    args = ap.parse_args(argv)
    if args.episodes < 1:
        ap.error(f"bad value for --episodes: {args.episodes} (expected 1 or more)")
    env = ego.gym.EgoEnv(ego.gym.ENV_IDS[args.env], CONFIG)
    indexes = env.action_type.actions_indexes
    env.close()
    bad = [a for a in args.actions if a not in indexes]
    if bad:
        ap.error(f"bad value for --actions: {bad[0]} (expected any of {', '.join(indexes)})")
    out = {}
    print(f"{args.env}, {CONFIG}, seeds 0-{args.episodes - 1}")
    for name in args.actions:
        index = indexes[name]
        report = ego.gym.evaluate(lambda obs, i=index: i, args.env, episodes=args.episodes, config=CONFIG)
        out[name] = report
        n = report["episodes"]
        collisions = sum(bool(r["collision"]) for r in report["per_episode"])
        successes = sum(bool(r["is_success"]) for r in report["per_episode"])
        lo, hi = report["collision_interval"]
        print(
            f"  always {name:7} collisions {collisions}/{n} (95 % {lo:.2f}-{hi:.2f}), successes {successes}/{n}, "
            f"mean return {report['mean_return']:.2f}"
        )
    return out


if __name__ == "__main__":
    main()
