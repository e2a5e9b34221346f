"""Actuator limits shared by every plant: steer angle and rate, longitudinal command
limits, and the standstill rule (braking stops the car, it never reverses it).

Pure functions and one frozen dataclass; each plant applies :meth:`ActuatorLimits.apply`
before it integrates, and reports the applied (saturated) input. The friction-aware
drive/brake limit of report 000's car sits in its model (``NonlinearBicycleParams.abs``),
because it depends on the tyre forces inside every integration stage.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

INF = math.inf


def clip(value: float, lo: float, hi: float) -> float:
    """``value`` limited to [lo, hi]."""
    return lo if value < lo else (hi if value > hi else value)


def rate_limit(value: float, previous: float, max_rate: float, dt: float) -> float:
    """``value`` moved at most ``max_rate * dt`` away from ``previous``."""
    step = max_rate * dt
    return clip(value, previous - step, previous + step)


def standstill(command: float, speed: float, stop_speed: float) -> float:
    """A braking (negative) command fades linearly below ``stop_speed`` (m/s) to zero at rest,
    so it stops the car instead of reversing it (the reports' models have no standstill)."""
    if command < 0.0 and speed < stop_speed:
        return command * (speed if speed > 0.0 else 0.0) / stop_speed
    return command


@dataclass(frozen=True)
class ActuatorLimits:
    """Limits of one car's actuators. ``command`` is the longitudinal input (Fx per driven
    wheel in N, or an acceleration in m/s^2, whatever the plant takes)."""

    max_steer: float = 0.5  #: |delta| limit (rad)
    max_steer_rate: float = INF  #: |d delta/dt| limit (rad/s)
    min_command: float = -INF  #: most negative longitudinal command (N or m/s^2)
    max_command: float = INF  #: largest longitudinal command (N or m/s^2)
    stop_speed: float = 0.5  #: braking fades below this speed (m/s); 0: no standstill rule

    def apply(
        self, command: float, delta: float, speed: float, previous_delta: float, dt: float
    ) -> tuple[float, float]:
        """The applied (command, delta) for a car at ``speed`` (m/s) whose steer was
        ``previous_delta`` (rad) one period ``dt`` (s) ago."""
        ms = self.max_steer
        delta = ms if delta > ms else (-ms if delta < -ms else delta)
        if self.max_steer_rate != INF:
            delta = rate_limit(delta, previous_delta, self.max_steer_rate, dt)
        if command < self.min_command:
            command = self.min_command
        elif command > self.max_command:
            command = self.max_command
        stop = self.stop_speed
        if stop > 0.0 and command < 0.0 and speed < stop:  # standstill(), inline: every control period
            command = command * (speed if speed > 0.0 else 0.0) / stop
        return command, delta
