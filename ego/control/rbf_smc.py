"""Report 000's RBF neural adaptive sliding-mode control (section "(d)").

Errors here follow the report: ``e = actual - reference``. Sliding surfaces
``s_X = c_X e_X + de_X`` and ``s_Y = c_Y e_Y + de_Y``; control
``u = -f_hat - s - eta * sign(s)`` on each channel, ``Fx = 1000 u_X``, ``delta = 0.6 u_Y``.
``f_hat = W^T h`` approximates the unknown dynamics with 10 Gaussian nodes on
``[X, Y, dX, dY]`` (road frame here), ``h_j = d exp(-|x - c_j|^2 / (2 b^2))``, centres
``0.5 * randn``, width ``b = 10``, scale ``d = 1e-5``, initial weights 0.1.

Adaptive law, derived for this error convention: with ``V = s^2/2 + |W~|^2/(2 gamma)`` and
``ds/dt = f - f_hat - s - eta sign(s)``, choosing ``dW/dt = gamma s h`` gives
``dV/dt = -s^2 - eta |s| <= 0`` - the report's sign.

Variants (``--set variant=...``):

* ``fixed`` (default) - each channel has its own weights, ``u_Y`` switches on ``sign(s_Y)``
  (the report's code uses ``sign(s_X)``), and a boundary layer ``sat(s/phi)`` replaces
  ``sign(s)`` (``phi_lon``, ``phi_lat``; 0 gives ``sign``) against chattering.
* ``report`` - the published S-function: one weight vector shared by both channels,
  updated with ``gamma (s_X + s_Y) h``, and ``sign(s_X)`` in ``u_Y``; pure ``sign``.

The Gaussians sit near the origin while X grows by 20 m each second, so ``h`` - and with
it the neural term - vanishes within seconds: in practice the report's controller is the
sliding-mode law with its proportional term. ``rbf_norm`` records the weights.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ego.control.base import Observation, feedforward_param
from ego.native import NATIVE
from ego.params import Params, param

N_NODES = 10


@dataclass(frozen=True)
class RBFSMCParams(Params):
    variant: str = param(
        "fixed",
        "-",
        "fixed (default: sign(s_Y), own weights per channel, boundary layer) or report (the published S-function)",
        choices=("fixed", "report"),
    )
    c_lon: float = param(1.0, "1/s", "sliding surface s_X = c_lon e_X + de_X (report: 1)", min=0.0, max=100.0)
    c_lat: float = param(0.5, "1/s", "sliding surface s_Y = c_lat e_Y + de_Y (report: 0.5)", min=0.0, max=100.0)
    eta_lon: float = param(2.0, "m/s", "switching gain, X (report: 2)", min=0.0, max=100.0)
    eta_lat: float = param(0.1, "m/s", "switching gain, Y (report: 0.1)", min=0.0, max=100.0)
    gamma: float = param(1000.0, "-", "adaptation rate (report: 1000)", min=0.0, max=1e6)
    width: float = param(10.0, "-", "Gaussian width b, in the errors' units (report: 10)", min=0.01, max=1000.0)
    scale: float = param(1e-5, "-", "Gaussian scale d (report: 1e-5)", min=0.0, max=1.0)
    centre_spread: float = param(0.5, "-", "centres ~ centre_spread * N(0, 1) (report: 0.5)", min=0.0, max=100.0)
    w0: float = param(0.1, "-", "initial weights (report: 0.1)", min=-100.0, max=100.0)
    fx_gain: float = param(1000.0, "N s/m", "Fx = fx_gain * u_X (report: 1000)", min=0.0, max=1e5)
    delta_gain: float = param(0.6, "rad s/m", "delta = delta_gain * u_Y (report: 0.6)", min=0.0, max=10.0)
    phi_lon: float = param(0.5, "m/s", "boundary layer on s_X (fixed variant; 0: sign)", min=0.0, max=100.0)
    phi_lat: float = param(0.1, "m/s", "boundary layer on s_Y (fixed variant; 0: sign)", min=0.0, max=100.0)
    feedforward: bool = feedforward_param()


# numpy's own routines without the module wrappers' dispatch (the same numbers): np.einsum
# without ``optimize`` hands its operands to this C function
try:
    from numpy._core.multiarray import c_einsum as _einsum
except ImportError:  # numpy < 2
    _einsum = np.einsum
_exp = np.exp
_RBF_SMC: Any = NATIVE.rbf_smc if NATIVE is not None else None


def _switch(s: float, phi: float) -> float:
    """sign(s), or sat(s/phi) inside a boundary layer of width phi."""
    if phi > 0.0:
        r = s / phi
        return 1.0 if r > 1.0 else (-1.0 if r < -1.0 else r)
    return 1.0 if s > 0.0 else (-1.0 if s < 0.0 else 0.0)


class RBFSMCController:
    """RBF adaptive sliding-mode control on both channels."""

    def __init__(self, params: RBFSMCParams, dt: float) -> None:
        self.params = params
        self.dt = dt
        self.report = params.variant == "report"
        self._x = np.empty(4)
        self._neg_two_w2 = -(2.0 * params.width * params.width)  #: -2 width^2 of the basis functions
        #: the network's step: the C twin when built, else :meth:`_network_py`
        self.native = _RBF_SMC is not None
        self._ctx: tuple[Any, ...] = ()
        self.reset(seed=0)

    def reset(self, *, seed: int | None = None) -> None:
        p = self.params
        rng = np.random.default_rng(seed)
        self.centres = p.centre_spread * rng.standard_normal((N_NODES, 4))
        self.w_lon = np.full(N_NODES, p.w0)
        self.w_lat = self.w_lon if self.report else np.full(N_NODES, p.w0)
        self.s_lon = self.s_lat = 0.0
        self.f_lon = self.f_lat = 0.0

    def _basis(self, x: np.ndarray) -> np.ndarray:
        diff = self.centres - x
        # -a / b as a / -b: IEEE division is symmetric in the signs (the same numbers, one call less)
        basis: np.ndarray = self.params.scale * _exp(_einsum("ij,ij->i", diff, diff) / self._neg_two_w2)
        return basis

    def step(self, obs: Observation) -> tuple[float, float]:
        p = self.params
        e_x, de_x = obs.s - obs.s_ref, obs.ds - obs.ds_ref
        e_y, de_y = obs.d - obs.d_ref, obs.dd - obs.dd_ref
        s_x = p.c_lon * e_x + de_x
        s_y = p.c_lat * e_y + de_y
        report = self.report
        # the adaptive law's steps: the report's one weight vector moves with s_X + s_Y
        if report:
            k_lon = k_lat = self.dt * p.gamma * (s_x + s_y)
        else:
            k_lon, k_lat = self.dt * p.gamma * s_x, self.dt * p.gamma * s_y
        if self.native:
            ctx = self._ctx
            if not ctx or ctx[1] is not self.centres or ctx[2] is not self.w_lon or ctx[3] is not self.w_lat:
                ctx = self._bind()
            f_x, f_y = _RBF_SMC(ctx, obs.s, obs.d, obs.ds, obs.dd, self._neg_two_w2, p.scale, k_lon, k_lat, not report)
        else:
            f_x, f_y = self._network_py(obs, k_lon, k_lat)
        if report:
            u_x = -s_x - f_x - p.eta_lon * _switch(s_x, 0.0)
            u_y = -s_y - f_y - p.eta_lat * _switch(s_x, 0.0)  # sic: the report's sign(s_X)
        else:
            u_x = -s_x - f_x - p.eta_lon * _switch(s_x, p.phi_lon)
            u_y = -s_y - f_y - p.eta_lat * _switch(s_y, p.phi_lat)
        self.s_lon, self.s_lat, self.f_lon, self.f_lat = s_x, s_y, f_x, f_y
        delta = p.delta_gain * u_y
        return p.fx_gain * u_x, (delta + obs.steer_ff if p.feedforward else delta)

    def _network_py(self, obs: Observation, k_lon: float, k_lat: float) -> tuple[float, float]:
        """The estimates (f_X, f_Y) = W^T h, then W += k h on each channel (the report's
        shared vector once): the reference of the C twin ``ego._native.rbf_smc``."""
        x = self._x
        x[0], x[1], x[2], x[3] = obs.s, obs.d, obs.ds, obs.dd
        h = self._basis(x)
        f_x = float(self.w_lon @ h)
        f_y = float(self.w_lat @ h)
        self.w_lon += k_lon * h
        if not self.report:
            self.w_lat += k_lat * h
        return f_x, f_y

    def _bind(self) -> tuple[Any, ...]:
        """What the C twin works on: the centres, the weights (in place), a work array's views
        and numpy's functions; bound again whenever one of those arrays is replaced."""
        n = len(self.w_lon)
        work = np.zeros(6 * n + 2)
        self._ctx = (
            work,
            self.centres,
            self.w_lon,
            self.w_lat,
            work[: 4 * n].reshape(n, 4),
            work[4 * n : 5 * n],
            work[5 * n : 6 * n],
            work[6 * n : 6 * n + 1].reshape(()),
            work[6 * n + 1 : 6 * n + 2].reshape(()),
            _einsum,
            "ij,ij->i",
            _exp,
            np.matmul,
            ("out",),
        )
        return self._ctx

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_ctx"] = ()  # views of a work array: made again after a copy
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self.native = self.native and _RBF_SMC is not None  # a process without the extension

    #: sliding variables s = c e + de, the RBF estimates f and their weights' norms, all in the
    #: units of u before the output gain (m/s: the basis functions are pure numbers)
    signal_units = {
        "s_lon": "m/s",
        "s_lat": "m/s",
        "f_hat_lon": "m/s",
        "f_hat_lat": "m/s",
        "rbf_norm_lon": "m/s",
        "rbf_norm_lat": "m/s",
    }

    def signals(self) -> dict[str, float]:
        return {
            "s_lon": self.s_lon,
            "s_lat": self.s_lat,
            "f_hat_lon": self.f_lon,
            "f_hat_lat": self.f_lat,
            "rbf_norm_lon": float(math.sqrt(self.w_lon @ self.w_lon)),
            "rbf_norm_lat": float(math.sqrt(self.w_lat @ self.w_lat)),
        }
