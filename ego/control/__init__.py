"""Controllers and their registry (the names the CLI accepts)."""

from __future__ import annotations

from dataclasses import dataclass

from ego.control.base import Controller, ControllerSpec, Observation
from ego.control.bp_pid import BPPIDController, BPPIDParams
from ego.control.fuzzy import FuzzyController, FuzzyParams
from ego.control.fuzzy_pid import FuzzyPIDController, FuzzyPIDParams
from ego.control.pid import PID, PIDController, PIDParams
from ego.control.rbf_smc import RBFSMCController, RBFSMCParams
from ego.params import ConfigError


@dataclass(frozen=True)
class NoParams:
    """No parameters."""


class NoController:
    """Controller switched off: Fx = 0 and delta = 0, so the ego coasts straight on."""

    def __init__(self, params: NoParams, dt: float) -> None:
        pass

    def reset(self, *, seed: int | None = None) -> None:
        pass

    def step(self, obs: Observation) -> tuple[float, float]:
        return 0.0, 0.0

    def signals(self) -> dict[str, float]:
        return {}


CONTROLLERS: dict[str, ControllerSpec] = {
    spec.name: spec
    for spec in (
        ControllerSpec("fuzzy", "report 000's 7x7 Mamdani fuzzy controller on both channels",
                       FuzzyParams, FuzzyController),
        ControllerSpec("pid", "PID baseline with anti-windup and filtered derivative",
                       PIDParams, PIDController),
        ControllerSpec("fuzzy-pid", "report 000's fuzzy-adaptive PID (classic dKp/dKi/dKd tables)",
                       FuzzyPIDParams, FuzzyPIDController),
        ControllerSpec("bp-pid", "report 000's BP neural-network PID (default: stabilised learning)",
                       BPPIDParams, BPPIDController),
        ControllerSpec("rbf-smc", "report 000's RBF adaptive sliding-mode control",
                       RBFSMCParams, RBFSMCController),
        ControllerSpec("none", "controller off: Fx = 0, delta = 0 (the ego coasts)",
                       NoParams, NoController),
    )
}


def controller_spec(name: str) -> ControllerSpec:
    """The registered controller ``name``, or a ConfigError naming the allowed ones."""
    try:
        return CONTROLLERS[name]
    except KeyError:
        raise ConfigError(
            f"unknown controller {name!r} (known: {', '.join(CONTROLLERS)})"
        ) from None


__all__ = [
    "BPPIDController",
    "BPPIDParams",
    "CONTROLLERS",
    "FuzzyPIDController",
    "FuzzyPIDParams",
    "RBFSMCController",
    "RBFSMCParams",
    "Controller",
    "ControllerSpec",
    "FuzzyController",
    "FuzzyParams",
    "NoController",
    "Observation",
    "PID",
    "PIDController",
    "PIDParams",
    "controller_spec",
]
