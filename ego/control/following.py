"""Report 004's car-following controllers: a PID and the 3-5-3 BP neural-network PID.

Each follower of a platoon has its own controller. It sees a :class:`FollowingObservation`
(gap and speeds from SUMO, its own state, the spacing policy) and returns the commanded
acceleration; a new command is computed every ``period`` s and held in between, as a
sampled controller does (report 004 sampled at 1 s). :class:`PlatoonControl` bundles one
controller per follower behind the ordinary controller interface, so the scenario loop
drives a platoon like a single car.

Signs: the spacing error delta_d = gap - d_s - lambda v is positive when the follower is too
far back, so a positive error asks for more acceleration.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ego.control.base import signal_units
from ego.control.pid import PID
from ego.models.longitudinal import SpacingPolicy
from ego.native import NATIVE
from ego.params import ConfigError, Params, param


@dataclass(slots=True)
class FollowingObservation:
    """One follower's view at one control step (SI units). The scenario fills it in place."""

    t: float = 0.0  #: time (s)
    gap: float = 0.0  #: bumper to bumper to the predecessor (m)
    speed: float = 0.0  #: own speed (m/s)
    accel: float = 0.0  #: own actual acceleration (m/s^2)
    lead_speed: float = 0.0  #: the predecessor's speed (m/s)
    lead_accel: float = 0.0  #: the predecessor's acceleration (m/s^2)
    #: the spacing policy the platoon keeps (d_s, lambda)
    policy: SpacingPolicy = field(default_factory=SpacingPolicy)
    max_accel: float = math.inf  #: the car's largest acceleration command (m/s^2)
    max_decel: float = math.inf  #: the car's largest deceleration command (m/s^2, positive)

    @property
    def desired_gap(self) -> float:
        """d_s + lambda v (m)."""
        return self.policy.desired_gap(self.speed)

    @property
    def spacing_error(self) -> float:
        """delta_d = gap - d_s - lambda v (m, positive: too far back)."""
        return self.policy.error(self.gap, self.speed)

    @property
    def spacing_error_rate(self) -> float:
        """d(delta_d)/dt = (v_lead - v) - lambda a (m/s)."""
        return self.policy.error_rate(self.lead_speed, self.speed, self.accel)


def _updates_every(period: float, dt: float) -> int:
    """Control periods per update; ``period`` must be a whole multiple of ``dt``."""
    ratio = period / dt
    if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
        raise ConfigError(f"bad value for period: {period:g} (expected a whole multiple of dt={dt:g} s)")
    return round(ratio)


class SampledFollower:
    """Base of the car-following controllers: a new command every ``period``, held between.

    Subclasses implement ``_update(obs) -> commanded acceleration`` and ``_reset(seed)``."""

    def __init__(self, period: float, dt: float) -> None:
        self.period = period
        self._every = _updates_every(period, dt)
        self._count = 0
        self._action = (0.0, 0.0)
        #: True on the steps that computed a new command (the signals changed then only)
        self.updated = True

    def reset(self, *, seed: int | None = None) -> None:
        self._count = 0
        self._action = (0.0, 0.0)
        self.updated = True
        self._reset(seed)

    def step(self, obs: FollowingObservation) -> tuple[float, float]:
        """(commanded acceleration in m/s^2, 0): the platoon keeps its lane."""
        count = self._count
        self.updated = count == 0
        if self.updated:
            self._action = (self._update(obs), 0.0)
        count += 1
        self._count = 0 if count == self._every else count
        return self._action

    def _reset(self, seed: int | None) -> None:
        raise NotImplementedError

    def _update(self, obs: FollowingObservation) -> float:
        raise NotImplementedError


@dataclass(frozen=True)
class FollowingPIDParams(Params):
    """Report 004's baseline PID on the spacing error."""

    kp: float = param(0.85, "1/s^2", "proportional gain (report 004: 0.85)", min=0.0, max=100.0)
    ki: float = param(0.2, "1/s^3", "integral gain (report 004: 0.2)", min=0.0, max=100.0)
    kd: float = param(0.3, "1/s", "derivative gain, on the measured error rate (report 004: 0.3)", min=0.0, max=100.0)
    period: float = param(
        0.1, "s", "control period: a new command every period, held between (report 004: 1 s)", min=0.01, max=2.0
    )


class FollowingPID(SampledFollower):
    """u = kp delta_d + ki int(delta_d) + kd d(delta_d)/dt, saturated to the car's limits
    with back-calculation anti-windup (:class:`ego.control.pid.PID`). The derivative acts on
    the measured error rate (relative speed minus lambda times own acceleration, what a
    radar and the car's own sensors give), so it has no kick and needs no filter."""

    def __init__(self, params: FollowingPIDParams, dt: float) -> None:
        super().__init__(params.period, dt)
        self.params = params
        self.pid = PID(params.kp, params.ki, params.kd, params.period, -math.inf, math.inf, tau_d=0.0)

    def _reset(self, seed: int | None) -> None:
        self.pid.reset()

    def _update(self, obs: FollowingObservation) -> float:
        pid = self.pid
        pid.u_min, pid.u_max = -obs.max_decel, obs.max_accel
        return pid.step(obs.spacing_error, obs.spacing_error_rate)

    signal_units = {"integral": "m s"}  #: integral of the spacing error

    def signals(self) -> dict[str, float]:
        return {"integral": self.pid.integral}


@dataclass(frozen=True)
class BPPIDAccParams(Params):
    """Report 004's BP neural-network PID for car following."""

    learning_rate: float = param(0.25, "-", "eta (report 004: 0.25; 0: no learning)", min=0.0, max=1.0)
    momentum: float = param(0.01, "-", "alpha (report 004: 0.01)", min=0.0, max=0.99)
    init_range: float = param(
        0.5,
        "-",
        "initial weights ~ U[-init_range, init_range] (report 004: 0.5)",
        min=0.0,
        max=10.0,
        min_exclusive=True,
    )
    period: float = param(
        0.1, "s", "control period: a new command every period, held between (report 004: 1 s)", min=0.01, max=2.0
    )


N_IN, N_HIDDEN, N_OUT = 3, 5, 3
#: the C twin's work array: (name, offset, length) of its views (ego/_native.c BA_*)
_WORK = (
    ("x", 0, N_IN),
    ("z1", 3, N_HIDDEN),
    ("h", 8, N_HIDDEN),
    ("z2", 13, N_OUT),
    ("o", 16, N_OUT),
    ("gains", 19, N_OUT),
    ("terms", 22, N_OUT),
    ("dot", 25, 1),
    ("delta3", 26, N_OUT),
    ("delta2", 29, N_HIDDEN),
)
_WORK_SIZE = 34
_BP_PID_ACC: Any = NATIVE.bp_pid_acc if NATIVE is not None else None


class BPPIDAcc(SampledFollower):
    """Report 004's 3-5-3 BP-NN PID (the textbook form: Liu, *Advanced PID control*, ch. 4).

    Inputs, in the report's loop r_in -> error -> PID -> G(s) -> y_out, written in a frame
    moving with the follower: r_in = gap - d_s (where the follower's compensated position
    should be), y_out = lambda v (where it is), error = r_in - y_out = delta_d. Hidden layer
    5 tanh units, outputs Kp, Ki, Kd = (1 + tanh)/2 in (0, 1). Incremental PID with the
    gains read as continuous ones (so the report's 1 s period gives its discrete law):

        u(k) = u(k-1) + Kp (e(k) - e(k-1)) + Ki T e(k) + Kd (e(k) - 2 e(k-1) + e(k-2)) / T

    saturated to the car's limits (the stored u too, so it never winds up). Learning: after
    each update, gradient descent on E = e(k)^2 / 2 with the plant's Jacobian sign(dy/du) =
    +1 (more acceleration always moves the follower's compensated position forward, so it
    is known rather than estimated online), momentum dW(k) = eta g + alpha dW(k-1); the
    report's eta 0.25, alpha 0.01 and weights U[-0.5, 0.5] are the defaults.
    """

    def __init__(self, params: BPPIDAccParams, dt: float) -> None:
        super().__init__(params.period, dt)
        self.params = params
        #: the C twin's work array and its views (x and terms: the network's input and the
        #: PID's increments, in either step)
        self._work = np.zeros(_WORK_SIZE)
        self._views: dict[str, np.ndarray] = {}
        self._make_views()
        #: the update: the C twin when built, else :meth:`_update_py`
        self.native = _BP_PID_ACC is not None
        self._ctx: tuple[Any, ...] = ()
        self._reset(0)

    def _make_views(self) -> None:
        v = self._views = {name: self._work[at : at + n] for name, at, n in _WORK}
        self.x, self.terms = v["x"], v["terms"]

    def __getstate__(self) -> dict[str, Any]:
        # a pickled (or deep-copied) view is an array of its own: made again from the work array
        state = self.__dict__.copy()
        for name in ("_views", "_ctx", "x", "terms", *(("gains",) if self.native else ())):
            del state[name]
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._make_views()
        if self.native:
            self.gains = self._views["gains"]
        self.native = self.native and _BP_PID_ACC is not None
        self._ctx = ()

    def _reset(self, seed: int | None) -> None:
        rng = np.random.default_rng(seed)
        r = self.params.init_range
        self.w1 = rng.uniform(-r, r, (N_HIDDEN, N_IN))
        self.w2 = rng.uniform(-r, r, (N_OUT, N_HIDDEN))
        self.dw1 = np.zeros_like(self.w1)
        self.dw2 = np.zeros_like(self.w2)
        # the C twin writes the gains into its work array
        self.gains = self._views["gains"] if self.native else np.empty(N_OUT)
        self.gains[:] = 0.5
        self.e1 = self.e2 = 0.0
        self.u = 0.0
        self._ctx = ()

    def _bind(self) -> tuple[Any, ...]:
        """What the C twin works on: the weights and their steps (in place), the work array's
        views and numpy's functions; bound again whenever one of those arrays is replaced."""
        v = self._views
        self._ctx = (
            self._work,
            self.w1,
            self.w2,
            self.dw1,
            self.dw2,
            *(v[n] for n in ("x", "z1", "h", "z2", "o", "gains", "terms")),
            v["dot"].reshape(()),
            v["delta3"],
            v["delta2"],
            self.w2.T,
            np.matmul,
            np.tanh,
            ("out",),
        )
        return self._ctx

    def _update(self, obs: FollowingObservation) -> float:
        T = self.period
        e = obs.spacing_error
        policy = obs.policy
        e1 = self.e1
        t0, t1, t2 = e - e1, T * e, (e - 2.0 * e1 + self.e2) / T
        if self.native:
            ctx = self._ctx
            if (
                not ctx
                or ctx[1] is not self.w1
                or ctx[2] is not self.w2
                or ctx[3] is not self.dw1
                or ctx[4] is not self.dw2
            ):
                ctx = self._bind()  # a weight array replaced since the last bind
            p = self.params
            u: float = _BP_PID_ACC(
                ctx,
                obs.gap - policy.standstill_gap,
                policy.headway * obs.speed,
                e,
                t0,
                t1,
                t2,
                self.u,
                obs.max_accel,
                -obs.max_decel,
                p.learning_rate,
                p.momentum,
            )
        else:
            u = self._update_py(obs, e, t0, t1, t2)
        self.e2, self.e1 = e1, e
        self.u = u
        return u

    def _update_py(self, obs: FollowingObservation, e: float, t0: float, t1: float, t2: float) -> float:
        """The network, the incremental PID and the learning step from the update's scalars:
        the reference of the C twin ``ego._native.bp_pid_acc``."""
        x = self.x
        x[0] = obs.gap - obs.policy.standstill_gap
        x[1] = obs.policy.headway * obs.speed
        x[2] = e
        h = np.tanh(self.w1 @ x)
        o = np.tanh(self.w2 @ h)
        self.gains = gains = 0.5 * (1.0 + o)
        terms = self.terms
        terms[0], terms[1], terms[2] = t0, t1, t2
        u = self.u + float(gains @ terms)
        hi, lo = obs.max_accel, -obs.max_decel
        u = hi if u > hi else (lo if u < lo else u)
        # dE/dK = -e sign(dy/du) du/dK; dK/dz = (1 - o^2)/2; descend
        delta3 = e * terms * 0.5 * (1.0 - o * o)
        delta2 = (self.w2.T @ delta3) * (1.0 - h * h)
        eta, alpha = self.params.learning_rate, self.params.momentum
        self.dw2 *= alpha
        self.dw2 += eta * np.outer(delta3, h)
        self.dw1 *= alpha
        self.dw1 += eta * np.outer(delta2, x)
        self.w2 += self.dw2
        self.w1 += self.dw1
        return u

    #: the network's gains, read as the continuous PID's (command in m/s^2 from errors in m)
    signal_units = {"kp": "1/s^2", "ki": "1/s^3", "kd": "1/s"}

    def signals(self) -> dict[str, float]:
        g = self.gains
        return {"kp": float(g[0]), "ki": float(g[1]), "kd": float(g[2])}


def member_seed(seed: int | None, index: int) -> int | None:
    """Each follower's own seed, drawn from the run's (so their random weights differ)."""
    if seed is None:
        return None
    return int(np.random.SeedSequence([int(seed), index]).generate_state(1)[0])


class PlatoonControl:
    """One controller per follower, behind the single-controller interface: ``step`` takes
    the followers' observations and returns their actions; signals are named
    ``<signal>_<follower id>``."""

    def __init__(self, members: Sequence[Any], ids: Sequence[str]) -> None:
        if len(members) != len(ids):
            raise ValueError(f"{len(members)} controllers for {len(ids)} followers")
        self.members = list(members)
        self.ids = tuple(ids)
        self._signals: dict[str, float] | None = None

    def reset(self, *, seed: int | None = None) -> None:
        for i, member in enumerate(self.members):
            member.reset(seed=member_seed(seed, i))
        self._signals = None

    def step(self, observations: Sequence[Any]) -> list[tuple[float, float]]:
        actions = [member.step(obs) for member, obs in zip(self.members, observations)]
        if self._signals is not None and any(getattr(m, "updated", True) for m in self.members):
            self._signals = None
        return actions

    @property
    def signal_units(self) -> dict[str, str]:
        """Every member's signal units, under the names :meth:`signals` gives them."""
        return {
            f"{name}_{vid}": unit
            for member, vid in zip(self.members, self.ids)
            for name, unit in signal_units(member).items()
        }

    def signals(self) -> dict[str, float]:
        """Every member's signals; rebuilt only after a member computed a new command
        (sampled controllers change nothing in between). Do not modify the dict."""
        if self._signals is None:
            self._signals = {
                f"{name}_{vid}": value
                for member, vid in zip(self.members, self.ids)
                for name, value in member.signals().items()
            }
        return self._signals
