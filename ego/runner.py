"""One run as a pure function of a picklable description: what sweeps and the CLI call.

The path of a run: a :class:`RunSpec` (names, overrides, output paths) is resolved once by
:func:`resolve` into a frozen :class:`ResolvedRun` (classes looked up, every value checked);
:func:`build` makes the scenario from it and :func:`run` runs it into a
:class:`~ego.results.RunResult`. Workers, plots and exports receive the resolved run.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any

from ego.control import CONTROLLERS, controller_spec
from ego.control.base import Controller, ControllerSpec
from ego.params import ConfigError, ParamInfo, apply_overrides, describe, unknown_parameter
from ego.record import RerunRecorder
from ego.results import RunResult
from ego.results.trace import Column, Metric
from ego.scenarios import Scenario, scenario_class
from ego.scenarios.base import check_backend
from ego.sim.registry import check_options
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
    #: (:func:`ego.results.export.write_trace`)
    trace: str | None = None
    #: write the recording from a separate process (False: in this one, e.g. in a pool
    #: worker that already has a core of its own)
    background_recording: bool = True
    #: the traffic simulator: "sumo" or "highway-env" (ego.highway_env.BACKENDS)
    backend: str = "sumo"
    #: a .gif or .mp4 of the run from highway-env's renderer (highway-env only; the same as
    #: ``backend_options={"video": ...}``)
    video: str | None = None
    #: options of the traffic simulator, as data (``ego.sim.registry``: each backend says
    #: which it takes), e.g. ``{"video": "run.gif"}`` for highway-env
    backend_options: Mapping[str, Any] = field(default_factory=dict)
    #: the controller's name in the results (``RunResult.controller``, the recording):
    #: ``ego compare``'s variant label, e.g. ``pid@kp_lat=0.02``; default ``controller``
    label: str = ""
    #: requirements checked on the run (``ego.requirements``): ((name, formula), ...) or a
    #: mapping; None: the scenario's defaults; (): none
    requirements: Any = None
    #: ``collision_preventable`` (:func:`collision_preventable`): None computes it when the
    #: run ends in a collision (``ego run``'s default), True always (where the careful driver
    #: can drive the scenario), False never (the default: a sweep, a falsification or a
    #: comparison asks for the second run explicitly, ``--preventable``)
    preventable: bool | None = False
    #: requirements are evaluated on every sample of the trace (0, the default) or on a grid
    #: of samples this many seconds apart (e.g. 0.1, the SUMO step; docs/requirements.md)
    requirement_period: float = 0.0

    @property
    def sim_options(self) -> dict[str, Any]:
        """The backend's options: ``backend_options`` plus ``video`` when set."""
        options = dict(self.backend_options)
        if self.video is not None:
            options["video"] = self.video
        return options

    @property
    def name(self) -> str:
        """The controller as the results name it: ``label``, else ``controller``."""
        return self.label or self.controller

    def __post_init__(self) -> None:
        """The fields' types, at once (names and values are checked by :func:`resolve`,
        before anything is built): ConfigError naming the field, never a TypeError later."""
        for name in ("scenario", "controller"):
            if not isinstance(getattr(self, name), str):
                raise ConfigError(f"bad {name} {getattr(self, name)!r} (expected a name, see ego list)")
        if not isinstance(self.overrides, Mapping) or not all(isinstance(k, str) for k in self.overrides):
            raise ConfigError(f"bad overrides {self.overrides!r:.60} (expected a mapping of parameter name to value)")
        if self.record is not None and not isinstance(self.record, (str, os.PathLike)):
            raise ConfigError(f"bad record {self.record!r} (expected a path ending in .rrd, or None)")
        if not isinstance(self.label, str):
            raise ConfigError(f"bad label {self.label!r} (expected text: the controller's name in the results)")
        for name in ("trace", "video"):
            value = getattr(self, name)
            if value is not None and not isinstance(value, (str, os.PathLike)):
                raise ConfigError(f"bad {name} {value!r} (expected a path, or None)")
        import numbers

        if isinstance(self.seed, numbers.Integral) and not isinstance(self.seed, (bool, int)):
            object.__setattr__(self, "seed", int(self.seed))  # a numpy integer is a seed too
        if self.requirements is not None:
            pairs = (
                tuple(self.requirements.items())
                if isinstance(self.requirements, Mapping)
                else tuple(tuple(p) for p in self.requirements)
            )
            object.__setattr__(self, "requirements", pairs)
        if not isinstance(self.background_recording, bool):
            raise ConfigError(f"bad background_recording {self.background_recording!r} (expected true or false)")
        if self.preventable is not None and not isinstance(self.preventable, bool):
            raise ConfigError(f"bad preventable {self.preventable!r} (expected true, false or None)")
        if self.requirement_period != 0.0:
            from ego.requirements import check_period

            object.__setattr__(self, "requirement_period", check_period(self.requirement_period, "requirement_period"))


def parameter_namespace(scenario: type[Scenario] | str, controllers: Iterable[str] = ()) -> dict[str, ParamInfo]:
    """Every parameter a run of ``scenario`` with any of ``controllers`` takes, by name: the
    scenario's configuration, then each controller's parameters (a name both declare is the
    scenario's). The one place this union is built: ``--set`` checking, compare's variants,
    sweep specs and the Gymnasium environment all ask here. ConfigError for an unknown
    scenario or controller."""
    cls = scenario_class(scenario) if isinstance(scenario, str) else scenario
    infos: dict[str, ParamInfo] = {}
    for name in controllers:
        infos.update({i.name: i for i in describe(controller_spec(name, cls.task).params)})
    infos.update({i.name: i for i in describe(cls.config_cls)})
    return infos


def split_overrides(scenario: str, controller: str, overrides: Mapping[str, Any]) -> dict:
    """The overrides that apply to this scenario and controller (others are dropped)."""
    known = parameter_namespace(scenario, [controller])
    return {k: v for k, v in overrides.items() if k in known}


@dataclass(frozen=True)
class ResolvedRun:
    """A :class:`RunSpec` with every name resolved and every value checked: what a run,
    its worker, the plots and the exports receive. Made only by :func:`resolve` (once per
    run; :meth:`with_outputs` derives a seed's or a recording's variant without resolving
    again). Frozen and picklable: the scenario class, the controller spec and both
    configurations travel to a worker by reference and value, so the worker needs no
    registry and repeats no check."""

    spec: RunSpec
    #: the scenario class the name resolved to
    scenario_cls: type[Scenario]
    #: the scenario's configuration, every override applied and checked (a ``Params``)
    config: Any
    #: the controller the name resolved to, for the scenario's task
    controller: ControllerSpec
    #: the controller's parameters, every override applied and checked (a ``Params``)
    controller_params: Any

    @property
    def name(self) -> str:
        """The controller as the results name it (:attr:`RunSpec.name`)."""
        return self.spec.name

    @property
    def seed(self) -> int:
        return self.spec.seed

    def with_outputs(self, **changes: Any) -> ResolvedRun:
        """The same run with other ``seed``, ``record``, ``trace``, ``label`` or
        ``background_recording``: none of them changes a configuration, so only the new
        values are checked."""
        allowed = {"seed", "record", "trace", "label", "background_recording"}
        bad = sorted(set(changes) - allowed)
        if bad:
            raise ConfigError(f"with_outputs cannot change {bad[0]!r} (allowed: {', '.join(sorted(allowed))})")
        spec = replace(self.spec, **changes)
        _check_outputs(spec)
        return replace(self, spec=spec)

    def build_controller(self) -> Controller:
        """A fresh controller for this run (the scenario's task decides how it is made)."""
        return self.scenario_cls.build_controller(self.controller, self.controller_params, self.config)

    def metrics_declared(self) -> tuple[Metric, ...]:
        """Every metric the run reports, as its scenario declares them (units, headline),
        its requirements' robustness (``requirements.<name>``) and first violation time
        (``first_violation.<name>``)."""
        reqs = requirements_of(self)
        return (
            tuple(self.scenario_cls.metrics_declared(self.config))
            + tuple(
                Metric(
                    f"requirements.{r.name}",
                    "-" if r.unit in ("bool", "mixed") else r.unit,
                    f"robustness of {r.formula} (negative: violated)",
                )
                for r in reqs
            )
            + tuple(
                Metric(f"first_violation.{r.name}", "s", f"the first time {r.name} is violated (empty: never)")
                for r in reqs
            )
        )

    def plots(self) -> tuple:
        """The plots ``ego compare`` draws for this configuration."""
        return tuple(self.scenario_cls.compare_plots(self.config))

    def __reduce__(self) -> tuple:
        # The scenario class and the controller spec travel as their names: a reference
        # (``file.py:Class``, an FMU) makes classes and builders that exist only in the
        # process that loaded it, and a worker loads it itself (cached by content hash);
        # both configurations travel by value and are not checked again.
        return _rebuilt, (self.spec, self.config, self.controller_params)


def _rebuilt(spec: RunSpec, config: Any, controller_params: Any) -> ResolvedRun:
    """A :class:`ResolvedRun` unpickled in a worker: names looked up, nothing checked again."""
    cls = scenario_class(spec.scenario)
    return ResolvedRun(spec, cls, config, controller_spec(spec.controller, cls.task), controller_params)


def _check_outputs(spec: RunSpec) -> None:
    from ego.checks import check_seed

    check_seed(spec.seed)
    if spec.trace is not None:
        from ego.results.export import check_trace_path

        check_trace_path(spec.trace)
    if spec.record is not None:
        from ego.checks import check_output_file

        check_output_file(os.fspath(spec.record), "--record path", ".rrd")
    from ego.paths import check_run_outputs

    check_run_outputs(spec)  # every file the run writes (sidecars too), before anything runs


def resolve(spec: RunSpec) -> ResolvedRun:
    """Resolve names and overrides and check every value (and the output paths): the run
    as a frozen :class:`ResolvedRun`. Raises ConfigError on any unknown name or bad value;
    builds nothing and starts nothing."""
    from ego.checks import check_seed

    check_seed(spec.seed)
    cls = scenario_class(spec.scenario)
    if cls.network is not None:  # a missing or garbled network fails here, not inside SUMO
        net_file(cls.network)
    check_backend(cls, spec.backend)
    check_options(spec.backend, spec.sim_options)
    ctrl = controller_spec(spec.controller, cls.task)
    config, rest = apply_overrides(cls.default_config(spec.overrides), spec.overrides, strict=False)
    ctrl_params, rest = apply_overrides(ctrl.params(), rest, strict=False)
    if rest:
        raise unknown_parameter(next(iter(rest)), parameter_namespace(cls, [ctrl.name]))
    cls.check_config(config)
    network = cls.network_of(config)
    if network != cls.network:  # a curved road: SUMO's network (highway-env builds a straight road)
        net_file(network)
        if spec.backend != "sumo":
            raise ConfigError(f"road={config.road} runs on the sumo backend only (highway-env builds a straight road)")
    check = getattr(ctrl_params, "check", None)  # parameters that check themselves as a whole (an FMU's mapping)
    if check is not None:
        check()
    _check_outputs(spec)
    return ResolvedRun(spec, cls, config, ctrl, ctrl_params)


def build(what: RunSpec | ResolvedRun) -> Scenario:
    """A ready scenario for ``what`` (a spec is resolved first; a resolved run is not checked
    again). Nothing starts until its ``run()`` or ``reset()``."""
    resolved = what if isinstance(what, ResolvedRun) else resolve(what)
    spec = resolved.spec
    controller = resolved.build_controller()
    reqs = requirements_of(resolved, controller)  # RequirementError before anything starts
    recorder = None
    if spec.record is not None:
        path = Path(os.fspath(spec.record))
        path.parent.mkdir(parents=True, exist_ok=True)
        recorder = RerunRecorder(path, recording_id=recording_id(spec), background=spec.background_recording)
    scenario = resolved.scenario_cls(
        resolved.config,
        controller,
        seed=spec.seed,
        recorder=recorder,
        controller_name=spec.name,
        backend=spec.backend,
        backend_options=spec.sim_options,
    )
    if reqs:
        from ego.requirements import PREVENTABLE_SIGNAL, check_run

        period = spec.requirement_period
        preventable = any(PREVENTABLE_SIGNAL in r.signals for r in reqs)

        def on_result(sc: Scenario, result: RunResult) -> None:
            if preventable and result.metrics.get("collision") and "collision_preventable" not in result.metrics:
                # no_preventable_collision's question, asked before the verdicts: the careful
                # driver's run on the same scenario (libsumo runs one simulation per process:
                # this run's is closed first; its trace and metrics are complete)
                sc._close_bridge()
                answer = collision_preventable(resolved, result)
                if answer is not None:
                    result.metrics["collision_preventable"] = answer
            check_run(sc, result, reqs, period)

        scenario.on_result = on_result
    return scenario


def run_command(
    scenario: str,
    controller: str,
    seed: int,
    overrides: Mapping[str, Any] | None = None,
    require: Iterable[tuple[str, str]] = (),
    record: str | None = None,
) -> str:
    """The ``ego run`` command that makes one run, shell-quoted: ``overrides`` as ``--set``
    (booleans as ``true``/``false``), ``require`` (name, formula) pairs as ``--require``, and
    a recording. The one place every reproducer (the pytest plugin, ``ego falsify``, ``ego
    report``) builds it."""
    import shlex

    parts = ["ego", "run", str(scenario), "-c", str(controller), "--seed", str(int(seed))]
    for k, v in (overrides or {}).items():
        parts += ["--set", f"{k}={str(v).lower() if isinstance(v, bool) else v}"]
    for name, formula in require:
        parts += ["--require", f"{name}: {formula}"]
    if record:
        parts += ["--record", record]
    return shlex.join(parts)


def recording_id(spec: RunSpec) -> str:
    """A run's recording id, one per run (recordings opened together merge by id):
    scenario, controller, the backend other than SUMO, a digest of the parameters set, and the
    seed last."""
    import hashlib

    parts = [str(spec.scenario), spec.name]
    if spec.backend != "sumo":
        parts.append(spec.backend)
    if spec.overrides:
        text = repr(sorted((str(k), str(v)) for k, v in spec.overrides.items()))
        parts.append(hashlib.sha256(text.encode()).hexdigest()[:8])
    return "-".join([*parts, str(spec.seed)])


def requirements_of(resolved: ResolvedRun, controller: Controller | None = None) -> tuple:
    """The run's requirements parsed against its signals (the scenario's defaults when
    ``spec.requirements`` is None; with ``controller``, its signals too); RequirementError
    before anything runs."""
    from ego.requirements import defaults, signal_units
    from ego.requirements import resolve as resolve_requirements

    spec, cls, config = resolved.spec, resolved.scenario_cls, resolved.config
    if spec.requirements == ():
        return ()
    texts = dict(spec.requirements) if spec.requirements is not None else defaults(spec.scenario, resolved.scenario_cls)
    if not texts:
        return ()
    columns = {c.name: c.unit for c in declared_columns(cls, config)}
    if controller is not None:
        try:
            columns.update({n: "-" for n in controller.signals() if n not in columns})
        except Exception:  # noqa: BLE001 - a controller that needs a reset first: its signals stay unnamed
            pass
    metrics = [m.name for m in cls.metrics_declared(config)]
    reqs = resolve_requirements(texts, signal_units(columns, metrics, cls))
    duration = getattr(config, "duration", None)
    if spec.requirements is not None and isinstance(duration, (int, float)):
        from ego.requirements import RequirementError

        for req in reqs:  # a window longer than the run holds no sample
            longest = max(req.bounds, default=0.0)
            if longest > duration:
                raise RequirementError(
                    f"bad requirement {req.name!r}: its interval bound {longest:g} s is longer than the run "
                    f"(duration {duration:g} s)"
                )
    return reqs


def run(what: RunSpec | ResolvedRun) -> RunResult:
    """Run one scenario to its end; SUMO and the recording are closed whatever happens.
    With ``spec.trace``, the trace is written there (an interrupted run's too)."""
    from ego.outputs import OutputError, output_error

    resolved = what if isinstance(what, ResolvedRun) else resolve(what)
    scenario = build(resolved)
    failed: OutputError | None = None
    try:
        result = scenario.run()
    except OutputError as exc:  # the recording could not be written: the run's metrics stand
        result = exc.result = scenario.result()
        failed = exc
    if resolved.spec.trace is not None:  # written whatever became of the recording
        from ego.results.export import write_trace

        try:
            write_trace(result, resolved.spec.trace)
        except OutputError as exc:
            exc.result = result
            raise failed or exc from None
        except OSError as exc:
            raise failed or output_error(resolved.spec.trace, exc, result) from None
    if failed is not None:
        raise failed
    spec = resolved.spec
    asked = "collision_preventable" in result.metrics  # by a requirement (no_preventable_collision)
    if not asked and (spec.preventable or (spec.preventable is None and result.metrics.get("collision"))):
        preventable = collision_preventable(resolved, result)
        if preventable is not None:
            result.metrics["collision_preventable"] = preventable
    return result


#: the reference driver of :func:`collision_preventable` (UN R157 Annex 4 Appendix 3)
REFERENCE_DRIVER = "careful-driver"
#: the ego's own systems the reference driver drives without: the scenario's evasion and AEB
REFERENCE_OFF = {"evade": False, "aeb": False}


def reference_run(resolved: ResolvedRun) -> ResolvedRun | None:
    """The same concrete scenario (the same file, configuration, seed, traffic and backend)
    with UN R157's careful driver (``careful-driver``) in place of the run's controller and
    the ego's own evasion and AEB switched off; no outputs, no requirements. None where the
    careful driver cannot drive the scenario (it is not in the scenario's task)."""
    cls = resolved.scenario_cls
    if REFERENCE_DRIVER not in CONTROLLERS.get(cls.task, {}):
        return None
    names = {f.name for f in fields(resolved.config)}
    config = replace(resolved.config, **{k: v for k, v in REFERENCE_OFF.items() if k in names})
    options = {k: v for k, v in resolved.spec.backend_options.items() if k != "video"}
    spec = replace(
        resolved.spec,
        controller=REFERENCE_DRIVER,
        overrides={},
        record=None,
        trace=None,
        video=None,
        backend_options=options,
        label="",
        requirements=(),
        preventable=False,
    )
    driver = CONTROLLERS[cls.task][REFERENCE_DRIVER]
    return ResolvedRun(spec, cls, config, driver, driver.params())


def collision_preventable(resolved: ResolvedRun, result: RunResult) -> bool | None:
    """UN R157's question for a run: would the competent and careful human driver (Annex 4,
    Appendix 3: :mod:`ego.control.careful`) have avoided the collision? True when the run
    collided and the careful driver, on the same concrete scenario
    (:func:`reference_run`), does not; False when it collides too, or when the run did not
    collide (there was nothing to prevent). None where it cannot be asked: the careful
    driver is not a controller of the scenario's task, or the scenario has no traffic."""
    if result.traffic is None or REFERENCE_DRIVER not in CONTROLLERS.get(resolved.scenario_cls.task, {}):
        return None
    if not result.metrics.get("collision"):
        return False
    if resolved.controller.name == REFERENCE_DRIVER and resolved.spec.controller == REFERENCE_DRIVER:
        return False  # the careful driver itself collided
    reference = reference_run(resolved)
    if reference is None:
        return None
    return not run(reference).metrics.get("collision")


def declared_metrics(what: RunSpec | ResolvedRun) -> tuple[Metric, ...]:
    """Every metric a run reports, as its scenario declares them (units, headline), and its
    requirements' robustness (checked here: RequirementError on a bad formula)."""
    resolved = what if isinstance(what, ResolvedRun) else resolve(what)
    return resolved.metrics_declared()


def declared_columns(cls: type[Scenario], config) -> tuple[Column, ...]:
    """The trace columns a run of ``cls`` with ``config`` writes before its controller's
    signals (which are unitless). Some depend on the configuration (one set per platoon
    follower), so the scenario is built - with its task's ``none`` controller, no SUMO
    started - and asked."""
    spec = CONTROLLERS[cls.task]["none"]
    scenario = cls(config, cls.build_controller(spec, spec.params(), config), controller_name="none")
    return tuple(scenario.trace_columns())
