"""The platoon's followers as agents: a PettingZoo ``ParallelEnv`` over ``ego/Platoon-v0``.

    from ego.gym.multi_agent import PlatoonParallelEnv

    env = PlatoonParallelEnv(config={"controlled_vehicles": 3})
    observations, infos = env.reset(seed=0)
    actions = {agent: env.action_space(agent).sample() for agent in env.agents}
    observations, rewards, terminations, truncations, infos = env.step(actions)

The same as one Gymnasium env, highway-env's ``MultiAgentAction`` / ``MultiAgentObservation``
way (tuples, one entry per agent): ``gym.make("ego/PlatoonMultiAgent-v0", config=...)``
(:class:`PlatoonMultiAgentEnv`).

highway-env's convention: ``controlled_vehicles`` (default: every follower) of the
platoon's followers, ``f1`` (right behind the SUMO leader) first, are agents; the followers
behind them keep the env's ``controller``. Every other key is the single-agent env's
(``ego.gym.EgoEnv("platoon", config)``: scenario parameters, ``randomize``, ``policy_frequency``,
the reward weights, the observation type and its options, the action type), applied to
each agent: its own observation of the configured type seen from its own car (``EgoState``:
its car-following fields), its own action (its acceleration command), and its own reward
(progress = its speed, centring = its spacing error, discomfort = its acceleration; the
crash term for every agent when the run crashes). All agents end together: the run's end (a
collision, a divergence) terminates every agent, the duration truncates them;
``infos[agent]["metrics"]`` then holds the run's metrics (per follower under ``followers``).
A reset that reconfigures the env (``options={"config": ...}``, ``controlled_vehicles``
included) rebuilds the agents, their spaces and the frame rate.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from ego.gym.env import _EVICTED, EgoEnv, EgoView
from ego.gym.spaces import observation_type
from ego.params import ConfigError
from ego.scenarios.platoon import follower_ids


def _check_randomize(config: Mapping[str, Any]) -> None:
    randomize = config.get("randomize")
    if isinstance(randomize, Mapping) and "followers" in randomize:
        raise ConfigError("bad value for randomize: followers cannot vary (the agents are fixed)")


class PlatoonParallelEnv(ParallelEnv):
    """The platoon's first ``controlled_vehicles`` followers as agents (module docstring)."""

    metadata: ClassVar[dict] = {
        "name": "ego_platoon_v0",
        "render_modes": ["rgb_array"],
        "render_fps": 100,
        "is_parallelizable": True,
    }

    def __init__(self, config: Mapping[str, Any] | None = None, render_mode: str | None = None) -> None:
        config = dict(config or {})
        self._controlled = config.pop("controlled_vehicles", None)
        _check_randomize(config)
        self._env = EgoEnv("platoon", config, render_mode)
        self.render_mode = render_mode
        self.agents: list[str] = []
        self._derive()

    def _derive(self) -> None:
        """The agents, their observation types and spaces from the env as built (again after a
        reset that reconfigured it: other followers, another action or observation type)."""
        env = self._env
        n = env.scenario.config.followers
        k = n if self._controlled is None else self._controlled
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or not 1 <= k <= n:
            raise ConfigError(
                f"bad value for controlled_vehicles: {k!r} (expected a whole number from 1 to followers = {n})"
            )
        self.possible_agents = list(follower_ids(n)[: int(k)])
        # each agent its own instance of the configured observation type (its own car's view)
        self._observers = [observation_type(env.config["observation"], env.task) for _ in self.possible_agents]
        for observer in self._observers:
            if hasattr(observer, "set_reach"):
                observer.set_reach(*env._reach)
        self._observation_space = self._observers[0].space
        self._action_space = env.action_space
        self.metadata = {**type(self).metadata, "render_fps": env.metadata["render_fps"]}
        self._built = env._built_config

    def observation_space(self, agent: str):
        return self._observation_space

    def action_space(self, agent: str):
        return self._action_space

    @property
    def config(self) -> dict:
        return self._env.config

    def reset(self, seed: int | None = None, options: Mapping[str, Any] | None = None):
        env = self._env
        controlled = self._controlled
        if options and "config" in options:
            config = options["config"]
            if isinstance(config, Mapping) and ("controlled_vehicles" in config or "randomize" in config):
                config = dict(config)
                _check_randomize(config)
                controlled = config.pop("controlled_vehicles", controlled)
                options = {**options, "config": config}
        _, info = env.reset(seed=seed, options=options)
        if env._built_config is not self._built or controlled != self._controlled:
            before, self._controlled = self._controlled, controlled
            try:
                self._derive()
            except ConfigError:
                self._controlled = before
                raise
        # one view per agent: the scenario's per-vehicle contract (observation, plant, signals)
        sc = env.scenario
        self._views = [EgoView(sc, env.np_random, vid) for vid in self.possible_agents]
        for observer, view in zip(self._observers, self._views):
            view.reset()
            observer.reset(view)
        self.agents = list(self.possible_agents)
        return self._observations(), {a: dict(info) for a in self.agents}

    def _observations(self) -> dict:
        return {a: o.observe(v) for a, o, v in zip(self.agents, self._observers, self._views)}

    def step(self, actions: Mapping[str, Any]):
        env = self._env
        sc = env.scenario
        if sc is None or sc.bridge is None or not self.agents:
            raise RuntimeError(_EVICTED if env._evicted and self.agents else "call reset() before step()")
        native = env.action_type.native
        missing = [a for a in self.agents if a not in actions]
        if missing:
            raise ValueError(
                f"bad actions: no action for agent(s) {', '.join(missing)} (expected one per "
                f"agent of {', '.join(self.agents)})"
            )
        commands = [native(actions[a])[0] for a in self.agents]
        total = sum(commands)
        if total - total != 0.0:  # nan or inf: the run ends before the models see it
            sc._end("diverged", f"an agent's action is not finite: {commands}", level="ERROR")
        else:
            step, controller_step, joint = sc.step, sc.controller.step, sc.joint_action
            agents = list(zip(self.agents, commands))
            for _ in range(env._every):
                own = controller_step(sc.obs)
                for agent, c in agents:
                    own = joint(own, agent, c, None)
                step(own)
                if sc.status != "running":
                    break
        status = sc.status
        crashed = status in ("collision", "diverged")
        rewards, infos = {}, {}
        for agent, view in zip(self.agents, self._views):
            rewards[agent], terms = env.reward(view, crashed)
            infos[agent] = {"status": status, "rewards": terms}
        observations = self._observations()
        done = status != "running"
        truncated = done and not crashed and sc.t >= sc.config.duration - 1e-9
        if done:
            metrics = sc.result().metrics
            for info in infos.values():
                info["status_detail"] = sc.status_detail
                info["metrics"] = metrics
        terminations = {a: done and not truncated for a in self.agents}
        truncations = {a: truncated for a in self.agents}
        if done:
            self.agents = []
        return observations, rewards, terminations, truncations, infos

    def render(self):
        return self._env.render()

    def close(self) -> None:
        self._env.close()

    def state(self) -> np.ndarray:
        """Every follower's observation, stacked (agents first)."""
        return np.concatenate([o.observe(v) for o, v in zip(self._observers, self._views)])


class PlatoonMultiAgentEnv(gym.Env):
    """highway-env's multi-agent convention as one Gymnasium env (``ego/PlatoonMultiAgent-v0``):
    ``controlled_vehicles`` followers, the action a ``Tuple`` of one action per agent
    (highway-env's ``MultiAgentAction``), the observation a ``Tuple`` of one ``EgoState`` per
    agent (``MultiAgentObservation``), the reward the agents' mean, ``info["agents_rewards"]``
    each agent's and ``info["agents_terminated"]`` each agent's end. Configured as
    :class:`PlatoonParallelEnv` is (the same keys); ``action`` and ``observation`` may be given
    highway-env's way (``{"type": "MultiAgentAction", "action_config": {...}}``,
    ``{"type": "MultiAgentObservation", "observation_config": {...}}``)."""

    metadata: ClassVar[dict] = {"render_modes": ["rgb_array"], "render_fps": 100}

    def __init__(self, config: Mapping[str, Any] | None = None, render_mode: str | None = None) -> None:
        self.parallel = PlatoonParallelEnv(_single_agent_types(config or {}), render_mode)
        self.render_mode = render_mode
        self._spaces()

    def _spaces(self) -> None:
        """The agents' tuples of spaces, from the parallel env as built."""
        agents = self.parallel.possible_agents
        self.controlled_vehicles = tuple(agents)
        self.action_space = spaces.Tuple([self.parallel.action_space(a) for a in agents])
        self.observation_space = spaces.Tuple([self.parallel.observation_space(a) for a in agents])
        self.metadata = {**type(self).metadata, "render_fps": self.parallel.metadata["render_fps"]}

    def reset(self, *, seed: int | None = None, options: Mapping[str, Any] | None = None):
        super().reset(seed=seed)
        if seed is None:
            seed = int(self.np_random.integers(0, 2**31 - 1))
        if options and isinstance(options.get("config"), Mapping):
            options = {**options, "config": _single_agent_types(options["config"])}
        observations, infos = self.parallel.reset(seed=seed, options=options)
        self._spaces()
        return tuple(observations[a] for a in self.controlled_vehicles), infos[self.controlled_vehicles[0]]

    def step(self, action):
        agents = self.controlled_vehicles
        if not isinstance(action, (tuple, list)) or len(action) != len(agents):
            raise ValueError(
                f"bad action {action!r:.60}: expected a tuple of {len(agents)} actions, one per "
                f"controlled vehicle ({', '.join(agents)})"
            )
        observations, rewards, terminations, truncations, infos = self.parallel.step(dict(zip(agents, action)))
        info = dict(infos[agents[0]])
        info["agents_rewards"] = tuple(rewards[a] for a in agents)
        info["agents_terminated"] = tuple(terminations[a] for a in agents)
        return (
            tuple(observations[a] for a in agents),
            float(np.mean(info["agents_rewards"])),
            terminations[agents[0]],
            truncations[agents[0]],
            info,
        )

    def render(self):
        return self.parallel.render()

    def close(self) -> None:
        self.parallel.close()


def _single_agent_types(config: Mapping[str, Any]) -> dict:
    """``config`` with highway-env's multi-agent action and observation types given as the
    one agent's (``MultiAgentAction``'s ``action_config``, ``MultiAgentObservation``'s
    ``observation_config``)."""
    config = dict(config)
    action, observation = config.get("action"), config.get("observation")
    if isinstance(action, Mapping) and action.get("type") == "MultiAgentAction":
        config["action"] = action.get("action_config", {"type": "ContinuousAction", "lateral": False})
    if isinstance(observation, Mapping) and observation.get("type") == "MultiAgentObservation":
        config["observation"] = observation.get("observation_config", {"type": "EgoState"})
    return config
