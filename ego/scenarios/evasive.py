"""What every evasive scenario shares besides its parts: the configuration of the manoeuvre,
its metrics (pure functions of the named trace and the run's facts, each declared with its
unit), the plots declared beside them and the recording's panels.

The scenarios themselves (``emergency_brake.py``, ``fast_follower.py``, ``cut_in.py``) are
:class:`~ego.scenarios.base.Scenario` subclasses wiring a
:class:`~ego.scenarios.motorway.MotorwayWorld`, a
:class:`~ego.scenarios.motorway.SurroundView`, an
:class:`~ego.scenarios.manoeuvre.EvasiveManoeuvre` and a
:class:`~ego.scenarios.safety.SafetyLayer` (:func:`compose`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ego.models import VehicleGeometry
from ego.params import param
from ego.record.base import Series
from ego.results import metrics as m
from ego.results.trace import Band, Marker, Metric, Plot, PlotSpec, Ref, Trajectory
from ego.scenarios.base import Parts, Scenario
from ego.scenarios.manoeuvre import PHASE_NAMES, EvasiveManoeuvre, InLane
from ego.scenarios.motorway import (
    EGO_BOX,
    HighwayConfig,
    MotorwayWorld,
    SurroundView,
    check_density,
    ego_limits,
    ego_plant,
    series,
)
from ego.scenarios.safety import SafetyLayer
from ego.sumo.net import MOTORWAY_ROADS


@dataclass(frozen=True)
class EvasiveConfig(HighwayConfig):
    """The manoeuvre shared by the evasive scenarios."""

    ttc_threshold: float = param(3.0, "s", "time-to-collision that triggers the manoeuvre", min=0.1, max=20.0)
    evade_speed: float = param(15.0, "m/s", "speed reference during the lane change", min=1.0, max=45.0)
    follow_gap: float = param(5.0, "m", "standstill gap kept to the leader once evading", min=0.0, max=50.0)
    follow_headway: float = param(0.5, "s", "time headway kept to the leader once evading", min=0.0, max=5.0)
    accept_gap: float = param(5.0, "m", "gap acceptance: minimum lead and lag gap", min=0.0, max=100.0)
    accept_time: float = param(1.5, "s", "gap acceptance: extra gap per m/s of closing speed", min=0.0, max=10.0)
    settle_band: float = param(0.2, "m", "lane change is done when |lateral error| stays below", min=0.01, max=2.0)
    block_left: bool = param(False, "-", "a car drives beside the ego in the left lane")
    block_right: bool = param(False, "-", "a car drives beside the ego in the right lane")
    aeb: bool = param(
        True,
        "-",
        "automatic emergency braking: full braking at the friction limit, "
        "overriding the controller's longitudinal command, when braking in lane needs "
        "more than aeb_decel, a lane change needs (0.9 of) the friction limit to stay behind the car it still "
        "overlaps, or the front TTC falls below aeb_ttc",
    )
    aeb_decel: float = param(
        3.0,
        "m/s^2",
        "AEB engages when braking in lane needs this much (the front object's deceleration + closing^2 / (2 gap))",
        min=0.5,
        max=12.0,
    )
    aeb_ttc: float = param(
        1.0,
        "s",
        "AEB engages in any phase below this front TTC, unless the ego clears the front object sideways first",
        min=0.0,
        max=10.0,
    )
    evade: bool = param(
        True,
        "-",
        "change lane when gap acceptance finds a lane; false: never "
        "change lane, always the in-lane manoeuvre at the trigger (pure emergency "
        "braking behind a braking car: what an AEB test measures)",
    )

    def __post_init__(self) -> None:
        super().__post_init__()
        # the background keeps a safe spacing; a denser flow cannot be placed, so say so
        # before the simulator starts
        check_density(self)


@dataclass(frozen=True)
class MotorwayRoadConfig(EvasiveConfig):
    """An evasive scenario on the built-in motorway, straight or curved."""

    road: str = param(
        "straight",
        "-",
        "the motorway: straight, or an arc of the middle lane's radius 250 m (180 deg) or 1000 m "
        "(90 deg) to the left or right, 350 m after its start (at the default ego_start the ego enters it within "
        "3 s), or clothoid: the road of changing curvature (clothoids between arcs of 500, 250 and 1000 m from "
        "350 to 1450 m); gaps and TTCs along the lane (sumo backend only)",
        choices=tuple(MOTORWAY_ROADS),
    )


def compose(
    scenario: Scenario,
    trigger_on: str,
    in_lane: InLane,
    traffic: Callable[[MotorwayWorld], None],
    choose: Callable[..., Any] | None = None,
    on_trigger: Callable[..., Any] | None = None,
    *,
    road: dict[str, Any] | None = None,
    manoeuvre_cls: type[EvasiveManoeuvre] = EvasiveManoeuvre,
) -> Parts:
    """The parts of an evasive scenario: the motorway world with ``traffic``, the ego's plant,
    the surround view, the manoeuvre triggered by the ``trigger_on`` TTC with the scenario's
    ``in_lane`` behaviour, and the AEB (when ``aeb`` is on). ``road``: the world's road
    (:class:`MotorwayWorld`'s keywords; default the motorway); ``manoeuvre_cls``: an
    :class:`EvasiveManoeuvre` with more references (a scenario file's storyboard)."""
    c = scenario.config
    scenario.geometry = VehicleGeometry()
    view = SurroundView(c, scenario.geometry)
    manoeuvre = manoeuvre_cls(c, view, trigger_on, in_lane, scenario.event, choose, on_trigger)
    safety = None
    if c.aeb:
        safety = SafetyLayer(c, view, scenario.event, lambda: scenario.t)
        safety.manoeuvre = manoeuvre
        manoeuvre.safety = safety
    return Parts(
        MotorwayWorld(c, scenario.geometry, traffic, **(road or {})),
        view,
        manoeuvre,
        safety,
        ego_plant,
        lambda names, units: evasive_series(c, names, units),
        ego_limits,
    )


#: the events marked on the time axis of every plot
MARKERS = (
    Marker("trigger", "trigger (TTC below the threshold)", "v"),
    Marker("lane", "lane chosen (or stay)", "s"),
    Marker("aeb", "AEB engages / releases", "P"),
    Marker("done", "manoeuvre done", "D"),
    Marker("collision", "collision", "X"),
)


def compare_plots(scenario_cls: Any, config: Any) -> tuple[PlotSpec, ...]:
    """The lateral position against its reference and the settle band, the speed against
    its reference, the actuators, the gap, front and rear TTC against the trigger's
    threshold, every one with the scenario's ``markers`` (events) marked; the top-down
    trajectory. A scenario's ``compare_plots = classmethod(compare_plots)``."""
    markers = scenario_cls.markers
    band = config.settle_band
    ttc_refs: tuple[Ref, ...] = (Ref(f"trigger threshold {config.ttc_threshold:g} s", value=config.ttc_threshold),)
    if config.aeb:
        ttc_refs += (Ref(f"AEB threshold {config.aeb_ttc:g} s", value=config.aeb_ttc),)
    return (
        Plot(
            "d",
            "lateral_error.png",
            "offset from the target lane centre (+ left)",
            refs=(Ref("lateral reference", "d_ref"),),
            band=Band(-band, band, f"settle band +-{band:g} m"),
            markers=markers,
        ),
        Plot("speed", "speed.png", "speed", refs=(Ref("speed reference", "speed_ref"),), markers=markers),
        Plot("delta", "steering.png", "front steer angle", markers=markers),
        Plot("Fx", "fx.png", "Fx per driven wheel", markers=markers),
        Plot("gap_front", "gap_front.png", "gap to the front object", markers=markers),
        Plot(
            "ttc_front",
            "ttc.png",
            "time to collision",
            lines=(("ttc_front", "front"), ("ttc_rear", "rear")),
            refs=ttc_refs,
            markers=markers,
            ylim=(0.0, max(10.0, 3.0 * config.ttc_threshold)),
        ),
        Trajectory(ego_box=EGO_BOX),
    )


def evasive_series(config: Any, signal_names: Sequence[str], signal_units: Mapping[str, str]) -> list[Series]:
    """The motorway's panels, the thresholds on the TTC panel and the manoeuvre's state."""
    c = config
    limits = [Series("", "plots/ttc/trigger", "s", "trigger", constant=c.ttc_threshold)]
    if c.aeb and c.aeb_ttc > 0.0:
        limits.append(Series("", "plots/ttc/aeb", "s", "AEB", constant=c.aeb_ttc))
    return [
        *series(signal_names, signal_units),
        *limits,
        Series("phase", "states/manoeuvre", "", "manoeuvre", states=PHASE_NAMES),
    ]


# --- metrics -----------------------------------------------------------------------------

METRICS = (
    Metric("lane_change_completed", "-", "the ego changed lane and settled in the target lane"),
    Metric("target_lane", "-", "SUMO index of the lane the ego ended in (after a trigger)"),
    Metric("target_side", "-", "left, right, or none (stayed in lane)"),
    Metric("trigger_time", "s", "when the TTC fell below the threshold"),
    Metric("trigger_ttc", "s", "the TTC at the trigger"),
    Metric("lane_choice", "-", "gap acceptance of both lanes at the trigger"),
    Metric("lane_change_duration", "s", "trigger to settled in the target lane", headline=True),
    Metric("max_overshoot", "m", "largest overshoot past the target lane centre", headline=True),
    Metric("min_ttc_front", "s", "smallest front TTC (surround sensor)", headline=True),
    Metric("min_ttc_rear", "s", "smallest rear TTC (surround sensor)", headline=True),
    Metric("min_gap_front", "m", "smallest bumper gap to the front object, from the outlines", headline=True),
    Metric("max_abs_lateral_accel", "m/s^2", "largest |lateral acceleration|", headline=True),
    Metric("max_decel", "m/s^2", "largest deceleration along the road"),
    Metric("aeb_time", "s", "when the AEB first engaged (none: never)"),
    Metric("aeb_engagements", "-", "how often the AEB engaged"),
    Metric("final_speed", "m/s", "speed at the end"),
)


def lane_change_metrics(
    col: dict[str, np.ndarray],
    status: str,
    config: Any,
    manoeuvre: EvasiveManoeuvre,
    target_lane: int,
    safety: SafetyLayer | None,
) -> dict[str, Any]:
    """:data:`METRICS` from the named trace ``col`` and the run's facts: its ``status``, the
    manoeuvre's trigger and choice, the lane it ended in, the AEB's engagements."""
    t = col["t"]
    trigger_t, chosen = manoeuvre.trigger_t, manoeuvre.chosen
    triggered = trigger_t is not None
    lane_change = triggered and chosen is not None
    duration = overshoot = None
    if lane_change:
        assert trigger_t is not None  # a lane change follows a trigger
        after = t >= trigger_t
        duration = m.settling_time(t, col["d"], config.settle_band, trigger_t)
        direction = 1.0 if chosen == "left" else -1.0
        overshoot = m.overshoot(col["d"][after], direction)
    completed = bool(lane_change and duration is not None and status in ("completed", "timeout"))
    return {
        "lane_change_completed": completed,
        "target_lane": target_lane if triggered else None,
        "target_side": chosen if triggered else None,
        "trigger_time": m.json_number(trigger_t, 4),
        "trigger_ttc": m.json_number(manoeuvre.trigger_ttc, 4),
        "lane_choice": manoeuvre.choice_reason or None,
        "lane_change_duration": m.json_number(duration, 4),
        "max_overshoot": m.json_number(overshoot, 4),
        "min_ttc_front": m.json_number(m.finite_min(col["ttc_front"]), 4),
        "min_ttc_rear": m.json_number(m.finite_min(col["ttc_rear"]), 4),
        "min_gap_front": m.json_number(m.finite_min(col["gap_front"]), 4),
        "max_abs_lateral_accel": m.json_number(m.max_abs(col["lat_accel"]), 4),
        "max_decel": m.json_number(max_decel(t, col["ds"]), 4),
        "aeb_time": m.json_number(safety.time if safety is not None else None, 4),
        "aeb_engagements": safety.engagements if safety is not None else 0,
        "final_speed": m.json_number(float(col["speed"][-1]) if len(t) else None, 4),
    }


def evasive_metrics(scenario: Scenario, trace: np.ndarray, names: tuple[str, ...]) -> dict[str, Any]:
    """:func:`lane_change_metrics` of a composed evasive scenario's run."""
    return lane_change_metrics(
        columns(trace, names),
        scenario.status,
        scenario.config,
        scenario.manoeuvre,
        scenario.view.target_lane,
        scenario.safety,
    )


def max_decel(t: np.ndarray, speed: np.ndarray, window: float = 0.1) -> float | None:
    """Largest deceleration (m/s^2) of ``speed`` averaged over ``window`` seconds (one SUMO
    step: a per-sample difference would report integration noise)."""
    if len(t) < 2:
        return None
    k = max(1, int(round(window / float(t[1] - t[0]))))
    if len(t) <= k:
        k = len(t) - 1
    rate = (speed[k:] - speed[:-k]) / (t[k:] - t[:-k])
    return max(0.0, float(-rate.min()))


def columns(trace: np.ndarray, names: tuple[str, ...]) -> dict[str, np.ndarray]:
    """The trace's columns by name."""
    return {name: trace[:, i] for i, name in enumerate(names)}
