"""Cost of the Gymnasium wrapper over the raw scenario step, and env steps/s, in one run.

    python benchmarks/bench_gym.py [--repeat 3] [--duration 20] [--ids ego/CutIn-v0 ...] [--vector-steps 2000]
                                   [--scenarios scenarios/openscenario/emergency_brake.xosc ...]

For every env id: the scenario's default controller drives one run (seed 0) and its actions
are kept; then the same actions are replayed (same trajectory, no controller cost) through
``env.step`` of ``gym.make(id)`` with the ``EgoAction`` type and the ``EgoState`` observation,
and with the ``Kinematics`` observation, timing both the whole ``env.step`` and the
``Scenario.step`` inside it (the raw step). The two are measured over the same steps, so the
ratio holds on a busy machine, where two separate loops do not. Printed: env steps/s, raw
steps/s and the wrapper's cost per step over the raw step (target <= 15 % with ``EgoState``),
the timer's own cost taken out. In the platoon the agent drives the first follower and the
env steps the others' controllers itself: they count as raw work, as ``ego run`` steps them
too; so does the run's result (its metrics), which the env computes once at the episode's
end for ``info["metrics"]`` and ``ego run`` computes at the end of its loop. The env is
``gym.make(id)`` as registered: ``TimeLimit`` included (the spec's ``max_episode_steps``), no
order-enforcing or passive-checker wrapper (the spec disables them: ``EgoEnv`` checks the
order itself and passes Gymnasium's checker). Best of ``--repeat``.

Then, per id, ``gym.make_vec(id, 2)`` (ego's ``EgoVectorEnv``: the first env in this process,
the second in a worker, the step's data and signals in shared memory) and Gymnasium's
``AsyncVectorEnv`` of the same two envs against one env in a process of its own: env steps/s
of each (target: make_vec >= 1.8x on 2 cores).

``--scenarios`` adds rows of ``ego/Scenario-v0`` (``config={"scenario": NAME_OR_FILE}``), the
same measures on a built-in scenario or an OpenSCENARIO file (default: the shipped
``emergency_brake.xosc``), its default controller's actions replayed the same way.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import gymnasium as gym  # noqa: E402
import numpy as np  # noqa: E402
from gymnasium.vector import AsyncVectorEnv  # noqa: E402

import ego.gym  # noqa: E402
from ego.gym.scenario_env import check_scenario  # noqa: E402
from ego.gym.vector import EgoVectorEnv, _Maker  # noqa: E402
from ego.params import ConfigError  # noqa: E402
from ego.runner import RunSpec, build  # noqa: E402
from ego.scenarios import scenario_class  # noqa: E402


def demonstration(scenario: str, controller: str, overrides: dict) -> list:
    """The controller's actions, step by step, over one run (the first follower's in a platoon)."""
    sc = build(RunSpec(scenario, controller, 0, overrides))
    try:
        obs = sc.reset()
        actions = []
        while not sc.done:
            action = sc.controller.step(obs)
            actions.append(action[0] if sc.task == "car-following" else action)
            obs = sc.step(action)
        return actions
    finally:
        sc.close()


def _timer_cost(number: int = 100000) -> float:
    """Seconds one timed call adds (two perf_counter calls and the closure)."""
    timed, spent = _timed(lambda: None)
    t0 = time.perf_counter()
    for _ in range(number):
        timed()
    return (time.perf_counter() - t0) / number


def _timed(fn):
    """``fn`` wrapped to add the seconds spent inside it to ``spent[0]``."""
    spent = [0.0]
    clock = time.perf_counter

    def timed(*args):
        t0 = clock()
        out = fn(*args)
        spent[0] += clock() - t0
        return out

    return timed, spent


def env_replay(env_id: str, overrides: dict, observation: dict, actions: np.ndarray) -> tuple[float, float, int]:
    """(seconds for ``env.step`` over ``actions``, seconds of them inside the scenario's own
    work, timed calls): the scenario's step, in a platoon its other followers' controllers,
    which the raw loop steps too, and the run's result (its metrics) at the end, which
    ``Scenario.run`` computes as well. Both are measured over the same steps, so a busy
    machine slows both alike."""
    # the demonstration's own scenario: no randomisation
    env = gym.make(
        env_id,
        config={**overrides, "randomize": {}, "observation": observation, "action": {"type": "EgoAction"}},
        max_episode_steps=len(actions),
    )
    try:
        env.reset(seed=0)
        sc = env.unwrapped.scenario
        sc.step, spent = _timed(sc.step)
        # the run's result (its metrics) at the end: Scenario.run (ego run) computes it too
        sc.result, spent_result = _timed(sc.result)
        calls = len(actions)
        if env.unwrapped.task == "car-following":
            sc.controller.step, spent_ctrl = _timed(sc.controller.step)
            calls *= 2
        else:
            spent_ctrl = [0.0]
        step = env.step
        t0 = time.perf_counter()
        for action in actions:
            step(action)
        return time.perf_counter() - t0, spent[0] + spent_ctrl[0] + spent_result[0], calls
    finally:
        env.close()


def separate_loops(env_id: str, overrides: dict, actions: np.ndarray, repeat: int) -> tuple[float, float]:
    """(seconds of ``env.step`` over ``actions``, seconds of the raw loop over the same
    commands), each the best of ``repeat``, the two alternating: the same env reset to seed 0
    for both, the raw loop stepping its scenario directly (``Scenario.step`` with the actions'
    native commands; in a platoon ``ego run``'s loop, the controllers of every follower, whose
    first follower's actions these are) and computing the run's result at the end, as the env
    does for ``info["metrics"]``. No timer inside either loop, so neither pays for one; the
    price is that a busy machine's changing load falls on the two unevenly (quote it from a
    quiet machine)."""
    env = gym.make(
        env_id,
        config={**overrides, "randomize": {}, "observation": {"type": "EgoState"}, "action": {"type": "EgoAction"}},
        max_episode_steps=len(actions),
    )
    clock = time.perf_counter
    best_env = best_raw = math.inf
    try:
        u = env.unwrapped
        env.reset(seed=0)
        commands = [u.action_type.native(a) for a in actions]
        platoon = u.task == "car-following"
        for _ in range(repeat):
            env.reset(seed=0)
            sc = u.scenario
            step = sc.step
            t0 = clock()
            if platoon:
                controller = sc.controller
                for _cmd in commands:
                    step(controller.step(sc.obs))
            else:
                for cmd in commands:
                    step(cmd)
            sc.result()
            best_raw = min(best_raw, clock() - t0)
            env.reset(seed=0)
            env_step = env.step
            t0 = clock()
            for a in actions:
                env_step(a)
            best_env = min(best_env, clock() - t0)
    finally:
        env.close()
    return best_env, best_raw


def _solo(env_id: str, config: dict, conn) -> None:
    """One env in a process of its own (its own libsumo): on ``k`` from ``conn``, ``k`` steps of
    zero actions (episodes reset as they end), replying the seconds they took; None ends it."""
    env = gym.make(env_id, config=config)
    try:
        env.reset(seed=0)
        zero = np.zeros(env.action_space.shape, dtype=env.action_space.dtype)
        env.step(zero)
        conn.send(0.0)
        clock = time.perf_counter
        while (k := conn.recv()) is not None:
            t0 = clock()
            for _ in range(k):
                *_, terminated, truncated, _ = env.step(zero)
                if terminated or truncated:
                    env.reset()
            conn.send(clock() - t0)
    finally:
        env.close()


def vector_speedup(env_id: str, steps: int, config: dict, rounds: int = 1) -> tuple[float, float, float, float]:
    """(one env's steps/s, ``gym.make_vec(env_id, 2)``'s env steps/s (ego's own vector env),
    ``gymnasium.vector.AsyncVectorEnv``'s of the same two envs, two envs in two processes of
    their own stepping at once with no vector env between them: what the machine allows): zero actions (the scenario's
    traffic and the ego's model still run), episodes reset as they end. ``config`` should fix
    the scenario (``"randomize": {}``): with the env's episode distribution, the one env and
    the two would play different scenarios, whose steps cost different times. The one env
    runs in a process of its own (make_vec steps its first env in this process, whose libsumo
    it holds), timing its own loop. The three take turns in slices of a twentieth of
    ``steps``, ``rounds`` x ``steps`` steps each in all, so that a busy machine's changing load
    falls on each alike; the vector envs' worker start-up is not timed."""
    import multiprocessing as mp

    maker = _Maker(env_id, {"config": config})
    ctx = mp.get_context("fork")
    pipes = [ctx.Pipe() for _ in range(2)]
    solos = [ctx.Process(target=_solo, args=(env_id, config, there), daemon=True) for _, there in pipes]
    for solo in solos:
        solo.start()
    here, other = pipes[0][0], pipes[1][0]
    vectors = [gym.make_vec(env_id, num_envs=2, config=config), AsyncVectorEnv([maker, maker])]
    try:
        here.recv()
        other.recv()
        for envs in vectors:
            envs.reset(seed=0)
        zero = np.zeros(vectors[0].single_action_space.shape, dtype=vectors[0].single_action_space.dtype)
        zeros = np.zeros((2, *zero.shape), dtype=zero.dtype)
        for envs in vectors:
            envs.step(zeros)
        chunk = max(steps // 20, 1)
        spent = [0.0, 0.0, 0.0, 0.0]
        clock = time.perf_counter
        for _ in range(rounds * (steps // chunk)):
            here.send(chunk)
            spent[0] += here.recv()
            here.send(chunk)
            other.send(chunk)
            spent[3] += max(here.recv(), other.recv())
            for k, envs in enumerate(vectors, 1):
                t0 = clock()
                for _ in range(chunk):
                    envs.step(zeros)
                spent[k] += clock() - t0
    finally:
        for conn, _ in pipes:
            conn.send(None)
        for solo in solos:
            solo.join(10)
        for envs in vectors:
            envs.close()
    n = rounds * (steps // chunk) * chunk
    return n / spent[0], 2 * n / spent[1], 2 * n / spent[2], 2 * n / spent[3]


class _NoOp(gym.Env):
    """An env whose step does nothing: a vector env over it costs its round trip alone."""

    observation_space = gym.spaces.Box(-1.0, 1.0, (15,), np.float64)
    action_space = gym.spaces.Box(-1.0, 1.0, (2,), np.float32)
    _obs = np.zeros(15)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        return self._obs.copy(), {}

    def step(self, action):
        return self._obs.copy(), 0.0, False, False, {"status": "running"}


def round_trip(steps: int, rounds: int) -> tuple[float, float, float]:
    """Microseconds per step of two no-op envs in ``EgoVectorEnv`` (the first env here, the
    default; every env in a worker, ``host=False``) and in ``AsyncVectorEnv`` (best of
    ``rounds``): what a vector step costs beyond the envs' own work."""
    out = []
    for envs in (
        EgoVectorEnv([_NoOp, _NoOp], context="fork"),
        EgoVectorEnv([_NoOp, _NoOp], context="fork", host=False),
        AsyncVectorEnv([_NoOp, _NoOp], context="fork"),
    ):
        try:
            envs.reset(seed=0)
            zeros = np.zeros((2, 2), np.float32)
            best = math.inf
            for _ in range(rounds):
                t0 = time.perf_counter()
                for _ in range(steps):
                    envs.step(zeros)
                best = min(best, (time.perf_counter() - t0) / steps)
            out.append(best * 1e6)
        finally:
            envs.close()
    return out[0], out[1], out[2]


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--duration", type=float, default=20.0, help="simulated seconds per run")
    ap.add_argument("--ids", nargs="*", default=list(ego.gym.ENV_IDS))
    ap.add_argument(
        "--scenarios",
        nargs="*",
        default=[str(ROOT / "scenarios/openscenario/emergency_brake.xosc")],
        help="scenarios (names or .xosc files) measured as ego/Scenario-v0 (none: skip)",
    )
    ap.add_argument(
        "--vector-steps",
        type=int,
        default=2000,
        help="steps of one env and of make_vec(id, 2) for the speed-up (0: skip)",
    )
    args = ap.parse_args(argv)
    os.environ.setdefault("MPLCONFIGDIR", tempfile.mkdtemp())
    # rows: (label, env id, scenario, the env's own config keys beside the scenario's)
    rows = [(env_id, env_id, ego.gym.ENV_IDS[env_id], {}) for env_id in args.ids]
    for name in args.scenarios:
        try:
            check_scenario(name)
        except ConfigError as exc:
            ap.error(str(exc))
        label = f"{ego.gym.SCENARIO_ENV_ID}:{Path(name).name}"
        rows.append((label, ego.gym.SCENARIO_ENV_ID, name, {"scenario": name}))
    duration = {"duration": args.duration}
    width = max([24, *(len(row[0]) for row in rows)])
    figures = {}
    timer = _timer_cost()
    print(
        f"env step against the raw scenario step, same actions, dt = 0.01 s, {args.duration:g} s "
        f"runs, best of {args.repeat}"
    )
    print(
        f"  {'env id':{width}} {'steps':>6} {'raw steps/s':>12} {'env steps/s':>12} {'overhead':>9} "
        f"{'Kinematics steps/s':>19} {'overhead':>9} {'overhead, separate loops':>25}"
    )
    for label, env_id, scenario, own in rows:
        # one env step per control period, as the raw scenario step (the ids' default is 10 Hz)
        overrides = {**duration, **own, "policy_frequency": 0}
        controller = scenario_class(scenario).reference_controller()
        recorded = demonstration(scenario, controller, duration)
        actions = np.array(recorded, dtype=np.float64).reshape(len(recorded), -1)
        if scenario_class(scenario).task == "car-following":
            actions = actions[:, :1]
        n = len(actions)
        row = {"steps": n}
        for key, observation in (("", "EgoState"), ("kinematics_", "Kinematics")):
            runs = []
            for _ in range(args.repeat):
                total, inner, calls = env_replay(env_id, overrides, {"type": observation}, actions)
                wrapper = max(total - inner - calls * timer, 0.0)
                runs.append((wrapper / inner, total, inner))
            overhead, total, inner = min(runs)
            row.update({f"{key}overhead": overhead, f"{key}env_steps_per_s": n / total})
            if not key:
                row["raw_steps_per_s"] = n / inner
        env_s, raw_s = separate_loops(env_id, overrides, actions, args.repeat)
        row["separate_loops_overhead"] = env_s / raw_s - 1.0
        figures[label] = row
        print(
            f"  {label:{width}} {n:6d} {row['raw_steps_per_s']:12.0f} {row['env_steps_per_s']:12.0f} "
            f"{100 * row['overhead']:8.1f}% {row['kinematics_env_steps_per_s']:19.0f} "
            f"{100 * row['kinematics_overhead']:8.1f}% {100 * row['separate_loops_overhead']:24.1f}%"
        )
    print(
        "  target: overhead <= 15 % with EgoState (the first overhead times the raw step inside the env's step, "
        "robust to a busy machine but paying for its timer in the loop; the last times two loops without a timer)"
    )
    if args.vector_steps:
        print(
            f"gym.make_vec(id, 2) (ego's EgoVectorEnv, the first env here, the second in a worker), gymnasium's "
            f"AsyncVectorEnv and two envs in processes of their own with no vector env (the machine's own scaling) "
            f"against one env, {args.repeat} x {args.vector_steps} steps each (/2 at 10 Hz), one fixed scenario (no randomisation), in turns of a twentieth, "
            f"{os.cpu_count()} cores"
        )
        print(
            f"  {'env id':{width}} {'policy_frequency':>16} {'1 env steps/s':>14} {'make_vec steps/s':>17} "
            f"{'speed-up':>9} {'Async steps/s':>14} {'speed-up':>9} {'2 processes':>12}"
        )
        for label, env_id, _, own in rows:
            for pf in (0, 10):
                # one fixed scenario for all three (the same work a step), the traffic seeded
                one, two, other, pair = vector_speedup(
                    env_id,
                    args.vector_steps // (2 if pf else 1),
                    {**duration, **own, "policy_frequency": pf, "randomize": {}},
                    args.repeat,
                )
                figures[label].update(
                    {
                        f"one_env_steps_per_s_pf{pf}": one,
                        f"make_vec2_steps_per_s_pf{pf}": two,
                        f"vector_speedup_pf{pf}": two / one,
                        f"async2_steps_per_s_pf{pf}": other,
                        f"async_speedup_pf{pf}": other / one,
                        f"two_processes_speedup_pf{pf}": pair / one,
                    }
                )
                print(
                    f"  {label:{width}} {pf:16d} {one:14.0f} {two:17.0f} {two / one:8.2f}x {other:14.0f} "
                    f"{other / one:8.2f}x {pair / one:11.2f}x"
                )
        print("  target: make_vec >= 1.8x on 2 cores")
        ego_us, workers_us, async_us = round_trip(args.vector_steps, args.repeat)
        figures["round_trip_us"] = {
            "EgoVectorEnv": ego_us,
            "EgoVectorEnv_host_false": workers_us,
            "AsyncVectorEnv": async_us,
        }
        print(
            f"a vector step of two no-op envs (the round trip alone), best of {args.repeat}: "
            f"EgoVectorEnv {ego_us:.1f} us (host=False {workers_us:.0f} us), AsyncVectorEnv {async_us:.0f} us"
        )
    return figures


if __name__ == "__main__":
    main()
