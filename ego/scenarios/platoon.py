"""Report 004's car following in SUMO: a platoon behind a leader that brakes, speeds up and stops.

A SUMO vehicle leads on a single-lane road (``sumo_nets/platoon``), driving a scripted speed
profile (default: cruise at 40 km/h, brake to 20 km/h, accelerate to 50 km/h, brake hard to
a stop). Behind it ``followers`` cars each run their own :class:`ego.models.Longitudinal`
model (a :class:`ego.models.LongitudinalPlant`, which saturates the command) and their own controller (one :class:`ego.control.following.PlatoonControl` member
each), and every SUMO step each one is pushed into SUMO with the bridge's multi-vehicle
support (``SumoBridge.control`` / ``push``), so SUMO holds the whole platoon.

Sensing: every SUMO step each follower reads its leader from SUMO (``getLeader``: who, and
the bumper-to-bumper gap). Between SUMO steps the gap is carried forward with the
predecessor's motion: the follower ahead is one of ours, so its exact motion is known; the
SUMO leader is extrapolated the way SUMO moves it (at its next speed, v + a * step, for the
whole step, with the acceleration SUMO last reported), which is exact while its acceleration
holds. Each car's spacing error is report 004's delta_d = gap - d_s - lambda v.

Metrics: per follower the RMS and peak spacing error, the smallest gap and time-to-collision,
the peak acceleration and jerk, and how long the spacing error takes to settle after each
leader manoeuvre; for the platoon, whether it is string stable, with the measured
amplification between consecutive vehicles (peak and L2 ratios of the spacing error and of
the acceleration; with a sinusoidal leader, the gain at its frequency). A run ends at
``duration`` (completed), at the first collision, or when a follower diverges.

``variant=scale-model`` is report 004's 3-car scale test: a leader setting off to 0.5 m/s
and two followers keeping 0.4 m standstill gaps, with small cars.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from typing import Any, Protocol, cast

import numpy as np

from ego.control.base import ControllerSpec
from ego.control.following import FollowingObservation, PlatoonControl
from ego.lane_frame import LanePolyline
from ego.models import Longitudinal, LongitudinalParams, LongitudinalPlant, SpacingPolicy, VehicleGeometry
from ego.params import ConfigError, param, shown
from ego.record.base import Scene, Series
from ego.results import metrics as m
from ego.results.trace import Band, Column, FrequencyResponse, Marker, Metric, Plot, PlotSpec, Ref
from ego.scenarios import string_stability as ss
from ego.scenarios.base import NO_COLLISION, CommonConfig, PartsLoop, Scenario
from ego.scenarios.events import INF, time_to_collision
from ego.sim.protocol import TrafficSim
from ego.sim.traffic import Manoeuvre, ProfiledLeader, SpeedProfile
from ego.sim.types import Collision, Neighbour, VehicleSpec, VehicleType, ego_type
from ego.sumo.net import lane_length

LEADER = "leader"
EDGE, ROUTE = "road", "road_route"
KMH = 1.0 / 3.6
TAIL = 10.0  #: m of road behind the last follower at t = 0
END_MARGIN = 20.0  #: m the leader must stay short of the end of the road
LEADER_COLOR = (255, 150, 0)
FOLLOWER_COLOR = (220, 40, 40)

#: ``--set variant=NAME`` starts from these values (anything set explicitly still wins)
VARIANTS: dict[str, dict[str, Any]] = {
    "road": {},
    "scale-model": {
        "followers": 2,
        "standstill_gap": 0.4,
        "start_speed": 0.0,
        "manoeuvres": "2:1.8:0.5,40:0:0.5",
        "duration": 60.0,
        "length": 0.4,
        "width": 0.2,
        "max_accel": 1.0,
        "max_decel": 2.0,
        "lag": 0.1,
        "settle_band": 0.02,
    },
}


def parse_manoeuvres(text: str) -> tuple[Manoeuvre, ...]:
    """``"10:20:2,35:50:1.5"`` (time s : target km/h : rate m/s^2, ...) or ``"none"``."""
    raw = text.strip().lower()
    if raw in ("", "none"):
        return ()
    bad = ConfigError(
        f"bad value for manoeuvres: {shown(text)} (expected time s:target km/h:rate m/s^2 "
        "items separated by commas with increasing times, e.g. 10:20:2,35:50:1.5,60:0:6; "
        "or none)"
    )
    out: list[Manoeuvre] = []
    for item in raw.split(","):
        try:
            t, v, rate = (float(x) for x in item.split(":"))
        except ValueError:
            raise bad from None
        if not (0.0 <= t <= 3600.0 and 0.0 <= v <= 150.0 and 0.0 < rate <= 12.0):
            raise bad
        if out and t <= out[-1].time:
            raise bad
        out.append(Manoeuvre(t, v * KMH, rate))
    return tuple(out)


@dataclass(frozen=True)
class PlatoonConfig(CommonConfig):
    """Report 004's platoon (``variant=road``, default) or its scale test (``scale-model``)."""

    variant: str = param(
        "road",
        "-",
        "road: report 004's simulation (40 km/h, d_s 3 m); scale-model: "
        "its 3-car test (leader to 0.5 m/s, 0.4 m gaps: followers=2, "
        "standstill_gap=0.4, start_speed=0, manoeuvres=2:1.8:0.5,40:0:0.5, "
        "duration=60, length=0.4, width=0.2, max_accel=1, max_decel=2, lag=0.1, "
        "settle_band=0.02)",
        choices=tuple(VARIANTS),
    )
    duration: float = param(90.0, "s", "simulated time", min=1.0, max=3600.0)
    followers: int = param(3, "-", "project-controlled followers behind the SUMO leader", min=1, max=10)
    standstill_gap: float = param(3.0, "m", "d_s: the gap kept at standstill (report 004: 3 m)", min=0.1, max=50.0)
    headway: float = param(
        2.0,
        "s",
        "lambda: time headway of the spacing policy, desired gap "
        "d_s + lambda v (report 004: 0.2 s, string unstable with its gains)",
        min=0.0,
        max=5.0,
    )
    start_speed: float = param(40.0, "km/h", "the platoon's speed at t = 0 (report 004: 40 km/h)", min=0.0, max=150.0)
    manoeuvres: str = param(
        "10:20:2,35:50:1.5,60:0:6",
        "-",
        "the leader's manoeuvres: time s:target "
        "km/h:rate m/s^2, comma-separated (default: brake to 20 km/h at 10 s, "
        "accelerate to 50 km/h at 35 s, brake hard to a stop at 60 s); none: cruise",
    )
    sine_amplitude: float = param(
        0.0,
        "km/h",
        "adds amplitude x sin(sine_omega t) to the leader's speed; the frequency-domain gains are measured then",
        min=0.0,
        max=30.0,
    )
    sine_omega: float = param(0.9, "rad/s", "angular frequency of the leader's speed oscillation", min=0.01, max=10.0)
    sine_transient: float = param(
        40.0, "s", "left out at the start when measuring the gains at sine_omega", min=0.0, max=3000.0
    )
    start_error: float = param(
        0.0,
        "m",
        "every follower starts this much farther back than its desired gap (negative: closer)",
        min=-40.0,
        max=100.0,
    )
    lag: float = param(0.2, "s", "first-order actuator lag of the followers (report 004: none)", min=0.0, max=2.0)
    max_accel: float = param(2.5, "m/s^2", "followers' largest acceleration command", min=0.1, max=10.0)
    max_decel: float = param(8.0, "m/s^2", "followers' largest deceleration command", min=0.1, max=12.0)
    length: float = param(4.5, "m", "length of every car", min=0.1, max=20.0)
    width: float = param(1.8, "m", "width of every car", min=0.05, max=3.0)
    settle_band: float = param(
        0.2, "m", "the spacing error has settled when |delta_d| stays below", min=0.001, max=10.0
    )

    def __post_init__(self) -> None:
        super().__post_init__()
        self.profile  # noqa: B018 - parse (and reject) the manoeuvres now
        if self.start_gap <= 0.0:
            raise ConfigError(
                f"bad value for start_error: {self.start_error:g} (the followers would "
                f"start at a gap of {self.start_gap:.2f} m; expected a positive gap)"
            )

    @property
    def profile(self) -> SpeedProfile:
        """The leader's speed profile (m/s)."""
        return SpeedProfile(
            self.start_speed * KMH, parse_manoeuvres(self.manoeuvres), self.sine_amplitude * KMH, self.sine_omega
        )

    @property
    def start_gap(self) -> float:
        """Bumper-to-bumper gap of every follower at t = 0 (m)."""
        return self.standstill_gap + self.headway * self.profile.speed(0.0) + self.start_error


def _check_road(c: PlatoonConfig, length: float) -> float:
    """The leader's start (m along the lane) if the drive fits on a lane of ``length`` m,
    else ConfigError."""
    lead_pos = TAIL + c.length + c.followers * (c.length + c.start_gap)
    need = lead_pos + c.profile.distance(c.duration) + END_MARGIN
    if need > length:
        raise ConfigError(
            f"the platoon and its leader's {c.duration:g} s drive need {need:.0f} m of "
            f"road; the platoon network has {length:.0f} m (shorten duration or "
            "lower the speeds)"
        )
    return lead_pos


class PlatoonSim(TrafficSim, Protocol):
    """What the platoon asks of its simulator besides :class:`TrafficSim` (SUMO's bridge:
    the followers pushed with their acceleration, the leader's and who leads whom)."""

    def push(self, vid: str, x: float, y: float, psi: float, speed: float, accel: float | None = None) -> None: ...
    def acceleration(self, vid: str) -> float: ...
    def lane_position(self, vid: str) -> float: ...
    def read_leader(self, vid: str, out: Neighbour) -> Neighbour: ...
    def box(self, vid: str) -> tuple[float, float, float, float, float, float]: ...


class PlatoonScenario(Scenario):
    """A SUMO leader and a platoon of project-controlled followers in one lane."""

    name = "platoon"
    requirements = (NO_COLLISION,)
    summary = (
        "report 004: a platoon of followers (own model and controller each) behind a SUMO "
        "leader that brakes, accelerates and stops; string stability measured "
        "(--set variant=scale-model: the report's 3-car scale test)"
    )
    task = "car-following"
    network = "platoon"
    needs = ("any_network", "several_egos")
    config_cls = PlatoonConfig
    #: one observation per follower, in platoon order (the controllers' PlatoonControl
    #: steps on them all), not the one Observation of a scenario with one ego
    obs: list[FollowingObservation]  # type: ignore[assignment]
    loop: PlatoonLoop
    ids: tuple[str, ...]
    profile: SpeedProfile
    metric_specs = (
        Metric(
            "followers.", "-", "per follower (id): the platoon's metrics below, each in its unit, and its settle_times"
        ),
        Metric("rms_spacing_error", "m", "worst follower's RMS spacing error delta_d", headline=True),
        Metric("max_abs_spacing_error", "m", "worst follower's largest |delta_d|", headline=True),
        Metric("min_gap", "m", "smallest gap of any follower", headline=True),
        Metric("min_ttc", "s", "smallest time-to-collision of any follower", headline=True),
        Metric("max_abs_accel", "m/s^2", "worst follower's largest |acceleration|", headline=True),
        Metric("max_abs_jerk", "m/s^3", "worst follower's largest |jerk|", headline=True),
        Metric(
            "settle_times.",
            "s",
            "per disturbance window: the slowest follower's time until "
            "|delta_d| stays within settle_band (None: some never settled)",
            headline=True,
        ),
        Metric("string_stable", "-", "no disturbance grew down the platoon (None: nothing tells)", headline=True),
        Metric(
            "amplification.",
            "-",
            "per pair of consecutive vehicles: peak and L2 ratios of the acceleration and of the spacing error",
        ),
        Metric(
            "frequency_gain.",
            "-",
            "per pair of consecutive vehicles: speed gain at sine_omega (with a sinusoidal leader)",
            headline=True,
        ),
    )

    @classmethod
    def check_config(cls, config: PlatoonConfig) -> None:
        """The leader's whole drive must fit on the network's road (read from its XML)."""
        _check_road(config, lane_length(cls.network, f"{EDGE}_0"))

    @classmethod
    def default_config(cls, overrides: Mapping[str, Any]) -> PlatoonConfig:
        preset = VARIANTS.get(str(overrides.get("variant", "road")).strip())
        base = cls.config_cls()
        return replace(base, variant=str(overrides["variant"]).strip(), **preset) if preset else base

    @classmethod
    def build_controller(  # type: ignore[override]  # one controller per follower, stepped on their observations
        cls, spec: ControllerSpec, params: Any, config: Any
    ) -> PlatoonControl:
        ids = follower_ids(config.followers)
        return PlatoonControl([spec.build(params, config.dt) for _ in ids], ids)

    @classmethod
    def compare_plots(cls, config: Any) -> tuple[PlotSpec, ...]:
        """Every follower's speed (the leader's dashed), spacing error (the settle band
        shaded), gap and acceleration, one line per follower in a panel per controller; the
        string stability's |H(jw)|."""
        ids = follower_ids(config.followers)

        def lines(q: str) -> tuple[tuple[str, str], ...]:
            return tuple((f"{q}_{vid}", vid) for vid in ids)

        sine = config.sine_amplitude > 0.0
        marks = (Marker("leader", "the leader's manoeuvre starts", "v"), Marker("collision", "collision", "X"))
        return (
            Plot(
                f"speed_{ids[0]}",
                "speed.png",
                "speed",
                lines=lines("speed"),
                refs=(Ref("leader", "lead_speed"),),
                markers=marks,
            ),
            Plot(
                f"e_{ids[0]}",
                "spacing_error.png",
                "spacing error delta_d",
                lines=lines("e"),
                band=Band(-config.settle_band, config.settle_band, f"settle band +-{config.settle_band:g} m"),
                markers=marks,
            ),
            Plot(
                f"gap_{ids[0]}",
                "gap.png",
                "gap to the car ahead",
                lines=lines("gap"),
                refs=(Ref("standstill gap d_s", value=config.standstill_gap),),
                markers=marks,
            ),
            Plot(
                f"accel_{ids[0]}",
                "accel.png",
                "acceleration",
                lines=lines("accel"),
                refs=(Ref("leader", "lead_accel"),),
                markers=marks,
            ),
            FrequencyResponse(
                "string_stability.png",
                ("lead_speed", *(f"speed_{vid}" for vid in ids)),
                (LEADER, *ids),
                config.headway,
                config.lag,
                config.sine_omega if sine else None,
                config.sine_transient if sine else 0.0,
                tuple(f"{g}_{vid}" for vid in ids for g in ("kp", "ki", "kd")),
            ),
        )

    def trace_columns(self) -> tuple[Column, ...]:
        """The leader's columns, then :data:`PER_FOLLOWER` for every follower."""
        return LEADER_COLUMNS + tuple(
            Column(f"{q}_{vid}", unit, f"{vid}: {text}")
            for vid in follower_ids(self.config.followers)
            for q, unit, text in PER_FOLLOWER
        )

    def make_loop(self) -> PlatoonLoop:
        """The followers' plants keyed by id, the leader's profile, no road sensor (each
        follower is measured along the one lane)."""
        c = self.config
        self.ids = follower_ids(c.followers)
        self.profile = c.profile
        self.geometry = VehicleGeometry(length=c.length, width=c.width, cg_to_front=0.5 * c.length)
        self.obs = []
        self.plants: dict[str, LongitudinalPlant] = {}
        self.lane: LanePolyline | None = None  #: the platoon's one lane (once a run has started)
        return PlatoonLoop(self)

    # -- the controlled vehicles by id (Scenario's contract) -------------------------------
    def observation(self, vid: str) -> FollowingObservation:
        return self.obs[self.ids.index(vid)]

    def plant(self, vid: str) -> LongitudinalPlant:
        return self.plants[vid]

    def action_limits(self, vid: str | None = None) -> tuple[float, float, float]:
        """A follower's commanded acceleration (m/s^2) within its limits; it keeps its lane."""
        c = self.config
        return -c.max_decel, c.max_accel, 0.0

    def joint_action(self, own: Any, vid: str, longitudinal: float | None, lateral: float | None) -> Any:
        """The controllers' actions (one per follower) with ``vid``'s longitudinal command
        replaced (a follower does not steer)."""
        own[self.ids.index(vid)] = (longitudinal, 0.0)
        return own

    def agent_signals(self, vid: str) -> tuple[float, float, float | None, float]:
        return self.agent_signals_reader(vid)()

    def agent_signals_reader(self, vid: str) -> Callable[[], tuple[float, float, float | None, float]]:
        i = self.ids.index(vid)
        o, e = self.obs[i], self.loop.e  # a run's observations; the errors updated in place
        return lambda: (o.speed, e[i], o.accel, 0.0)

    def lane_rows(self, vid: str) -> tuple[tuple[float, ...], Any, float]:
        """The leader and the followers behind ``vid``, all on the platoon's one lane."""
        i = self.ids.index(vid)
        half = 0.5 * self.config.length
        loop = self.loop
        own = loop.chain[i].state
        ego = (own[0] - half, 0.0, own[1], 0.0, 0.0)
        lead = self.obs[0]
        rows = [(loop.chain[0].state[0] + loop.gap[0] + half, 0.0, lead.lead_speed, 0.0, 0.0)]
        rows += [(p.state[0] - half, 0.0, p.state[1], 0.0, 0.0) for j, p in enumerate(loop.chain) if j != i]
        return ego, rows, self.config.length

    # -- results ------------------------------------------------------------------------------
    def _metrics(self, trace: np.ndarray, columns: tuple[str, ...]) -> dict[str, Any]:
        if not trace.size:
            return {"string_stable": None}
        c = self.config
        col = {name: trace[:, j] for j, name in enumerate(columns)}
        t = col["t"]
        windows = self.windows(float(t[-1]) + c.dt)
        followers: dict[str, dict[str, Any]] = {}
        for vid in self.ids:
            e, acc = col[f"e_{vid}"], col[f"accel_{vid}"]
            jerk = np.diff(acc) / c.dt if len(acc) > 1 else np.zeros(1)
            followers[vid] = {
                "rms_spacing_error": m.json_number(float(np.sqrt(np.mean(e * e)))),
                "max_abs_spacing_error": m.json_number(m.max_abs(e)),
                "min_gap": m.json_number(float(np.min(col[f"gap_{vid}"])), 4),
                "min_ttc": m.json_number(m.finite_min(col[f"ttc_{vid}"]), 4),
                "max_abs_accel": m.json_number(m.max_abs(acc)),
                "max_abs_jerk": m.json_number(m.max_abs(jerk)),
                "settle_times": {name: _settle(t, e, c.settle_band, start, stop) for name, start, stop in windows},
            }
        per = list(followers.values())

        def worst(key: str, pick: Callable[[list[Any]], Any] = max) -> Any:
            values = [f[key] for f in per if f[key] is not None]
            return pick(values) if values else None

        settle = {}
        for name, _, _ in windows:
            times = [f["settle_times"][name] for f in per]
            settle[name] = None if any(x is None for x in times) else max(times)
        amplification = self._amplification(col)
        gains = self._sine_gains(col)
        ratios = [r["l2_accel"] for r in amplification.values()]
        ratios += [r["l2_spacing_error"] for r in amplification.values() if "l2_spacing_error" in r]
        ratios += list(gains.values()) if gains else []
        stable = _string_stable([r for r in ratios if r is not None], self.status)
        return {
            "followers": followers,
            "rms_spacing_error": worst("rms_spacing_error"),
            "max_abs_spacing_error": worst("max_abs_spacing_error"),
            "min_gap": worst("min_gap", min),
            "min_ttc": worst("min_ttc", min),
            "max_abs_accel": worst("max_abs_accel"),
            "max_abs_jerk": worst("max_abs_jerk"),
            "settle_times": settle,
            "string_stable": stable,
            "amplification": amplification,
            "frequency_gain": gains,
        }

    def windows(self, end: float) -> list[tuple[str, float, float]]:
        """(name, start, end) of every disturbance the spacing error settles from: the
        start (when the followers start off their desired gaps) and each manoeuvre."""
        out = self.profile.windows(end)
        if self.config.start_error:
            first = min([w[1] for w in out] + [end])
            out.insert(0, ("start@0s", 0.0, first))
        return out

    def _amplification(self, col: dict[str, np.ndarray]) -> dict[str, dict[str, float | None]]:
        """Ratios between consecutive vehicles, over the whole run: peak and L2 of the
        acceleration (from the leader on) and of the spacing error (between followers)."""
        out = {}
        names = (LEADER, *self.ids)
        accel = [col["lead_accel"]] + [col[f"accel_{vid}"] for vid in self.ids]
        for k in range(len(self.ids)):
            up, down = names[k], names[k + 1]
            pair = {
                "peak_accel": _num(ss.peak_ratio(accel[k], accel[k + 1], ACCEL_FLOOR)),
                "l2_accel": _num(ss.l2_ratio(accel[k], accel[k + 1], ACCEL_FLOOR)),
            }
            if k:
                e_up, e_down = col[f"e_{up}"], col[f"e_{down}"]
                pair["peak_spacing_error"] = _num(ss.peak_ratio(e_up, e_down, ERROR_FLOOR))
                pair["l2_spacing_error"] = _num(ss.l2_ratio(e_up, e_down, ERROR_FLOOR))
            out[f"{up}->{down}"] = pair
        return out

    def _sine_gains(self, col: dict[str, np.ndarray]) -> dict[str, float | None] | None:
        """With a sinusoidal leader: |V_i / V_(i-1)| at its frequency, after the transient."""
        c = self.config
        if c.sine_amplitude <= 0.0:
            return None
        t = col["t"]
        keep = t >= c.sine_transient
        if not keep.any():
            return None
        names = (LEADER, *self.ids)
        speeds = [col["lead_speed"]] + [col[f"speed_{vid}"] for vid in self.ids]
        return {
            f"{names[k]}->{names[k + 1]}": _num(
                ss.sine_gain(t[keep], speeds[k][keep], speeds[k + 1][keep], c.sine_omega)
            )
            for k in range(len(self.ids))
        }


class PlatoonLoop(PartsLoop):
    """The platoon's loop: the followers' plants (keyed by vehicle id, in platoon order), the
    SUMO leader on its speed profile (the leader's manoeuvres are its events), the gaps read
    from SUMO every step and carried forward between steps, every follower's observation."""

    sc: PlatoonScenario
    #: the simulator of the run (set by :meth:`setup`)
    sim: PlatoonSim

    def __init__(self, sc: PlatoonScenario) -> None:
        super().__init__(sc)
        c = sc.config
        self.ids = sc.ids
        #: the trace columns in the order act collects a row's values
        self._row_names = tuple(c.name for c in sc.trace_columns())
        self.profile = sc.profile
        self.policy = SpacingPolicy(c.standstill_gap, c.headway)
        self.geometry = sc.geometry
        self.model = Longitudinal(LongitudinalParams(lag=c.lag, max_accel=c.max_accel, max_decel=c.max_decel))
        self.lane: LanePolyline | None = None
        self.obs: list[FollowingObservation] = sc.obs
        n = c.followers
        #: the followers, f1 first: state (front bumper along the lane m, speed m/s, acceleration m/s^2)
        #: the followers' plants in platoon order (f1 first) and the same keyed by vehicle id
        self.chain: list[LongitudinalPlant] = []
        self.plants: dict[str, LongitudinalPlant] = {}
        self.gap = [0.0] * n
        self.e = [0.0] * n  #: spacing errors delta_d (m)
        self.ttc = [INF] * n
        self._gap_sync = [0.0] * n
        self._s_sync = [0.0] * n
        self._lead = Neighbour()
        self._lead_a = self._lead_v_now = 0.0
        self._lead_s_sync = 0.0
        self._sync_t = 0.0
        self._bad: str | None = None
        #: the traffic log's ids (the leader, then the followers) and the followers' poses
        #: pushed into SUMO for the last step (centre of gravity x, y in m, yaw in rad)
        self._log_ids = (LEADER, *self.ids)
        self._pushed: list[tuple[float, float, float]] = []

    # -- set-up ---------------------------------------------------------------------------
    def setup(self, rng: np.random.Generator) -> None:
        sc = self.sc
        self._write_row = sc.trace.bind(self._row_names)
        c = sc.config
        bridge = sc.bridge
        assert bridge is not None  # the platoon drives in SUMO
        self.sim = sim = cast(PlatoonSim, bridge)
        width, points = bridge.lane_shapes()[f"{EDGE}_0"]
        self.lane = lane = sc.lane = LanePolyline(points, width, f"{EDGE}_0")
        L, gap0, n = c.length, c.start_gap, c.followers
        v0 = self.profile.speed(0.0)
        lead_pos = _check_road(c, lane.length)
        bridge.add_type(
            VehicleType(
                LEADER,
                length=L,
                width=c.width,
                accel=10.0,
                decel=12.0,
                emergency_decel=12.0,
                max_speed=60.0,
                sigma=0.0,
                color=LEADER_COLOR,
            )
        )
        bridge.add_type(ego_type("follower", self.geometry, decel=c.max_decel))
        bridge.add_route(ROUTE, [EDGE])
        fronts = [lead_pos - (i + 1) * (L + gap0) for i in range(n)]
        bridge.add_vehicles(
            [VehicleSpec(LEADER, LEADER, ROUTE, 0, lead_pos, v0)]
            + [VehicleSpec(vid, "follower", ROUTE, 0, pos, v0) for vid, pos in zip(self.ids, fronts)]
        )
        bridge.insert(required=[LEADER, *self.ids])
        self.leader = ProfiledLeader(LEADER, self.profile)
        self.leader.start(sim)
        for vid in self.ids:
            bridge.control(vid, self.geometry, keep_route=1)
        sc.controlled_ids = self.ids
        sc.colors = {LEADER: LEADER_COLOR, **{vid: FOLLOWER_COLOR for vid in self.ids}}

        self.chain = [LongitudinalPlant(self.model, lane, self.geometry, c.dt, front, v0) for front in fronts]
        self.plants = sc.plants = dict(zip(self.ids, self.chain))
        self.obs = sc.obs = [
            FollowingObservation(policy=self.policy, max_accel=c.max_accel, max_decel=c.max_decel) for _ in self.ids
        ]
        self._bad = None
        self._pushed = [plant.pose() for plant in self.chain]
        self._manoeuvre = 0  #: the leader's next manoeuvre (index into profile.manoeuvres)
        self._manoeuvre_at = self._next_manoeuvre_time()
        self.after_sim_step()

    # -- per step ---------------------------------------------------------------------------
    def act(self, actions: Any) -> None:
        """Every follower's command through its plant; the trace row for t (states before
        the step, the command as the actuator took it)."""
        sc = self.sc
        gap, e, ttc = self.gap, self.e, self.ttc
        values = [sc.t, self._lead_v_now, self._lead_a]
        for i, (plant, (cmd, _)) in enumerate(zip(self.chain, actions)):
            if not -math.inf < cmd < math.inf:  # NaN fails both comparisons
                self._bad = f"the controller of {self.ids[i]} commanded {cmd} m/s^2"
                cmd = 0.0
            _, v, a = plant.state
            plant.step((cmd,))
            # in PER_FOLLOWER order
            values += (gap[i], e[i], v, a, plant.applied[0], ttc[i])
        self._write_row(sc.controller.signals(), tuple(values))  # a tuple: the writer's C path

    def before_sim_step(self) -> None:
        sc = self.sc
        bridge = self.sim
        self.leader.update(bridge, sc.t)
        pushed = self._pushed = []
        for vid, plant in zip(self.ids, self.chain):
            x, y, psi = plant.pose()
            _, v, a = plant.state
            bridge.push(vid, x, y, psi, v, a)
            pushed.append((x, y, psi))

    def after_sim_step(self) -> None:
        """Read who leads whom and the gaps from SUMO; the leader's speed and acceleration."""
        sc = self.sc
        bridge = self.sim
        lead_v, self._lead_a = bridge.speed(LEADER), bridge.acceleration(LEADER)
        # SUMO moves its vehicles at their new speed for the whole step (Euler): the leader
        # keeps its acceleration, so until the next step it drives at v + a * step
        self._lead_v_now = max(lead_v + self._lead_a * sc.config.sumo_step, 0.0)
        self._lead_s_sync = bridge.lane_position(LEADER)
        self._sync_t = sc.t
        L = sc.config.length
        s = [plant.state[0] for plant in self.chain]
        for i, vid in enumerate(self.ids):
            ahead = LEADER if i == 0 else self.ids[i - 1]
            found = bridge.read_leader(vid, self._lead)
            if found.id == ahead:
                self._gap_sync[i] = found.gap
            else:  # beyond SUMO's look-ahead: from the lane positions
                front = self._lead_s_sync if i == 0 else s[i - 1]
                self._gap_sync[i] = front - L - s[i]
            self._s_sync[i] = s[i]

    def log_traffic(self) -> None:
        """Every vehicle within RADIUS of a follower (every follower is an ego): the
        followers where they were pushed into SUMO for this step, the leader from SUMO."""
        sc = self.sc
        rows = [self.sim.box(LEADER)]
        L, W = sc.config.length, sc.config.width
        for plant, (x, y, psi) in zip(self.chain, self._pushed):
            rows.append((x, y, psi, plant.state[1], L, W))  # the CG is the box centre here
        traffic = sc.traffic
        assert traffic is not None  # a run in SUMO logs its traffic
        traffic.add(sc.t, [p[:2] for p in self._pushed], self._log_ids, rows)

    def diverged(self) -> str | None:
        if self._bad is not None:
            return self._bad
        states = [plant.state for plant in self.chain]
        # one sum is finite only if every state is (NaN and infinity propagate)
        if math.isfinite(sum(map(sum, states))) and max(map(_speed_of, states)) <= 80.0:
            return None
        for vid, (s, v, a) in zip(self.ids, states):
            if not (math.isfinite(s) and math.isfinite(v) and math.isfinite(a)):
                return f"the state of {vid} is not finite (NaN or infinity)"
            if v > 80.0:
                return f"{vid} drives at {v:.1f} m/s: absurd"
        return None

    def update(self) -> None:
        """Gaps now (carried forward from the last SUMO step), observations, collisions."""
        sc = self.sc
        t = sc.t
        if t >= self._manoeuvre_at:
            self._leader_manoeuvre()
        since = t - self._sync_t
        lead_v, lead_a = self._lead_v_now, self._lead_a
        moved = lead_v * since
        s_sync, gap_sync = self._s_sync, self._gap_sync
        error = self.policy.error
        ahead_s = 0.0
        for i, (o, plant) in enumerate(zip(self.obs, self.chain)):
            s, speed, accel = plant.state
            if i:
                moved = ahead_s - s_sync[i - 1]
            gap = gap_sync[i] + moved - (s - s_sync[i])
            self.gap[i] = gap
            self.e[i] = error(gap, speed)
            self.ttc[i] = time_to_collision(gap, speed - lead_v)
            o.t = t
            o.gap = gap
            o.speed = speed
            o.accel = accel
            o.lead_speed = lead_v
            o.lead_accel = lead_a
            if gap <= 0.0:
                ahead = LEADER if i == 0 else self.ids[i - 1]
                sc._collided(Collision(self.ids[i], ahead, "rear-end (gap <= 0)", speed, lead_v))
                return
            ahead_s, lead_v, lead_a = s, speed, accel

    def _next_manoeuvre_time(self) -> float:
        ms = self.profile.manoeuvres
        return ms[self._manoeuvre].time if self._manoeuvre < len(ms) else INF

    def _leader_manoeuvre(self) -> None:
        """The leader starts its next manoeuvre: an event (the log, the recording's events)."""
        sc = self.sc
        m = self.profile.manoeuvres[self._manoeuvre]
        self._manoeuvre += 1
        self._manoeuvre_at = self._next_manoeuvre_time()
        before = self.profile.base_speed(m.time)
        kind = m.kind(before)
        if kind == "hold":
            sc.event("leader", f"{LEADER} holds its speed ({before / KMH:.0f} km/h)")
            return
        what = "stops" if kind == "stop" else f"{kind}s to {m.speed / KMH:g} km/h"
        sc.event("leader", f"{LEADER} {what} at {m.rate:g} m/s^2 (from {before / KMH:.0f} km/h)")

    # -- recording ----------------------------------------------------------------------------
    def record_boxes(self) -> None:
        sc = self.sc
        ids, poses = self.sim.poses()
        back = self.chain[-1].state[0] - sc.config.length
        assert self.lane is not None  # set up
        x, y = self.lane.offset_point(0.5 * (self._lead_s_sync + back), 0.0)
        sc.recorder.vehicles(sc.t, ids, poses, (x, y))

    def scene(self) -> Scene:
        sc = self.sc
        c = sc.config
        top = max(self.profile.speed(k * 0.5) for k in range(int(c.duration * 2) + 1))
        span = c.followers * (c.length + c.standstill_gap + c.headway * top + max(c.start_error, 0.0)) + c.length
        half = 0.6 * span + 2.0 * c.length
        lane = self.lane
        assert lane is not None  # set up
        # the wide view: twice the close one (300 m for report 004's platoon at 50 km/h)
        return Scene(
            lanes=[(lane.width, lane.points)],
            title=sc.name,
            followed="the platoon",
            follow_view=(-half, half, -0.25 * half, 0.25 * half),
            around_view=(-2.0 * half, 2.0 * half, -0.3 * half, 0.3 * half),
        )

    def series(self) -> list[Series]:
        sc = self.sc
        out = [
            Series("lead_speed", "plots/speed/leader", "m/s", "leader"),
            Series("lead_accel", "plots/accel/leader", "m/s^2", "leader"),
        ]
        for vid in self.ids:
            out += [
                Series(f"e_{vid}", f"plots/spacing_error/{vid}", "m", vid),
                Series(f"gap_{vid}", f"plots/gap/{vid}", "m", vid),
                Series(f"speed_{vid}", f"plots/speed/{vid}", "m/s", vid),
                Series(f"accel_{vid}", f"plots/accel/{vid}", "m/s^2", vid),
                Series(f"command_{vid}", f"plots/command/{vid}", "m/s^2", vid),
                Series(f"ttc_{vid}", f"plots/ttc/{vid}", "s", vid),
            ]
        for name in sc._signal_names:  # one panel per signal: each has one unit
            signal, _, vid = name.rpartition("_")
            out.append(Series(name, f"plots/{signal}/{vid}", sc._signal_units.get(name, ""), vid))
        return out


#: the leader's trace columns (after t)
LEADER_COLUMNS = (
    Column("t", "s", "time"),
    Column("lead_speed", "m/s", "the SUMO leader's speed (as extrapolated between SUMO steps)"),
    Column("lead_accel", "m/s^2", "the SUMO leader's acceleration in SUMO's last step"),
)
#: per-follower trace columns, each named ``<quantity>_<follower id>``: (quantity, unit, what)
PER_FOLLOWER = (
    ("gap", "m", "gap to the car ahead"),
    ("e", "m", "spacing error delta_d"),
    ("speed", "m/s", "speed"),
    ("accel", "m/s^2", "actual acceleration"),
    ("command", "m/s^2", "the command as the actuator took it"),
    ("ttc", "s", "time-to-collision with the car ahead"),
)
#: string stable: no measured amplification above 1 + this
STABLE_TOLERANCE = 1e-3
#: below these peaks a signal is sensing noise, and its ratios are not reported
ACCEL_FLOOR = 0.01  #: m/s^2
ERROR_FLOOR = 0.005  #: m


_speed_of = operator.itemgetter(1)  #: a follower's speed in its state (s, v, a)


def follower_ids(n: int) -> tuple[str, ...]:
    """f1 (right behind the leader) .. fn."""
    return tuple(f"f{i}" for i in range(1, n + 1))


def _string_stable(ratios: list[float], status: str) -> bool | None:
    """False when any disturbance grew down the platoon (even in a run that then crashed);
    True when a completed run measured only shrinking ones; None when nothing tells."""
    if any(r > 1.0 + STABLE_TOLERANCE for r in ratios):
        return False
    return True if ratios and status == "completed" else None


def _num(x: float | None) -> float | None:
    return m.json_number(x, 4)


def _settle(t: np.ndarray, e: np.ndarray, band: float, start: float, stop: float) -> float | None:
    """Seconds from ``start`` until |e| stays below ``band`` up to ``stop``; None if it never does."""
    inside = (t >= start) & (t < stop)
    if not inside.any():
        return None
    return m.json_number(m.settling_time(t[inside], e[inside], band, start), 3)
