"""Controllers and their registry (the names the CLI accepts)."""

from __future__ import annotations

from ego.control.base import Controller, ControllerSpec, NoParams, Observation
from ego.control.bp_pid import BPPIDController, BPPIDParams
from ego.control.careful import CarefulDriver, CarefulDriverParams
from ego.control.cascade import CascadePID, CascadePIDParams
from ego.control.curve import CurvePID, CurvePIDParams, FuzzyCurve, FuzzyCurveParams
from ego.control.following import (
    BPPIDAcc,
    BPPIDAccParams,
    FollowingObservation,
    FollowingPID,
    FollowingPIDParams,
    PlatoonControl,
)
from ego.control.fuzzy import FuzzyController, FuzzyParams
from ego.control.fuzzy_pid import FuzzyPIDController, FuzzyPIDParams
from ego.control.narma import NarmaL2Controller, NarmaL2Params
from ego.control.pid import PID, PIDController, PIDParams
from ego.control.rbf_smc import RBFSMCController, RBFSMCParams
from ego.control.references import load_controller_plugins, resolve_controller
from ego.control.tasks import TASKS, Signal, Task
from ego.params import ConfigError, did_you_mean
from ego.plugins import is_reference


class NoController:
    """Controller switched off: zero longitudinal command (Fx or a_x) and delta = 0, so the
    ego coasts straight on."""

    def __init__(self, params: NoParams, dt: float) -> None:
        pass

    def reset(self, *, seed: int | None = None) -> None:
        pass

    def step(self, obs: Observation) -> tuple[float, float]:
        return 0.0, 0.0

    signal_units: dict[str, str] = {}

    def signals(self) -> dict[str, float]:
        return {}


_NONE = ControllerSpec(
    "none", "controller off: zero longitudinal command, delta = 0 (the ego coasts straight on)", NoParams, NoController
)

#: task -> name -> spec: the one controller registry. A scenario belongs to one task
#: (``ego.control.tasks.TASKS`` says what its controllers observe and return); its
#: controllers are looked up there.
CONTROLLERS: dict[str, dict[str, ControllerSpec]] = {
    "tracking": {
        spec.name: spec
        for spec in (
            ControllerSpec(
                "fuzzy", "report 000's 7x7 Mamdani fuzzy controller on both channels", FuzzyParams, FuzzyController
            ),
            ControllerSpec("pid", "PID baseline with anti-windup and filtered derivative", PIDParams, PIDController),
            ControllerSpec(
                "fuzzy-pid",
                "report 000's fuzzy-adaptive PID (classic dKp/dKi/dKd tables)",
                FuzzyPIDParams,
                FuzzyPIDController,
            ),
            ControllerSpec(
                "bp-pid",
                "report 000's BP neural-network PID (default: stabilised learning)",
                BPPIDParams,
                BPPIDController,
            ),
            ControllerSpec("rbf-smc", "report 000's RBF adaptive sliding-mode control", RBFSMCParams, RBFSMCController),
            ControllerSpec(
                "careful-driver",
                "UN R157 Annex 4 Appendix 3's competent and careful human driver (keeps its lane; "
                "brakes 0.4 + 0.75 s after a risk, up to 0.774 g in 0.6 s)",
                CarefulDriverParams,
                CarefulDriver,
            ),
            _NONE,
        )
    },
    "curve": {
        spec.name: spec
        for spec in (
            ControllerSpec("pid", "report 002's PI on e = e_lat + e_head (Kp 2, Ki 0.5)", CurvePIDParams, CurvePID),
            ControllerSpec(
                "fuzzy-curve",
                "report 002's two 5x5 fuzzy tables (speed x position error, speed x angle error), mixed with weight w",
                FuzzyCurveParams,
                FuzzyCurve,
            ),
            ControllerSpec(
                "narma-l2",
                "report 002's NARMA-L2: f and g networks trained on "
                "20-40 km/h, delta = (r - f) / g with a move penalty",
                NarmaL2Params,
                NarmaL2Controller,
            ),
            _NONE,
        )
    },
    "lane-centering": {
        spec.name: spec
        for spec in (
            ControllerSpec(
                "cascade-pid",
                "report 003's four-loop cascade PID with curvature feed-forward (preset tuned or report)",
                CascadePIDParams,
                CascadePID,
            ),
            _NONE,
        )
    },
    "car-following": {
        spec.name: spec
        for spec in (
            ControllerSpec(
                "pid",
                "report 004's PID on the spacing error (Kp 0.85, Ki 0.2, Kd 0.3)",
                FollowingPIDParams,
                FollowingPID,  # type: ignore[arg-type]  # list in, list out
            ),
            ControllerSpec(
                "bp-pid-acc",
                "report 004's 3-5-3 BP neural-network PID (inputs r_in, "
                "y_out, error; outputs Kp, Ki, Kd; incremental PID)",
                BPPIDAccParams,
                BPPIDAcc,  # type: ignore[arg-type]
            ),
            ControllerSpec(
                "none", "controller off: zero acceleration command (the followers coast)", NoParams, NoController
            ),
        )
    },
}


def controller_names(task: str | None = None) -> list[str]:
    """Registered names of one task, or of every task (each name once)."""
    load_controller_plugins(CONTROLLERS)
    tasks = [task] if task is not None else list(CONTROLLERS)
    return list(dict.fromkeys(n for t in tasks for n in CONTROLLERS[t]))


def controller_spec(name: str, task: str = "tracking") -> ControllerSpec:
    """The controller ``name`` of ``task``, or a ConfigError naming the allowed ones. Besides
    a registered name (entry-point plugins included), ``name`` may be a reference:
    ``package.module:Class``, ``path/to/file.py:Class`` or ``path/to/controller.fmu``
    (:mod:`ego.plugins`)."""
    load_controller_plugins(CONTROLLERS)
    try:
        return CONTROLLERS[task][name]
    except KeyError:
        if task in CONTROLLERS and is_reference(name):
            spec: ControllerSpec = resolve_controller(name, task)
            return spec
        if task not in CONTROLLERS:
            raise ConfigError(
                f"unknown task {task!r} (known: {', '.join(CONTROLLERS)}){did_you_mean(task, CONTROLLERS)}"
            ) from None
        others = [t for t in CONTROLLERS if name in CONTROLLERS[t]]
        # the right name for another task, or a misspelt one
        hint = f"; {name!r} is a {others[0]} controller" if others else did_you_mean(name, CONTROLLERS[task])
        raise ConfigError(
            f"unknown controller {name!r} for the {task} task (known: {', '.join(CONTROLLERS[task])}){hint}"
        ) from None


__all__ = [
    "BPPIDAcc",
    "BPPIDAccParams",
    "BPPIDController",
    "BPPIDParams",
    "CONTROLLERS",
    "TASKS",
    "CarefulDriver",
    "CarefulDriverParams",
    "CascadePID",
    "CascadePIDParams",
    "CurvePID",
    "CurvePIDParams",
    "FuzzyCurve",
    "FuzzyCurveParams",
    "NarmaL2Controller",
    "NarmaL2Params",
    "controller_names",
    "FollowingObservation",
    "FollowingPID",
    "FollowingPIDParams",
    "FuzzyPIDController",
    "FuzzyPIDParams",
    "RBFSMCController",
    "Signal",
    "Task",
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
    "PlatoonControl",
    "controller_spec",
]
