"""Report 003's linear lateral-error model: the bicycle in the lane's frame at constant speed.

State ``x = [e, psi_err, vy, r]``: lateral offset of the centre of gravity from the lane
centre (m, positive left), heading minus the lane's heading (rad, positive left), body
lateral speed (m/s) and yaw rate (rad/s). Input: front steer delta (rad, positive left);
exogenous: the lane's curvature kappa (1/m, positive left) at the car. Speed v is constant.

    de/dt       = vy + v psi_err
    dpsi_err/dt = r - v kappa
    dvy/dt      = -(2Cf + 2Cr)/(m v) vy - (v + (2Cf lf - 2Cr lr)/(m v)) r + 2Cf/m delta
    dr/dt       = -(2Cf lf - 2Cr lr)/(Iz v) vy - (2Cf lf^2 + 2Cr lr^2)/(Iz v) r + 2Cf lf/Iz delta

**fix** (SPEC.md): the report drops the -v r in dvy/dt (the centripetal term of the body
frame); without it a car on a curve would need no steering at steady state. Stiffnesses
are per tyre and positive here (two tyres per axle).

Being linear and time-invariant at a given speed, it is integrated exactly over a step
with the input held (zero-order hold, :meth:`LateralError.discrete`); the tuner and the
scenario use the same matrices, and :meth:`LateralError.rhs` serves the generic RK4.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class LateralErrorParams:
    """Report 003's car."""

    m: float = 1650.0  #: mass (kg)
    Iz: float = 3200.0  #: yaw moment of inertia (kg m^2)
    lf: float = 1.25  #: centre of gravity to front axle (m)
    lr: float = 1.55  #: centre of gravity to rear axle (m)
    Cf: float = 65000.0  #: front cornering stiffness PER TYRE (N/rad, positive)
    Cr: float = 65000.0  #: rear cornering stiffness PER TYRE (N/rad, positive)

    @property
    def wheelbase(self) -> float:
        return self.lf + self.lr

    @property
    def understeer_gradient(self) -> float:
        """K_us (rad/(m/s^2)) = (m/L) (lr/(2Cf) - lf/(2Cr))."""
        return self.m / self.wheelbase * (self.lr / (2.0 * self.Cf) - self.lf / (2.0 * self.Cr))

    def feedforward(self, kappa: float, speed: float) -> float:
        """Steady-state steer on curvature ``kappa`` at ``speed``: kappa (L + K_us v^2).

        (**fix**: the report writes L kappa / (1 + K v^2) with a mis-scaled K.)"""
        return kappa * (self.wheelbase + self.understeer_gradient * speed * speed)


class LateralError:
    """The model at one ``speed`` (m/s)."""

    state_names = ("E", "PSI_ERR", "VY", "R")

    def __init__(self, params: LateralErrorParams | None = None, speed: float = 8.0) -> None:
        if not speed > 0:
            raise ValueError(f"the lateral-error model needs a positive speed, got {speed}")
        self.params = p = params if params is not None else LateralErrorParams()
        self.speed = v = float(speed)
        cf, cr = 2.0 * p.Cf, 2.0 * p.Cr  # per axle
        a33 = -(cf + cr) / (p.m * v)
        a34 = -v - (cf * p.lf - cr * p.lr) / (p.m * v)
        a43 = -(cf * p.lf - cr * p.lr) / (p.Iz * v)
        a44 = -(cf * p.lf**2 + cr * p.lr**2) / (p.Iz * v)
        self.A = np.array([[0.0, v, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0], [0.0, 0.0, a33, a34], [0.0, 0.0, a43, a44]])
        self.B = np.array([0.0, 0.0, cf / p.m, cf * p.lf / p.Iz])  # per rad of steer
        self.E = np.array([0.0, -v, 0.0, 0.0])  # per 1/m of curvature
        b3, b4 = cf / p.m, cf * p.lf / p.Iz

        def rhs(x: Sequence[float], u: Sequence[float]) -> tuple[float, ...]:
            _, psi, vy, r = x
            delta, kappa = u
            return (vy + v * psi, r - v * kappa, a33 * vy + a34 * r + b3 * delta, a43 * vy + a44 * r + b4 * delta)

        self.rhs = rhs

    def derivatives(self, x: Sequence[float], u: Sequence[float]) -> np.ndarray:
        """dx/dt for ``x = [e, psi_err, vy, r]`` and ``u = [delta, kappa]``."""
        return np.array(self.rhs(tuple(map(float, x)), tuple(map(float, u))))

    def discrete(self, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(Ad, Bd, Ed): x(k+1) = Ad x(k) + Bd delta(k) + Ed kappa(k), exact for inputs held
        over ``dt`` (the matrix exponential of the augmented system, :func:`expm_fixed_order`:
        the same bits on every processor)."""
        n = 4
        M = np.zeros((n + 2, n + 2))
        M[:n, :n] = self.A
        M[:n, n] = self.B
        M[:n, n + 1] = self.E
        Md = expm_fixed_order(M * dt)
        return Md[:n, :n].copy(), Md[:n, n].copy(), Md[:n, n + 1].copy()

    def columns(self, dt: float) -> list[np.ndarray]:
        """The zero-order-hold matrices as columns [c_e, c_psi, c_vy, c_r, c_delta, c_kappa]:
        x' = c_e e + c_psi psi + c_vy vy + c_r r + c_delta delta + c_kappa kappa."""
        Ad, Bd, Ed = self.discrete(dt)
        return [Ad[:, j].copy() for j in range(4)] + [Bd, Ed]

    def stepper(self, dt: float) -> Callable[[Sequence[float], float, float], tuple[float, ...]]:
        """``step(x, delta, kappa) -> x'`` over ``dt`` on plain floats, summing the columns
        in :meth:`columns` order (the tuner's batch simulation does the same)."""
        cols = [tuple(float(v) for v in c) for c in self.columns(dt)]
        rows = tuple(tuple(c[i] for c in cols) for i in range(4))

        def step(x: Sequence[float], delta: float, kappa: float) -> tuple[float, ...]:
            e, psi, vy, r = x
            return tuple(a * e + b * psi + c * vy + d * r + f * delta + g * kappa for a, b, c, d, f, g in rows)

        return step

    def steady_state(self, kappa: float) -> tuple[np.ndarray, float]:
        """(state with e = 0, steer) that hold the car on curvature ``kappa`` forever."""
        v = self.speed
        # unknowns psi, vy, delta with r = v kappa: rows 1, 3, 4 of A x + B delta + E kappa = 0
        r = v * kappa
        A, B = self.A, self.B
        M = np.array([[v, 1.0, 0.0], [0.0, A[2, 2], B[2]], [0.0, A[3, 2], B[3]]])
        rhs = -np.array([0.0, A[2, 3] * r, A[3, 3] * r])
        psi, vy, delta = np.linalg.solve(M, rhs)
        return np.array([0.0, psi, vy, r]), float(delta)

    def lateral_accel(self, x: Sequence[float], delta: float) -> float:
        """a_y = dvy/dt + v r (m/s^2)."""
        return float(self.A[2, 2] * x[2] + self.A[2, 3] * x[3] + self.B[2] * delta + self.speed * x[3])


#: Taylor terms of exp(X) for ||X||_1 <= 1/2: the first left out, 0.5^19 / 19!, is ~1e-23
_TAYLOR_TERMS = 18


def expm_fixed_order(m: np.ndarray) -> np.ndarray:
    """exp(m) of a small square matrix with every sum in one fixed order on Python floats:
    the same bits on every processor.

    Scaling and squaring of a Taylor series: m / 2^s with ``||m / 2^s||_1 <= 1/2``, the
    series to a fixed 18 terms (the next would be below 1e-22 of the sum), then s squarings.
    scipy's ``expm`` gives the same matrix to a few units in the last place, but it multiplies
    through BLAS, whose kernels (picked by the processor: OpenBLAS's Haswell, SkylakeX, ...)
    add in different orders; report 003's unstable gains amplify that last bit into another
    run, so a results table made on one processor did not regenerate on another. The 6 x 6
    of a lane-centring plant takes ~1 ms, once per run and speed."""
    a = [[float(v) for v in row] for row in np.asarray(m, dtype=float)]
    n = len(a)
    if any(len(row) != n for row in a):
        raise ValueError(f"expm_fixed_order needs a square matrix, got {np.shape(m)}")
    norm = max((sum(abs(a[i][j]) for i in range(n)) for j in range(n)), default=0.0)
    if not math.isfinite(norm):
        raise ValueError("expm_fixed_order needs a finite matrix")
    s = 0
    while norm > 0.5:
        norm *= 0.5
        s += 1
    scale = 0.5**s  # a power of two: exact
    x = [[v * scale for v in row] for row in a]

    def mul(p: list[list[float]], q: list[list[float]]) -> list[list[float]]:
        out = []
        for i in range(n):
            pi = p[i]
            row = []
            for j in range(n):
                acc = 0.0
                for k in range(n):
                    acc += pi[k] * q[k][j]
                row.append(acc)
            out.append(row)
        return out

    result = [[1.0 if i == j else 0.0 for j in range(n)] for i in range(n)]
    term = [row[:] for row in result]
    for k in range(1, _TAYLOR_TERMS + 1):
        term = [[v / k for v in row] for row in mul(term, x)]
        result = [[r + t for r, t in zip(rr, tr)] for rr, tr in zip(result, term)]
    for _ in range(s):
        result = mul(result, result)
    return np.array(result)
