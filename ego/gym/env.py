"""One Gymnasium environment over every SUMO scenario, configured as highway-env's are.

``EgoEnv(scenario, config)`` wraps :class:`ego.scenarios.Scenario` (``reset`` / ``step``): one env
step is one control period ``dt`` of the scenario (or ``1 / policy_frequency`` s, the action
held), SUMO and the ego's own model stepping inside it exactly as in ``ego run``. The
configuration is one dict: the env's own keys (:data:`ENV_KEYS`: observation and action types,
the controller of the channels the agent does not drive, the reward, rendering) and the
scenario's and that controller's parameters, validated as ``ego run --set`` values are.

Episodes: ``terminated`` when the run ends before its duration (a collision or a divergence
of the ego, or the task's own end: the curve left, the road's end reached); ``truncated``
when the simulated time reaches ``duration``. ``info`` has ``status`` (``running``,
``completed``, ``ended``, ``collision``, ``diverged``, ``timeout``, ``error``) and ``rewards`` (the
reward's terms) every step, and at the end ``status_detail`` and ``metrics``: what ``ego run``
reports (also where the registered ``TimeLimit`` truncates). A non-finite action ends the run
``diverged`` before anything sees it.

Each reset draws the episode's ``randomize`` parameters from its seed (:data:`DEFAULT_RANDOMIZE`),
so an env is a distribution of scenarios. An env pickles (mid-episode: the episode's commands
are replayed in a new SUMO). Several envs run in one process (``multi_instance``, true by
default): the one that starts while another's SUMO holds the process's libsumo runs its SUMO
through TraCI, with the same results; ``multi_instance=False`` is one env per process (its
reset ends the run of any other).

The platoon: the agent drives the first follower (``f1``, right behind the SUMO leader); the
followers behind it keep the scenario's controller, so the agent's driving propagates down
a platoon whose string stability the metrics measure.
"""

from __future__ import annotations

import copy
import functools
import math
import sys
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, fields
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np

from ego.checks import MAX_SEED, check_seed
from ego.control import CONTROLLERS
from ego.control.tasks import TASKS
from ego.gym.spaces import _COMMAND, _OBSERVE, action_type, observation_type
from ego.native import NATIVE
from ego.params import ConfigError, apply_overrides, describe, param, unknown_parameter
from ego.runner import RunSpec, parameter_namespace, resolve
from ego.scenarios import scenario_class
from ego.scenarios.sensor import SurroundSensor
from ego.sim import sharing_instances

#: each env's default episode distribution: scenario parameter -> [low, high], sampled at
#: every reset from the episode's seed (``config["randomize"]``; ``{}``: one fixed scenario)
DEFAULT_RANDOMIZE: dict[str, dict[str, list[float]]] = {
    "emergency-brake": {
        "ego_speed": [17.0, 23.0],
        "lead_gap": [20.0, 45.0],
        "lead_decel": [3.0, 9.0],
        "lead_brake_time": [1.0, 3.0],
        "traffic_density": [5.0, 15.0],
    },
    "fast-follower": {"follower_gap": [40.0, 80.0], "follower_speed": [30.0, 36.0], "traffic_density": [5.0, 15.0]},
    "cut-in": {
        "ego_speed": [20.0, 30.0],
        "cut_in_gap": [10.0, 25.0],
        "cut_in_speed": [2.0, 8.0],
        "cut_in_duration": [1.5, 3.0],
    },
    "curve": {"entry_speed": [25.0, 35.0], "accel": [0.1, 0.5], "approach": [15.0, 25.0]},
    "lane-centering": {"offset": [-0.5, 0.5], "speed": [6.0, 10.0], "traffic_density": [4.0, 12.0]},
    "platoon": {"headway": [1.5, 2.5], "start_speed": [30.0, 50.0], "start_error": [0.0, 3.0]},
}


@dataclass(frozen=True)
class EnvConfig:
    """The env's scalar keys (besides ``observation``, ``action``, ``controller`` and
    ``reward_speed_range``). Reward per env step (see :class:`Reward`):
    ``collision_reward * crashed + progress_reward * progress + lane_centering_reward *
    centring + comfort_reward * discomfort``, and on a step that completes the task before
    ``duration`` the completion term on top (``completion_reward``)."""

    policy_frequency: float = param(
        0.0,
        "Hz",
        "env steps per simulated second, the action held in between; 0: one env step per control period dt",
        min=0.0,
        max=1000.0,
    )
    collision_reward: float = param(
        -1.0, "-", "weight of the crash term (1 on the step the ego collides or diverges)", min=-1e6, max=1e6
    )
    progress_reward: float = param(
        0.4,
        "-",
        "weight of the progress term: the ego's speed along its lane mapped from reward_speed_range to [0, 1]",
        min=-1e6,
        max=1e6,
    )
    lane_centering_reward: float = param(
        0.2,
        "-",
        "weight of the centring term 1 / (1 + "
        "lane_centering_cost e^2), e the lateral error (m) from the "
        "reference; for the platoon the spacing error",
        min=-1e6,
        max=1e6,
    )
    lane_centering_cost: float = param(
        4.0, "1/m^2", "how fast the centring term falls with the error", min=0.0, max=1e6
    )
    comfort_reward: float = param(
        -0.1, "-", "weight of the discomfort term min(1, (a_lon^2 + a_lat^2) / comfort_accel^2)", min=-1e6, max=1e6
    )
    comfort_accel: float = param(
        5.0, "m/s^2", "acceleration at which the discomfort term saturates", min=0.01, max=100.0
    )
    completion_reward: float = param(
        1.0,
        "-",
        "weight of the completion term, on the step that completes the task before duration (the "
        "curve's arc driven, the lane-centring road's end reached): the env steps left to duration "
        "times that step's reward (at least 0), so that finishing sooner never earns less than "
        "lingering; 0: none",
        min=0.0,
        max=1e6,
    )
    screen_width: int = param(600, "px", "width of the rgb_array frame", min=16, max=4096)
    screen_height: int = param(150, "px", "height of the rgb_array frame", min=16, max=4096)
    scaling: float = param(5.5, "px/m", "zoom of the rgb_array frame", min=0.1, max=100.0)


_ENV_SCALARS = tuple(f.name for f in fields(EnvConfig))
#: the env's own configuration keys; every other key is a scenario or controller parameter
ENV_KEYS = ("observation", "action", "controller", "reward_speed_range", "randomize", "multi_instance", *_ENV_SCALARS)


def _signals_reader(sc, vid: str) -> Callable[[], tuple]:
    """``sc.agent_signals_reader(vid)`` where the class that defines ``agent_signals`` also
    defines the reader (a subclass that overrides only ``agent_signals`` keeps its own)."""
    mro = type(sc).__mro__
    signals = next(k for k in mro if "agent_signals" in vars(k))
    reader = next((k for k in mro if "agent_signals_reader" in vars(k)), None)
    if reader is signals:
        return sc.agent_signals_reader(vid)
    return functools.partial(sc.agent_signals, vid)


class EgoView:
    """What the env reads of a scenario's ego, the same for every task: the controller's
    observation, the speed along the lane, the tracking error, the accelerations and the
    traffic around it in its lane's frame. ``np_random`` is the env's generator."""

    def __init__(self, scenario, np_random, vid: str | None = None) -> None:
        self.scenario = scenario
        self.np_random = np_random
        self._vid = vid
        self._sensor: SurroundSensor | None = None
        self._looked = -1
        self._prev = [0.0, 0.0]  # (t, speed along the lane) at the last reward: _rate

    @property
    def agent(self) -> str:
        """The vehicle the agent drives (the ego; the platoon's first follower; ``vid`` when
        given: one agent of several)."""
        return self.scenario.agent_id if self._vid is None else self._vid

    @property
    def road(self):
        """The scenario's road state (s, d_road, lanes, target lane): a composed scenario's
        view, else the scenario itself."""
        sc = self.scenario
        return getattr(sc, "view", None) or sc

    def lane_centres(self) -> list[float]:
        """The road's lane centres (m, + left) in the frame of the agent's start lane: the
        surround view's lanes, else the scenario's lanes met along the agent's lane (a curve's
        oncoming lane), else its own lane alone."""
        road = self.road
        offsets = getattr(road, "lane_offset", None)
        if offsets:
            return sorted(offsets.values())
        frame = getattr(road, "road", None)
        lanes = getattr(self.scenario, "lanes", None)
        out = {0.0}
        if frame is not None and isinstance(lanes, Mapping):
            for lane in lanes.values():
                points = getattr(lane, "points", None)
                if not points:
                    continue
                s, d, _ = frame.project(*points[len(points) // 2])
                if 0.0 < s < frame.length and abs(d) < 20.0:
                    out.add(round(d, 2))
        return sorted(out)

    @property
    def steers(self) -> bool:
        """The agent's vehicle steers (False: it keeps its one lane, the platoon's followers)."""
        return TASKS[self.scenario.task].returns[1].high > 0.0

    @property
    def obs(self):
        """The observation the agent's vehicle's controller gets."""
        return self.scenario.observation(self.agent)

    def plant(self):
        return self.scenario.plant(self.agent)

    def reward_signals(self) -> tuple[float, float, float, float]:
        """(speed along the lane m/s, tracking error m, longitudinal and lateral acceleration
        m/s^2) now; without a measured longitudinal acceleration, the rate of the speed along
        the lane since the last call."""
        speed, error, a_lon, a_lat = self._signals()
        if a_lon is None:
            a_lon = self._rate(speed)
        return speed, error, a_lon, a_lat

    def _rate(self, speed: float) -> float:
        """The rate of the speed along the lane since the last call (m/s^2)."""
        t = self._obs.t  # the time the observation was taken
        prev = self._prev  # [t0, ds0], updated in place (the bound reward holds it)
        t0, ds0 = prev
        prev[0], prev[1] = t, speed
        return (speed - ds0) / (t - t0) if t > t0 else 0.0

    def bind_reward(self, reward: Reward) -> Callable[[bool], tuple[float, dict]]:
        """``reward(self, crashed)`` as a function of ``crashed`` until the run ends (bound
        after :meth:`reset`): the env step's hot path, one call into C where the reference
        makes four (``ego._native.reward_of``: the scenario's signals reader, :meth:`_rate`'s
        arithmetic where it measures no longitudinal acceleration, :class:`Reward`'s)."""
        if _REWARD_OF is None:
            return functools.partial(reward, self)
        return functools.partial(_REWARD_OF, self._signals, self._obs, self._prev, reward._params)

    def reset(self) -> None:
        sc = self.scenario
        # the agent's vehicle and its observation hold still over a run (the scenario fills
        # one observation in place): looked up once here, not at every step
        agent = self.agent
        self._obs = sc.observation(agent)
        self._signals = _signals_reader(sc, agent)
        self._prev = [sc.t, self._signals()[0]]
        self._looked = -1
        self._sensor = None

    # -- traffic for the Kinematics observation ---------------------------------------------
    def traffic(self) -> tuple[tuple, list[tuple], float]:
        """(ego row, rows of the others, ego length m); a row is (s, d, v_s, v_d, heading) of
        a box centre in the ego's lane frame (m, m/s, rad; + left)."""
        sc = self.scenario
        ego, rows, length = sc.lane_rows(self.agent)
        if rows is None:  # no surround sensor of its own
            rows = self._own_sensor().tracks(sc.t)
        return ego, rows, length

    def _own_sensor(self) -> SurroundSensor:
        """A surround sensor of the env's own for a scenario without one (the curve, lane
        centring): it looks at every SUMO step, as a scenario's sensor does."""
        sc = self.scenario
        c = sc.config
        if self._sensor is None:
            g = sc.geometry
            self._sensor = SurroundSensor(self.road.road, {}, g.cg_to_front, g.length, g.width, horizon=c.sumo_step)
            sc.bridge.subscribe_surroundings(self.agent, OWN_SENSOR_REACH)
        per = c.control_per_sumo
        look = sc.k // per
        if look != self._looked:
            self._looked = look
            self._sensor.sync(look * per * c.dt, *sc.bridge.surroundings(self.agent))
        return self._sensor


#: Reward.__call__'s arithmetic in C, or None (its Python lines)
_REWARD = None if NATIVE is None else NATIVE.reward
_REWARD_OF = None if NATIVE is None else NATIVE.reward_of
_ENV_STEP = None if NATIVE is None else NATIVE.env_step


class Reward:
    """The default reward of an env step and its terms: crashed (1 on the step the ego
    collides or diverges, else 0), progress (the speed along the lane mapped from
    ``speed_range`` (m/s) to [0, 1]), centring (1 / (1 + lane_centering_cost e^2), e the
    tracking error in m) and discomfort (min(1, (a_lon^2 + a_lat^2) / comfort_accel^2)), each
    weighted by its ``*_reward`` of :class:`EnvConfig`."""

    def __init__(self, cfg: EnvConfig, speed_range: tuple[float, float]) -> None:
        self.speed_range = speed_range
        self._weights = (cfg.collision_reward, cfg.progress_reward, cfg.lane_centering_reward, cfg.comfort_reward)
        self._lo, self._per_speed = speed_range[0], 1.0 / (speed_range[1] - speed_range[0])
        self._cost = cfg.lane_centering_cost
        self._per_accel2 = 1.0 / (cfg.comfort_accel * cfg.comfort_accel)
        self._params = (self._lo, self._per_speed, self._cost, self._per_accel2, *self._weights)

    def __call__(self, view: EgoView, crashed: bool) -> tuple[float, dict]:
        speed, error, a_lon, a_lat = view.reward_signals()
        if _REWARD is not None:  # the same arithmetic in C
            return _REWARD(speed, error, a_lon, a_lat, crashed, self._params)
        progress = (speed - self._lo) * self._per_speed
        progress = 0.0 if progress < 0.0 else (1.0 if progress > 1.0 else progress)
        centring = 1.0 / (1.0 + self._cost * error * error)
        discomfort = (a_lon * a_lon + a_lat * a_lat) * self._per_accel2
        if discomfort > 1.0:
            discomfort = 1.0
        crash = 1.0 if crashed else 0.0
        w_crash, w_progress, w_centring, w_comfort = self._weights
        reward = w_crash * crash + w_progress * progress + w_centring * centring + w_comfort * discomfort
        if reward - reward != 0.0:  # a diverged ego's signals (nan, inf): those terms count 0
            progress, centring, discomfort = (x if math.isfinite(x) else 0.0 for x in (progress, centring, discomfort))
            reward = w_crash * crash + w_progress * progress + w_centring * centring + w_comfort * discomfort
        return reward, {"crashed": crash, "progress": progress, "centring": centring, "discomfort": discomfort}


class AgentSlot:
    """The scenario's controller when the agent drives every channel: it commands nothing (the
    env hands the agent's action to the scenario) and counts the resets the scenario makes
    (each run's start, and a hand-over such as the curve's engagement), so that a
    :class:`ego.gym.ControllerPolicy` resets its controller at the same steps."""

    def __init__(self) -> None:
        self.resets = 0
        self.seed: int | None = None

    def reset(self, *, seed: int | None = None) -> None:
        self.resets += 1
        self.seed = seed

    def step(self, obs) -> tuple[float, float]:
        return 0.0, 0.0

    def signals(self) -> dict:
        return {}


#: the env whose SUMO runs through libsumo in this process (libsumo runs one simulation per
#: process; a ``multi_instance`` env started while it runs talks TraCI instead)
_running: list = [None]

#: why a step is refused after another env's reset ended this env's run
_EVICTED = (
    "this env's SUMO run was ended by the reset of another ego env in this process made with "
    "multi_instance=False: libsumo runs one simulation per process. Leave multi_instance at its "
    "default (true) for several envs in one process (the second and later run SUMO through "
    "TraCI, slower), or use gym.make_vec(id, n) or SB3's SubprocVecEnv (one process per env)"
)

#: why an env runs its SUMO through TraCI beside a multi_instance env in this process
_BESIDE_MULTI = (
    "an ego env made with multi_instance=True runs its SUMO through libsumo in this process (one "
    "simulation per process): this env runs its SUMO through TraCI (slower) rather than end that "
    "env's run"
)

#: why an env runs its SUMO through TraCI beside a vector env's env in this process
_SHARED = (
    "an ego vector env (gym.make_vec) steps its first env in this process through libsumo, which "
    "runs one simulation per process: this env runs its SUMO through TraCI (slower). "
    "gym.make_vec(id, n, host=False) keeps every env of the vector env in a worker process"
)


#: the scenarios whose task has an end of its own (the curve's arc, the lane-centring road):
#: there only these statuses are a success - ``completed``, and on the lane-centring drive,
#: whose speed is the scenario's (so the drive's length in time is the config's choice),
#: ``ended``: its duration reached before the road's end (the benchmark's 30 s drive)
_ENDING_TASKS = {"curve": ("completed",), "lane-centering": ("completed", "ended")}


#: the keys of an episode's outcome (:func:`outcome`), in the order it gives them
OUTCOME_KEYS = (
    "is_success",
    "collision",
    "collision_avoidable",
    "lane_departure",
    "off_road",
    "completion",
    "termination_reason",
)


def outcome(sc, reason: str, metrics: Mapping[str, Any]) -> dict[str, Any]:
    """The episode's outcome as RL benchmarks report it, for the ``info`` of its last step:
    ``is_success`` (SB3's key: no collision, divergence, error or lane departure, and, where
    the task has an end of its own, that end reached, :data:`_ENDING_TASKS`), ``collision``, ``collision_avoidable``
    (the scenario's metric, None where it has none), ``lane_departure`` (the run's
    ``max_lane_departure`` metric above 0 m: the ego's side beyond its lane's marking outside a
    commanded lane change; None where the scenario does not measure it), ``off_road``
    (diverged by leaving the road), ``completion`` (the share of the run's duration elapsed
    when it ended, 1 when the task was completed) and ``termination_reason`` (the status, or
    ``max_episode_steps`` where the registered TimeLimit cut it)."""
    collision = reason == "collision"
    failed = collision or reason in ("diverged", "error")
    ends = _ENDING_TASKS.get(sc.name)
    duration = sc.config.duration
    departure = metrics.get("max_lane_departure")
    departed = None if departure is None else bool(departure > 0.0)
    return {
        "is_success": not failed and not departed and (ends is None or reason in ends),
        "collision": collision,
        "collision_avoidable": metrics.get("collision_avoidable") if collision else None,
        "lane_departure": departed,
        "off_road": reason == "diverged" and "left the road" in str(sc.status_detail or ""),
        "completion": 1.0 if reason == "completed" else min(1.0, max(0.0, sc.t / duration)),
        "termination_reason": reason,
    }


def _control_periods_per_action(policy_frequency: float, dt: float) -> int:
    """Control periods an action is held (``policy_frequency`` in Hz; 0: every period);
    ConfigError unless 1 / dt is a whole multiple of it."""
    if policy_frequency <= 0.0:
        return 1
    ratio = 1.0 / (policy_frequency * dt)
    if abs(ratio - round(ratio)) > 1e-6 or round(ratio) < 1:
        raise ConfigError(
            f"bad value for policy_frequency: {policy_frequency:g} (expected "
            f"1 / dt = {1.0 / dt:g} Hz divided by a whole number)"
        )
    return round(ratio)


class EgoEnv(gym.Env):
    """An ego scenario as a Gymnasium env (see the module docstring). ``scenario`` is a name
    of ``ego list``; ``config`` updates :meth:`default_config`.

    libsumo runs one simulation per process: an env that starts while another env of the
    process runs through libsumo runs its SUMO through TraCI (a ``sumo`` subprocess behind a
    socket; the same episode for the same seed and actions). ``config["multi_instance"] =
    False`` keeps one env per process instead: its ``reset`` ends the run of any other ego env
    of the process (whose next ``step`` then raises, saying so). Envs in parallel live in
    their own processes: ``gym.make_vec(id, n)`` does that by default.
    """

    metadata: ClassVar[dict] = {"render_modes": ["rgb_array"], "render_fps": 100}
    #: the configuration keys that are the env's own (every other is a scenario or controller
    #: parameter)
    own_keys: ClassVar[tuple[str, ...]] = ENV_KEYS

    def __init__(
        self,
        scenario: str = "emergency-brake",
        config: Mapping[str, Any] | None = None,
        render_mode: str | None = None,
        defaults: Mapping[str, Any] | None = None,
    ) -> None:
        """``defaults``: keys set before ``config`` (the registered ids' benchmark setting,
        :data:`ego.gym.BENCHMARK`); ``config`` overrides them key by key."""
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ConfigError(f"bad value for render_mode: {render_mode!r} (expected rgb_array or None)")
        self.scenario_name = scenario
        self.scenario_cls = scenario_class(scenario)
        self.task = self.scenario_cls.task
        self.render_mode = render_mode
        # env.default_config() lists this env's scenario (the class method takes a name)
        self.default_config = functools.partial(type(self).default_config, scenario)
        self.config = self.default_config()
        if defaults:
            self.configure(defaults)
        self.configure(config or {})
        self.scenario = None
        self._renderer = None
        self._history: list = []
        self._substep = None
        self._evicted = False
        #: the first env of an EgoVectorEnv, stepped in the vector env's own process
        self._hosted = False
        #: env steps since the reset (``ego._native.env_step`` counts them too)
        self.elapsed = 0
        self._limit = None
        self._limit_steps = math.inf
        self._fast_step: functools.partial | None = None
        self.randomized: dict[str, float] = {}
        self._build()

    @classmethod
    def default_config(cls, scenario: str = "emergency-brake") -> dict:
        """Every key with its default: the env's (:data:`ENV_KEYS`) and the scenario's
        parameters (``ego list``); the controller's parameters may be added."""
        sc = scenario_class(scenario)
        config: dict[str, Any] = {
            "observation": {"type": "EgoState"},
            "action": {
                "type": "ContinuousAction",
                "longitudinal": True,
                "lateral": TASKS[sc.task].returns[1].high > 0.0,
            },  # a task that steers
            "controller": sc.reference_controller(),
            "reward_speed_range": [0.0, 30.0],
            "randomize": {k: list(v) for k, v in DEFAULT_RANDOMIZE.get(scenario, {}).items()},
            "multi_instance": True,
        }
        env = EnvConfig()
        config.update({name: getattr(env, name) for name in _ENV_SCALARS})
        base = sc.config_cls()
        config.update({i.name: getattr(base, i.name) for i in describe(sc.config_cls)})
        return config

    def configure(self, config: Mapping[str, Any]) -> None:
        """Update the configuration (highway-env's: a plain update); it takes effect at
        construction or at the next ``reset`` (as an edit of ``env.config`` does), which
        rebuilds the spaces and types; a configuration the reset rejects is taken back."""
        if not isinstance(config, Mapping):
            raise ConfigError(f"bad value for config: {config!r} (expected a dict)")
        self.config.update(config)

    def _config_changed(self) -> bool:
        """The configuration differs from the one the env was built on."""
        try:
            return bool(self.config != self._built_config)
        except (ValueError, TypeError):  # an array among the values: compare by rebuilding
            return True

    def _rebuild(self) -> None:
        """Build on the (changed) configuration, or take it back to the built one and raise."""
        try:
            self._build()
        except Exception:
            self.config = copy.deepcopy(self._built_config)
            raise

    # -- building ----------------------------------------------------------------------------
    def _build(self) -> None:
        """Validate the configuration and build the scenario, the spaces and the types; no
        SUMO starts (``reset`` starts it)."""
        cfg = self.config
        cls = self.scenario_cls
        controller = cfg.get("controller")
        if controller not in CONTROLLERS[self.task] or controller == "none":
            names = [n for n in CONTROLLERS[self.task] if n != "none"]
            raise ConfigError(
                f"bad value for controller: {controller!r} (the {self.task} task's controllers: {', '.join(names)})"
            )
        params = {k: v for k, v in cfg.items() if k not in self.own_keys}
        known = set(self.own_keys) | set(parameter_namespace(cls, [controller]))
        for key in cfg:
            if key not in known:
                raise unknown_parameter(key, known)
        env, _ = apply_overrides(EnvConfig(), {k: cfg[k] for k in _ENV_SCALARS})
        lo, hi = cfg["reward_speed_range"] if _pair(cfg["reward_speed_range"]) else (None, None)
        if lo is None or not lo < hi:
            raise ConfigError(
                f"bad value for reward_speed_range: {cfg['reward_speed_range']!r} "
                "(expected [low, high] in m/s with low < high)"
            )
        multi = cfg["multi_instance"]
        if not isinstance(multi, (bool, np.bool_)):
            raise ConfigError(f"bad value for multi_instance: {multi!r} (expected true or false)")
        # the scenario's defaults are not overrides: a preset (the platoon's variant) would lose
        base = cls.config_cls()
        overrides = {k: v for k, v in params.items() if not (hasattr(base, k) and getattr(base, k) == v)}
        randomize = _check_randomize(cfg["randomize"], cls.config_cls, base)
        if cfg["randomize"] == DEFAULT_RANDOMIZE.get(self.scenario_name):
            if "variant" in overrides:
                randomize = {}  # the defaults are the road's: a preset (scale-model) runs as it is
            else:  # a parameter set to a value of its own keeps it: the default draws the rest
                randomize = {k: v for k, v in randomize.items() if k not in overrides}
        resolved = resolve(RunSpec(self.scenario_name, controller, 0, overrides))
        sc_config, spec, ctrl_params = resolved.config, resolved.controller, resolved.controller_params
        observation = observation_type(cfg["observation"], self.task)
        self._reach = sensor_reach(cls, sc_config)
        if hasattr(observation, "set_reach"):
            observation.set_reach(*self._reach)
        # the agent's action box as its scenario declares it, and its lanes (no simulator starts)
        probe = cls(sc_config, AgentSlot(), seed=0)
        limits = probe.action_limits()
        action = action_type(cfg["action"], self.task, limits)
        every = _control_periods_per_action(env.policy_frequency, sc_config.dt)
        meta = action.type_name == "DiscreteMetaAction"
        if meta and getattr(probe.view, "lane_offset", None) is None:  # a view of lanes to change
            raise ConfigError(
                f"bad value for action: DiscreteMetaAction needs lanes to change (the motorway "
                f"scenarios: emergency-brake, fast-follower, cut-in), not {self.scenario_name}"
            )
        if meta and action.lateral and getattr(sc_config, "evade", False):
            # the agent's lane actions choose the lane: the scenario's planner changes none itself
            # (one owner of the view's target lane; its trigger then brakes or speeds up in lane)
            overrides = {**overrides, "evade": False}
            sc_config = resolve(RunSpec(self.scenario_name, controller, 0, overrides)).config
        self._check_corners(controller, overrides, randomize)
        # the agent drives both channels: the loop needs no controller of its own
        helper = not (action.longitudinal and action.lateral) or meta
        self.close()
        self._controller_name = f"agent+{controller}" if helper else "agent"
        self._spec, self._ctrl_params, self._overrides = spec, ctrl_params, overrides
        self._randomize = randomize
        self._multi = bool(multi)
        self.env_config = env
        self.reward = Reward(env, (float(lo), float(hi)))
        self.observation_type = observation
        self.action_type = action
        self.observation_space = observation.space
        self.action_space = action.space
        self._every = every
        self._helper = helper
        self._make_scenario(sc_config)
        # one frame per env step: a video plays in simulated time
        self.metadata = {**type(self).metadata, "render_fps": 1.0 / (every * sc_config.dt)}
        self._built_config = copy.deepcopy(cfg)

    def _check_corners(self, controller: str, overrides: dict, randomize: dict) -> None:
        """The corners of the randomised distribution must make valid runs: checked when the
        env is built, not at a reset."""
        for corner in (0, 1):
            if randomize:
                values = {k: v[corner] for k, v in randomize.items()}
                try:
                    resolve(RunSpec(self.scenario_name, controller, 0, {**overrides, **values}))
                except ConfigError as exc:
                    shown = ", ".join(f"{k}={v:g}" for k, v in values.items())
                    raise ConfigError(
                        f"bad value for randomize: its {('low', 'high')[corner]} corner ({shown}) makes no valid run: {exc}"
                    ) from None

    def _make_scenario(self, sc_config) -> None:
        """The scenario object (no SUMO yet) on ``sc_config``, its controller and the view."""
        cls = self.scenario_cls
        own = cls.build_controller(self._spec, self._ctrl_params, sc_config) if self._helper else AgentSlot()
        self.scenario = cls(sc_config, own, seed=0, controller_name=self._controller_name)
        self._view = EgoView(self.scenario, self.np_random)
        if not self._helper:
            self._apply = self._apply_both
        elif self.action_type.type_name == "DiscreteMetaAction":
            self._apply, self._meta_command = self._apply_meta, None
        else:
            self._apply = self._apply_channels
        # one scenario step an env step, the agent driving every channel or some (the
        # scenario's controllers the rest): env.step applies the command itself (what
        # _apply_both and _apply_channels do, without the call)
        self._direct = not self._helper and self._every == 1
        self._channels = self._apply == self._apply_channels and self._every == 1

    def _sample(self, run_seed: int) -> dict[str, float]:
        """The randomised parameters of the episode with ``run_seed`` (its own stream of the
        seed), rounded as ``ego run --set`` would print them, so the episode is re-runnable."""
        rng = np.random.default_rng((run_seed, 0x52414E44))
        out = {}
        for name, (lo, hi) in self._randomize.items():
            if isinstance(lo, int) and isinstance(hi, int):
                out[name] = int(rng.integers(lo, hi + 1))
            else:
                out[name] = round(float(rng.uniform(lo, hi)), 3)
        return out

    # -- the Gymnasium interface -------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: Mapping[str, Any] | None = None):
        """Start a run: SUMO restarted, the traffic drawn from the seed. ``seed``: the run's seed
        (``ego run --seed``); without one a seed is drawn from the env's generator.
        ``options={"config": {...}}`` reconfigures first (spaces rebuilt). The randomised
        parameters (``config["randomize"]``) are drawn from the run's seed: ``info["randomized"]``."""
        super().reset(seed=seed)
        if options and "config" in options:
            self.configure(options["config"])
        if self._config_changed():
            self._rebuild()
        run_seed = run_seed_of(seed) if seed is not None else int(self.np_random.integers(0, MAX_SEED + 1))
        self._start(run_seed)
        self._set_limit(_time_limit_calling(self, sys._getframe(1)))
        self._fast_step = self._bind_step()
        return self.observation_type.observe(self._view), {
            "status": self.scenario.status,
            "randomized": dict(self.randomized),
        }

    def _start(self, run_seed: int) -> None:
        """Start the run with ``run_seed`` (the episode's parameters sampled from it)."""
        other = _running[0]
        share = self._multi
        if other is not None and other is not self and not self._multi:
            if other._hosted or self._hosted:  # a vector env's own env here is never evicted
                share = True
                warnings.warn(_SHARED, stacklevel=3)
            elif other._multi:  # it runs beside others by choice: this one goes through TraCI
                share = True
                warnings.warn(_BESIDE_MULTI, stacklevel=3)
            else:
                other._evicted = True
                other.close()
        if self._randomize:
            self.randomized = self._sample(run_seed)
            self.scenario.close()
            sc_config = resolve(
                RunSpec(self.scenario_name, self._spec.name, 0, {**self._overrides, **self.randomized})
            ).config
            self._make_scenario(sc_config)
        sc = self.scenario
        with sharing_instances(share):
            sc.reset(seed=run_seed)
        if sc.bridge is not None and not getattr(sc.bridge, "via_traci", False):
            _running[0] = self
        self._evicted = False
        self._history = []
        self._substep = None
        self.elapsed = 0
        view = self._view
        view.np_random = self.np_random
        view.reset()
        self._step_reward = view.bind_reward(self.reward)
        self._agent = view.agent
        self.observation_type.reset(view)
        self._observe = self.observation_type.bind(view)
        if self.action_type.type_name == "DiscreteMetaAction":
            self.action_type.reset(view)
            self._meta_command = None
        elif self.action_type.longitudinal:
            plant = view.plant()
            p = plant.model.params
            self.action_type.set_plant(p.m / p.Nw if plant.input_names[0] == "Fx" else 1.0)
        self._native = self.action_type.bind()
        self._crashed = False

    # one scenario step with the agent's command (also the replay of an unpickled env)
    def _apply_both(self, command) -> None:
        self._history.append(command)
        self.scenario.step(command)

    def _apply_channels(self, command) -> None:
        # the scenario's controllers step as in a run; the agent's vehicle takes the agent's
        # channels (the platoon's other followers keep theirs)
        self._history.append(command)
        lon, lat = command
        self.scenario.step_joint(self._agent, lon, lat)

    def _apply_meta(self, command) -> None:
        # a new command tuple is a new env step: the meta action moves the targets once
        self._history.append(command)
        meta = self.action_type
        if command is not self._meta_command:
            self._meta_command = command
            meta.update(command[0])
        sc = self.scenario
        sc.step(sc.controller.step(meta.controller_observation()))

    def step(self, action):
        fast = self._fast_step
        if fast is not None:  # the step below in one call into C (see _bind_step)
            return fast(action)
        return self._step(action)

    def _step(self, action):
        # the hot path: what holds still over a run is looked up at the reset, not here
        sc = self.scenario
        if sc is None or sc.bridge is None:
            raise RuntimeError(_EVICTED if self._evicted else "call reset() before step()")
        command = self._native(action)
        lon, lat = command
        check = (0.0 if lon is None else lon) + (0.0 if lat is None else lat)
        if check - check != 0.0:  # nan or inf: the episode ends before SUMO or the model see it
            self._substep = None
            sc._end("diverged", f"the agent's action is not finite: {np.asarray(action).tolist()}", level="ERROR")
        elif self._direct:
            self._history.append(command)
            sc.step(command)
        elif self._channels:
            self._history.append(command)
            sc.step_joint(self._agent, lon, lat)
        elif self._every == 1:
            self._apply(command)
        else:
            substep, self._substep = self._substep, None
            apply = self._apply
            apply(command)
            for _ in range(self._every - 1):
                if sc.status != "running":
                    break
                apply(command if substep is None else substep())
        elapsed = self.elapsed = self.elapsed + 1
        status = sc.status
        if status == "running":
            reward, terms = self._step_reward(False)
            info = {"status": status, "rewards": terms}
            if elapsed >= self._limit_steps:
                # the TimeLimit around the env truncates this step: the run's metrics so far
                info["status_detail"] = self._limit_detail()
                info["metrics"] = sc.result().metrics
                info.update(outcome(sc, "max_episode_steps", info["metrics"]))
            return self._observe(), reward, False, False, info
        return self._ended(status)

    def _ended(self, status: str):
        """The return of the env step at which the run ended with ``status``."""
        sc = self.scenario
        crashed = status == "collision" or status == "diverged"
        reward, terms = self._step_reward(crashed)
        # the duration reached is a truncation; anything before it ends the task
        truncated = not crashed and sc.t >= sc.config.duration - 1e-9
        weight = self.env_config.completion_reward
        if status == "completed" and not truncated and weight:
            # the task done early: the steps left count at this step's reward (a positive
            # reward per step must not make lingering pay more than finishing)
            terms["completion"] = bonus = weight * self._steps_left() * (reward if reward > 0.0 else 0.0)
            reward += bonus
        metrics = sc.result().metrics
        info = {"status": status, "rewards": terms, "status_detail": sc.status_detail, "metrics": metrics}
        info.update(outcome(sc, status, metrics))
        return self._observe(), reward, not truncated, truncated, info

    def _bind_step(self) -> functools.partial | None:
        """:meth:`_step` in one call into C (``ego._native.env_step``) until the run ends, where
        the env step is one scenario step with the default reward, the ``EgoState``
        observation and a continuous action, each bound to C (the extension built); else None.
        Bound after the reset and its TimeLimit (the step that reaches it runs in Python)."""
        parts = (self._native, self._step_reward, self._observe)
        natives = (_COMMAND, _REWARD_OF, _OBSERVE)
        if _ENV_STEP is None or not (self._direct or self._channels):
            return None
        if not all(isinstance(p, functools.partial) and p.func is f for p, f in zip(parts, natives)):
            return None
        agent = None if self._direct else self._agent
        limit = float(self._limit_steps)
        ctx = (self._step, self._ended, self, self.scenario, self._native.args[0], self._history, agent)
        return functools.partial(_ENV_STEP, (*ctx, self._step_reward.args, self._observe.args, limit))

    def _steps_left(self) -> int:
        """Env steps from now to the run's duration (or the registered TimeLimit, if sooner)."""
        sc = self.scenario
        period = sc.config.dt * self._every
        most = math.ceil(sc.config.duration / period - 1e-9)
        return max(0, min(most, self._limit_steps) - self.elapsed)

    def _limit_detail(self) -> str:
        """Why the registered TimeLimit ends the episode, and, where that is before the run's
        duration (another policy_frequency than the benchmark's), what keeps the whole run."""
        sc = self.scenario
        whole = math.ceil(sc.config.duration / (sc.config.dt * self._every) - 1e-9)
        detail = f"max_episode_steps ({self._limit}) reached"
        if self._limit is not None and self._limit < whole:
            detail += (
                f" at {self._limit * sc.config.dt * self._every:g} s of the run's {sc.config.duration:g} s "
                f"(policy_frequency {self.env_config.policy_frequency:g}; gym.make(..., "
                f"max_episode_steps={whole}) keeps the whole run)"
            )
        return detail

    def _set_limit(self, limit: int | float | None = math.nan) -> None:
        """The step at which the episode is truncated: ``limit`` (None: no TimeLimit), by
        default the registered ``max_episode_steps`` (an unpickled env)."""
        if limit is not None and math.isnan(limit):
            limit = _registered_limit(self.spec)
        self._limit = limit
        self._limit_steps = self._limit if self._limit is not None else math.inf

    def metrics(self) -> dict:
        """The current run's metrics so far (what ``info["metrics"]`` holds at its end)."""
        if self.scenario is None or self.scenario.bridge is None:
            raise RuntimeError("call reset() first")
        return self.scenario.result().metrics

    def render(self):
        if self.render_mode != "rgb_array" or self.scenario is None or self.scenario.bridge is None:
            return None
        if self._renderer is None:
            from ego.gym.render import TopDown

            self._renderer = TopDown(self.env_config)
        return self._renderer.draw(self.scenario, self._view)

    def close(self) -> None:
        self._fast_step = None
        if _running[0] is self:
            _running[0] = None
        if self.scenario is not None:
            self.scenario.close()
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    # -- pickling: the configuration, the generator and the run replayed ----------------------
    def __getstate__(self) -> dict:
        sc = self.scenario
        running = sc is not None and sc.bridge is not None
        return {
            "scenario": self.scenario_name,
            # the run replays on the configuration it was built on; a pending one (configure()
            # since) takes effect at the copy's next reset, as at the original's
            "config": self._built_config,
            "pending": self.config,
            "render_mode": self.render_mode,
            "np_random": self._np_random,
            "spec": self.spec,
            "run": (sc.seed, list(self._history), tuple(self._view._prev), self.elapsed) if running else None,
        }

    def __setstate__(self, state: dict) -> None:
        self.__init__(state["scenario"], state["config"], state["render_mode"])
        self.spec = state["spec"]
        run = state["run"]
        if run is not None:
            seed, history, prev, elapsed = run
            self._start(seed)
            self._set_limit()
            apply = self._apply
            for command in history:  # same seed, same commands: the same run (determinism)
                apply(command)
            self._view._prev[:], self.elapsed = prev, elapsed  # in place: the bound reward holds it
            self._fast_step = self._bind_step()
        self._np_random = state["np_random"]
        self.config = copy.deepcopy(state.get("pending", self.config))


#: how far the env's own surround sensor sees (m), for a scenario without one (curve, lane centring)
OWN_SENSOR_REACH = 200.0


def sensor_reach(cls, config) -> tuple[float, str]:
    """How far an env's surround view reaches (m) and how to see farther: no limit where the
    scenario gives the rows itself (the platoon: from its own states), else its
    ``sensor_range`` (the motorway scenarios), else the env's own sensor's reach."""
    from ego.scenarios.base import Scenario

    if cls.lane_rows is not Scenario.lane_rows:
        return math.inf, ""
    if hasattr(config, "sensor_range"):
        return float(config.sensor_range), ": its sensor_range, up to 500 m"
    return OWN_SENSOR_REACH, ""


def run_seed_of(seed: Any) -> int:
    """The run's seed (``ego run --seed``) for an env seed: the seed itself up to 2^31 - 1 (the
    range of SUMO's and ego's seeds); a larger one (Gymnasium takes any non-negative whole
    number, SB3's ``VecEnv.seed`` draws below 2^32) folded into that range by numpy's
    ``SeedSequence`` (``env.unwrapped.scenario.seed`` says which run it is)."""
    if isinstance(seed, np.integer):
        seed = int(seed)
    if type(seed) is int and seed > MAX_SEED:
        return int(np.random.SeedSequence(seed).generate_state(1, np.uint32)[0]) & MAX_SEED
    return check_seed(seed)


def _time_limit_calling(env, frame) -> int | None:
    """The ``max_episode_steps`` of the TimeLimit wrapper whose ``reset`` called ``env``'s
    (gym.make's, from the registration or its ``max_episode_steps`` argument, or one added by
    hand), from the calling frames: gymnasium gives a wrapped env no reference to its
    wrappers. None where no TimeLimit wraps it (EgoEnv made directly, max_episode_steps=-1)."""
    for _ in range(16):
        if frame is None:
            return None
        wrapper = frame.f_locals.get("self")
        if isinstance(wrapper, gym.wrappers.TimeLimit) and wrapper.unwrapped is env:
            return int(wrapper._max_episode_steps)
        frame = frame.f_back
    return None


def _registered_limit(spec) -> int | None:
    """The ``max_episode_steps`` of the id's registration: the step at which gym.make's
    TimeLimit truncates (gym.make leaves the env's own spec without it)."""
    if spec is None:
        return None
    if spec.max_episode_steps is not None:
        return spec.max_episode_steps
    try:
        return gym.spec(spec.id).max_episode_steps
    except gym.error.Error:
        return None


def _check_randomize(value: Any, config_cls, base) -> dict[str, tuple]:
    """``config["randomize"]``: scenario parameter -> [low, high], each bound checked as a
    ``--set`` value; whole numbers stay whole for an int parameter."""
    if not isinstance(value, Mapping):
        raise ConfigError(f"bad value for randomize: {value!r} (expected a dict: parameter -> [low, high])")
    infos = {i.name: i for i in describe(config_cls)}
    out = {}
    for name, bounds in value.items():
        info = infos.get(name)
        if info is None:
            raise unknown_parameter(name, set(infos))
        if info.type not in (int, float):
            raise ConfigError(f"bad value for randomize[{name}]: {name} is not a number (a {info.type.__name__})")
        if name in ("dt", "sumo_step"):  # valid values are not an interval: whole multiples
            raise ConfigError(
                f"bad value for randomize[{name}]: the control period and SUMO's step cannot vary "
                "(SUMO's step must be a whole number of control periods at every draw)"
            )
        if not _pair(bounds) or not bounds[0] <= bounds[1]:
            raise ConfigError(f"bad value for randomize[{name}]: {bounds!r} (expected [low, high] with low <= high)")
        lo, hi = bounds
        if info.type is int:
            if lo != int(lo) or hi != int(hi):
                raise ConfigError(f"bad value for randomize[{name}]: {bounds!r} (expected whole numbers)")
            lo, hi = int(lo), int(hi)
        else:
            lo, hi = float(lo), float(hi)
        for v in (lo, hi):
            apply_overrides(base, {name: v})
        out[name] = (lo, hi)
    return out


def _pair(value: Any) -> bool:
    try:
        lo, hi = value
        return all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in (lo, hi))
    except (TypeError, ValueError):
        return False
