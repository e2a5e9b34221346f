"""Observation and action types of :class:`ego.gym.EgoEnv`, after highway-env's.

Observation types (``config["observation"]["type"]``):

* ``EgoState``: the task's own observation (``ego.control.tasks.TASKS[task].observes``) as a
  float64 vector, one named field per entry (``names``), in SI units: exactly what the
  scenario's controllers see, so a controller can drive the env (:class:`ego.gym.ControllerPolicy`).
* ``Kinematics``: highway-env's ``Kinematics``: ``vehicles_count`` rows of ``features`` (presence,
  x, y, vx, vy, heading, cos_h, sin_h), the ego first, then the nearest vehicles sorted by
  distance, in the road frame of the ego's lane (x along it, y across it, + left; heading
  relative to the lane), relative to the ego unless ``absolute``, mapped from
  ``features_range`` to [-1, 1] when ``normalize`` (and clipped when ``clip``).

Action types (``config["action"]["type"]``), each with ``longitudinal`` / ``lateral`` flags
(a channel switched off is driven by the scenario's own ``controller``):

* ``ContinuousAction``: highway-env's: [acceleration, steering] in [-1, 1], mapped linearly onto
  ``acceleration_range`` (m/s^2) and ``steering_range`` (rad), then onto the ego's own model
  inputs: report 000's Fx per driven wheel = m a / Nw, report 002's a_x = a, report 004's
  commanded acceleration = a; delta = steering.
* ``EgoAction``: the ego's model inputs in their own units (``ego.control.tasks``): (Fx N, delta
  rad), (a_x m/s^2, delta rad) or (command m/s^2). Values outside the box go to the plant,
  which saturates them as it saturates a controller's command, so a controller's own action
  passes unchanged.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Mapping, Sequence
from operator import attrgetter
from typing import Any

import numpy as np
from gymnasium import spaces

from ego.control.tasks import TASKS
from ego.native import NATIVE
from ego.params import ConfigError

#: the observed fields that are not numbers, and what a vector carries instead
_NOT_NUMERIC = {"lane": (), "surround": (), "policy": ("policy.standstill_gap", "policy.headway")}
_array, _empty, _F64 = np.array, np.empty, np.float64
#: EgoStateObservation.observe's arithmetic in C, or None (its Python lines)
_FILL_OBS = None if NATIVE is None else NATIVE.fill_obs
_OBSERVE = None if NATIVE is None else NATIVE.observe
_COMMAND = None if NATIVE is None else NATIVE.command
INF = math.inf
#: observed fields fixed for a whole run
_RUN_CONSTANT = ("policy.standstill_gap", "policy.headway", "max_accel", "max_decel")

#: physical bounds (SI) of the EgoState fields, finite so that Gymnasium's and SB3's checkers
#: are silent. A run stays well inside them while it runs: the divergence check ends it at a
#: speed along the ego's axis beyond -1 or 80 m/s, a yaw rate beyond 2.5 rad/s, a heading
#: error beyond 75 deg or the road's edge; the last observation of a diverged run (a state
#: gone wild, even NaN) may lie outside. Stations up to 1000 km, times up to 10^6 s.
STATION, SPEED, ACCEL = 1.0e6, 100.0, 100.0
EGO_STATE_BOUNDS: dict[str, tuple[float, float]] = {
    "t": (0.0, 1.0e6),
    "s_ref": (-STATION, STATION),
    "ds_ref": (-SPEED, SPEED),
    "d_ref": (-SPEED, SPEED),  # m: across a road of any number of lanes
    "dd_ref": (-SPEED, SPEED),
    "s": (-STATION, STATION),
    "ds": (-SPEED, SPEED),
    "d": (-SPEED, SPEED),  # m
    "dd": (-SPEED, SPEED),
    "speed": (-SPEED, SPEED),
    "yaw_rate": (-10.0, 10.0),
    "vy": (-SPEED, SPEED),
    "heading_error": (-math.pi, math.pi),
    "curvature": (-1.0, 1.0),  # 1/m: no lane is tighter than a radius of 1 m
    "steer_ff": (-10.0, 10.0),  # rad: kappa (L + K_us v^2) at |kappa| <= 1 1/m
    "accel_ref": (-ACCEL, ACCEL),
    "gap": (-STATION, STATION),
    "accel": (-ACCEL, ACCEL),
    "lead_speed": (-SPEED, SPEED),
    "lead_accel": (-ACCEL, ACCEL),
    "standstill_gap": (0.0, 1000.0),
    "headway": (0.0, 100.0),
    "max_accel": (0.0, ACCEL),
    "max_decel": (0.0, ACCEL),
}
#: raw bounds of the Kinematics features (positions up to STATION: the ego's row is absolute;
#: velocities relative to the ego up to twice SPEED)
KINEMATICS_BOUNDS: dict[str, tuple[float, float]] = {
    "presence": (0.0, 1.0),
    "x": (-STATION, STATION),
    "y": (-STATION, STATION),
    "vx": (-2.0 * SPEED, 2.0 * SPEED),
    "vy": (-2.0 * SPEED, 2.0 * SPEED),
    "heading": (-math.pi, math.pi),
    "cos_h": (-1.0, 1.0),
    "sin_h": (-1.0, 1.0),
}


def _options(kind: str, given: Mapping[str, Any], allowed: Sequence[str]) -> dict:
    """``given`` without its ``type``, every key one of ``allowed``."""
    if not isinstance(given, Mapping):
        raise ConfigError(f"bad value for {kind}: {given!r} (expected a dict with a 'type')")
    out = {k: v for k, v in given.items() if k != "type"}
    for key in out:
        if key not in allowed:
            raise ConfigError(f"unknown {kind} option {key!r} for {given.get('type')} (known: {', '.join(allowed)})")
    return out


def _flag(name: str, value: Any) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise ConfigError(f"bad value for {name}: {value!r} (expected true or false)")
    return bool(value)


def _features(kind: str, value: Any, known: Sequence[str]) -> tuple[str, ...]:
    """A list of distinct feature names, each one of ``known`` (a string is refused, not split
    into letters; an empty list too: an observation of nothing)."""
    if isinstance(value, str) or not isinstance(value, (list, tuple)) or not value:
        raise ConfigError(
            f"bad value for features: {value!r} (expected a non-empty list of {kind} features: {', '.join(known)})"
        )
    for f in value:
        if f not in known:
            raise ConfigError(f"unknown {kind} feature {f!r} (known: {', '.join(known)})")
    if len(set(value)) != len(value):
        raise ConfigError(f"bad value for features: {value!r} (each {kind} feature once)")
    return tuple(value)


def _range(name: str, value: Any) -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in value)
    except (TypeError, ValueError):
        raise ConfigError(f"bad value for {name}: {value!r} (expected [low, high])") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise ConfigError(f"bad value for {name}: {value!r} (expected finite low < high)")
    return lo, hi


# -- observations ----------------------------------------------------------------------------


class _ObservationType:
    """What the observation types share: :meth:`bind`, the env step's way to observe."""

    def observe(self, view) -> np.ndarray:
        raise NotImplementedError

    def bind(self, view) -> Callable[[], np.ndarray]:
        """``observe(view)`` as a function of nothing until the run ends (bound after ``reset``)."""
        return functools.partial(self.observe, view)


class EgoStateObservation(_ObservationType):
    """The task's own observation as a vector; ``names`` are its fields (``standstill_gap`` and
    ``headway`` stand for the car-following task's spacing policy).

    ``normalize`` (default): time and station are relative, not raw: ``t`` becomes the share
    of the run's duration elapsed (0 to 1); where the task tracks a moving station reference
    (the motorway scenarios) ``s`` becomes the station error ``s - s_ref`` (m) and ``s_ref``
    the reference's station since the reset over the distance it covers in the run at its
    starting speed (about 0 to 1); where it does not (the curve, lane centring: ``s_ref`` 0)
    ``s`` becomes the station since the reset over the distance the ego covers in the run at
    its starting speed (about 0 to 1). Every other field stays in its SI unit.
    ``normalize=False``: every field raw."""

    type_name = "EgoState"
    OPTIONS = ("normalize",)

    def __init__(self, task: str, normalize: bool = True) -> None:
        paths = []
        for signal in TASKS[task].observes:
            paths += _NOT_NUMERIC.get(signal.name, (signal.name,))
        #: attribute paths into the scenario's observation, and the vector's field names
        self.paths = tuple(paths)
        self.names = tuple(p.rsplit(".", 1)[-1] for p in paths)
        self.normalize = _flag("normalize", normalize)
        # the trailing fields that hold still over a run (the platoon's spacing policy and
        # limits) are read once per reset, not every step
        n_const = 0
        while n_const < len(paths) and paths[-1 - n_const] in _RUN_CONSTANT:
            n_const += 1
        self._const_get = attrgetter(*paths[len(paths) - n_const :]) if n_const else None
        self._const: list = []
        dynamic = paths[: len(paths) - n_const]
        get = attrgetter(*dynamic)
        self._get = get if len(dynamic) > 1 else (lambda o: (get(o),))
        # what the bound observation reads in C: the attribute names where none is a path
        self._read = tuple(dynamic) if not any("." in p for p in dynamic) else self._get
        self.space = spaces.Box(*self._bounds(self.names, self.normalize), dtype=np.float64)
        names = self.names
        self._t = names.index("t")
        self._s = names.index("s") if "s" in names else None
        self._s_ref = names.index("s_ref") if "s_ref" in names else None
        self._per_duration = 1.0
        self._s_ref0, self._per_distance = 0.0, 1.0
        self._s0, self._tracks = 0.0, True
        self._size = len(self.names)
        self._norm: tuple | None = None
        self._fill = None

    @staticmethod
    def _bounds(names: Sequence[str], normalize: bool) -> tuple[np.ndarray, np.ndarray]:
        """The space's low and high: :data:`EGO_STATE_BOUNDS`; normalised, ``t`` in [0, 1] (the
        relative stations keep the station's bounds)."""
        low, high = np.array([EGO_STATE_BOUNDS[n] for n in names], dtype=np.float64).T
        if normalize:
            high[names.index("t")] = 1.0
        return low, high

    def reset(self, view) -> None:
        # the scenario fills one observation in place all run long
        self._source = source = view.obs
        self._per_duration = 1.0 / view.scenario.config.duration
        if self._const_get is not None:
            const = self._const_get(source)
            self._const = list(const) if isinstance(const, tuple) else [const]
        if self._s_ref is not None:
            self._tracks = source.s_ref != 0.0 or source.ds_ref != 0.0
            speed = source.ds_ref if self._tracks else source.ds
            self._s_ref0, self._s0 = source.s_ref, source.s
            self._per_distance = self._per_duration / max(abs(speed), 1.0)
        s, r = self._s, self._s_ref
        self._norm = (
            (
                self._t,
                self._per_duration,
                -1 if s is None else s,
                -1 if r is None else r,
                self._tracks,
                self._s_ref0,
                self._s0,
                self._per_distance,
            )
            if self.normalize
            else None
        )
        # C where the extension is built (a station without its reference stays in Python,
        # which raises for it as before)
        self._fill = _FILL_OBS if (s is None or r is not None or not self._tracks) else None

    def bind(self, view) -> Callable[[], np.ndarray]:
        """:meth:`observe` of ``view`` as a function of nothing until the run ends (bound after
        :meth:`reset`): the env step's hot path, one call into C where the extension is built."""
        if self._fill is not None and _OBSERVE is not None:
            return functools.partial(_OBSERVE, self._size, self._read, self._source, self._norm, self._const)
        return functools.partial(self.observe, view)

    def observe(self, view) -> np.ndarray:
        if self._fill is not None:  # the same arithmetic in C, into a new array
            out = _empty(self._size)  # float64, the default dtype (half the cost of naming it)
            self._fill(out, self._get(self._source), self._norm, self._const)
            return out
        values = list(self._get(self._source))
        if self.normalize:
            values[self._t] *= self._per_duration
            s = self._s
            if s is not None:
                r = self._s_ref
                if self._tracks:
                    values[s] -= values[r]
                    values[r] = (values[r] - self._s_ref0) * self._per_distance
                else:
                    values[s] = (values[s] - self._s0) * self._per_distance
        if self._const:
            values += self._const
        return _array(values, _F64)


class KinematicsObservation(_ObservationType):
    """highway-env's ``Kinematics`` (see the module docstring), built with numpy from the
    vehicles around the ego in its lane's frame (:meth:`ego.gym.env.EgoView.traffic`)."""

    type_name = "Kinematics"
    FEATURES = ("presence", "x", "y", "vx", "vy")
    KNOWN = ("presence", "x", "y", "vx", "vy", "heading", "cos_h", "sin_h")
    #: highway-env's defaults: 5 and 2 times its largest speed (40 m/s), 3 lanes of 4 m
    FEATURES_RANGE = {"x": [-200.0, 200.0], "y": [-12.0, 12.0], "vx": [-80.0, 80.0], "vy": [-80.0, 80.0]}
    OPTIONS = (
        "features",
        "vehicles_count",
        "features_range",
        "absolute",
        "order",
        "normalize",
        "clip",
        "see_behind",
        "perception_distance",
    )

    def __init__(
        self,
        features: Sequence[str] | None = None,
        vehicles_count: int = 5,
        features_range: Mapping[str, Sequence[float]] | None = None,
        absolute: bool = False,
        order: str = "sorted",
        normalize: bool = True,
        clip: bool = True,
        see_behind: bool = False,
        perception_distance: float | None = None,
    ) -> None:
        self.features = _features("Kinematics", features, self.KNOWN) if features is not None else self.FEATURES
        if (
            isinstance(vehicles_count, bool)
            or not isinstance(vehicles_count, (int, np.integer))
            or not 1 <= vehicles_count <= 100
        ):
            raise ConfigError(
                f"bad value for vehicles_count: {vehicles_count!r} (expected a whole number from 1 to 100)"
            )
        if order not in ("sorted", "shuffled"):
            raise ConfigError(f"bad value for order: {order!r} (expected one of sorted, shuffled)")
        ranges = dict(self.FEATURES_RANGE)
        for key, value in (features_range or {}).items():
            if key not in ("x", "y", "vx", "vy"):
                raise ConfigError(f"unknown features_range key {key!r} (known: x, y, vx, vy)")
            ranges[key] = _range(f"features_range[{key}]", value)
        if perception_distance is not None and not (
            isinstance(perception_distance, (int, float))
            and not isinstance(perception_distance, bool)
            and 0.0 < perception_distance <= 1000.0
        ):
            raise ConfigError(
                f"bad value for perception_distance: {perception_distance!r} (expected a "
                "number above 0 and up to 1000 (m))"
            )
        self.vehicles_count = int(vehicles_count)
        self.absolute = _flag("absolute", absolute)
        self.normalize = _flag("normalize", normalize)
        self.clip = _flag("clip", clip)
        self.see_behind = _flag("see_behind", see_behind)
        self.order = order
        #: as asked (None: highway-env's 200 m, cut where the env's sensor stops seeing)
        self._asked = None if perception_distance is None else float(perception_distance)
        self.perception_distance = 200.0 if perception_distance is None else float(perception_distance)
        self.names = self.features
        # per feature: the column of the (s, d, v_s, v_d, heading) rows, or how to derive it
        lo = np.array([ranges[f][0] if f in ranges else -1.0 for f in self.features])
        hi = np.array([ranges[f][1] if f in ranges else 1.0 for f in self.features])
        self._scaled = np.array([f in ranges for f in self.features])
        self._lo, self._span = lo, hi - lo
        # finite bounds: each feature's physical ones (KINEMATICS_BOUNDS), normalised as the
        # observation is; [-1, 1] where normalised and clipped
        low, high = np.array([KINEMATICS_BOUNDS[f] for f in self.features], dtype=np.float64).T
        if self.normalize:
            scaled = self._scaled
            low[scaled] = (low[scaled] - lo[scaled]) / self._span[scaled] * 2.0 - 1.0
            high[scaled] = (high[scaled] - lo[scaled]) / self._span[scaled] * 2.0 - 1.0
            if self.clip:
                low[scaled], high[scaled] = -1.0, 1.0
        shape = (self.vehicles_count, len(self.features))
        self.space = spaces.Box(
            np.broadcast_to(low, shape).astype(np.float32),
            np.broadcast_to(high, shape).astype(np.float32),
            shape,
            np.float32,
        )
        self._rng = np.random.default_rng()

    def set_reach(self, reach: float, how: str = "") -> None:
        """The farthest the env's surround sensor sees (m; ``how`` says how to see farther): a
        larger distance asked for is refused (it would be cut there, silently); the default,
        highway-env's 200 m, is whatever the sensor sees up to that."""
        if self._asked is not None and self._asked > reach:
            raise ConfigError(
                f"bad value for perception_distance: {self._asked:g} (this env's surround sensor sees {reach:g} m{how})"
            )

    def reset(self, view) -> None:
        self._rng = view.np_random

    def observe(self, view) -> np.ndarray:
        ego, others, length = view.traffic()
        rows = np.asarray(others, dtype=np.float64).reshape(-1, 5)
        ego = np.asarray(ego, dtype=np.float64)
        rel = rows[:, :4] - ego[:4]
        dist = np.hypot(rel[:, 0], rel[:, 1])
        keep = dist <= self.perception_distance
        if not self.see_behind:
            # highway-env drops the vehicles more than two car lengths behind
            keep &= rel[:, 0] > -2.0 * length
        rows, rel, dist = rows[keep], rel[keep], dist[keep]
        nearest = np.argsort(dist, kind="stable")[: self.vehicles_count - 1]
        rows, rel = rows[nearest], rel[nearest]
        if not self.absolute:
            rows = np.concatenate([rel, rows[:, 4:]], axis=1)
        table = np.concatenate([ego[None, :], rows])
        out = np.zeros((self.vehicles_count, len(self.features)))
        n = len(table)
        heading = table[:, 4]
        columns = {
            "presence": np.ones(n),
            "x": table[:, 0],
            "y": table[:, 1],
            "vx": table[:, 2],
            "vy": table[:, 3],
            "heading": heading,
            "cos_h": np.cos(heading),
            "sin_h": np.sin(heading),
        }
        for j, f in enumerate(self.features):
            out[:n, j] = columns[f]
        if self.normalize:
            scaled = self._scaled
            values = (out[:n, scaled] - self._lo[scaled]) / self._span[scaled] * 2.0 - 1.0
            out[:n, scaled] = np.clip(values, -1.0, 1.0) if self.clip else values
        if self.order == "shuffled" and n > 2:
            self._rng.shuffle(out[1:n])
        return out.astype(np.float32)


def _lane_width(view) -> float:
    """The width (m) of the ego's lane (the platoon's one lane)."""
    sc = view.road
    lane = getattr(sc, "road", None) or getattr(sc, "lane", None)
    return float(getattr(lane, "width", 3.5) or 3.5)


class TimeToCollisionObservation(_ObservationType):
    """highway-env's ``TimeToCollision``: a (3, 3, ``horizon``) grid over (ego speed: one
    ``speed_step`` slower, as now, one faster) x (lane: right, own, left) x (time bins of
    1 s): 1 in the bin of the predicted time to collision with the nearest vehicle ahead in
    that lane at that speed (vehicles closing from behind count as well), else 0. Built from
    the same vehicles as ``Kinematics``, in the ego's lane frame; lanes that do not exist,
    seen from where the ego is (:meth:`ego.gym.env.EgoView.lane_centres`), are 1 throughout
    (highway-env marks off-road lanes as occupied)."""

    type_name = "TimeToCollision"
    OPTIONS = ("horizon", "speed_step")

    def __init__(self, horizon: int = 10, speed_step: float = 5.0) -> None:
        if isinstance(horizon, bool) or not isinstance(horizon, (int, np.integer)) or not 1 <= horizon <= 100:
            raise ConfigError(f"bad value for horizon: {horizon!r} (expected a whole number of seconds from 1 to 100)")
        if not (isinstance(speed_step, (int, float)) and 0.0 < speed_step <= 20.0):
            raise ConfigError(f"bad value for speed_step: {speed_step!r} (expected a number above 0 up to 20 (m/s))")
        self.horizon, self.speed_step = int(horizon), float(speed_step)
        self.names = ("speed", "lane", "time")
        self.space = spaces.Box(0.0, 1.0, (3, 3, self.horizon), np.float32)

    def reset(self, view) -> None:
        self._width = _lane_width(view)
        #: the road's lane centres (m, + left, the ego's start-lane frame)
        self._centres = view.lane_centres()

    def observe(self, view) -> np.ndarray:
        ego, others, _ = view.traffic()
        out = np.zeros((3, 3, self.horizon), dtype=np.float32)
        # which of (right, own, left) exist, seen from where the ego is now
        d, w = ego[1], self._width
        self._exists = [dl == 0 or any(abs(c - d - dl * w) < 0.5 * w for c in self._centres) for dl in (-1, 0, 1)]
        for j, exists in enumerate(self._exists):
            if not exists:
                out[:, j, :] = 1.0
        if not others:
            return out
        rows = np.asarray(others, dtype=np.float64).reshape(-1, 5)
        gap = rows[:, 0] - ego[0]
        lane = np.rint((rows[:, 1] - ego[1]) / self._width).astype(int)
        for j, dl in enumerate((-1, 0, 1)):
            if not self._exists[j]:
                continue
            here = lane == dl
            if not here.any():
                continue
            g, v = gap[here], rows[here, 2]
            for i, dv in enumerate((-self.speed_step, 0.0, self.speed_step)):
                closing = np.where(g > 0.0, ego[2] + dv - v, v - ego[2] - dv)
                with np.errstate(divide="ignore", invalid="ignore"):
                    ttc = np.where(closing > 0.0, np.abs(g) / closing, np.inf)
                ttc = ttc[ttc < self.horizon]
                if ttc.size:
                    out[i, j, int(ttc.min())] = 1.0
        return out


class OccupancyGridObservation(_ObservationType):
    """highway-env's ``OccupancyGrid``: ``features`` (presence, vx, vy, on_road) on a grid
    of ``grid_step`` cells over ``grid_size`` (m, [[x_min, x_max], [y_min, y_max]]) around the
    ego, in its lane's frame (x along, y across, + left), velocities relative to the ego
    mapped from ``features_range`` to [-1, 1]. Shape (features, nx, ny)."""

    type_name = "OccupancyGrid"
    KNOWN = ("presence", "vx", "vy", "on_road")
    OPTIONS = ("features", "grid_size", "grid_step", "features_range")

    def __init__(
        self,
        features: Sequence[str] = ("presence", "vx", "vy", "on_road"),
        grid_size: Sequence[Sequence[float]] = ((-27.5, 27.5), (-27.5, 27.5)),
        grid_step: Sequence[float] = (5.0, 5.0),
        features_range: Mapping[str, Sequence[float]] | None = None,
    ) -> None:
        self.features = _features("OccupancyGrid", features, self.KNOWN)
        try:
            (x0, x1), (y0, y1) = ((float(a), float(b)) for a, b in grid_size)
            sx, sy = (float(v) for v in grid_step)
        except (TypeError, ValueError):
            raise ConfigError(
                f"bad value for grid_size/grid_step: {grid_size!r}, {grid_step!r} (expected "
                "[[x_min, x_max], [y_min, y_max]] and [step_x, step_y] in m)"
            ) from None
        if not (x0 < x1 and y0 < y1 and sx > 0.0 and sy > 0.0) or (x1 - x0) / sx > 200 or (y1 - y0) / sy > 200:
            raise ConfigError(
                f"bad value for grid_size/grid_step: {grid_size!r}, {grid_step!r} (expected "
                "min < max, steps above 0, at most 200 cells a side)"
            )
        ranges = {"vx": (-80.0, 80.0), "vy": (-80.0, 80.0)}
        for key, value in (features_range or {}).items():
            if key not in ranges:
                raise ConfigError(f"unknown features_range key {key!r} (known: vx, vy)")
            ranges[key] = _range(f"features_range[{key}]", value)
        self._ranges = ranges
        self._origin, self._step = (x0, y0), (sx, sy)
        self.shape = (len(self.features), round((x1 - x0) / sx), round((y1 - y0) / sy))
        self.names = self.features
        self.space = spaces.Box(-1.0, 1.0, self.shape, np.float32)

    def reset(self, view) -> None:
        # the road's lanes in the ego's start-lane frame (y of lane centres, half a lane)
        self._centres = np.array(view.lane_centres())
        self._half = 0.5 * _lane_width(view)

    def observe(self, view) -> np.ndarray:
        ego, others, _ = view.traffic()
        _, nx, ny = self.shape
        out = np.zeros(self.shape, dtype=np.float32)
        (x0, y0), (sx, sy) = self._origin, self._step
        if "on_road" in self.features:
            y = y0 + sy * (np.arange(ny) + 0.5) + ego[1]
            road = (np.abs(y[:, None] - self._centres[None, :]).min(axis=1) <= self._half).astype(np.float32)
            out[self.features.index("on_road")] = road[None, :]
        if others:
            rows = np.asarray(others, dtype=np.float64).reshape(-1, 5)
            ix = np.floor((rows[:, 0] - ego[0] - x0) / sx).astype(int)
            iy = np.floor((rows[:, 1] - ego[1] - y0) / sy).astype(int)
            inside = (ix >= 0) & (ix < nx) & (iy >= 0) & (iy < ny)
            ix, iy, rows = ix[inside], iy[inside], rows[inside]
            for k, name in enumerate(self.features):
                if name == "presence":
                    out[k, ix, iy] = 1.0
                elif name in ("vx", "vy"):
                    col = 2 if name == "vx" else 3
                    lo, hi = self._ranges[name]
                    rel = rows[:, col] - ego[col]
                    out[k, ix, iy] = np.clip((rel - lo) / (hi - lo) * 2.0 - 1.0, -1.0, 1.0)
        return out


def observation_type(config: Mapping[str, Any], task: str):
    """The observation type ``config`` (``{"type": ..., options}``) names."""
    kind = config.get("type") if isinstance(config, Mapping) else None
    if kind == "EgoState":
        return EgoStateObservation(task, **_options("observation", config, EgoStateObservation.OPTIONS))
    for cls in (KinematicsObservation, TimeToCollisionObservation, OccupancyGridObservation):
        if kind == cls.type_name:
            return cls(**_options("observation", config, cls.OPTIONS))
    raise ConfigError(
        f"bad value for observation: {config!r} (expected a dict whose type is one of "
        "EgoState, Kinematics, TimeToCollision, OccupancyGrid)"
    )


# -- actions ---------------------------------------------------------------------------------


class ActionType:
    """The agent's action -> the ego's (longitudinal command, delta), ``None`` for a channel
    the agent does not drive; and back (:meth:`from_native`) for a controller's command."""

    type_name = ""
    OPTIONS = ("longitudinal", "lateral")

    def __init__(
        self, task: str, limits: tuple[float, float, float], longitudinal: bool = True, lateral: bool | None = None
    ) -> None:
        steerable = TASKS[task].returns[1].high > 0.0
        self.longitudinal = _flag("longitudinal", longitudinal)
        self.lateral = _flag("lateral", steerable if lateral is None else lateral)
        if self.lateral and not steerable:
            raise ConfigError(
                f"bad value for lateral: true (the {task} task does not steer: its followers keep their lane)"
            )
        if not (self.longitudinal or self.lateral):
            raise ConfigError("bad action: longitudinal and lateral are both false (the agent would drive nothing)")
        #: (most negative, largest longitudinal command, largest |delta|) in the plant's units
        self.limits = limits
        self.channels = (self.longitudinal, self.lateral)
        self.size = self.longitudinal + self.lateral
        #: Fx per driven wheel (N) per m/s^2 of acceleration (report 000's model); 1 otherwise
        self.force_per_accel = 1.0

    def set_plant(self, force_per_accel: float) -> None:
        self.force_per_accel = force_per_accel

    def bind(self) -> Callable[[Any], tuple]:
        """:meth:`native` for the env step until the run ends (bound after :meth:`set_plant`)."""
        return self.native

    def _bound_command(self, scaled: bool, clip: bool, mid: Sequence[float], half: Sequence[float]) -> Callable:
        """``native`` as one call into C (``ego._native.command``: the same arithmetic) where
        the extension is built; anything but an array of the space's shape goes to ``native``."""
        if _COMMAND is None:
            return self.native
        mid, half = [*mid, 0.0, 0.0], [*half, 1.0, 1.0]
        params = (self.native, self.size, scaled, self.longitudinal, clip, mid[0], half[0], mid[1], half[1])
        return functools.partial(_COMMAND, (*params, float(self.force_per_accel)))

    def _shaped(self, action) -> np.ndarray:
        """``action`` as a float array of the space's shape, or a ValueError naming the action
        given and what the space takes (complex numbers and what is no number refused)."""
        given = action
        shape = getattr(action, "shape", None)
        kind = getattr(getattr(action, "dtype", None), "kind", "")
        if kind == "c" or isinstance(action, (str, bytes)) or action is None:
            shape = None
        else:
            try:
                action = np.asarray(action, dtype=np.float64)
            except (TypeError, ValueError):
                shape = None
            else:
                shape = action.shape
        if shape != self._shape:
            raise ValueError(
                f"bad action {_short(given)}: expected real numbers in an array of shape "
                f"{self.space.shape} ({self._describe()})" + (f", got shape {shape}" if shape is not None else "")
            )
        return action

    def _describe(self) -> str:
        names = [n for n, on in zip(("longitudinal", "steering"), self.channels) if on]
        return f"{self.type_name}: [{', '.join(names)}]"


def _short(action) -> str:
    text = repr(action)
    return text if len(text) <= 60 else text[:57] + "..."


class ContinuousAction(ActionType):
    type_name = "ContinuousAction"
    OPTIONS = ("longitudinal", "lateral", "acceleration_range", "steering_range", "clip")

    def __init__(
        self,
        task: str,
        limits,
        longitudinal: bool = True,
        lateral: bool | None = None,
        acceleration_range: Sequence[float] = (-5.0, 5.0),
        steering_range: Sequence[float] = (-math.pi / 4, math.pi / 4),
        clip: bool = True,
    ) -> None:
        super().__init__(task, limits, longitudinal, lateral)
        self.acceleration_range = _range("acceleration_range", acceleration_range)
        self.steering_range = _range("steering_range", steering_range)
        self.clip = _flag("clip", clip)
        self.space = spaces.Box(-1.0, 1.0, (self.size,), np.float32)
        self._shape = self.space.shape
        # native = offset + half_span * x for each channel the agent drives
        ranges = [r for r, on in zip((self.acceleration_range, self.steering_range), self.channels) if on]
        self._mid = [0.5 * (lo + hi) for lo, hi in ranges]
        self._half = [0.5 * (hi - lo) for lo, hi in ranges]

    def bind(self) -> Callable[[Any], tuple]:
        return self._bound_command(True, self.clip, self._mid, self._half)

    def native(self, action) -> tuple[float | None, float | None]:
        # the hot path (every env step): one or two floats, no list built
        if type(action) is not np.ndarray or action.shape != self._shape or action.dtype.kind not in "fiub":
            action = self._shaped(action)
        clip = self.clip
        if self.size == 2:
            x, y = action.tolist()
            if clip:  # NaN and infinities pass through (the env ends the run on them)
                x = -1.0 if -INF < x < -1.0 else (1.0 if 1.0 < x < INF else x)
                y = -1.0 if -INF < y < -1.0 else (1.0 if 1.0 < y < INF else y)
            mid, half = self._mid, self._half
            return (mid[0] + half[0] * x) * self.force_per_accel, mid[1] + half[1] * y
        (x,) = action.tolist()
        if clip:
            x = -1.0 if -INF < x < -1.0 else (1.0 if 1.0 < x < INF else x)
        x = self._mid[0] + self._half[0] * x
        return (x * self.force_per_accel, None) if self.longitudinal else (None, x)

    def from_native(self, command: float, delta: float) -> np.ndarray:
        values = []
        if self.longitudinal:
            values.append(command / self.force_per_accel)
        if self.lateral:
            values.append(delta)
        x = [(v - mid) / half for v, mid, half in zip(values, self._mid, self._half)]
        return np.clip(np.array(x, dtype=np.float32), -1.0, 1.0)


class EgoAction(ActionType):
    type_name = "EgoAction"

    def __init__(self, task: str, limits, longitudinal: bool = True, lateral: bool | None = None) -> None:
        super().__init__(task, limits, longitudinal, lateral)
        lo, hi, steer = limits
        low = [b for b, on in zip((lo, -steer), self.channels) if on]
        high = [b for b, on in zip((hi, steer), self.channels) if on]
        self.space = spaces.Box(np.array(low), np.array(high), dtype=np.float64)
        self._shape = self.space.shape
        both = self.longitudinal and self.lateral
        self.native = self._both if both else self._one

    def bind(self) -> Callable[[Any], tuple]:
        return self._bound_command(False, False, (), ())

    def _both(self, action) -> tuple[float, float]:
        if type(action) is not np.ndarray or action.shape != self._shape or action.dtype.kind not in "fiub":
            action = self._shaped(action)
        lon, lat = action.tolist()
        return lon, lat

    def _one(self, action) -> tuple[float | None, float | None]:
        if type(action) is not np.ndarray or action.shape != self._shape or action.dtype.kind not in "fiub":
            action = self._shaped(action)
        (x,) = action.tolist()
        return (x, None) if self.longitudinal else (None, x)

    def from_native(self, command: float, delta: float) -> np.ndarray:
        return np.array([v for v, on in zip((command, delta), self.channels) if on], dtype=np.float64)


class DiscreteMetaAction(ActionType):
    """highway-env's ``DiscreteMetaAction`` through ego's controllers: LANE_LEFT, IDLE,
    LANE_RIGHT, FASTER, SLOWER (those of the channels switched on) set a target lane and a
    target speed (one of ``target_speeds``, m/s); every control period the env's
    ``controller`` then tracks them: its observation gets the references (the target lane's
    centre as ``d_ref``; a station reference moving at the target speed, at most
    ``max_lag`` m from the ego) in place of the scenario's planner's. Motorway scenarios only
    (they have lanes); the scenario's AEB still brakes when a collision is imminent, and
    once it has engaged the longitudinal target **holds behind the front object** until the
    agent chooses FASTER: the speed target at most the front object's speed, the station
    reference at most ``follow_gap + follow_headway * v_front`` (the scenario's, m and s)
    behind its rear - as a car's AEB cancels its cruise control - so that IDLE (or SLOWER, or
    a lane change) does not drive the ego back into what the AEB braked for.

    With the lane actions the agent chooses the lane, not the scenario's planner (the env
    runs the scenario with ``evade`` false): the view's ``target_lane`` is the agent's (the
    observation's and the trace's ``d`` are measured from it), and from a lane action until the
    ego is within ``settle_band`` of the new lane's centre the view's ``agent_lane_change``
    makes the trace's ``phase`` a lane change, so that a commanded lane change is no lane
    departure in the run's metrics, as the planner's own is not."""

    type_name = "DiscreteMetaAction"
    OPTIONS = ("longitudinal", "lateral", "target_speeds", "max_lag")
    ALL = ("LANE_LEFT", "IDLE", "LANE_RIGHT", "FASTER", "SLOWER")

    def __init__(
        self,
        task: str,
        limits,
        longitudinal: bool = True,
        lateral: bool | None = None,
        target_speeds: Sequence[float] = (10.0, 15.0, 20.0, 25.0, 30.0, 35.0),
        max_lag: float = 2.0,
    ) -> None:
        super().__init__(task, limits, longitudinal, lateral)
        try:
            speeds = sorted(float(v) for v in target_speeds)
        except (TypeError, ValueError):
            speeds = []
        if not speeds or not all(0.0 <= v <= 60.0 for v in speeds):
            raise ConfigError(
                f"bad value for target_speeds: {target_speeds!r} (expected a list of speeds from 0 to 60 (m/s))"
            )
        if not (isinstance(max_lag, (int, float)) and 0.0 < max_lag <= 50.0):
            raise ConfigError(f"bad value for max_lag: {max_lag!r} (expected a number above 0 up to 50 (m))")
        self.target_speeds, self.max_lag = tuple(speeds), float(max_lag)
        names = []
        if self.lateral:
            names += ["LANE_LEFT", "IDLE", "LANE_RIGHT"]
        if self.longitudinal:
            names += ["FASTER", "SLOWER"] if self.lateral else ["SLOWER", "IDLE", "FASTER"]
        #: action index -> its name (highway-env's ``actions``)
        self.actions = dict(enumerate(names))
        self.actions_indexes = {v: k for k, v in self.actions.items()}
        self.space = spaces.Discrete(len(names))
        self._shape = ()
        self.lane, self.speed_index = 0, 0
        self._s_ref = 0.0
        #: the AEB has engaged since the agent last chose FASTER: the target holds behind the
        #: front object
        self.held = False

    def reset(self, view) -> None:
        road, obs = view.road, view.obs
        self._view = view
        self._offsets = road.lane_offset
        self._safety = getattr(view.scenario, "safety", None)
        self._sensor = getattr(road, "sensor", None)
        c = view.scenario.config
        self._follow = (getattr(c, "follow_gap", 5.0), getattr(c, "follow_headway", 0.5))
        self.held = False
        self.lane = road.target_lane
        self._road = road
        road.agent_lane_change = False
        self._settle = getattr(c, "settle_band", 0.2)
        self.speed_index = int(np.argmin([abs(v - obs.ds) for v in self.target_speeds]))
        self._s_ref = obs.s
        self._dt = view.scenario.config.dt
        from copy import copy

        self._obs = copy(obs)
        self._fields = type(obs).__slots__

    def native(self, action) -> tuple[int, None]:
        """A fresh (index, None) each env step (the env updates the targets once per tuple)."""
        try:
            index = int(action)
        except (TypeError, ValueError):
            index = -1
        if index != action or not 0 <= index < len(self.actions):
            raise ValueError(
                f"bad action {_short(action)}: expected an integer from 0 to "
                f"{len(self.actions) - 1} ({self._describe()})"
            )
        return (index, None)

    def _describe(self) -> str:
        return f"{self.type_name}: " + ", ".join(f"{k} {v}" for k, v in self.actions.items())

    def from_native(self, command: float, delta: float):
        raise ConfigError(
            "a controller policy cannot drive DiscreteMetaAction (its commands are not "
            "meta actions); use ContinuousAction or EgoAction"
        )

    def update(self, index: int) -> None:
        """Apply meta action ``index`` to the targets."""
        name = self.actions[index]
        if name in ("LANE_LEFT", "LANE_RIGHT"):
            lane = self.lane + (1 if name == "LANE_LEFT" else -1)
            if lane in self._offsets:  # a commanded lane change: the view measures from the new lane
                self.lane = self._road.target_lane = lane
                self._road.agent_lane_change = True
        elif name == "FASTER":
            self.speed_index = min(self.speed_index + 1, len(self.target_speeds) - 1)
            self.held = False  # the agent's own choice ends the hold behind the front object
        elif name == "SLOWER":
            self.speed_index = max(self.speed_index - 1, 0)

    def controller_observation(self):
        """The scenario's observation with the targets as references (a private copy)."""
        view = self._view
        src, o = view.obs, self._obs
        for name in self._fields:
            setattr(o, name, getattr(src, name))
        if self.lateral:
            road = self._road
            o.d = d = road.d_road - self._offsets[self.lane]
            o.d_ref = o.dd_ref = 0.0
            if road.agent_lane_change and abs(d) < self._settle:  # arrived: the lane change is over
                road.agent_lane_change = False
        if self.longitudinal:
            v = self.target_speeds[self.speed_index]
            s = src.s
            lag = self.max_lag
            s_ref = self._s_ref
            safety = self._safety
            if safety is not None and safety.active:
                self.held = True
            if self.held and self._sensor is not None and self._sensor.front.gap < INF:
                front = self._sensor.front  # behind it: no faster, and not closer than the follow distance
                lead = max(front.speed, 0.0)
                gap, headway = self._follow
                v = min(v, lead)
                s_ref = min(s_ref + v * self._dt, s + front.gap - gap - headway * lead)
            else:
                s_ref += v * self._dt
            self._s_ref = min(max(s_ref, s - lag), s + lag)
            o.s_ref, o.ds_ref, o.accel_ref = self._s_ref, v, 0.0
        return o


def action_type(config: Mapping[str, Any], task: str, limits) -> ActionType:
    """The action type ``config`` (``{"type": ..., options}``) names."""
    kind = config.get("type") if isinstance(config, Mapping) else None
    for cls in (ContinuousAction, EgoAction, DiscreteMetaAction):
        if kind == cls.type_name:
            return cls(task, limits, **_options("action", config, cls.OPTIONS))
    raise ConfigError(
        f"bad value for action: {config!r} (expected a dict whose type is one of "
        "ContinuousAction, EgoAction, DiscreteMetaAction)"
    )
