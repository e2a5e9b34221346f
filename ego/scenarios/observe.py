"""The observation builders: one per task, shared by every scenario of that task.

A road task's controller (``tracking``, ``curve``) sees the ego in the lane frame of its
reference lane (``ego.control.Observation``); :func:`road_observation` is the one place that
fills it from the road sensor's measurements. The references (``s_ref``, ``d_ref``,
``accel_ref``...) are the manoeuvre's to set. Observations are keyed by vehicle id
(:meth:`ego.scenarios.base.Scenario.observations`): one entry for a single ego, one per
follower in the platoon.
"""

from __future__ import annotations

from collections.abc import Sequence

from ego.control.base import Observation
from ego.models.cornering import SteadySteer


def road_observation(
    obs: Observation,
    t: float,
    s: float,
    ds: float,
    d: float,
    dd: float,
    state: Sequence[float],
    heading_error: float,
    curvature: float,
    steady: SteadySteer | None = None,
) -> None:
    """Fill ``obs`` in place (it is the controller's, reused every step): time ``t`` (s), the
    centre of gravity at ``s`` along the lane and ``d`` across it (m, + left) moving at
    ``ds``/``dd`` (m/s), the plant's ``state`` (X, u, Y, v, psi, r) for the body speeds and yaw
    rate, the heading error (rad) and the lane's curvature (1/m); ``steady`` (the plant's
    :class:`~ego.models.cornering.SteadySteer`) makes ``steer_ff`` its steady-state steer on
    that curvature at the body speed (rad; without it 0)."""
    obs.t = t
    obs.s = s
    obs.ds = ds
    obs.d = d
    obs.dd = dd
    obs.speed = state[1]
    obs.yaw_rate = state[5]
    obs.vy = state[3]
    obs.heading_error = heading_error
    obs.curvature = curvature
    if steady is not None:  # SteadySteer.__call__, inline: every control period
        u = state[1]
        obs.steer_ff = curvature * (steady.wheelbase + steady.understeer * u * u)
