"""Report 003's four-loop cascade PID for lane centring, with curvature feed-forward.

    e --PID1--> psi_err_ref --PID2--> vy_ref --PID3--> r_ref --PID4--> delta_fb
    delta = sat_rate(sat(delta_fb + kappa (L + K_us v^2)))

Each loop's error is reference - measurement (loop 1's reference is the lane centre,
e = 0), and each loop is a PID with the report's numerics: the integral of the error
clipped to +-``integral_limit`` (anti-windup), the derivative of the error (a backward
difference, none on the first step) low-pass filtered as D = alpha d + (1 - alpha) D_prev,
and - on loop 1, the loop whose error is in metres -
the report's adaptive gain: 1.5 when |e| > 0.5 m, 0.8 when |e| < 0.1 m, else 1. The steer
is limited to 25 degrees and to ``steer_rate``.

Signs: e is the centre of gravity's offset LEFT of the lane centre, psi_err the heading
left of the lane's, vy the body lateral speed (left), r the yaw rate (left), delta > 0
steers left.

Gains: the report's (``preset=report``) or ours from ``ego tune lane-centering``
(``preset=tuned``, the default, shipped in ``ego/control/trained/cascade_pid_tuned.json``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from importlib.resources import files
from pathlib import Path

from ego.checks import finite_number, read_json
from ego.control.base import Observation
from ego.models.lateral_error import LateralErrorParams
from ego.params import ConfigError, Params, did_you_mean, param

#: Kp, Ki, Kd of the e, psi, vy and r loops: report 003's differential-evolution result
REPORT_GAINS = (0.2036, 0.3188, 0.1748, 1.5698, 0.0482, 0.0236, 0.1837, 0.4796, 0.2856, 1.0627, 0.3497, 0.1980)
GAIN_NAMES = tuple(f"{k}_{loop}" for loop in ("e", "psi", "vy", "r") for k in ("kp", "ki", "kd"))
TUNED_PRESET = Path(str(files("ego.control") / "trained" / "cascade_pid_tuned.json"))  # package data


#: a preset's gains lie in 0..MAX_GAIN (the tuner searches 0..2; a negative gain is a sign error)
MAX_GAIN = 100.0


@lru_cache(maxsize=4)
def load_preset(path: str = str(TUNED_PRESET)) -> tuple[float, ...]:
    """The 12 gains of a preset file written by ``ego tune lane-centering``; ConfigError
    naming the file and what is wrong with it (not JSON, a gain missing, not a finite number
    from 0 to ``MAX_GAIN``)."""
    p = Path(path)
    if not p.exists():
        raise ConfigError(f"no tuned gains at {p} (run: ego tune lane-centering)")
    data = read_json(p, "gains_file")
    gains = data.get("gains") if isinstance(data, dict) else None
    if not isinstance(gains, dict):
        raise ConfigError(
            f'bad gains_file {path!r}: expected an object with "gains": '
            f"{{{', '.join(GAIN_NAMES[:2])}, ...}} as ego tune writes"
        )
    for name in GAIN_NAMES:
        if name not in gains:
            raise ConfigError(f"bad gains_file {path!r}: the gain {name} is missing (expected {', '.join(GAIN_NAMES)})")
        value = gains[name]
        if not finite_number(value) or not 0.0 <= value <= MAX_GAIN:
            raise ConfigError(
                f"bad gains_file {path!r}: {name} = {value!r:.40} (expected a number from 0 to {MAX_GAIN:g})"
            )
    extra = sorted(set(gains) - set(GAIN_NAMES))
    if extra:
        raise ConfigError(
            f"bad gains_file {path!r}: unknown gain {extra[0]!r} (expected "
            f"{', '.join(GAIN_NAMES)}){did_you_mean(extra[0], GAIN_NAMES)}"
        )
    return tuple(float(gains[n]) for n in GAIN_NAMES)


def adaptive_gain(e: float) -> float:
    """Report 003's gain schedule on the lateral error (m)."""
    a = abs(e)
    return 1.5 if a > 0.5 else (0.8 if a < 0.1 else 1.0)


@dataclass(frozen=True)
class CascadePIDParams(Params):
    """Report 003's cascade; ``preset`` picks the gains."""

    preset: str = param(
        "tuned", "-", "gains: tuned (ego tune lane-centering) or report (report 003's)", choices=("tuned", "report")
    )
    gains_file: str = param("", "-", "a preset file written by ego tune (overrides preset)")
    integral_limit: float = param(
        1.0, "-", "|integral| limit of every loop (anti-windup)", min=0, max=100.0, min_exclusive=True
    )
    alpha: float = param(
        0.2, "-", "derivative filter: D = alpha d + (1 - alpha) D_prev", min=0, max=1, min_exclusive=True
    )
    adaptive: bool = param(True, "-", "report 003's adaptive gain on the position loop")
    feedforward: bool = param(True, "-", "curvature feed-forward kappa (L + K_us v^2)")
    steer_limit: float = param(25.0, "deg", "|delta| limit (report 003: 25 deg)", min=1.0, max=45.0)
    steer_rate: float = param(30.0, "deg/s", "|d delta/dt| limit", min=1.0, max=1000.0)

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.gains_file:  # read and check it now, before any run starts
            load_preset(self.gains_file)

    def gains(self) -> tuple[float, ...]:
        if self.gains_file:
            return load_preset(self.gains_file)
        return REPORT_GAINS if self.preset == "report" else load_preset()


class Cascade:
    """The control law on plain floats: ``step(e, psi_err, vy, r, kappa, speed) -> delta``.

    :func:`ego.train.lane_centering.simulate_batch` is the same law on numpy arrays (tests
    hold them equal member by member)."""

    __slots__ = (
        "kp",
        "ki",
        "kd",
        "beta",
        "ilim",
        "adaptive",
        "ff",
        "lim",
        "rate",
        "L",
        "K",
        "integ",
        "dfilt",
        "prev",
        "delta",
        "first",
        "out",
    )

    def __init__(
        self,
        gains: tuple[float, ...],
        dt: float,
        integral_limit: float = 1.0,
        alpha: float = 0.2,
        adaptive: bool = True,
        feedforward: bool = True,
        steer_limit: float = math.radians(25),
        steer_rate: float = math.radians(30),
        vehicle: LateralErrorParams | None = None,
    ) -> None:
        if len(gains) != 12:
            raise ValueError(f"the cascade needs 12 gains, got {len(gains)}")
        g = [float(x) for x in gains]
        # the integral is kept divided by dt and the filtered derivative divided by
        # alpha/dt, so a step costs fewer operations (the batch tuner does the same)
        self.kp = tuple(g[0::3])
        self.ki = tuple(k * dt for k in g[1::3])
        self.kd = tuple(k * (alpha / dt) for k in g[2::3])
        self.beta = 1.0 - alpha
        self.ilim = integral_limit / dt
        self.adaptive, self.ff = adaptive, feedforward
        self.lim, self.rate = steer_limit, steer_rate * dt
        vehicle = vehicle or LateralErrorParams()
        self.L, self.K = vehicle.wheelbase, vehicle.understeer_gradient
        self.reset()

    def reset(self) -> None:
        self.integ = [0.0] * 4
        self.dfilt = [0.0] * 4
        self.prev = [0.0] * 4
        self.delta = 0.0
        self.first = True
        self.out = [0.0] * 4  # psi_ref, vy_ref, r_ref, delta_fb

    def _loop(self, i: int, err: float) -> float:
        lim = self.ilim
        integ = self.integ[i] + err
        integ = lim if integ > lim else (-lim if integ < -lim else integ)
        self.integ[i] = integ
        d = self.beta * self.dfilt[i]
        if not self.first:
            d = (d - self.prev[i]) + err
        self.dfilt[i] = d
        self.prev[i] = err
        return self.kp[i] * err + self.ki[i] * integ + self.kd[i] * d

    def step(self, e: float, psi: float, vy: float, r: float, kappa: float, speed: float) -> float:
        out = self.out
        psi_ref = self._loop(0, -e)
        if self.adaptive:
            psi_ref *= adaptive_gain(e)
        out[0] = psi_ref
        out[1] = vy_ref = self._loop(1, psi_ref - psi)
        out[2] = r_ref = self._loop(2, vy_ref - vy)
        out[3] = cmd = self._loop(3, r_ref - r)
        self.first = False
        if self.ff:
            cmd += kappa * (self.L + self.K * speed * speed)
        prev, rate = self.delta, self.rate
        hi, lo = prev + rate, prev - rate
        cmd = hi if cmd > hi else (lo if cmd < lo else cmd)
        lim = self.lim
        cmd = lim if cmd > lim else (-lim if cmd < -lim else cmd)
        self.delta = cmd
        return cmd


class CascadePID:
    """The scenario's controller: (a_x, delta) with a_x the plan (``obs.accel_ref``)."""

    def __init__(self, params: CascadePIDParams, dt: float) -> None:
        self.params = p = params
        self.law = Cascade(
            p.gains(),
            dt,
            p.integral_limit,
            p.alpha,
            p.adaptive,
            p.feedforward,
            math.radians(p.steer_limit),
            math.radians(p.steer_rate),
        )

    def reset(self, *, seed: int | None = None) -> None:
        self.law.reset()

    def step(self, obs: Observation) -> tuple[float, float]:
        delta = self.law.step(obs.d - obs.d_ref, obs.heading_error, obs.vy, obs.yaw_rate, obs.curvature, obs.speed)
        return obs.accel_ref, delta

    #: the outer loops' outputs (references of the inner loops) and the feedback steer
    signal_units = {"psi_err_ref": "rad", "vy_ref": "m/s", "r_ref": "rad/s", "delta_fb": "rad"}

    def signals(self) -> dict[str, float]:
        o = self.law.out
        return {"psi_err_ref": o[0], "vy_ref": o[1], "r_ref": o[2], "delta_fb": o[3]}
