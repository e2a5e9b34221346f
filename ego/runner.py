"""One run as a pure function of a picklable description: what sweeps and the CLI call."""

from __future__ import annotations

import importlib.util
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from ego.control import CONTROLLERS, controller_spec
from ego.params import ConfigError, apply_overrides, describe, unknown_parameter
from ego.record import RerunRecorder
from ego.scenarios import RunResult, Scenario, scenario_class
from ego.scenarios.base import check_backend
from ego.scenarios.trace import Column, Metric
from ego.sumo.net import net_file


@dataclass(frozen=True)
class RunSpec:
    """Everything that defines a run. Same spec, same metrics (``wall_time`` aside)."""

    scenario: str
    controller: str
    seed: int = 0
    overrides: Mapping[str, Any] = field(default_factory=dict)
    record: str | None = None
    #: write the trace (and traffic log) here after the run: .csv, .parquet or .mat
    #: (:func:`ego.export.write_trace`)
    trace: str | None = None
    #: write the recording from a separate process (False: in this one, e.g. in a pool
    #: worker that already has a core of its own)
    background_recording: bool = True
    #: the traffic simulator: "sumo" or "highway-env" (ego.highway_env.BACKENDS)
    backend: str = "sumo"
    #: a .gif or .mp4 of the run from highway-env's renderer (highway-env only)
    video: str | None = None
    #: the controller's name in the results (``RunResult.controller``, the recording):
    #: ``ego compare``'s variant label, e.g. ``pid@kp_lat=0.02``; default ``controller``
    label: str = ""
    #: requirements checked on the run (``ego.requirements``): ((name, formula), ...) or a
    #: mapping; None: the scenario's defaults; (): none
    requirements: Any = None

    @property
    def name(self) -> str:
        """The controller as the results name it: ``label``, else ``controller``."""
        return self.label or self.controller

    def __post_init__(self) -> None:
        """The fields' types, at once (names and values are checked by :func:`configure`,
        before anything is built): ConfigError naming the field, never a TypeError later."""
        for name in ("scenario", "controller"):
            if not isinstance(getattr(self, name), str):
                raise ConfigError(f"bad {name} {getattr(self, name)!r} (expected a name, see ego list)")
        if not isinstance(self.overrides, Mapping) or not all(isinstance(k, str) for k in self.overrides):
            raise ConfigError(f"bad overrides {self.overrides!r:.60} (expected a mapping of parameter "
                              "name to value)")
        if self.record is not None and not isinstance(self.record, (str, os.PathLike)):
            raise ConfigError(f"bad record {self.record!r} (expected a path ending in .rrd, or None)")
        if self.requirements is not None:
            pairs = tuple(self.requirements.items()) if isinstance(self.requirements, Mapping) \
                else tuple(tuple(p) for p in self.requirements)
            object.__setattr__(self, "requirements", pairs)
        if not isinstance(self.background_recording, bool):
            raise ConfigError(f"bad background_recording {self.background_recording!r} (expected true or false)")


def split_overrides(scenario: str, controller: str, overrides: Mapping[str, Any]) -> dict:
    """The overrides that apply to this scenario and controller (others are dropped)."""
    cls = scenario_class(scenario)
    known = {i.name for i in describe(cls.config_cls)}
    known |= {i.name for i in describe(controller_spec(controller, cls.task).params)}
    return {k: v for k, v in overrides.items() if k in known}


def configure(spec: RunSpec):
    """Resolve names and overrides: (scenario class, its config, controller spec, its params).
    Raises ConfigError on any unknown name or bad value; builds nothing."""
    from ego.checks import check_seed

    check_seed(spec.seed)
    cls = scenario_class(spec.scenario)
    if cls.network is not None:  # a missing or garbled network fails here, not inside SUMO
        net_file(cls.network)
    check_backend(cls, spec.backend)
    if spec.backend == "highway-env" and importlib.util.find_spec("highway_env") is None:
        raise ConfigError("--backend highway-env needs the highway-env package: pip install 'ego[highway]'")
    if spec.video is not None:
        if spec.backend != "highway-env":
            raise ConfigError("--video needs --backend highway-env (a SUMO run is recorded with --record)")
        from ego.highway_env.video import check_video_path

        check_video_path(spec.video)
    ctrl = controller_spec(spec.controller, cls.task)
    config, rest = apply_overrides(cls.default_config(spec.overrides), spec.overrides, strict=False)
    ctrl_params, rest = apply_overrides(ctrl.params(), rest, strict=False)
    if rest:
        known = [i.name for i in describe(cls.config_cls)] + [i.name for i in describe(ctrl.params)]
        raise unknown_parameter(next(iter(rest)), known)
    cls.check_config(config)
    return cls, config, ctrl, ctrl_params


def build(spec: RunSpec):
    """Resolve names and overrides into a ready scenario (validates everything first)."""
    cls, config, ctrl, ctrl_params = configure(spec)
    controller = cls.build_controller(ctrl, ctrl_params, config)
    reqs = requirements_of(spec, cls, config, controller)
    if spec.trace is not None:
        from ego.export import check_trace_path

        check_trace_path(spec.trace)
    recorder = None
    if spec.record is not None:
        from ego.checks import check_output_file

        path = check_output_file(os.fspath(spec.record), "--record path", ".rrd")
        path.parent.mkdir(parents=True, exist_ok=True)
        recorder = RerunRecorder(path, recording_id=f"{spec.scenario}-{spec.name}-{spec.seed}",
                                 background=spec.background_recording)
    scenario = cls(config, controller, seed=spec.seed, recorder=recorder, controller_name=spec.name,
                   backend=spec.backend, video=spec.video)
    if reqs:
        from ego.requirements import check_run

        scenario.on_result = lambda sc, result: check_run(sc, result, reqs)
    return scenario


def requirements_of(spec: RunSpec, cls, config, controller=None) -> tuple:
    """The run's requirements parsed against its signals (the scenario's defaults when
    ``spec.requirements`` is None); RequirementError before anything runs."""
    from ego.requirements import defaults, resolve, signal_units

    if spec.requirements == ():
        return ()
    columns = {c.name: c.unit for c in declared_columns(cls, config)}
    if controller is not None:
        try:
            columns.update({n: "-" for n in controller.signals() if n not in columns})
        except Exception:  # noqa: BLE001 - a controller that needs a reset first: its signals stay unnamed
            pass
    texts = dict(spec.requirements) if spec.requirements is not None else defaults(spec.scenario)
    if not texts:
        return ()
    metrics = [m.name for m in cls.metrics_declared(config)]
    return resolve(texts, signal_units(columns, metrics, cls))


def run(spec: RunSpec) -> RunResult:
    """Run one scenario to its end; SUMO and the recording are closed whatever happens.
    With ``spec.trace``, the trace is written there (an interrupted run's too)."""
    result = build(spec).run()
    if spec.trace is not None:
        from ego.export import write_trace

        write_trace(result, spec.trace)
    return result


def declared_metrics(spec: RunSpec) -> tuple[Metric, ...]:
    """Every metric a run of ``spec`` reports, as its scenario declares them (units, headline)."""
    cls, config, _, _ = configure(spec)
    reqs = requirements_of(spec, cls, config)
    return cls.metrics_declared(config) + tuple(
        Metric(f"requirements.{r.name}", "-" if r.unit in ("bool", "mixed") else r.unit,
               f"robustness of {r.formula} (negative: violated)") for r in reqs)


def declared_columns(cls: type[Scenario], config) -> tuple[Column, ...]:
    """The trace columns a run of ``cls`` with ``config`` writes before its controller's
    signals (which are unitless). Some depend on the configuration (one set per platoon
    follower), so the scenario is built - with its task's ``none`` controller, no SUMO
    started - and asked."""
    spec = CONTROLLERS[cls.task]["none"]
    scenario = cls(config, cls.build_controller(spec, spec.params(), config), controller_name="none")
    return tuple(scenario.trace_columns())
