"""Fixed-step integration shared by every model.

A model exposes ``rhs(x, u) -> tuple`` on plain float sequences (the fast path used in
the simulation loop) and ``derivatives(x, u) -> ndarray`` (the public, array-returning
form). :func:`rk4_step` integrates any dimension; :class:`FixedStepIntegrator` uses a
version unrolled for the state dimension (generated once per dimension), which runs
several times faster in CPython than the generic loop over components.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from functools import cache
from typing import Any

#: a model's ``stepper(...)``: ``step(state, first input, second input) -> (state, lateral
#: acceleration m/s^2)``
Stepper = Callable[[Sequence[float], float, float], tuple[tuple[float, ...], float]]

Rhs = Callable[[Sequence[float], Sequence[float]], Sequence[float]]


def rk4_step(
    rhs: Rhs, x: Sequence[float], u: Sequence[float], h: float, k1: Sequence[float] | None = None
) -> tuple[float, ...]:
    """Advance ``x`` by one classical Runge-Kutta step of length ``h`` (s), input held.

    ``rhs(x, u)`` returns dx/dt. The input ``u`` is held constant over the step
    (zero-order hold), as a sampled controller does. ``k1`` may pass ``rhs(x, u)`` when
    the caller has already evaluated it.
    """
    half = 0.5 * h
    if k1 is None:
        k1 = rhs(x, u)
    k2 = rhs([xi + half * ki for xi, ki in zip(x, k1)], u)
    k3 = rhs([xi + half * ki for xi, ki in zip(x, k2)], u)
    k4 = rhs([xi + h * ki for xi, ki in zip(x, k3)], u)
    sixth = h / 6.0
    return tuple(xi + sixth * (a + 2.0 * b + 2.0 * c + d) for xi, a, b, c, d in zip(x, k1, k2, k3, k4))


@cache
def unrolled_rk4(n: int) -> Callable[..., tuple[float, ...]]:
    """:func:`rk4_step` written out for an ``n``-dimensional state (same arithmetic)."""
    idx = range(n)
    xs = ", ".join(f"x{i}" for i in idx)

    def unpack(name: str) -> str:
        return ", ".join(f"{name}{i}" for i in idx) + ("," if n == 1 else "")

    def stage(name: str, scale: str) -> str:
        return "(" + ", ".join(f"x{i} + {scale} * {name}{i}" for i in idx) + ("," if n == 1 else "") + ")"

    src = f"""
def rk4(rhs, x, u, h, k1=None):
    {xs}{"," if n == 1 else ""} = x
    if k1 is None:
        k1 = rhs(x, u)
    {unpack("a")} = k1
    half = 0.5 * h
    {unpack("b")} = rhs({stage("a", "half")}, u)
    {unpack("c")} = rhs({stage("b", "half")}, u)
    {unpack("d")} = rhs({stage("c", "h")}, u)
    sixth = h / 6.0
    return ({", ".join(f"x{i} + sixth * (a{i} + 2.0 * b{i} + 2.0 * c{i} + d{i})" for i in idx)}{"," if n == 1 else ""})
"""
    namespace: dict[str, Any] = {}
    exec(compile(src, f"<rk4 unrolled for {n} states>", "exec"), namespace)
    rk4: Callable[..., tuple[float, ...]] = namespace["rk4"]
    return rk4


class FixedStepIntegrator:
    """RK4 over one control period split into ``substeps`` equal physics steps.

    Multi-rate stepping is explicit: the control period ``dt`` (s) is what the
    controller sees; ``substeps`` physics steps of ``dt / substeps`` are taken inside it.
    ``n_states`` selects the unrolled stepper; without it the generic one is used.
    """

    __slots__ = ("rhs", "dt", "substeps", "_h", "_rk4")

    def __init__(self, rhs: Rhs, dt: float, substeps: int = 1, n_states: int | None = None) -> None:
        if not dt > 0.0:
            raise ValueError(f"dt must be > 0 s, got {dt!r}")
        if int(substeps) != substeps or substeps < 1:
            raise ValueError(f"substeps must be a whole number >= 1, got {substeps!r}")
        self.rhs = rhs
        self.dt = float(dt)
        self.substeps = int(substeps)
        self._h = self.dt / self.substeps
        self._rk4 = unrolled_rk4(n_states) if n_states else rk4_step

    def step(self, x: Sequence[float], u: Sequence[float], k1: Sequence[float] | None = None) -> tuple[float, ...]:
        """Integrate one control period with the input held; returns the new state.

        ``k1``, when given, is ``rhs(x, u)`` already evaluated by the caller.
        """
        h = self._h
        rhs = self.rhs
        rk4 = self._rk4
        x = rk4(rhs, x, u, h, k1)
        for _ in range(self.substeps - 1):
            x = rk4(rhs, x, u, h)
        return x
