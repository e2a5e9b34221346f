"""The trajectory shapes of a FollowTrajectoryAction besides the polyline: clothoids (one, or a
clothoid spline's segments) and NURBS, sampled into dense polylines that the trajectory
follower moves an entity along (:class:`ego.openscenario.actions.FollowTrajectory`).

A clothoid's heading is h(s) = h0 + k0 s + c s^2 / 2 (curvature k0 + c s); its points are the
integrals of (cos h, sin h), taken here by Simpson's rule on 2 cm panels (the error is of the
order of panel^4 k^3 per metre: far below a micrometre for any road curvature). A NURBS curve
is the rational combination of its control points with the B-spline basis of its knots (Cox-de
Boor); a control point's time is combined the same way (the reference player's reading: the
standard gives each control point a time and says nothing of the times between)."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

#: the spacing (m) of the polyline a clothoid is sampled into
CLOTHOID_STEP = 0.1
#: Simpson panels per polyline step
PANELS = 5
#: samples of a NURBS curve's parameter
NURBS_SAMPLES = 2001


def clothoid(
    x0: float, y0: float, h0: float, k0: float, k1: float, length: float, step: float = CLOTHOID_STEP
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Points of the clothoid from (x0, y0) with heading h0 (rad), whose curvature goes
    linearly from k0 to k1 (1/m) over ``length`` (m): (x, y, heading, s) every ``step`` m
    (and at the end)."""
    n = max(1, math.ceil(length / step - 1e-9))
    c = (k1 - k0) / length
    # Simpson's rule on 2 n PANELS sub-intervals between the samples
    m = 2 * PANELS * n
    s = np.linspace(0.0, length, m + 1)
    h = h0 + k0 * s + 0.5 * c * s * s
    w = np.ones(m + 1)
    w[1:-1:2], w[2:-1:2] = 4.0, 2.0
    ds = length / m
    cos, sin = np.cos(h), np.sin(h)
    # the integral up to every sample (every 2 PANELS sub-intervals)
    xs, ys = [x0], [y0]
    per = 2 * PANELS
    for i in range(n):
        a, b = i * per, (i + 1) * per
        ww = w[a : b + 1].copy()
        ww[0] = ww[-1] = 1.0
        xs.append(xs[-1] + ds / 3.0 * float(ww @ cos[a : b + 1]))
        ys.append(ys[-1] + ds / 3.0 * float(ww @ sin[a : b + 1]))
    ss = s[::per]
    return np.array(xs), np.array(ys), h[::per], ss


def basis(knots: Sequence[float], order: int, u: np.ndarray) -> np.ndarray:
    """The B-spline basis functions of ``order`` (degree + 1) on ``knots`` at the parameters
    ``u``: an array (len(u), len(knots) - order) (Cox-de Boor; the last knot span closed)."""
    t = np.asarray(knots, dtype=float)
    n_spans = len(t) - 1
    b = np.zeros((len(u), n_spans))
    last = np.max(np.nonzero(t[1:] > t[:-1])[0])  # the last non-empty span
    for i in range(n_spans):
        if t[i + 1] > t[i]:
            inside = (u >= t[i]) & (u < t[i + 1])
            if i == last:
                inside |= u == t[i + 1]
            b[:, i] = inside
    for k in range(2, order + 1):
        nb = np.zeros((len(u), n_spans - k + 1))
        for i in range(n_spans - k + 1):
            left = t[i + k - 1] - t[i]
            right = t[i + k] - t[i + 1]
            if left > 0:
                nb[:, i] += (u - t[i]) / left * b[:, i]
            if right > 0:
                nb[:, i] += (t[i + k] - u) / right * b[:, i + 1]
        b = nb
    return b


def nurbs(
    points: Sequence[tuple[float, float]],
    weights: Sequence[float],
    knots: Sequence[float],
    order: int,
    times: Sequence[float] | None = None,
    samples: int = NURBS_SAMPLES,
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """The NURBS curve sampled at ``samples`` parameters over its domain [knot[order - 1],
    knot[n]]: (x, y, times or None), the times combined like the points."""
    n = len(points)
    u = np.linspace(knots[order - 1], knots[n], samples)
    b = basis(knots, order, u)
    w = np.asarray(weights, dtype=float)
    bw = b * w
    den = bw.sum(axis=1)
    p = np.asarray(points, dtype=float)
    x = bw @ p[:, 0] / den
    y = bw @ p[:, 1] / den
    tt = None if times is None else bw @ np.asarray(times, dtype=float) / den
    return x, y, tt
