"""ego's own vector env (``gym.make_vec(id, n)``): one worker process per env, the step's data
in shared memory. The same results as the same envs stepped one by one, Gymnasium 1.x's
semantics (NEXT_STEP autoreset, seeds, masks, infos), a worker's error raised in the parent,
and no worker left behind by close(), a kill or Ctrl-C of the parent."""

import os
import signal
import subprocess
import sys
import textwrap

import gymnasium as gym
import numpy as np
import psutil
import pytest
from gymnasium.vector import AutoresetMode, VectorEnv
from process_group import survivors, wait_for

import ego.gym  # noqa: F401 - registers the ids
from ego.gym.vector import EgoVectorEnv, _Maker
from ego.params import ConfigError

pytestmark = [pytest.mark.sumo, pytest.mark.filterwarnings("ignore::UserWarning")]

#: short episodes (10 env steps of 0.1 s) so the vector env resets some in a few steps
SHORT = {"duration": 1.0, "policy_frequency": 10}


def _actions(space, n_steps, seed=0, n_envs=2):
    rng = np.random.default_rng(seed)
    return [0.5 * rng.uniform(-1.0, 1.0, (n_envs, *space.shape)).astype(space.dtype) for _ in range(n_steps)]


def _same(a, b) -> bool:
    """Equal values (arrays elementwise, NaN equal to NaN), the metrics' wall time aside (the
    only value that differs between two runs of the same episode)."""
    if isinstance(a, dict) and isinstance(b, dict):
        keys = set(a) - {"wall_time", "_wall_time"}
        return keys == set(b) - {"wall_time", "_wall_time"} and all(_same(a[k], b[k]) for k in keys)
    if isinstance(a, np.ndarray) and isinstance(b, np.ndarray):
        if a.dtype == object or b.dtype == object:
            return a.shape == b.shape and all(_same(x, y) for x, y in zip(a.tolist(), b.tolist()))
        return a.dtype == b.dtype and np.array_equal(a, b, equal_nan=a.dtype.kind == "f")
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(a, (float, np.floating)) and isinstance(b, (float, np.floating)):
        return a == b or (a != a and b != b)
    return type(a) is type(b) and a == b


class _Merge(VectorEnv):
    """Gymnasium's own merge of the envs' infos into a vector info (``_add_info``)."""

    num_envs = 2


def _one_by_one(env_id, config, seed, actions, n_envs=2):
    """Each env alone, one after the other, with Gymnasium's NEXT_STEP autoreset by hand:
    per env the (observations, rewards, terminations, truncations, infos) per step."""
    runs = []
    for i in range(n_envs):
        env = gym.make(env_id, config=config)
        try:
            obs, info = env.reset(seed=seed + i)
            rows = [(obs, 0.0, False, False, info)]
            autoreset = False
            for batch in actions:
                if autoreset:
                    obs, info = env.reset()
                    rows.append((obs, 0.0, False, False, info))
                    autoreset = False
                    continue
                obs, reward, terminated, truncated, info = env.step(batch[i])
                rows.append((obs, reward, terminated, truncated, info))
                autoreset = terminated or truncated
        finally:
            env.close()
        runs.append(rows)
    return runs


@pytest.mark.parametrize(
    ("env_id", "num_envs", "host"),
    [("ego/CutIn-v0", 2, None), ("ego/Platoon-v0", 2, None), ("ego/CutIn-v0", 2, False), ("ego/CutIn-v0", 3, None)],
    ids=["cut-in-hosted", "platoon-hosted", "cut-in-all-workers", "cut-in-3-envs"],
)
def test_same_results_as_the_envs_stepped_one_by_one(env_id, num_envs, host):
    """Hosted (the default: the first env here, signals in shared memory on 2 cores), every env
    in a worker (pipes), and more envs than cores (the first here, the others on pipes)."""
    envs = gym.make_vec(env_id, num_envs=num_envs, config=SHORT, info="all", host=host)
    assert isinstance(envs, EgoVectorEnv)
    assert len(envs._processes) == num_envs - (host is not False)
    assert envs.spinning == (host is not False and num_envs <= len(os.sched_getaffinity(0)))
    actions = _actions(envs.single_action_space, 25, n_envs=num_envs)
    try:
        obs, infos = envs.reset(seed=3)
        vector = [(obs, np.zeros(num_envs), np.zeros(num_envs, bool), np.zeros(num_envs, bool), infos)]
        for batch in actions:
            vector.append(envs.step(batch))
    finally:
        envs.close()
    expected = _one_by_one(env_id, SHORT, 3, actions, n_envs=num_envs)
    merge, ends = _Merge(), 0
    merge.num_envs = num_envs
    for k, (obs, rewards, terminated, truncated, infos) in enumerate(vector):
        e_infos: dict = {}
        for i in range(num_envs):
            e_obs, e_reward, e_term, e_trunc, e_info = expected[i][k]
            assert np.array_equal(obs[i], e_obs), (k, i)
            assert rewards[i] == e_reward and terminated[i] == e_term and truncated[i] == e_trunc, (k, i)
            e_infos = merge._add_info(e_infos, e_info, i)
            ends += bool(e_term or e_trunc)
        assert _same(infos, e_infos), (k, infos, e_infos)
    assert ends >= 4  # the comparison went through autoresets


@pytest.mark.parametrize("host", [None, False], ids=["hosted", "all-workers"])
def test_discrete_actions_reach_each_env_and_a_bad_one_is_refused(host):
    """A Discrete action is a scalar per env: each env steps its own (here one speeds up, the
    other slows down), as the same envs stepped one by one do, and an action outside the space
    is the single env's ValueError, not a silent 0."""
    config = {**SHORT, "duration": 3.0, "action": {"type": "DiscreteMetaAction", "lateral": False}}
    actions = [np.array([2, 0])] * 6  # FASTER, SLOWER
    envs = gym.make_vec("ego/EmergencyBrake-v0", num_envs=2, config=config, host=host)
    try:
        envs.reset(seed=3)
        for batch in actions:
            obs, *_ = envs.step(batch)
        with pytest.raises(ValueError, match=r"bad action np.int64\(9\): expected an integer from 0 to 2"):
            envs.step(np.array([9, 1]))
    finally:
        envs.close()
    expected = _one_by_one("ego/EmergencyBrake-v0", config, 3, actions)
    assert np.array_equal(obs[0], expected[0][-1][0]) and np.array_equal(obs[1], expected[1][-1][0])
    assert obs[0][6] > obs[1][6]  # the faster one is faster


def test_gymnasium_semantics_and_light_infos():
    envs = gym.make_vec("ego/CutIn-v0", num_envs=2, config=SHORT)
    try:
        assert envs.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP
        assert envs.single_observation_space.shape == (16,) and envs.observation_space.shape == (2, 16)
        assert envs.single_action_space.shape == (2,) and envs.action_space.shape == (2, 2)
        obs, infos = envs.reset(seed=5)
        assert obs in envs.observation_space and list(infos["status"]) == ["running", "running"]
        again, infos2 = envs.reset(seed=[5, 6])
        assert np.array_equal(obs, again) and _same(infos2, infos)
        zeros = np.zeros((2, 2), np.float32)
        seen_end = seen_reset = False
        for _ in range(12):
            obs, rewards, terminated, truncated, infos = envs.step(zeros)
            assert rewards.dtype == np.float64 and terminated.dtype == np.bool_
            ended = terminated | truncated
            if ended.any():
                # by default an info crosses only where it carries something: the end's (metrics)
                assert list(infos["_metrics"]) == list(ended) and list(infos["_rewards"]) == list(ended)
                seen_end = True
            elif seen_end and not seen_reset:
                # the step after an end resets that env (NEXT_STEP): its reset info, reward 0
                assert "randomized" in infos and rewards[infos["_randomized"]].tolist() == [0.0, 0.0]
                seen_reset = True
            else:
                assert infos == {}
        assert seen_end and seen_reset
        # reset_mask: only the masked env restarts
        before = obs.copy()
        obs, infos = envs.reset(seed=9, options={"reset_mask": np.array([False, True])})
        assert np.array_equal(obs[0], before[0]) and list(infos["_status"]) == [False, True]
        assert envs.get_attr("task") == ("tracking", "tracking")
        assert [m["steps"] for m in envs.call("metrics")] == [m["steps"] for m in envs.call("metrics")]
        envs.set_attr("marker", [1, 2])
        assert envs.get_attr("marker") == (1, 2)
        # Gymnasium's vector wrappers work over it
        stats = gym.wrappers.vector.RecordEpisodeStatistics(envs)
        stats.reset(seed=0)
        for _ in range(11):
            _, _, terminated, truncated, infos = stats.step(zeros)
            if (terminated | truncated).any():
                break
        assert list(infos["_episode"]) == list(terminated | truncated) and infos["episode"]["l"].max() == 10
    finally:
        envs.close()


def test_a_workers_error_is_raised_in_the_parent_and_close_reaps_the_workers():
    envs = gym.make_vec("ego/CutIn-v0", num_envs=2, config=SHORT)
    workers = [psutil.Process(p.pid) for p in envs._processes]
    assert all(w.is_running() for w in workers)
    with pytest.raises(RuntimeError, match=r"call reset\(\) before step\(\)"):
        envs.step(np.zeros((2, 2), np.float32))
    with pytest.raises(RuntimeError, match="workers are gone"):
        envs.step(np.zeros((2, 2), np.float32))
    envs.close()
    assert not any(w.is_running() and w.status() != psutil.STATUS_ZOMBIE for w in workers)
    # a clean close
    envs = gym.make_vec("ego/CutIn-v0", num_envs=2, config=SHORT)
    workers = [psutil.Process(p.pid) for p in envs._processes]
    envs.reset(seed=0)
    with pytest.raises(ValueError, match="bad actions: expected shape"):
        envs.step(np.zeros((2, 3), np.float32))
    envs.close()
    envs.close()  # twice is fine
    assert not any(w.is_running() and w.status() != psutil.STATUS_ZOMBIE for w in workers)
    with pytest.raises(RuntimeError, match="closed"):
        envs.reset()


def test_bad_configuration_fails_before_any_worker_starts():
    children = set(psutil.Process().children())
    with pytest.raises(ConfigError, match="bad value for ego_speed"):
        gym.make_vec("ego/CutIn-v0", num_envs=2, config={"ego_speed": 1000})
    with pytest.raises(ConfigError, match="bad value for info"):
        EgoVectorEnv([_Maker("ego/CutIn-v0", {})] * 2, info="some")
    assert set(psutil.Process().children()) == children


_PARENT = textwrap.dedent(
    """
    import sys, time
    import numpy as np, gymnasium as gym
    import ego.gym
    envs = gym.make_vec("ego/Platoon-v0", num_envs=2, config={"policy_frequency": 10}, host=HOST)
    envs.reset(seed=0)
    print(" ".join(str(p.pid) for p in envs._processes), flush=True)
    zeros = np.zeros((2, 1), np.float32)
    while True:
        envs.step(zeros)
    """
)


@pytest.mark.parametrize("how", ["SIGKILL", "SIGINT"])
@pytest.mark.parametrize("host", [True, False], ids=["hosted", "all-workers"])
def test_no_orphan_worker_when_the_parent_is_killed_or_interrupted(how, host, tmp_path):
    """Hosted (the default): the first env here, one worker watching shared memory; else two
    workers on their pipes."""
    env = {**os.environ, "MPLCONFIGDIR": str(tmp_path)}
    proc = subprocess.Popen(
        [sys.executable, "-c", f"HOST = {host}\n" + _PARENT],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env=env,
        start_new_session=True,
    )
    try:
        line = []
        wait_for(lambda: line.append(proc.stdout.readline()) or line[-1], proc, "the workers' pids")
        pids = [int(p) for p in line[-1].split()]
        assert len(pids) == (1 if host else 2) and all(psutil.pid_exists(p) for p in pids)
        if how == "SIGINT":  # Ctrl-C in a terminal: the whole foreground group gets it
            os.killpg(proc.pid, signal.SIGINT)
        else:
            proc.kill()
        proc.wait(60)
        assert survivors(proc.pid, timeout=30.0) == []
        if how == "SIGINT":
            assert b"KeyboardInterrupt" in proc.stderr.read()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def test_a_second_env_here_beside_the_hosted_one_runs_through_traci_and_evicts_nothing():
    """The vector env's first env holds this process's libsumo: an ego env started here
    meanwhile runs its SUMO through TraCI (a warning says so) and neither stops the other;
    once the vector env is closed a new env runs through libsumo again."""
    envs = gym.make_vec("ego/CutIn-v0", num_envs=2, config=SHORT)
    other = gym.make("ego/CutIn-v0", config={**SHORT, "multi_instance": False})  # even one-per-process
    try:
        envs.reset(seed=0)
        with pytest.warns(UserWarning, match="runs its SUMO through TraCI"):
            other.reset(seed=5)
        assert other.unwrapped.scenario.bridge.via_traci
        zeros = np.zeros((2, 2), np.float32)
        for _ in range(3):
            envs.step(zeros)
            other.step(zeros[0])
        # the hosted env was not evicted: its episode goes on as the same env stepped alone
        obs, *_ = envs.step(zeros)
        alone = gym.make("ego/CutIn-v0", config={**SHORT, "multi_instance": True})
        try:
            alone.reset(seed=0)
            for _ in range(4):
                expected, *_ = alone.step(zeros[0])
        finally:
            alone.close()
        assert np.array_equal(obs[0], expected)
    finally:
        other.close()
        envs.close()
    env = gym.make("ego/CutIn-v0", config=SHORT)
    try:
        env.reset(seed=0)
        assert not env.unwrapped.scenario.bridge.via_traci
    finally:
        env.close()


def test_host_must_be_a_bool_or_none():
    with pytest.raises(ConfigError, match="bad value for host: 'yes'"):
        gym.make_vec("ego/CutIn-v0", num_envs=2, host="yes")


class _Counter(gym.Env):
    """A pure-Python env (no SUMO): its observation counts its steps; its step raises at
    ``fail_at`` (None: never)."""

    observation_space = gym.spaces.Box(-1e6, 1e6, (3,), np.float64)
    action_space = gym.spaces.Box(-1.0, 1.0, (2,), np.float32)

    def __init__(self, fail_at=None):
        self.fail_at, self.n = fail_at, 0

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.n = 0
        return np.array([0.0, float(seed or 0), 0.0]), {"seed": seed}

    def step(self, action):
        self.n += 1
        if self.fail_at is not None and self.n == self.fail_at:
            raise ValueError(f"step {self.n} refused")
        return np.array([float(self.n), float(action[0]), float(action[1])]), 1.0, False, self.n >= 50, {}


class _Failing:
    """Picklable: makes a _Counter failing at ``fail_at``."""

    def __init__(self, fail_at=None):
        self.fail_at = fail_at

    def __call__(self):
        return _Counter(self.fail_at)


@pytest.mark.parametrize("host", [None, False], ids=["hosted", "all-workers"])
def test_a_workers_error_mid_step_is_raised_in_the_parent_with_its_note(host):
    """The error of the second env, raised in its worker during a step (through the shared
    counters when hosted, the pipe otherwise), reaches the parent with its message and the
    worker's traceback; the vector env is closed; a healthy run of the same envs before it
    gives each env's own results."""
    envs = EgoVectorEnv([_Failing(), _Failing(fail_at=5)], context="fork", host=host)
    workers = [psutil.Process(p.pid) for p in envs._processes]
    try:
        obs, infos = envs.reset(seed=10)
        assert obs[:, 1].tolist() == [10.0, 11.0] and list(infos["seed"]) == [10, 11]
        for k in range(1, 5):
            actions = np.array([[0.5, -0.5], [0.25, k / 10]], np.float32)
            obs, rewards, terminated, truncated, _ = envs.step(actions)
            assert obs[:, 0].tolist() == [k, k] and obs[1, 2] == np.float32(k / 10)
        with pytest.raises(ValueError, match="step 5 refused") as caught:
            envs.step(np.zeros((2, 2), np.float32))
        assert any("raised in worker 1 of EgoVectorEnv" in note for note in caught.value.__notes__)
        with pytest.raises(RuntimeError, match="workers are gone"):
            envs.step(np.zeros((2, 2), np.float32))
    finally:
        envs.close()
    assert not any(w.is_running() and w.status() != psutil.STATUS_ZOMBIE for w in workers)


def test_the_hosted_envs_error_mid_step_closes_the_vector_env():
    envs = EgoVectorEnv([_Failing(fail_at=3), _Failing()], context="fork")
    workers = [psutil.Process(p.pid) for p in envs._processes]
    try:
        envs.reset(seed=0)
        envs.step(np.zeros((2, 2), np.float32))
        envs.step(np.zeros((2, 2), np.float32))
        with pytest.raises(ValueError, match="step 3 refused"):
            envs.step(np.zeros((2, 2), np.float32))
        with pytest.raises(RuntimeError, match="workers are gone"):
            envs.reset()
    finally:
        envs.close()
    assert not any(w.is_running() and w.status() != psutil.STATUS_ZOMBIE for w in workers)


def test_a_worker_asleep_on_its_pipe_is_woken_for_the_next_step():
    """After a pause longer than its watch (SPIN_S) a worker sleeps on its pipe; the next
    step wakes it (a byte), and the results go on as before."""
    import time

    from ego.gym import vector

    envs = EgoVectorEnv([_Failing(), _Failing()], context="fork")
    try:
        assert envs.spinning or len(os.sched_getaffinity(0)) < 2
        envs.reset(seed=0)
        envs.step(np.zeros((2, 2), np.float32))
        asleep = vector._SLOTS * 1 + vector._ASLEEP
        deadline = time.monotonic() + 10
        while not envs._ctrl[asleep] and time.monotonic() < deadline:
            time.sleep(vector.SPIN_S)
        assert envs._ctrl[asleep] == 1  # the worker sleeps on its pipe now
        obs, *_ = envs.step(np.ones((2, 2), np.float32))
        assert obs.tolist() == [[2.0, 1.0, 1.0], [2.0, 1.0, 1.0]]
    finally:
        envs.close()


def test_a_script_without_a_main_guard_is_told_what_the_forkserver_needs(tmp_path):
    """With a SUMO running here the workers start by forkserver, which imports the main script
    again: a script without `if __name__ == "__main__":` gets the rule in the error."""
    script = tmp_path / "no_guard.py"
    script.write_text(
        textwrap.dedent(
            """
            import warnings
            import numpy as np, gymnasium as gym
            import ego.gym
            warnings.simplefilter("ignore")
            env = gym.make("ego/CutIn-v0")
            env.reset(seed=0)
            envs = gym.make_vec("ego/CutIn-v0", 2)
            envs.reset(seed=0)
            envs.step(np.zeros((2, 2), np.float32))
            """
        )
    )
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert out.returncode != 0
    assert "its workers start by forkserver" in out.stderr and "if __name__ == '__main__':" in out.stderr


def test_a_reset_that_would_change_the_spaces_is_refused_and_the_vector_env_goes_on():
    envs = gym.make_vec("ego/CutIn-v0", num_envs=2, config=SHORT)
    try:
        envs.reset(seed=0)
        with pytest.raises(ConfigError, match=r"changes the observation space .* make a new vector env"):
            envs.reset(seed=0, options={"config": {"observation": {"type": "Kinematics"}}})
        with pytest.raises(ConfigError, match=r"changes the action space"):
            envs.reset(seed=0, options={"config": {"action": {"type": "ContinuousAction", "lateral": False}}})
        with pytest.raises(ConfigError, match="bad value for policy_frequency: 3"):
            envs.reset(seed=0, options={"config": {"policy_frequency": 3}})
        obs, _ = envs.reset(seed=0, options={"config": {"ego_speed": 25.0}})  # the spaces kept
        obs, *_ = envs.step(np.zeros((2, 2), np.float32))
        assert obs.shape == (2, 16) and envs.get_attr("config")[1]["ego_speed"] == 25.0
    finally:
        envs.close()
