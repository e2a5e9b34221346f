"""Report 000's BP neural-network PID (section "(c) BP neural-network PID").

One network for both channels: inputs ``[p_x, i_x, d_x, 1, p_y, i_y, d_y, 1]`` (the error,
its integral and its rate on each channel, with biases), 10 ReLU hidden units, 6 sigmoid
outputs; each gain is ``1 + sigmoid`` (the report's fix against gains collapsing to 0).
The report's control law: ``u_x = Kp p + 4 Ki i + 2 Kd d`` and
``u_y = Kp p + 0.1 Ki i + 0.55 Kd d``; ``Fx = fx_gain * u_x``, ``delta = delta_gain * u_y``
(the report's Simulink output gains were not given; ours are chosen to give the same
loop gains as the other controllers).

Two variants (``--set variant=...``):

* ``report`` - the report's S-function as published: weights ~ N(0, 1); raw (unsquashed)
  inputs and an unbounded integral; the "gradient" ``sigmoid'(z) * [p, i, d]`` (it never
  sees whether the tracking error shrank); and the momentum term subtracted,
  ``W -= eta*g + alpha*(W_k - W_(k-1))``, which damps rather than carries the motion. It
  uses the report's experiment values (learning rate 0.05, momentum 0.01) and control law
  (weights 4, 2, 0.1, 0.55) whatever the other parameters say.
* ``stable`` (default) - the textbook rule (Liu, *Advanced PID control*, ch. 4): gradient
  descent on E = e^2/2 of each channel with the plant Jacobian replaced by its sign (+1
  here: more Fx moves the car forward, more steer moves it left), the correct momentum
  ``W += -eta*g + alpha*(W_k - W_(k-1))``, inputs squashed by tanh, small initial weights,
  gradients clipped; and a control law that does not wind up: the report's 4 Ki on the
  X position error saturates the tyres (the rear friction circle then lets the car spin),
  so the integral weights are 0.05 (X) and 0 (Y), the lateral derivative weight 2.5. It
  still adapts the gains online, but cannot blow them up.

numpy, not torch: per step the network is a handful of 10x8 and 6x10 products, where
numpy's call overhead (~1 us) is far below torch's (~5-10 us per operation), and there is
no batch to amortise it over. Even so its ~45 numpy calls cost ~40 us a step, many times a
fuzzy controller's; the C twin ``ego._native.bp_pid`` does the step's element-wise
arithmetic itself and calls numpy only where the numbers are numpy's own (the products,
tanh, exp): the same numbers to the bit, ~6x faster (``benchmarks/bench_controllers.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ego.control.base import Observation, feedforward_param
from ego.native import NATIVE
from ego.params import Params, param

N_IN, N_HIDDEN, N_OUT = 8, 10, 6
#: the C twin's work array: (name, offset, length) of the views it holds (ego/_native.c BP_*)
_WORK = (
    ("x", 0, N_IN),
    ("z1", 8, N_HIDDEN),
    ("h", 18, N_HIDDEN),
    ("z2", 28, N_OUT),
    ("tanh_in", 34, 18),
    ("tanh_out", 52, 18),
    ("expd", 70, N_OUT),
    ("delta3", 76, N_OUT),
    ("delta2", 82, N_HIDDEN),
    ("gains", 92, N_OUT),
)
_WORK_SIZE = 98
_BP_PID: Any = NATIVE.bp_pid if NATIVE is not None else None
_SUM_SQUARES: Any = NATIVE.sum_squares if NATIVE is not None else None
# numpy's ufuncs called directly (the module functions' wrappers cost more than a 10 x 8
# product here); the same operations, so the same numbers
_maximum, _minimum, _exp, _tanh, _outer, _sum = (
    np.maximum,
    np.minimum,
    np.exp,
    np.tanh,
    np.multiply.outer,
    np.add.reduce,
)
#: the report's control law: u_x = Kp p + 4 Ki i + 2 Kd d, u_y = Kp p + 0.1 Ki i + 0.55 Kd d
REPORT_WEIGHTS = (4.0, 2.0, 0.1, 0.55)


@dataclass(frozen=True)
class BPPIDParams(Params):
    variant: str = param(
        "stable",
        "-",
        "stable (textbook learning, default) or report (the published S-function)",
        choices=("stable", "report"),
    )
    learning_rate: float = param(
        0.002, "-", "eta of the stable variant (report: 0.05; 0: no learning)", min=0.0, max=1.0
    )
    momentum: float = param(0.01, "-", "alpha of the stable variant (report: 0.01)", min=0.0, max=0.99)
    fx_gain: float = param(500.0, "N", "Fx = fx_gain * u_x", min=0.0, max=20000.0)
    delta_gain: float = param(0.004, "rad", "delta = delta_gain * u_y", min=0.0, max=1.0)
    ki_lon_weight: float = param(
        0.05,
        "-",
        "u_x = Kp p + ki_lon_weight Ki i + kd_lon_weight Kd d, stable variant (report: 4)",
        min=0.0,
        max=100.0,
    )
    kd_lon_weight: float = param(2.0, "-", "stable variant (report: 2)", min=0.0, max=100.0)
    ki_lat_weight: float = param(
        0.0,
        "-",
        "u_y = Kp p + ki_lat_weight Ki i + kd_lat_weight Kd d, stable variant (report: 0.1)",
        min=0.0,
        max=100.0,
    )
    kd_lat_weight: float = param(2.5, "-", "stable variant (report: 0.55)", min=0.0, max=100.0)
    integral_limit: float = param(
        5.0,
        "m s",
        "|integral of the error| limit of the stable variant (anti-windup)",
        min=0.0,
        max=1000.0,
        min_exclusive=True,
    )
    init_scale: float = param(
        0.1, "-", "initial weights ~ N(0, init_scale^2), stable variant (report: 1)", min=0.0, max=10.0
    )
    feedforward: bool = feedforward_param()


class BPPIDController:
    """The report's BP-NN PID (``variant=report``) or its stabilised form (default)."""

    def __init__(self, params: BPPIDParams, dt: float) -> None:
        self.params = params
        self.dt = dt
        self.report = params.variant == "report"
        p = params
        self.eta = 0.05 if self.report else p.learning_rate
        self.alpha = 0.01 if self.report else p.momentum
        self.integral_limit = math.inf if self.report else p.integral_limit
        weights = (
            REPORT_WEIGHTS if self.report else (p.ki_lon_weight, p.kd_lon_weight, p.ki_lat_weight, p.kd_lat_weight)
        )
        self.coef = np.array([1.0, weights[0], weights[1], 1.0, weights[2], weights[3]])
        #: the C twin's work array and its views (x: the network's input, its biases
        #: x[3] = x[7] = 1 stay)
        self._work = np.zeros(_WORK_SIZE)
        self._views: dict[str, np.ndarray] = {}
        self.x = self._make_views()
        self.x[3] = self.x[7] = 1.0  # the biases
        self._terms = np.empty(6)
        self._e = np.empty(6)
        #: the step after the integrals: the C twin when built, else :meth:`_step_py`
        self.native = _BP_PID is not None
        self._ctx: tuple[Any, ...] = ()
        self.reset(seed=0)

    def reset(self, *, seed: int | None = None) -> None:
        rng = np.random.default_rng(seed)
        scale = 1.0 if self.report else self.params.init_scale
        self.w1 = scale * rng.standard_normal((N_HIDDEN, N_IN))
        self.w2 = scale * rng.standard_normal((N_OUT, N_HIDDEN))
        self.w1_prev = self.w1.copy()
        self.w2_prev = self.w2.copy()
        self.i_lon = self.i_lat = 0.0
        # the C twin writes the gains into its work array
        self.gains = self._views["gains"] if self.native else np.empty(N_OUT)
        self.gains[:] = 1.0
        self._u = (0.0, 0.0)
        self._ctx = ()

    def _make_views(self) -> np.ndarray:
        """The views of the work array (the C twin's buffers); returns x."""
        self._views = {name: self._work[at : at + n] for name, at, n in _WORK}
        return self._views["x"]

    def __getstate__(self) -> dict[str, Any]:
        # a pickled (or deep-copied) view is an array of its own: the views are made again
        # from the work array instead
        state = self.__dict__.copy()
        for name in ("_views", "_ctx", "x", *(("gains",) if self.native else ())):
            del state[name]
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self.x = self._make_views()
        if self.native:
            self.gains = self._views["gains"]
        self.native = self.native and _BP_PID is not None
        self._ctx = ()

    def _bind(self) -> tuple[Any, ...]:
        """What the C twin works on: the weights (in place), the work array's views and numpy's
        functions; bound again whenever a weight array is replaced."""
        v = self._views
        self._ctx = (
            self._work,
            self.w1,
            self.w2,
            self.w1_prev,
            self.w2_prev,
            self.coef,
            *(v[name] for name in ("x", "z1", "h", "z2", "tanh_in", "tanh_out", "expd", "delta3", "delta2")),
            self.w2.T,
            np.matmul,
            np.tanh,
            np.exp,
            ("out",),
        )
        return self._ctx

    def _forward(self, x: np.ndarray) -> tuple[Any, ...]:
        z1 = self.w1 @ x
        h = _maximum(z1, 0.0)
        z2 = self.w2 @ h
        # clip(z2, -50, 50) without np.clip's Python wrapper (the same values, NaN included)
        k = 1.0 / (1.0 + _exp(-_minimum(_maximum(z2, -50.0), 50.0)))
        return z1, h, k

    def step(self, obs: Observation) -> tuple[float, float]:
        p = self.params
        dt = self.dt
        e_x, de_x = obs.s_ref - obs.s, obs.ds_ref - obs.ds
        e_y, de_y = obs.d_ref - obs.d, obs.dd_ref - obs.dd
        lim = self.integral_limit
        self.i_lon = min(lim, max(-lim, self.i_lon + dt * e_x))
        self.i_lat = min(lim, max(-lim, self.i_lat + dt * e_y))
        if self.native:
            ctx = self._ctx
            if (
                not ctx
                or ctx[1] is not self.w1
                or ctx[2] is not self.w2
                or ctx[3] is not self.w1_prev
                or ctx[4] is not self.w2_prev
                or ctx[5] is not self.coef
            ):  # a weight array replaced since the last bind
                ctx = self._bind()
            u_x, u_y = _BP_PID(ctx, e_x, self.i_lon, de_x, e_y, self.i_lat, de_y, self.report, self.eta, self.alpha)
        else:
            u_x, u_y = self._step_py(e_x, de_x, e_y, de_y)
        self._u = (u_x, u_y)
        delta = p.delta_gain * u_y
        return p.fx_gain * u_x, (delta + obs.steer_ff if p.feedforward else delta)

    def _step_py(self, e_x: float, de_x: float, e_y: float, de_y: float) -> tuple[float, float]:
        """The network's forward pass, the control law (u_x, u_y) and the learning step: the
        reference of the C twin."""
        terms = self._terms
        terms[0], terms[1], terms[2] = e_x, self.i_lon, de_x
        terms[3], terms[4], terms[5] = e_y, self.i_lat, de_y
        x = self.x  # its biases x[3] = x[7] = 1 stay
        if self.report:
            x[0:3] = terms[0:3]
            x[4:7] = terms[3:6]
        else:
            _tanh(terms[0:3], out=x[0:3])
            _tanh(terms[3:6], out=x[4:7])
        z1, h, k = self._forward(x)
        self.gains = gains = 1.0 + k
        c = self.coef * terms
        # the same double products and sums as numpy's scalars, on Python floats
        g0, g1, g2, g3, g4, g5 = gains.tolist()
        c0, c1, c2, c3, c4, c5 = c.tolist()
        u_x = g0 * c0 + g1 * c1 + g2 * c2
        u_y = g3 * c3 + g4 * c4 + g5 * c5
        self._learn(x, z1, h, k, terms, c, e_x, e_y)
        return u_x, u_y

    def _learn(self, x: Any, z1: Any, h: Any, k: Any, terms: Any, c: Any, e_x: Any, e_y: Any) -> None:
        dk = k * (1.0 - k)
        if self.report:
            # as published: "error" = [p, i, d] per channel, no tracking error, momentum
            # subtracted
            delta3 = dk * terms
            sign = -1.0
        else:
            # dE/dK = -e * sign(dy/du) * du/dK, sign(dy/du) = +1 on both channels
            e = self._e
            e[0:3] = e_x
            e[3:6] = e_y
            delta3 = -_tanh(e) * _tanh(c) * dk
            sign = 1.0
        delta2 = (self.w2.T @ delta3) * (z1 > 0.0)
        g2 = _outer(delta3, h)  # np.outer's own product, without its wrapper
        g1 = _outer(delta2, x)
        if not self.report:  # clip the step, not its direction
            norm = math.sqrt(float(_sum(g2 * g2, None) + _sum(g1 * g1, None)))
            if norm > 1.0:
                g2 /= norm
                g1 /= norm
        for w, w_prev, g in ((self.w2, self.w2_prev, g2), (self.w1, self.w1_prev, g1)):
            step = -self.eta * g + sign * self.alpha * (w - w_prev)
            w_prev[:] = w
            w += step

    #: the network's gain multipliers (1 + k) and the norm of its weights: pure numbers
    signal_units = {
        "kp_lon": "-",
        "ki_lon": "-",
        "kd_lon": "-",
        "kp_lat": "-",
        "ki_lat": "-",
        "kd_lat": "-",
        "weight_norm": "-",
    }

    def signals(self) -> dict[str, float]:
        g0, g1, g2, g3, g4, g5 = self.gains.tolist()
        w1, w2 = self.w1, self.w2
        return {
            "kp_lon": g0,
            "ki_lon": g1,
            "kd_lon": g2,
            "kp_lat": g3,
            "ki_lat": g4,
            "kd_lat": g5,
            "weight_norm": math.sqrt(
                _SUM_SQUARES(w1) + _SUM_SQUARES(w2) if self.native else float(_sum(w1 * w1, None) + _sum(w2 * w2, None))
            ),
        }
