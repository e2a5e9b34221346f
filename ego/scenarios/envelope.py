"""The operating envelope of emergency-brake: sampled cases and the braking criterion that
classifies a collision.

A collision is *avoidable* when the ego, braking at its friction limit from the moment the
front TTC triggered the manoeuvre, would have stayed behind the braking lead car (the
lead's scripted speed profile is known exactly); a controller or planner that collides
there has failed. A collision braking could not have avoided is physics (only an
evasion could), and is reported as such, never hidden.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

import numpy as np

from ego.results.metrics import json_number
from ego.results.trace import Metric
from ego.scenarios.sensor import Detection

#: the envelope the issue asks for: (low, high) per parameter
RANGES = {
    "ego_speed": (15.0, 33.0),  # m/s
    "lead_decel": (3.0, 9.0),  # m/s^2
    "lead_gap": (20.0, 60.0),  # m
    "traffic_density": (0.0, 25.0),  # veh/km
}


def lead_speed(t: np.ndarray, speed: float, brake_time: float, decel: float, final: float) -> np.ndarray:
    """The lead car's scripted speed (m/s) at times ``t`` (s): ``speed`` until
    ``brake_time``, then falling at ``decel`` to ``final``."""
    if final >= speed:
        return np.full_like(t, speed)
    return np.maximum(final, speed - decel * np.clip(t - brake_time, 0.0, None))


def braking_min_gap(
    t0: float,
    gap0: float,
    ego_speed0: float,
    decel: float,
    lead_speed_fn: Callable[[np.ndarray], np.ndarray],
    horizon: float = 30.0,
    dt: float = 0.001,
    lead_step: float | None = None,
) -> float:
    """Smallest gap (m) over ``horizon`` seconds when the ego brakes at ``decel`` (m/s^2)
    from ``ego_speed0`` at ``t0`` with ``gap0`` to a lead moving at ``lead_speed_fn(t)``.

    With ``lead_step`` (s) the lead moves as the run sees it: SUMO steps fall on the
    simulation's clock (multiples of ``lead_step``, not ``t0`` plus multiples: a trigger comes
    between steps), each moves the lead by its speed at the step's end times the step (SUMO's
    Euler update; a braking car then covers ``decel * step^2 / 2`` less per step than the
    continuous profile), and between steps the surround sensor carries it on at its last
    step's speed, as ``gap0`` was measured. Without it the lead follows the continuous profile
    (trapezoidal rule)."""
    t = t0 + np.arange(0.0, horizon, dt)
    v_ego = np.maximum(ego_speed0 - decel * (t - t0), 0.0)
    ego_x = np.concatenate(([0.0], np.cumsum(0.5 * (v_ego[1:] + v_ego[:-1]) * dt)))
    if lead_step:
        tk = (np.floor(t0 / lead_step + 1e-9) + np.arange(int(horizon / lead_step) + 2)) * lead_step
        vk = lead_speed_fn(tk)
        xk = np.concatenate(([0.0], np.cumsum(vk[1:] * lead_step)))
        k = np.clip(np.floor((t - tk[0]) / lead_step + 1e-9).astype(int), 0, len(tk) - 2)
        lead_x = xk[k] + vk[k] * (t - tk[k])
        lead_x -= lead_x[0]
    else:
        v_lead = lead_speed_fn(t)
        lead_x = np.concatenate(([0.0], np.cumsum(0.5 * (v_lead[1:] + v_lead[:-1]) * dt)))
    return float(np.min(gap0 + lead_x - ego_x))


class ReachCriterion:
    """The braking criterion of a car that cuts in (cut-in's, issue 21): braking at the
    friction limit from the moment the car ``vehicle`` first intrudes into the ego's lane
    (becomes its front object), the car holding its speed from then on."""

    __slots__ = ("vehicle", "at")
    METRICS = (
        Metric("reach_time", "s", "when the cutting car first intruded into the ego's lane (became its front object)"),
        Metric(
            "collision_avoidable",
            "-",
            "true: braking at the friction limit from the moment the car "
            "intruded into the ego's lane would have kept the ego behind it, so the collision is the "
            "controller's or the planner's; false: physics (or the car hit the ego's side before it "
            "intruded into its lane); none: no collision",
        ),
    )

    def __init__(self, vehicle: str) -> None:
        self.vehicle = vehicle
        #: (t s, gap m, ego speed m/s, car's speed m/s) when the car first intruded into the ego's lane
        self.at: tuple[float, float, float, float] | None = None

    def watch(self, t: float, front: Detection, ds: float) -> None:
        """Each control period: ``front`` is the sensor's front object, ``ds`` the ego's speed."""
        if self.at is None and front.id == self.vehicle and front.gap != float("inf"):
            self.at = (t, front.gap, ds, front.speed)

    def margin(self, decel: float, lead_step: float) -> float | None:
        """The smallest gap (m) braking at ``decel`` from the reach would leave (the car moved
        as SUMO moves it, every ``lead_step`` s); None if the car never intruded."""
        if self.at is None:
            return None
        t0, gap, speed, car_speed = self.at
        return braking_min_gap(t0, gap, speed, decel, lambda t: np.full_like(t, car_speed), lead_step=lead_step)

    def metrics(self, collided: bool, decel: float, lead_step: float) -> dict[str, Any]:
        """``reach_time`` and ``collision_avoidable`` (none without a collision; false when the
        car hit the ego's side before it intruded into its lane: no time to brake)."""
        margin = self.margin(decel, lead_step)
        return {
            "reach_time": json_number(self.at[0] if self.at else None, 4),
            "collision_avoidable": None if not collided else False if margin is None else bool(margin > 0.0),
        }


def avoidable(
    metrics: dict[str, Any], trace_gap_at_trigger: float, ego_speed_at_trigger: float, config: Any, decel_limit: float
) -> bool:
    """Would braking at ``decel_limit`` from the trigger have kept the ego behind the lead (the
    lead moving as SUMO moves it, step by step)?"""

    def fn(t: np.ndarray) -> np.ndarray:
        return lead_speed(
            t, config.lead_cruise_speed, config.lead_brake_time, config.lead_decel, config.lead_final_speed
        )

    return (
        braking_min_gap(
            metrics["trigger_time"],
            trace_gap_at_trigger,
            ego_speed_at_trigger,
            decel_limit,
            fn,
            lead_step=config.sumo_step,
        )
        > 0.0
    )


def sample(n: int, seed: int) -> Iterator[dict[str, Any]]:
    """``n`` Latin-hypercube cases over :data:`RANGES` with random lane blockers (about one
    case in four blocks a lane, one in eight both)."""
    from scipy.stats import qmc

    names = list(RANGES)
    lo = np.array([RANGES[k][0] for k in names])
    hi = np.array([RANGES[k][1] for k in names])
    points = qmc.scale(qmc.LatinHypercube(d=len(names), seed=seed).random(n), lo, hi)
    rng = np.random.default_rng(seed)
    for row in points:
        case: dict[str, Any] = {k: round(float(v), 2) for k, v in zip(names, row)}
        u = rng.random()
        case["block_left"] = bool(u < 0.125 or 0.25 <= u < 0.375)
        case["block_right"] = bool(u < 0.25)
        case["seed"] = int(rng.integers(0, 10_000))
        yield case
