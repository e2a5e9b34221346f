"""String stability of a platoon: the linear theory and the measurements (pure numpy).

A platoon is *string stable* when disturbances shrink as they travel down it. For
predecessor following with the constant time-headway policy delta_d = gap - d_s - lambda v,
a follower whose command is u = K(s) delta_d, with K(s) = kp + ki/s + kd s (the derivative
acting on the measured d(delta_d)/dt), an actuator lag 1/(tau s + 1) and a delay theta
(a controller sampling every T s holds its command, which delays it by about T/2), has
from its predecessor's speed to its own

    H(s) = K e^(-s theta) / (s^2 (tau s + 1) + K e^(-s theta) (lambda s + 1))

(speeds, accelerations and - from the second follower on - spacing errors all propagate
through the same H). The platoon is string stable in the L2 sense iff |H(jw)| <= 1 at every
frequency. With no lag and no delay this needs lambda >= sqrt(2 / kp), whatever ki and kd:
|D|^2 - |N|^2 = ki^2 lambda^2 w^2 + (kp^2 lambda^2 - 2 kp - 2 ki lambda (1 + kd lambda)) w^4
+ (1 + kd lambda)^2 w^6, which stays positive for all w exactly when kp lambda^2 >= 2.

Measured counterparts (from a run's traces): the ratio of the peak and of the L2 norm of a
signal between consecutive vehicles, and the gain at the frequency of a sinusoidal leader.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

#: frequencies scanned for the peak gain (rad/s)
OMEGAS = np.logspace(-3, 2, 5000)


def pid_transfer(
    omega: ArrayLike, kp: float, ki: float, kd: float, headway: float, lag: float = 0.0, delay: float = 0.0
) -> np.ndarray:
    """H(jw) from the predecessor's speed to the follower's (see the module docstring)."""
    s = 1j * np.asarray(omega, dtype=float)
    k = (kp + kd * s + ki / s) * np.exp(-s * delay)
    return k / (s * s * (lag * s + 1.0) + k * (headway * s + 1.0))


def peak_gain(transfer: Callable[[np.ndarray], np.ndarray], omegas: np.ndarray = OMEGAS) -> tuple[float, float]:
    """(max |H(jw)|, the w where it peaks) of a callable H(omega) -> complex array."""
    gains = np.abs(transfer(omegas))
    i = int(np.argmax(gains))
    return float(gains[i]), float(omegas[i])


def min_stable_headway(
    kp: float, ki: float, kd: float, lag: float = 0.0, delay: float = 0.0, upper: float = 30.0, tol: float = 1e-4
) -> float | None:
    """Smallest time headway lambda (s) with max |H| <= 1, by bisection; None above ``upper``.

    The low-frequency limit of |H| is 1 from below when stable, so 1 + 1e-9 is the test."""

    def stable(h: float) -> bool:
        return peak_gain(lambda w: pid_transfer(w, kp, ki, kd, h, lag, delay))[0] <= 1.0 + 1e-9

    if not stable(upper):
        return None
    lo, hi = 0.0, upper
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if stable(mid) else (mid, hi)
    return hi


def peak_ratio(upstream: np.ndarray, downstream: np.ndarray, floor: float = 0.0) -> float | None:
    """max |downstream| / max |upstream|; None when the upstream signal never exceeds
    ``floor`` (a ratio of two noises says nothing)."""
    top = float(np.max(np.abs(upstream))) if len(upstream) else 0.0
    return float(np.max(np.abs(downstream))) / top if top > floor else None


def l2_ratio(upstream: np.ndarray, downstream: np.ndarray, floor: float = 0.0) -> float | None:
    """||downstream||_2 / ||upstream||_2 over the same samples; None when the upstream
    signal never exceeds ``floor`` in magnitude."""
    if not len(upstream) or float(np.max(np.abs(upstream))) <= floor:
        return None
    return float(np.sqrt(np.sum(np.square(downstream)) / np.sum(np.square(upstream))))


def sine_amplitude(t: np.ndarray, x: np.ndarray, omega: float) -> complex:
    """Complex amplitude A + jB of x ~ A sin(wt) + B cos(wt) + c (least squares)."""
    basis = np.column_stack([np.sin(omega * t), np.cos(omega * t), np.ones_like(t)])
    coef, *_ = np.linalg.lstsq(basis, x, rcond=None)
    return complex(coef[0], coef[1])


def sine_gain(t: np.ndarray, upstream: np.ndarray, downstream: np.ndarray, omega: float) -> float | None:
    """|amplitude of downstream| / |amplitude of upstream| at ``omega`` (rad/s), fitted over
    the whole periods at the end of ``t`` (the caller drops the transient)."""
    period = 2.0 * math.pi / omega
    whole = math.floor((t[-1] - t[0]) / period)
    if whole < 1:
        return None
    keep = t >= t[-1] - whole * period
    a_up = abs(sine_amplitude(t[keep], upstream[keep], omega))
    return abs(sine_amplitude(t[keep], downstream[keep], omega)) / a_up if a_up > 0.0 else None
