"""Report 000's fuzzy-adaptive PID (section "(b) Fuzzy-adaptive PID").

A PID on each channel whose gains a Mamdani rule base adjusts from the error e and its
rate ec: 49 rules each for dKp, dKi, dKd. The report's table is an image that was not
kept; these are the classic tables (Liu Jinkun, *Advanced PID control*), as in SPEC.md.

The rule base is defined with scikit-fuzzy (one system, three outputs, like the report's
``fuzzyadp.fis``) and evaluated by :class:`~ego.control.fuzzy_engine.FastMamdani`. The
report scales [Kp, Ki, Kd] by [800, 200, 800] for X and [0.0005, 0, 0.002] for Y; how the
fuzzy outputs enter was in the lost figure, so here each gain is
``scale * (1 + adapt * dK)`` with dK in [-1, 1]: the rule base moves every gain by up to
``adapt`` (50 %) around its scale.

Variants: ``tuned`` (default) keeps the report's X scales but steers with Y scales
[0.008, 0, 0.016]; ``report`` uses the report's Y scales [0.0005, 0, 0.002], with which the
lane change takes ~20 s (as the report says) - too slow to get clear of a braking car, so
the ego ends up braking behind it at low speed, where steering has little authority, and
does not settle within the emergency-brake run.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Any

from ego.control.base import Observation, feedforward_param, lateral_gain, lateral_speed_param
from ego.control.fuzzy import INPUT_RANGE, INPUT_SAMPLES, OUTPUT_SAMPLES, TERMS
from ego.control.fuzzy_engine import FastMamdani, table_rules, table_system
from ego.control.pid import PID
from ego.params import HALF_PI, Params, param


def _table(text: str) -> tuple[tuple[str, ...], ...]:
    return tuple(tuple(row.split()) for row in text.strip().split("|"))


#: rows E NB..PB, columns EC NB..PB
DKP = _table(
    "PB PB PM PM PS ZO ZO | PB PB PM PS PS ZO NS | PM PM PM PS ZO NS NS | "
    "PM PM PS ZO NS NM NM | PS PS ZO NS NS NM NM | PS ZO NS NM NM NM NB | "
    "ZO ZO NM NM NM NB NB"
)
DKI = _table(
    "NB NB NM NM NS ZO ZO | NB NB NM NS NS ZO ZO | NB NM NS NS ZO PS PS | "
    "NM NM NS ZO PS PM PM | NM NS ZO PS PS PM PB | ZO ZO PS PS PM PB PB | "
    "ZO ZO PS PM PM PB PB"
)
DKD = _table(
    "PS NS NB NB NB NM PS | PS NS NB NM NM NS ZO | ZO NS NM NM NS NS ZO | "
    "ZO NS NS NS NS NS ZO | ZO ZO ZO ZO ZO ZO ZO | PB NS PS PS PS PS PB | "
    "PB PM PM PM PS PS PB"
)


#: the report's [Kp, Ki, Kd] scales for Y
REPORT_LAT_SCALES = (0.0005, 0.0, 0.002)


#: the three tables as :func:`~ego.control.fuzzy_engine.table_rules` takes them
TABLE: dict[str, Any] = {
    "inputs": [("e", -INPUT_RANGE, INPUT_RANGE), ("ec", -INPUT_RANGE, INPUT_RANGE)],
    "outputs": [("dkp", -1.0, 1.0), ("dki", -1.0, 1.0), ("dkd", -1.0, 1.0)],
    "term_labels": TERMS,
    "tables": {"dkp": DKP, "dki": DKI, "dkd": DKD},
    "samples": INPUT_SAMPLES,
    "output_samples": OUTPUT_SAMPLES,
}


def rule_base() -> Any:
    """The three 7x7 tables as one scikit-fuzzy ControlSystem (inputs e, ec; outputs dkp,
    dki, dkd on [-1, 1])."""
    return table_system(**TABLE)


@lru_cache(maxsize=1)
def evaluator() -> FastMamdani:
    """The compiled tables (from their rules, without scikit-fuzzy's ControlSystem)."""
    return FastMamdani.from_rules(table_rules(**TABLE), ["e", "ec"], ["dkp", "dki", "dkd"])


@dataclass(frozen=True)
class FuzzyPIDParams(Params):
    """Report 000's gain scales; ``adapt`` and the input gains are ours (lost figure)."""

    variant: str = param(
        "tuned",
        "-",
        "tuned (default) or report (the report's lateral scales, overriding kp_lat, ki_lat, kd_lat)",
        choices=("tuned", "report"),
    )
    kp_lon: float = param(800.0, "N/m", "longitudinal Kp scale (report: 800)", min=0, max=1e5)
    ki_lon: float = param(200.0, "N/(m s)", "longitudinal Ki scale (report: 200)", min=0, max=1e5)
    kd_lon: float = param(800.0, "N s/m", "longitudinal Kd scale (report: 800)", min=0, max=1e5)
    kp_lat: float = param(0.008, "rad/m", "lateral Kp scale (report: 0.0005)", min=0, max=10.0)
    ki_lat: float = param(0.0, "rad/(m s)", "lateral Ki scale (report: 0)", min=0, max=10.0)
    kd_lat: float = param(0.016, "rad s/m", "lateral Kd scale (report: 0.002)", min=0, max=10.0)
    adapt: float = param(0.5, "-", "how far the rules move each gain: scale*(1 + adapt*dK)", min=0.0, max=1.0)
    ke_lon: float = param(1.0, "1/m", "longitudinal error input gain", min=0, max=1000.0)
    kec_lon: float = param(1.0, "s/m", "longitudinal error-rate input gain", min=0, max=1000.0)
    ke_lat: float = param(1.0, "1/m", "lateral error input gain", min=0, max=1000.0)
    kec_lat: float = param(1.0, "s/m", "lateral error-rate input gain", min=0, max=1000.0)
    tau_d: float = param(0.05, "s", "derivative low-pass time constant", min=0, max=10.0)
    fx_limit: float = param(
        4805.0, "N", "|Fx| limit per driven wheel (0.7 m g / Nw)", min=0, max=20000.0, min_exclusive=True
    )
    steer_limit: float = param(0.5, "rad", "|delta| limit", min=0, max=HALF_PI, min_exclusive=True)
    feedforward: bool = feedforward_param()
    lat_speed: float = lateral_speed_param()


class _Channel:
    """One PID whose gains the rule base re-schedules every step."""

    __slots__ = ("pid", "scales", "adapt", "ke", "kec", "dk", "_rules", "gain")

    def __init__(
        self,
        scales: tuple[float, float, float],
        adapt: float,
        ke: float,
        kec: float,
        dt: float,
        limit: float,
        tau_d: float,
        rules: Any,
    ) -> None:
        self.scales = scales
        self.adapt = adapt
        self.ke, self.kec = ke, kec
        self.pid = PID(*scales, dt, -limit, limit, tau_d)
        self.dk = (0.0, 0.0, 0.0)
        self._rules = rules
        self.gain = 1.0  #: a factor on the three scales (the lateral channel's speed schedule)

    def step(self, e: float, de: float) -> float:
        x0, x1 = self.ke * e, self.kec * de
        dk = self.dk = (self._rules[0](x0, x1), self._rules[1](x0, x1), self._rules[2](x0, x1))
        a = self.adapt
        pid = self.pid
        kp, ki, kd = self.scales
        if self.gain != 1.0:
            g = self.gain
            kp, ki, kd = kp * g, ki * g, kd * g
        pid.kp = kp * (1.0 + a * dk[0])
        pid.ki = ki * (1.0 + a * dk[1])
        pid.kd = kd * (1.0 + a * dk[2])
        return pid.step(e, de)


class FuzzyPIDController:
    """Fuzzy-adaptive PID on both channels."""

    def __init__(self, params: FuzzyPIDParams, dt: float) -> None:
        p = self.params = params
        engine = evaluator()
        rules = tuple(engine.single2_output(o) for o in range(3))
        lat = REPORT_LAT_SCALES if p.variant == "report" else (p.kp_lat, p.ki_lat, p.kd_lat)
        self.lon = _Channel(
            (p.kp_lon, p.ki_lon, p.kd_lon), p.adapt, p.ke_lon, p.kec_lon, dt, p.fx_limit, p.tau_d, rules
        )
        self.lat = _Channel(lat, p.adapt, p.ke_lat, p.kec_lat, dt, p.steer_limit, p.tau_d, rules)

    def reset(self, *, seed: int | None = None) -> None:
        for ch in (self.lon, self.lat):
            ch.pid.reset()
            ch.dk = (0.0, 0.0, 0.0)

    def step(self, obs: Observation) -> tuple[float, float]:
        fx = self.lon.step(obs.s_ref - obs.s, obs.ds_ref - obs.ds)
        self.lat.gain = lateral_gain(self.params.lat_speed, obs.speed)
        delta = self.lat.step(obs.d_ref - obs.d, obs.dd_ref - obs.dd)
        return fx, (delta + obs.steer_ff if self.params.feedforward else delta)

    #: the scheduled gains: Fx (N) and delta (rad) per m of error, per m s, per m/s
    signal_units = {
        "kp_lon": "N/m",
        "ki_lon": "N/(m s)",
        "kd_lon": "N s/m",
        "kp_lat": "rad/m",
        "ki_lat": "rad/(m s)",
        "kd_lat": "rad s/m",
    }

    def signals(self) -> dict[str, float]:
        lon, lat = self.lon.pid, self.lat.pid
        return {
            "kp_lon": lon.kp,
            "ki_lon": lon.ki,
            "kd_lon": lon.kd,
            "kp_lat": lat.kp,
            "ki_lat": lat.ki,
            "kd_lat": lat.kd,
        }
