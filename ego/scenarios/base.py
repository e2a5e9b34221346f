"""The simulation loop shared by every scenario.

A scenario is steppable (``reset`` / ``step``), not only a closed loop, so it can back a
Gymnasium environment or be driven by an external policy; :meth:`Scenario.run` is the
closed loop with the scenario's own controller. Each call to :meth:`Scenario.step` advances
one control period ``dt``: the controller's action is held while the ego's model integrates
(``substeps`` RK4 steps). In SUMO scenarios, every ``sumo_step / dt`` periods the ego's pose
is pushed into SUMO and SUMO advances one step so the traffic reacts; scenarios without
traffic (the bare model) simply have no bridge.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, Protocol, runtime_checkable

import numpy as np

from ego.control.base import (
    Controller,
    ControllerError,
    ControllerSpec,
    Observation,
    UserControllerError,
    signal_units,
)
from ego.control.tasks import TASKS
from ego.lane_frame import LANE_CHANGE_PHASE
from ego.models.plant import Plant
from ego.params import ConfigError, Params, param
from ego.processes import signals_deferred
from ego.record.base import NullRecorder, Recorder, Scene, Series, unit_path
from ego.results.metrics import json_number, trace_metrics, trace_metrics_declared
from ego.results.run import Event, RunResult
from ego.results.trace import Column, Metric, PlotSpec, Trace
from ego.results.traffic_log import TrafficCollector
from ego.sim.protocol import TrafficSim
from ego.sim.registry import SimSetup, make_sim
from ego.sim.types import EGO, Collision

STATUSES = ("completed", "ended", "collision", "diverged", "timeout", "interrupted", "error", "failed")
#: the statuses that are no failure: the scenario's own end, or the duration ran out in a
#: scenario whose end the controller does not decide (``ended``: a shortened run)
NOT_FAILED = ("completed", "ended")
_log = logging.getLogger("ego.scenario")
_LOG_LEVELS = {"INFO": logging.INFO, "WARN": logging.WARNING, "ERROR": logging.ERROR}
ONE_G = 9.81  #: m/s^2: the default action box of an acceleration command without a limit of its own


@dataclass(frozen=True)
class TimingConfig(Params):
    """Timing of every scenario."""

    dt: float = param(0.01, "s", "control period: controller and model step", min=0.001, max=0.1)
    substeps: int = param(1, "-", "RK4 physics sub-steps per control period", min=1, max=100)
    duration: float = param(25.0, "s", "simulated time", min=1.0, max=3600.0)

    @property
    def control_per_sumo(self) -> int:
        """Control periods per SUMO step (0: no SUMO)."""
        return 0


@dataclass(frozen=True)
class CommonConfig(TimingConfig):
    """Timing of the scenarios that run in SUMO."""

    sumo_step: float = param(0.1, "s", "SUMO step, a whole multiple of dt", min=0.01, max=1.0)
    lateral_resolution: float = param(0.875, "m", "width of SUMO's sublanes (sublane model)", min=0.1, max=3.5)
    plant: str = param(
        "",
        "-",
        "an FMI co-simulation FMU (path/to/vehicle.fmu) replacing the ego's "
        "vehicle model (see docs/fmi.md); empty: the scenario's own model",
    )
    plant_map: str = param("", "-", "TOML file mapping the plant FMU's variables (default: by name)")

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.plant.lower().endswith(".fmu"):  # the FMU checked with the parameters, before anything runs
            from ego.fmi.plant import check_plant_fmu

            check_plant_fmu(self.plant, self.plant_map)
        elif self.plant_map and not self.plant:
            raise ConfigError("plant_map needs plant (the FMU it maps)")
        ratio = self.sumo_step / self.dt
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise ConfigError(
                f"bad value for sumo_step: {self.sumo_step} (expected a whole multiple of dt={self.dt} s)"
            )

    @property
    def control_per_sumo(self) -> int:
        """Control periods per SUMO step."""
        return round(self.sumo_step / self.dt)


def divergence(state: Sequence[float], offset: float, heading_error: float, road_halfwidth: float) -> str | None:
    """Why the ego's state is beyond anything a controller should produce, or None."""
    X, u, Y, v, psi, r = state
    if not all(map(math.isfinite, state)):
        return "the state is not finite (NaN or infinity)"
    if abs(offset) > road_halfwidth:
        return f"left the road: lateral offset {offset:+.2f} m from the reference lane"
    if u < -1.0:
        return f"driving backwards at {u:.1f} m/s"
    if u > 80.0:
        return f"speed {u:.1f} m/s is absurd"
    if abs(r) > 2.5:
        return f"yaw rate {r:+.2f} rad/s: the car is spinning"
    if abs(heading_error) > math.radians(75.0):
        return f"heading {math.degrees(heading_error):+.0f} deg off the road direction"
    return None


#: default requirements several scenarios share (Scenario.requirements)
NO_COLLISION = ("no_collision", "always (not collision)")
NO_AVOIDABLE_COLLISION = ("no_avoidable_collision", "always (not avoidable_collision)")
#: UN R157's verdict: no collision the competent and careful driver would have avoided
#: (``preventable_collision``; the default of the R157 scenario files, ego.openscenario)
NO_PREVENTABLE_COLLISION = ("no_preventable_collision", "always (not preventable_collision)")
#: the ego stays inside its lane's markings outside a commanded lane change (``lane_departure``)
STAYS_IN_LANE = ("stays_in_lane", "always (lane_departure <= 0 m)")


def check_backend(cls: type[Scenario], backend: str) -> None:
    """ConfigError unless scenario ``cls`` runs on traffic simulator ``backend``: the registry
    matches the scenario's ``needs`` to the backend's capabilities, and a backend that lacks
    one is refused naming what it lacks (curve on highway-env lacks any_network). A scenario
    without a traffic simulator (report-000) takes no other backend than the default."""
    from ego.sim.registry import DEFAULT_BACKEND, check_needs
    from ego.sim.registry import backend as registered

    registered(backend)  # a name no backend has
    if not cls.runs_traffic():
        if backend != DEFAULT_BACKEND:
            raise ConfigError(
                f"bad value for --backend: {backend!r} (scenario {cls.name} runs without a traffic simulator)"
            )
        return
    check_needs(f"scenario {cls.name}", cls.needs, backend)


def backends_for(cls: type[Scenario]) -> tuple[str, ...]:
    """The registered backends scenario ``cls`` runs on: those with every capability it needs
    (none for a scenario without a traffic simulator)."""
    from ego.sim.registry import backend, backend_names

    if not cls.runs_traffic():
        return ()
    return tuple(n for n in backend_names() if not backend(n).lacks(cls.needs))


class Scenario:
    """Base of every scenario: a declaration (``name``, ``config_cls``, trace ``columns``,
    ``metric_specs``, default ``requirements``, the ``needs`` of a simulator) and the run's
    state and order (:meth:`reset`, :meth:`step`, the flush, :meth:`result`).

    What a scenario does in a run is its loop object (:attr:`loop`, a :class:`Loop`): a
    motorway scenario returns its :class:`Parts` from :meth:`compose` and runs on their
    :class:`ComposedLoop`; a scenario off the motorway returns its own loop from
    :meth:`make_loop` (a :class:`PartsLoop`). No method is replaced on an instance. Its
    results are ``_metrics`` (and ``_meta`` for the recording's run panel).
    """

    name: ClassVar[str] = ""
    summary: ClassVar[str] = ""
    #: which controllers drive it (``ego.control.CONTROLLERS[task]``) and what they return
    task: ClassVar[str] = "tracking"
    #: the controller a run gets where none is named (an env's ``config["controller"]``, a
    #: benchmark's demonstration); None: its task's (``TASKS[task].default_controller``)
    default_controller: ClassVar[str | None] = None
    config_cls: ClassVar[type] = CommonConfig
    #: the SUMO network it runs on (``ego.sumo.net.net_file``; checked before any run), or
    #: None without SUMO
    network: ClassVar[str | None] = None
    #: the edge it drives on, for a backend that builds one straight road (highway-env)
    edge: ClassVar[str | None] = None
    #: trace columns written by name every control step; ``t`` first
    columns: tuple[Column, ...] = (Column("t", "s", "time"),)
    #: the scenario's own metrics (besides COMMON_METRICS), with units; headline ones are
    #: the columns of ``ego compare``'s metrics.md
    metric_specs: ClassVar[tuple[Metric, ...]] = ()
    #: trace columns ``ego compare`` plots, one line per controller
    plots: ClassVar[tuple[PlotSpec, ...]] = ()
    #: what it needs of a traffic simulator: field names of ego.sim.registry.Capabilities;
    #: it runs on every registered backend that has them all (``check_backend``,
    #: :func:`backends_for`)
    needs: ClassVar[tuple[str, ...]] = ()
    #: the requirements every run checks unless told otherwise: (name, formula) each
    #: (ego.requirements.defaults; docs/requirements.md)
    requirements: ClassVar[tuple[tuple[str, str], ...]] = ()

    @classmethod
    def runs_traffic(cls) -> bool:
        """It runs in a traffic simulator (``--backend``): a network of its own, or one it
        builds itself (a scenario file's road); False for the bare model (report-000)."""
        return cls.network is not None or cls._make_bridge is not Scenario._make_bridge

    @classmethod
    def default_config(cls, overrides: Mapping[str, Any]) -> Any:
        """The configuration the overrides apply to: the defaults of ``config_cls``; a
        scenario with variants starts from the variant's preset (``--set variant=...``)."""
        return cls.config_cls()

    @classmethod
    def network_of(cls, config: Any) -> str | None:
        """The SUMO network a run of ``config`` drives on: ``network``, or for a configuration
        with a ``road`` the motorway it names (``ego.sumo.net.MOTORWAY_ROADS``)."""
        road = getattr(config, "road", None)
        if cls.network is None or road is None:
            return cls.network
        from ego.sumo.net import MOTORWAY_ROADS

        return MOTORWAY_ROADS[road]

    @classmethod
    def check_config(cls, config: Any) -> None:
        """Checks of a configuration that need more than the configuration (the network's
        geometry, say), made by ``ego.runner.resolve`` before anything runs: ConfigError.
        Default: none."""

    @classmethod
    def build_controller(cls, spec: ControllerSpec, params: Any, config: Any) -> Controller:
        """The controller the loop drives: one of ``spec`` stepping every ``config.dt``;
        a scenario with several controlled vehicles builds one per vehicle."""
        return spec.build(params, config.dt)

    @classmethod
    def compare_plots(cls, config: Any) -> tuple[PlotSpec, ...]:
        """Trace columns ``ego compare`` plots for this configuration (default: ``plots``)."""
        return cls.plots

    @classmethod
    def metrics_declared(cls, config: Any = None) -> tuple[Metric, ...]:
        """Every metric a run reports: the common ones, then the scenario's own, then the
        registered trace metrics its trace has the columns of (``ego.results.metrics``)."""
        backend = (BACKEND_METRIC,) if cls.runs_traffic() else ()
        names = tuple(c.name for c in cls.columns)
        lanes = (LANE_DEPARTURE_METRIC,) if set(LANE_DEPARTURE_NEEDS) <= set(names) else ()
        return COMMON_METRICS + backend + cls.metric_specs + trace_metrics_declared(names) + lanes + COMMON_TAIL_METRICS

    def trace_columns(self) -> tuple[Column, ...]:
        """The declared trace columns of this run (default: the class's ``columns``)."""
        return self.columns

    def __init__(
        self,
        config: Any,
        controller: Controller,
        *,
        seed: int = 0,
        recorder: Recorder | None = None,
        controller_name: str = "",
        backend: str = "sumo",
        backend_options: Mapping[str, Any] | None = None,
    ) -> None:
        check_backend(type(self), backend)
        self.config = config
        #: the traffic simulator (one of ``backends``; ``ego.sim.registry``) and its options
        #: as data (highway-env: ``video``)
        self.backend = backend
        self.backend_options = dict(backend_options or {})
        self.controller = controller
        self.controller_name = controller_name or type(controller).__name__
        self.seed = int(seed)
        self.recorder: Recorder = recorder if recorder is not None else NullRecorder()
        #: the recording wants the vehicles' outlines (none to fetch from SUMO for a null one)
        self._outlines = not isinstance(self.recorder, NullRecorder)
        self.bridge: TrafficSim | None = None
        self.traffic: TrafficCollector | None = None
        self._lanes: tuple[tuple[float, tuple[tuple[float, ...], ...]], ...] = ()
        self.obs = Observation()
        self.events: list[Event] = []
        self.trace = Trace(self.trace_columns())
        self.t = 0.0
        self.k = 0
        self.status = "running"
        self.status_detail = ""
        self.collision: Collision | None = None
        self._flushed = 0
        self._next_flush = 1.0
        self._wall0 = 0.0
        self._wall = 0.0
        self._signal_names: tuple[str, ...] = ()
        self._signal_units: dict[str, str] = {}
        self.controlled_ids: tuple[str, ...] = ()
        #: vehicle id -> RGB for the recording (others: grey)
        self.colors: dict[str, tuple[int, int, int]] = {}
        parts = self.parts = self.compose()
        if parts is not None:
            self.world, self.view, self.manoeuvre, self.safety = parts.world, parts.view, parts.manoeuvre, parts.safety
        #: the run's loop: what :meth:`reset` and :meth:`step` call (:class:`Loop`)
        self.loop: Loop = self.make_loop()

    #: once a run has started: the ego's plant, every controlled vehicle's plant by id, the
    #: lanes (lane id -> LanePolyline) and the ego's body (set by the scenario's loop)
    ego: Any
    plants: dict[str, Any]
    lanes: Any
    geometry: Any
    #: a composed scenario's parts (:meth:`compose`; None: the scenario returns its own loop)
    parts: Parts | None = None
    world: Any = None
    view: Any = None
    manoeuvre: Any = None
    safety: Any = None
    #: a composed scenario's own work after the actors' updates before a simulator step, and
    #: after the step's surround sensing (None: nothing)
    before_sim_step: Callable[[], None] | None = None
    after_sim_step: Callable[[], None] | None = None
    #: a composed scenario's own work once its parts are set up, before the first
    #: observation (None: nothing)
    after_setup: Callable[[], None] | None = None
    #: ... and each control period before the manoeuvre plans (the surround view updated)
    before_plan: Callable[[], None] | None = None

    def compose(self) -> Parts | None:
        """The scenario's parts (:class:`Parts`), or None for one that returns its own loop
        from :meth:`make_loop`."""
        return None

    def make_loop(self) -> Loop:
        """The loop object of this scenario's runs (:class:`Loop`, made once, from the
        constructor): a composed scenario's is the :class:`ComposedLoop` of its parts; a
        scenario off the motorway returns its own (a :class:`PartsLoop` with ``setup``,
        ``act`` and ``update``: curve, lane-centering, platoon, report-000)."""
        if self.parts is None:
            raise NotImplementedError(
                f"scenario {self.name} returns its parts from compose() or its loop from make_loop()"
            )
        return ComposedLoop(self, self.parts)

    # -- Gymnasium-style interface -----------------------------------------------------------
    def reset(self, *, seed: int | None = None) -> Observation:
        """Start a fresh run (SUMO restarted, traffic regenerated from the seed)."""
        if seed is not None:
            self.seed = int(seed)
        self._close_bridge()
        self._wall0 = time.perf_counter()
        self.events = []
        self.t, self.k = 0.0, 0
        self.status, self.status_detail, self.collision = "running", "", None
        self._flushed, self._next_flush = 0, 1.0
        c = self.config
        self._dt, self._per_sumo, self._t_end = c.dt, c.control_per_sumo, c.duration - 1e-9
        bind = getattr(self.controller, "bind_events", None)
        if bind is not None:  # an FMU controller's log messages become the run's events
            bind(self.event)
        try:
            self.controller.reset(seed=self.seed)
            self._signal_names = tuple(self.controller.signals())
        except UserControllerError as exc:  # a user's class failed before the run: bad input
            raise ConfigError(str(exc)) from None
        self._signal_units = signal_units(self.controller)
        self.bridge = self._make_bridge()
        self.trace = Trace(self.trace_columns(), self._signal_names, self._signal_units)
        self.traffic = None
        if self.bridge is not None:
            self.bridge.start()
            self.traffic = TrafficCollector()
        loop = self.loop
        loop.setup(np.random.default_rng(self.seed))
        if self._fmu_plant() and not getattr(self.ego, "is_fmu", False):
            raise ConfigError(
                f"--set plant= replaces a bicycle plant; the {self.name} scenario has none "
                "(motorway and curve scenarios have)"
            )
        scene = loop.scene()
        self._lanes = tuple((w, tuple(tuple(p) for p in pts)) for w, pts in scene.lanes)
        self.recorder.begin(scene, loop.series(), self._meta())
        if self._outlines:
            loop.record_boxes()
        if self.traffic is not None:
            loop.subscribe_traffic()
            loop.log_traffic()
        loop.update()
        return self.obs

    @property
    def done(self) -> bool:
        return self.status != "running"

    def step(self, action: tuple[float, float]) -> Observation:
        """Apply ``action`` = (longitudinal command, delta in rad) for one control period:
        Fx per driven wheel (N) in tracking scenarios, a_x (m/s^2) in the curve task."""
        if self.status != "running":
            raise RuntimeError(f"the run has ended ({self.status}); call reset()")
        loop = self.loop
        loop.act(action)
        k = self.k = self.k + 1
        t = self.t = k * self._dt
        if self._per_sumo and k % self._per_sumo == 0:
            self._sumo_step()
        if self.status == "running":
            reason = loop.diverged()
            if reason is not None:
                self._end("diverged", reason, level="ERROR")
            else:
                loop.update()
                if t >= self._t_end and self.status == "running":
                    self._end(*loop.final_status())
        if t >= self._next_flush or self.status != "running":
            self._flush()
        return self.obs

    def run(self) -> RunResult:
        """The closed loop: reset, then the scenario's controller until the run ends.

        Ctrl-C (SIGINT) or SIGTERM ends the run at the next control step with status
        ``interrupted``: the metrics so far, the recording closed with every step simulated
        (a second signal interrupts at once)."""
        restore = self._catch_stop_signals()
        try:
            try:
                obs = self.reset()
                controller = self.controller
                step = self.step
                while self.status == "running" and not self._stop:
                    obs = step(controller.step(obs))
            except ControllerError as exc:  # an FMU's error or a non-finite command
                if getattr(exc, "interrupted", False):  # Ctrl-C/SIGTERM while an FMU was in a call
                    self._stop = True
                    self._end("interrupted", str(exc), level="WARN")
                    self._flush()
                else:
                    self._end("error", str(exc), level="ERROR")
                    self._flush()
            if self._stop and self.status == "running":
                self._end("interrupted", "interrupted (SIGINT or SIGTERM)", level="WARN")
                self._flush()
            result = self.result()
            if self.on_result is not None:  # e.g. requirements checked while the recording is open
                self.on_result(self, result)
            return result
        finally:
            restore()
            self.close()

    _stop = False
    #: called as ``on_result(scenario, result)`` after a run's result, before the recording
    #: closes (ego.runner sets it to check the run's requirements)
    on_result = None

    def _catch_stop_signals(self) -> Callable[[], None]:
        """Make SIGINT and SIGTERM request a stop at the next step; returns the undo."""
        import signal
        import threading

        self._stop = False
        if threading.current_thread() is not threading.main_thread():
            return lambda: None

        def request(signum: int, frame: Any) -> None:
            if self._stop:  # asked twice: stop now
                from ego.usercode import SignalInterrupt

                raise SignalInterrupt
            self._stop = True

        # a process that ignores a signal (a sweep's worker: the parent handles Ctrl-C) keeps
        # ignoring it
        old = {
            sig: signal.signal(sig, request)
            for sig in (signal.SIGINT, signal.SIGTERM)
            if signal.getsignal(sig) is not signal.SIG_IGN
        }

        def restore() -> None:
            for sig, handler in old.items():
                signal.signal(sig, handler)

        return restore

    def _fmu_plant(self) -> bool:
        """Whether the configuration puts an FMU in place of the ego's own model."""
        return str(getattr(self.config, "plant", "")).lower().endswith(".fmu")

    def own_plant(self, plant: Plant) -> Plant:
        """The ego's plant: ``plant``, or the FMU of ``--set plant=vehicle.fmu`` in its place
        (started from its state)."""
        if not self._fmu_plant():
            return plant
        from ego.fmi.plant import fmu_plant

        fmu: Plant = fmu_plant(self, plant)  # an FmuPlant
        return fmu

    def close(self) -> None:
        """Close SUMO, the recording and the controller's resources (an FMU instance); safe
        to call twice."""
        try:
            self._close_bridge()
        finally:
            try:
                self.recorder.close()
            finally:
                for part in (self.controller, getattr(self, "ego", None)):
                    close = getattr(part, "close", None)  # an FMU controller's or plant's instance
                    if close is not None:
                        close()

    def _close_bridge(self) -> None:
        if self.bridge is not None:
            self.bridge.close()
            self.bridge = None

    # -- shared machinery ----------------------------------------------------------------------
    def _make_bridge(self) -> TrafficSim | None:
        """The traffic simulator of a scenario with a ``network`` (``ego.sim.registry``:
        ``self.backend`` with ``self.backend_options``); None for the bare model."""
        if self.network is None:
            return None
        from ego.sumo.net import net_file

        c = self.config
        network = self.network_of(c)
        assert network is not None  # a scenario with a network drives on one
        return make_sim(
            self.backend,
            SimSetup(net_file(network), c.sumo_step, self.seed, c.lateral_resolution, self.edge, c.duration),
            self.backend_options,
        )

    def _sumo_step(self) -> None:
        bridge = self.bridge
        assert bridge is not None  # a scenario with simulator steps has a simulator
        loop = self.loop
        loop.before_sim_step()
        collisions = bridge.step()
        loop.after_sim_step()
        if self._outlines:
            loop.record_boxes()
        loop.log_traffic()
        if collisions:
            mine = [c for c in collisions if c.collider in bridge.controlled or c.victim in bridge.controlled]
            if mine:
                self._collided(mine[0])
            else:
                for c in collisions:
                    self.event("traffic", f"collision in the traffic: {c.collider} hit {c.victim}", "WARN")

    def _collided(self, c: Collision) -> None:
        """End the run on a collision involving the ego."""
        self.collision = c
        self._end(
            "collision",
            f"{c.collider} ({c.collider_speed:.1f} m/s) hit {c.victim} ({c.victim_speed:.1f} m/s): {c.kind}",
            level="ERROR",
        )

    def event(self, kind: str, text: str, level: str = "INFO") -> None:
        """Record an event: the run's event list, the ``ego`` logger and the recording."""
        ev = Event(self.t, kind, text, level)
        self.events.append(ev)
        _log.log(_LOG_LEVELS.get(level, logging.INFO), "%s t=%.2f s [%s] %s", self.name, self.t, kind, text)
        self.recorder.event(self.t, f"[{kind}] {text}", level)

    def _end(self, status: str, detail: str, level: str = "INFO") -> None:
        self.status = status
        self.status_detail = detail
        self.event(status, f"run ends: {status} at t = {self.t:.2f} s: {detail}", level)
        self._wall = time.perf_counter() - self._wall0

    def _flush(self) -> None:
        if type(self.recorder) is NullRecorder:  # no batch to keep whole
            self._flush_now()
            return
        with signals_deferred():  # Ctrl-C lands before or after a batch, never inside it
            self._flush_now()

    def _flush_now(self) -> None:
        if len(self.trace) > self._flushed:
            if type(self.recorder) is not NullRecorder:  # no rows to build for no recording
                data = self.trace.array(self._flushed)
                data[np.isinf(data)] = np.nan  # infinite TTC: a gap in the plot
                self.recorder.write_rows(self.trace.names, data)
            self._flushed = len(self.trace)
        self.recorder.flush()
        self._next_flush = math.floor(self.t) + 1.0

    def _lane_departure(self, trace: np.ndarray, columns: Sequence[str], events: list[Event]) -> float | None:
        """The run's largest lane departure (m); a ``lane_departure`` event (into ``events``, in
        time order) where the first one starts."""
        from ego.lane_frame import lane_departure

        col = {n: i for i, n in enumerate(columns)}
        if not len(trace):
            return None
        width = getattr(getattr(self, "geometry", None), "width", None) or 1.8
        out = lane_departure(
            trace[:, col["d"]], trace[:, col["d_ref"]], trace[:, col["phase"]], self._lanes[0][0], width
        )
        worst = float(out.max())
        if worst > 0.0:
            i = int(np.argmax(out > 0.0))
            t0 = float(trace[i, col["t"]])
            text = f"lane departure: the ego's side beyond its lane's marking, by up to {worst:.2f} m"
            at = next((k for k, e in enumerate(events) if e.t > t0), len(events))
            events.insert(at, Event(t0, "lane_departure", text, "WARN"))
        return json_number(worst, 4)

    def result(self) -> RunResult:
        columns = self.trace.names
        trace = self.trace.array()
        metrics = {
            "scenario": self.name,
            "controller": self.controller_name,
            "seed": self.seed,
            "status": self.status,
            "status_detail": self.status_detail,
            "collision": self.collision is not None,
            "collision_with": self._other_party(),
        }
        if self.runs_traffic():
            metrics["backend"] = self.backend
        metrics.update(self._metrics(trace, columns))
        metrics.update(trace_metrics(trace, columns, (c.name for c in type(self).columns)))
        events = list(self.events)
        if self._lanes and set(LANE_DEPARTURE_NEEDS) <= set(columns):
            worst = metrics["max_lane_departure"] = self._lane_departure(trace, columns, events)
            if worst and self.status in NOT_FAILED:  # a run that left its lane did not complete
                first = next(e for e in events if e.kind == "lane_departure")
                self.status = metrics["status"] = "failed"
                self.status_detail = metrics["status_detail"] = (
                    f"left its lane at t = {first.t:.2f} s (outside a lane change: the ego's side up to "
                    f"{worst:.2f} m beyond the marking; requirement stays_in_lane)"
                )
        metrics.update(
            {
                "sim_time": json_number(self.t, 4),
                "wall_time": json_number(self._wall, 4),
                "steps": self.k,
            }
        )
        return RunResult(
            self.name,
            self.controller_name,
            self.seed,
            self.status,
            metrics,
            events,
            columns,
            trace,
            self.trace.units(),
            self.traffic.log() if self.traffic is not None else None,
            self._lanes,
        )

    # -- one contract for every task: the controlled vehicles by id ------------------------
    # (what a front-end driving one vehicle, ego.gym, reads; the platoon has one per follower)
    @property
    def agent_id(self) -> str:
        """The vehicle an agent drives: the first controlled one (the ego, the platoon's first
        follower)."""
        return self.controlled_ids[0]

    def observation(self, vid: str) -> Any:
        """What vehicle ``vid``'s controller observes now (its task's observation)."""
        return self.obs

    def plant(self, vid: str) -> Plant:
        """Vehicle ``vid``'s plant."""
        plant: Plant = self.ego
        return plant

    @classmethod
    def reference_controller(cls) -> str:
        """The controller a run of this scenario gets where none is named."""
        return cls.default_controller or TASKS[cls.task].default_controller

    def action_limits(self, vid: str | None = None) -> tuple[float, float, float]:
        """Vehicle ``vid``'s action box in its plant's units (None: the agent's vehicle), known
        from the configuration before a run starts: (most negative and largest longitudinal
        command, largest |steer| rad). A composed scenario's plant declares it (``Parts.limits``); default: 1 g of
        acceleration either way and the configuration's steer limit."""
        if self.parts is not None and self.parts.limits is not None:
            return self.parts.limits(self.config)
        return -ONE_G, ONE_G, getattr(self.config, "max_steer", 0.0)

    def joint_action(self, own: Any, vid: str, longitudinal: float | None, lateral: float | None) -> Any:
        """The action :meth:`step` takes when vehicle ``vid`` gets ``longitudinal`` and
        ``lateral`` (None: that channel stays ``own``'s, the scenario's controller's)."""
        return (own[0] if longitudinal is None else longitudinal, own[1] if lateral is None else lateral)

    def step_joint(self, vid: str, longitudinal: float | None, lateral: float | None) -> Any:
        """One :meth:`step` in which vehicle ``vid`` takes ``longitudinal`` and ``lateral`` (None:
        that channel stays the scenario's controller's) and every other vehicle its controller's
        command: the step of an agent driving ``vid`` beside the scenario's controllers."""
        return self.step(self.joint_action(self.controller.step(self.obs), vid, longitudinal, lateral))

    def agent_signals(self, vid: str) -> tuple[float, float, float | None, float]:
        """Vehicle ``vid`` now: (speed along its lane m/s, tracking error m, longitudinal and
        lateral acceleration m/s^2); the longitudinal one None when the scenario does not
        measure it (the rate of the speed stands for it)."""
        o = self.obs
        return o.ds, o.d - o.d_ref, None, self.plant(vid).lateral_accel

    def agent_signals_reader(self, vid: str) -> Callable[[], tuple[float, float, float | None, float]]:
        """:meth:`agent_signals` of ``vid`` as a function of nothing, valid until the run ends
        (made after the reset: the observation and the plant it reads hold still over a run).
        An env calls it at every step, so it looks nothing up. A class that defines
        ``agent_signals`` defines this beside it (ego.gym falls back to ``agent_signals``
        where the two come from different classes)."""
        o, plant = self.obs, self.plant(vid)
        return lambda: (o.ds, o.d - o.d_ref, None, plant.lateral_accel)

    def lane_rows(self, vid: str) -> tuple[tuple[float, ...], Any, float]:
        """(vehicle ``vid``'s row, the other vehicles' rows or None without a surround sensor,
        its length m); a row is (s, d, v_s, v_d, heading) of a box centre in its lane's frame
        (m, m/s, rad; + left)."""
        road: Any = self.view or self  # a composed scenario's road and surround sensors are its view
        ego = (road.s, road.d_road, road.ds, road.dd, road.heading_error)
        sensor = getattr(road, "sensor", None)
        return ego, (sensor.tracks(self.t) if sensor is not None else None), self.geometry.length

    def _other_party(self) -> str | None:
        c = self.collision
        if c is None:
            return None
        return c.victim if c.collider in self.controlled_ids else c.collider

    # -- what a run reports --------------------------------------------------------------------
    def _metrics(self, trace: np.ndarray, columns: tuple[str, ...]) -> dict[str, Any]:
        return {}

    def _meta(self) -> dict[str, Any]:
        """What the recording's "run" panel lists: names, seed and every parameter."""
        meta = {"scenario": self.name, "controller": self.controller_name, "seed": self.seed}
        if self.runs_traffic():  # which traffic simulator ran (the /run panel says so)
            meta["backend"] = self.backend
        meta.update({k: getattr(self.config, k) for k in self.config.__dataclass_fields__})
        if self.colors:
            meta["colors"] = self.colors
        return meta


class Parts:
    """A scenario composed of parts, each with one job (see docs/architecture.md):

    * ``world``: the traffic simulator, the traffic actors, the lanes
      (:class:`ego.scenarios.motorway.MotorwayWorld`);
    * ``plants``: vehicle id -> :class:`~ego.models.plant.Plant` (the ego: ``ego``);
    * ``view``: the task's sensors and its one observation builder
      (:class:`ego.scenarios.motorway.SurroundView`);
    * ``manoeuvre``: the named state machine whose state is the trace's ``phase``
      (:class:`ego.scenarios.manoeuvre.EvasiveManoeuvre`, or a plain reference);
    * ``safety``: the filter between the controller's action and the plant
      (:class:`ego.scenarios.safety.SafetyLayer`), or None.

    :meth:`Scenario.compose` returns one; the scenario's loop is then a
    :class:`ComposedLoop` calling these parts' methods, bound once per run."""

    __slots__ = ("world", "view", "manoeuvre", "safety", "make_plant", "series", "limits")

    def __init__(
        self,
        world: Any,
        view: Any,
        manoeuvre: Any,
        safety: Any = None,
        make_plant: Callable[[Any, Any, tuple[float, float, float]], Any] | None = None,
        series: Callable[[Sequence[str], Mapping[str, str]], list[Series]] | None = None,
        limits: Callable[[Any], tuple[float, float, float]] | None = None,
    ) -> None:
        self.world, self.view, self.manoeuvre, self.safety = world, view, manoeuvre, safety
        #: (config, geometry, pose) -> the ego's plant
        self.make_plant = make_plant
        #: config -> that plant's action box (:meth:`Scenario.action_limits`; None: the default)
        self.limits = limits
        #: (signal names, signal units) -> the recording's panels (None: the controller's)
        self.series = series


class Loop(Protocol):
    """What :meth:`Scenario.reset` and :meth:`Scenario.step` call on a run: one object per
    scenario (``Scenario.loop``), made once by :meth:`Scenario.make_loop`. The scenario owns
    the run's state (time, status, trace, events, the simulator) and the order of the calls;
    the loop object owns what a scenario does in them."""

    def setup(self, rng: np.random.Generator) -> None:
        """The run's vehicles, plants and sensors (the simulator started; ``rng`` seeded)."""

    def act(self, action: Any) -> None:
        """One control period of the plants under ``action`` and the trace row of time t."""

    def before_sim_step(self) -> None:
        """Before a simulator step: the ego pushed, the scripted actors."""

    def after_sim_step(self) -> None:
        """After a simulator step: read the scene."""

    def diverged(self) -> str | None:
        """Why the run diverged, or None."""

    def update(self) -> None:
        """Events, references and the observation of time t."""

    def final_status(self) -> tuple[str, str]:
        """Status and detail when the duration runs out."""

    def scene(self) -> Scene:
        """The recording's static scene (lanes)."""

    def series(self) -> list[Series]:
        """The recording's panels."""

    def record_boxes(self) -> None:
        """Every vehicle's outline into the recording (a simulator step)."""

    def subscribe_traffic(self) -> None:
        """Ask the simulator for what :meth:`log_traffic` reads (after :meth:`setup`)."""

    def log_traffic(self) -> None:
        """This simulator step's vehicles into the traffic log."""


# -- the fast paths a part may offer the composed loop (bound once a run; C where built) ---
@runtime_checkable
class BindsStep(Protocol):
    """A plant whose step the loop binds once a run (``BicyclePlant``: ego._native)."""

    def bind_step(self) -> Callable[[tuple[float, float]], None]: ...


@runtime_checkable
class BindsFrame(Protocol):
    """A road sensor whose lane frame the loop binds once a run (``RoadSensor``)."""

    def bind_frame(self) -> Callable[[], None]: ...


class PartsLoop:
    """The loop of a scenario whose parts are a plant (or several, keyed by vehicle id),
    optionally a road's ``world`` (:class:`ego.scenarios.road.RoadWorld`: the lanes, the
    scripted actors, the traffic log, the recording's vehicles) with its road sensor
    (``world.view``: the lane frame, the divergence check, the ego's push) and the
    scenario's plan. A scenario's loop subclasses it with ``setup``, ``act`` and ``update``;
    what the world does is done here: before every simulator step the ego is pushed and the
    actors act, and the traffic log, the recording's vehicles and lanes are the world's.
    Without a world: no simulator work, no divergence check, no lanes."""

    def __init__(self, sc: Scenario, world: Any = None) -> None:
        self.sc = sc
        self.world = world
        self.view = world.view if world is not None else None

    def setup(self, rng: np.random.Generator) -> None:
        raise NotImplementedError

    def act(self, action: Any) -> None:
        raise NotImplementedError

    def update(self) -> None:
        raise NotImplementedError

    def before_sim_step(self) -> None:
        sc = self.sc
        self.world.before_step(sc.t - sc.config.sumo_step)

    def after_sim_step(self) -> None:
        pass

    def diverged(self) -> str | None:
        view = self.view
        return view.diverged() if view is not None else None

    def final_status(self) -> tuple[str, str]:
        return "completed", "reached the end of the simulated time"

    def scene(self) -> Scene:
        lanes = self.world.lanes.values() if self.world is not None else ()
        return Scene(lanes=[(lane.width, lane.points) for lane in lanes], title=self.sc.name)

    def series(self) -> list[Series]:
        sc = self.sc
        return signal_series(sc._signal_names, sc._signal_units)

    def record_boxes(self) -> None:
        if self.world is not None:
            sc = self.sc
            self.world.record(sc.recorder, sc.t)

    def subscribe_traffic(self) -> None:
        if self.world is not None:
            self.world.subscribe()

    def log_traffic(self) -> None:
        if self.world is not None:
            sc = self.sc
            self.world.log(sc.traffic, sc.t)


class ComposedLoop:
    """The loop of a composed scenario (:class:`Parts`): one step calls the parts directly:
    safety filter -> plant -> trace row -> road sensor; at a simulator step: ego pushed,
    actors, step, surround sensor; then divergence, the surround view, the manoeuvre and the
    observation. The scenario's own optional work (``after_setup``, ``before_sim_step``,
    ``after_sim_step``, ``before_plan``: None or a method) is called at its place."""

    def __init__(self, sc: Scenario, parts: Parts) -> None:
        self.sc, self.parts = sc, parts
        self.view, self.world, self.manoeuvre = parts.view, parts.world, parts.manoeuvre
        # the parts' own methods where the loop's call is exactly theirs
        self.diverged: Callable[[], str | None] = parts.view.diverged
        self.final_status: Callable[[], tuple[str, str]] = parts.manoeuvre.final_status
        self._road_y = 0.0

    def setup(self, rng: np.random.Generator) -> None:
        sc, parts = self.sc, self.parts
        world, view = parts.world, parts.view
        bridge = sc.bridge
        missing = world.setup(bridge, rng)
        if missing:
            sc.event(
                "traffic",
                f"SUMO could not place {len(missing)} background vehicles: "
                f"{', '.join(missing[:5])}{'...' if len(missing) > 5 else ''}",
                "WARN",
            )
        sc.controlled_ids = (EGO,)
        sc.colors.update(world.colors)
        sc.lanes = world.lanes
        assert bridge is not None and parts.make_plant is not None  # a composed scenario's simulator and plant
        ego = self.ego = sc.ego = sc.own_plant(parts.make_plant(sc.config, sc.geometry, bridge.cg_pose(EGO)))
        sc.plants = {EGO: ego}
        view.setup(bridge, world.lanes, ego)
        sc.obs.lane = view.road
        self._road_y = view.road.points[0][1]
        self.manoeuvre.reset(ego)
        safety = parts.safety
        if safety is not None:
            safety.reset(ego)
            self._filter = safety.filter
        else:
            self._filter = _unfiltered
        self._write_row = sc.trace.bind(view.row_names)
        self._signals = sc.controller.signals
        self._obs = sc.obs
        # the parts' own fast paths where they declare them (C kernels of ego._native)
        self._frame = view.bind_frame() if isinstance(view, BindsFrame) else view.frame
        self._look = view.look
        self._plant_step = ego.bind_step() if isinstance(ego, BindsStep) else ego.step
        man = self.manoeuvre
        self._plan = man.plan
        view.sense(sc.t)
        if sc.after_setup is not None:
            sc.after_setup()

    def rebind_plant(self) -> None:
        """Bind the plant's step again (after the plant changed its model: a road's friction)."""
        ego = self.ego
        self._plant_step = ego.bind_step() if isinstance(ego, BindsStep) else ego.step

    def act(self, action: tuple[float, float]) -> None:
        ego = self.ego
        self._plant_step(self._filter(action))
        fx, delta = ego.applied
        obs, view = self._obs, self.view
        # the row describes time t: the state before this step and the action applied
        d = obs.d
        self._write_row(
            self._signals(),
            (
                obs.t,
                view.X,
                view.Y,
                view.s,
                d,
                obs.d_ref,
                d - obs.d_ref,
                view.d_road,
                obs.speed,
                view.ds,
                obs.s_ref,
                obs.ds_ref,
                fx,
                delta,
                view.ttc_front,
                view.ttc_rear,
                view.gap_front,
                view.gap_rear,
                ego.lateral_accel,
                obs.yaw_rate,
                # an agent's commanded lane change is a lane change, as the manoeuvre's own
                LANE_CHANGE_PHASE if view.agent_lane_change else self.manoeuvre.phase,
                view.target_lane,
            ),
        )
        self._frame()

    def before_sim_step(self) -> None:
        sc = self.sc
        bridge = sc.bridge
        self.view.push(bridge)
        t = sc.t - sc.config.sumo_step
        for actor in self.world.actors:
            actor.update(bridge, t)
        if sc.before_sim_step is not None:
            sc.before_sim_step()

    def after_sim_step(self) -> None:
        sc = self.sc
        self.view.sense(sc.t)
        if sc.after_sim_step is not None:
            sc.after_sim_step()

    def scene(self) -> Scene:
        return Scene(lanes=[(lane.width, lane.points) for lane in self.world.lanes.values()], title=self.sc.name)

    def series(self) -> list[Series]:
        sc, series = self.sc, self.parts.series
        if series is None:
            return signal_series(sc._signal_names, sc._signal_units)
        return series(sc._signal_names, sc._signal_units)

    def record_boxes(self) -> None:
        sc = self.sc
        assert sc.bridge is not None
        ids, poses = sc.bridge.poses()
        sc.recorder.vehicles(sc.t, ids, poses, (self.ego.state[0], self._road_y))

    def subscribe_traffic(self) -> None:
        pass  # the surround sensor's subscription reaches as far

    def log_traffic(self) -> None:
        sc = self.sc
        centre, ids, rows = self.view.traffic_row()
        assert sc.traffic is not None
        sc.traffic.add(sc.t, centre, ids, rows)

    def update(self) -> None:
        sc = self.sc
        t = sc.t
        collision = self._look(t)
        if collision is not None and sc.status == "running":
            sc._collided(collision)
            if sc.status != "running":
                return
        obs = self._obs
        if sc.before_plan is not None:
            sc.before_plan()
        self._plan(obs, t)
        self.view.observe(obs, t)


def _unfiltered(action: tuple[float, float]) -> tuple[float, float]:
    return action


#: metrics every run reports first ...
COMMON_METRICS = (
    Metric("scenario", "-", "scenario name"),
    Metric("controller", "-", "controller name"),
    Metric("seed", "-", "random seed of the traffic and the controller"),
    Metric(
        "status",
        "-",
        "completed; ended (the duration ran out before the scenario's end, "
        "not a failure); collision, diverged or timeout (the duration ran out during a "
        "manoeuvre); interrupted",
    ),
    Metric("status_detail", "-", "why the run ended"),
    Metric("collision", "-", "the ego (or a controlled vehicle) was in a collision"),
    Metric("collision_with", "-", "the other party of the collision"),
)
#: ... then, for a scenario with several traffic simulators, which one ran ...
BACKEND_METRIC = Metric(
    "backend", "-", "traffic simulator that ran it (ego.sim.registry: sumo, highway-env, a plugin's)"
)
#: ... and last
#: the trace columns the lane departure is measured from (``ego.lane_frame.lane_departure``)
LANE_DEPARTURE_NEEDS = ("d", "d_ref", "phase")
LANE_DEPARTURE_METRIC = Metric(
    "max_lane_departure",
    "m",
    "largest reach of the ego's side beyond the outer edge of its lane's marking outside a "
    "commanded lane change (0: it stayed in its lane; UN R157 5.2.1, docs/scenarios.md)",
)
COMMON_TAIL_METRICS = (
    Metric("sim_time", "s", "simulated time"),
    Metric("wall_time", "s", "wall-clock time of the run"),
    Metric("steps", "-", "control steps"),
)


def signal_series(names: Sequence[str], units: Mapping[str, str]) -> list[Series]:
    """Recording series for a controller's internal signals: one "controller" panel per
    unit (``units``: name -> unit, as the controller declares them)."""
    return [Series(n, f"plots/controller/{unit_path(units.get(n, ''))}/{n}", units.get(n, ""), n) for n in names]


def vehicle_series() -> list[Series]:
    """Recording series every scenario has: speed and its reference, the actuators and the
    lateral acceleration."""
    return [
        Series("speed", "plots/speed/ego", "m/s", "ego"),
        Series("speed_ref", "plots/speed/reference", "m/s", "reference"),
        Series("Fx", "plots/Fx/Fx", "N", "Fx per driven wheel"),
        Series("delta", "plots/delta/delta", "rad", "front steer delta"),
        Series("lat_accel", "plots/lateral_accel/ego", "m/s^2", "lateral acceleration"),
    ]
