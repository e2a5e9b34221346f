"""A scenario without SUMO for testing the kit's edges (compare, run, list): a point mass
on a straight line tracking a position that moves at a constant reference speed.

It declares its trace columns, metrics and plots the way every scenario does and drives the
tracking task's controllers (Fx per driven wheel; delta is ignored).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ego.params import param
from ego.results.metrics import json_number, settling_time
from ego.results.trace import Column, Metric, Plot
from ego.scenarios.base import PartsLoop, Scenario, TimingConfig

DRIVEN_WHEELS = 2


@dataclass(frozen=True)
class PointMassConfig(TimingConfig):
    """A short run of a point mass chasing a moving reference."""

    duration: float = param(4.0, "s", "simulated time", min=0.1, max=60.0)
    ref_speed: float = param(10.0, "m/s", "speed of the reference position", min=0.0, max=40.0)
    mass: float = param(1500.0, "kg", "mass of the point", min=100.0, max=5000.0)


class PointMass(Scenario):
    """Position s (m) and speed v (m/s); a = DRIVEN_WHEELS * Fx / mass, explicit Euler."""

    name = "point-mass"
    summary = "a point mass chasing a moving reference (tests only, no SUMO)"
    task = "tracking"
    config_cls = PointMassConfig
    columns = (
        Column("t", "s", "time"),
        Column("s", "m", "position"),
        Column("speed", "m/s", "speed"),
        Column("e_lon", "m", "position - reference"),
        Column("Fx", "N", "force per driven wheel"),
    )
    metric_specs = (
        Metric("rms_speed_error", "m/s", "RMS of speed - reference speed", headline=True),
        Metric("final_position", "m", "position at the end"),
        Metric("settle_times.", "s", "time until |speed error| stays within each band", headline=True),
        Metric("reached_speed", "-", "the speed came within 1 m/s of the reference", headline=True),
    )
    plots = (
        Plot("speed", "speed.png", "speed"),
        Plot("e_lon", "lon_error.png", "position error"),
    )

    def make_loop(self) -> PointMassLoop:
        return PointMassLoop(self)

    def _metrics(self, trace: np.ndarray, columns: tuple[str, ...]) -> dict:
        t = trace[:, columns.index("t")]
        error = trace[:, columns.index("speed")] - self.config.ref_speed
        return {
            "rms_speed_error": json_number(math.sqrt(float(np.mean(error**2)))),
            "final_position": json_number(self.loop.position),
            "settle_times": {f"band{band:g}": json_number(settling_time(t, error, band, 0.0)) for band in (5.0, 1.0)},
            "reached_speed": bool(np.any(np.abs(error) < 1.0)),
        }


class PointMassLoop(PartsLoop):
    """The point mass's loop: its own explicit Euler step, the reference of time, no simulator."""

    def setup(self, rng: np.random.Generator) -> None:
        self.position = 0.0
        self.velocity = 0.0

    def act(self, action: tuple[float, float]) -> None:
        sc = self.sc
        fx, _ = action
        c = sc.config
        sc.trace.append(
            sc.controller.signals(),
            t=sc.t,
            s=self.position,
            speed=self.velocity,
            e_lon=self.position - c.ref_speed * sc.t,
            Fx=fx,
        )
        self.velocity += DRIVEN_WHEELS * fx / c.mass * c.dt
        self.position += self.velocity * c.dt

    def update(self) -> None:
        sc = self.sc
        obs, c = sc.obs, sc.config
        obs.t = sc.t
        obs.s_ref, obs.ds_ref = c.ref_speed * sc.t, c.ref_speed
        obs.s, obs.ds, obs.speed = self.position, self.velocity, self.velocity
